//! Scenario files (TOML): what to simulate. Every key is documented in
//! docs/SIMULATOR.md. Angles are degrees in the file and radians inside; times are
//! GPS seconds of week for absolute instants and seconds from the start for events.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use navfuse_core::time::SECONDS_PER_WEEK;
use navfuse_io::error::InputError;
use serde::Deserialize;

use crate::gnss_sim::GnssSpec;
use crate::imu_model::ImuSpec;
use crate::trajectory::{Rig, Segment, Start, Trajectory};

/// A scenario file as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Seed of every random stream.
    pub seed: u64,
    /// Free text, copied into the summary.
    #[serde(default)]
    pub description: String,
    pub start: StartSpec,
    #[serde(rename = "segment")]
    pub segments: Vec<SegmentSpec>,
    #[serde(default)]
    pub vehicle: VehicleSpec,
    #[serde(default)]
    pub imu: Option<ImuSpec>,
    /// Engine-like vibration of the IMU (vibration.rs).
    #[serde(default)]
    pub vibration: Option<crate::vibration::VibrationSpec>,
    #[serde(default)]
    pub odometer: Option<OdometerSpec>,
    /// Simulated barometer (baro_sim.rs).
    #[serde(default)]
    pub baro: Option<crate::baro_sim::BaroSpec>,
    #[serde(default)]
    pub gnss: Option<GnssSpec>,
    #[serde(default)]
    pub output: OutputSpec,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// GPS week of the start.
    pub gps_week: u32,
    /// GPS seconds of week at the start.
    pub time_s: f64,
    /// Latitude \[deg\], longitude \[deg\], ellipsoidal height \[m\] of the IMU.
    pub position_deg_m: [f64; 3],
    #[serde(default)]
    pub heading_deg: f64,
    #[serde(default)]
    pub speed_mps: f64,
}

/// One `[[segment]]` table; `type` selects the manoeuvre.
#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SegmentSpec {
    Static {
        duration_s: f64,
    },
    Hold {
        duration_s: f64,
    },
    Accelerate {
        accel_mps2: f64,
        to_speed_mps: Option<f64>,
        duration_s: Option<f64>,
        #[serde(default)]
        ramp_s: f64,
    },
    Turn {
        rate_dps: f64,
        angle_deg: f64,
        #[serde(default)]
        ramp_s: f64,
    },
    CoordinatedTurn {
        rate_dps: f64,
        angle_deg: f64,
        #[serde(default = "default_roll_s")]
        roll_s: f64,
    },
    Climb {
        vertical_speed_mps: f64,
        height_m: f64,
        #[serde(default = "default_transition_s")]
        transition_s: f64,
    },
    LaneChange {
        width_m: f64,
        duration_s: f64,
    },
    BodyProfile {
        duration_s: f64,
        accel_body_mps2: [f64; 3],
        euler_rates_dps: [f64; 3],
    },
}

fn default_roll_s() -> f64 {
    3.0
}
fn default_transition_s() -> f64 {
    3.0
}

impl SegmentSpec {
    fn to_segment(&self) -> Segment {
        match *self {
            SegmentSpec::Static { duration_s } => Segment::Static { duration_s },
            SegmentSpec::Hold { duration_s } => Segment::Hold { duration_s },
            SegmentSpec::Accelerate {
                accel_mps2,
                to_speed_mps,
                duration_s,
                ramp_s,
            } => Segment::Accelerate {
                accel_mps2,
                to_speed_mps,
                duration_s,
                ramp_s,
            },
            SegmentSpec::Turn {
                rate_dps,
                angle_deg,
                ramp_s,
            } => Segment::Turn {
                rate_dps,
                angle_deg,
                ramp_s,
            },
            SegmentSpec::CoordinatedTurn {
                rate_dps,
                angle_deg,
                roll_s,
            } => Segment::CoordinatedTurn {
                rate_dps,
                angle_deg,
                roll_s,
            },
            SegmentSpec::Climb {
                vertical_speed_mps,
                height_m,
                transition_s,
            } => Segment::Climb {
                vertical_speed_mps,
                height_m,
                transition_s,
            },
            SegmentSpec::LaneChange {
                width_m,
                duration_s,
            } => Segment::LaneChange {
                width_m,
                duration_s,
            },
            SegmentSpec::BodyProfile {
                duration_s,
                accel_body_mps2,
                euler_rates_dps,
            } => Segment::BodyProfile {
                duration_s,
                accel_body_mps2,
                euler_rates_dps,
            },
        }
    }
}

/// How the IMU sits in the vehicle (see [`Rig`]).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleSpec {
    /// IMU frame relative to the vehicle frame: roll, pitch, yaw \[deg\] (ZYX).
    #[serde(default)]
    pub imu_mounting_deg: [f64; 3],
    /// Lever arm from the IMU to the vehicle reference point (odometer wheel /
    /// rear-axle centre), IMU frame, forward-right-down \[m\].
    #[serde(default)]
    pub imu_to_reference_m: [f64; 3],
}

/// Odometer (SYSTEM.md §4b; seed 004): pulses from the distance travelled by the
/// vehicle reference point.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OdometerSpec {
    /// Output rate \[Hz\].
    #[serde(default = "default_odo_rate")]
    pub rate_hz: f64,
    /// Nominal distance per pulse K_OD \[m\] (seed 004: 0.00324).
    #[serde(default = "default_k_od")]
    pub meters_per_pulse: f64,
    /// Pulses per wheel revolution (seed 004: 1024); informational (circumference =
    /// K_OD * pulses_per_rev), written to the summary.
    #[serde(default = "default_ppr")]
    pub pulses_per_rev: u32,
    /// Scale-factor error dk \[ppm\]: true distance = (1 + dk) * K_OD * pulses.
    #[serde(default)]
    pub scale_error_ppm: f64,
    /// White noise on the speed column [m/s] (the pulse count itself is exact).
    #[serde(default)]
    pub speed_noise_mps: f64,
}

fn default_odo_rate() -> f64 {
    10.0
}
fn default_k_od() -> f64 {
    0.00324
}
fn default_ppr() -> u32 {
    1024
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Rate of truth.nav \[Hz\]; default = the IMU rate. Must divide the IMU rate.
    pub truth_rate_hz: Option<f64>,
    /// Also write the true IMU errors (truth_imu_err.txt) at the truth rate.
    #[serde(default = "yes")]
    pub truth_imu_errors: bool,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            truth_rate_hz: None,
            truth_imu_errors: true,
        }
    }
}

fn yes() -> bool {
    true
}

/// A loaded, validated scenario.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub file: ScenarioFile,
    pub path: PathBuf,
    /// The scenario text (copied to the output directory).
    pub text: String,
    pub trajectory: Trajectory,
    pub rig: Rig,
    pub imu: ImuSpec,
    pub imu_grade: crate::imu_model::ImuGrade,
    /// Truth output decimation (every n-th IMU sample).
    pub truth_every: u64,
}

fn key_err(path: &Path, text: &str, key: &str, needle: Option<&str>, msg: String) -> InputError {
    // Best effort: the line of the first occurrence of the key.
    let line = needle.and_then(|n| {
        text.lines()
            .position(|l| l.trim_start().starts_with(n))
            .map(|k| k + 1)
    });
    InputError {
        path: path.to_path_buf(),
        line,
        field: Some(key.to_string()),
        message: msg,
    }
}

/// Line number (1-based) of byte offset `pos` in `text`.
fn line_of(text: &str, pos: usize) -> usize {
    text[..pos.min(text.len())]
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        + 1
}

/// Line of the k-th (0-based) `[[segment]]` header.
fn segment_line(text: &str, k: usize) -> Option<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with("[[segment]]"))
        .nth(k)
        .map(|(i, _)| i + 1)
}

/// Longest scenario: 30 days \[s\].
pub const MAX_DURATION_S: f64 = 30.0 * 86_400.0;
/// Most IMU samples a scenario may generate: 30 days at 100 Hz.
pub const MAX_IMU_SAMPLES: f64 = MAX_DURATION_S * 100.0;

impl Scenario {
    /// Read and validate a scenario file.
    pub fn load(path: &Path) -> Result<Scenario, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::open(path, &e))?;
        Self::from_text(path, text)
    }

    /// Validate scenario text (`path` is used in messages and to resolve relative
    /// paths inside the scenario).
    pub fn from_text(path: &Path, text: String) -> Result<Scenario, InputError> {
        let file: ScenarioFile = toml::from_str(&text).map_err(|e| InputError {
            path: path.to_path_buf(),
            line: e.span().map(|s| line_of(&text, s.start)),
            field: None,
            message: e.message().trim().to_string(),
        })?;
        Self::from_file(path, file, text)
    }

    /// Validate a scenario value, e.g. one loaded and then changed in code (segments,
    /// events, seed). `text` becomes [`Scenario::text`] (the copy `generate` writes);
    /// error messages take their line numbers from it.
    pub fn from_file(
        path: &Path,
        file: ScenarioFile,
        text: String,
    ) -> Result<Scenario, InputError> {
        let s = &file.start;
        let [lat, lon, h] = s.position_deg_m;
        if !(lat.is_finite() && lat.abs() < 89.0 && lon.is_finite() && h.is_finite()) {
            return Err(key_err(
                path,
                &text,
                "start.position_deg_m",
                Some("position_deg_m"),
                format!(
                    "expected [lat in (-89, 89), lon, h] in deg, deg, m; got {:?}",
                    s.position_deg_m
                ),
            ));
        }
        if !(s.time_s.is_finite() && (0.0..SECONDS_PER_WEEK).contains(&s.time_s)) {
            return Err(key_err(
                path,
                &text,
                "start.time_s",
                Some("time_s"),
                format!(
                    "expected GPS seconds of week in [0, 604800), got {}",
                    s.time_s
                ),
            ));
        }
        let start = Start {
            t0: s.time_s,
            lla: Vector3::new(lat.to_radians(), lon.to_radians(), h),
            heading_rad: s.heading_deg.to_radians(),
            speed_mps: s.speed_mps,
        };
        let segments: Vec<Segment> = file.segments.iter().map(SegmentSpec::to_segment).collect();
        let trajectory = Trajectory::new(start, &segments).map_err(|e| InputError {
            path: path.to_path_buf(),
            line: segment_line(&text, e.index),
            field: Some(format!("segment[{}]", e.index + 1)),
            message: e.message.clone(),
        })?;
        let dur = trajectory.duration();
        if !(dur.is_finite() && dur <= MAX_DURATION_S) {
            return Err(key_err(
                path,
                &text,
                "segments",
                Some("[[segment]]"),
                format!(
                    "the segments last {dur} s in total: expected at most 30 days \
                     ({MAX_DURATION_S} s); split the scenario"
                ),
            ));
        }
        let v = &file.vehicle;
        if !v
            .imu_mounting_deg
            .iter()
            .chain(&v.imu_to_reference_m)
            .all(|x| x.is_finite())
        {
            return Err(key_err(
                path,
                &text,
                "vehicle",
                Some("[vehicle]"),
                "values must be finite".into(),
            ));
        }
        let rig = Rig::new(
            &Vector3::from(v.imu_mounting_deg).map(f64::to_radians),
            Vector3::from(v.imu_to_reference_m),
        );
        let imu = file.imu.clone().unwrap_or_else(default_imu);
        let imu_grade = imu
            .to_grade()
            .map_err(|m| key_err(path, &text, "imu", Some("[imu]"), m))?;
        if !(imu.rate_hz.is_finite() && imu.rate_hz > 0.0 && imu.rate_hz <= 10_000.0) {
            return Err(key_err(
                path,
                &text,
                "imu.rate_hz",
                Some("rate_hz"),
                format!("expected a rate in (0, 10000] Hz, got {}", imu.rate_hz),
            ));
        }
        let samples = imu.rate_hz * dur;
        if samples > MAX_IMU_SAMPLES {
            return Err(key_err(
                path,
                &text,
                "imu.rate_hz",
                Some("rate_hz"),
                format!(
                    "{} Hz for {dur} s gives {samples:.3e} IMU samples: expected at most \
                     {MAX_IMU_SAMPLES:.1e} (30 days at 100 Hz, tens of GB of text); lower \
                     the rate or shorten the scenario",
                    imu.rate_hz
                ),
            ));
        }
        let truth_every = match file.output.truth_rate_hz {
            None => 1,
            Some(r) => {
                let n = imu.rate_hz / r;
                if !(r.is_finite() && r > 0.0 && (n - n.round()).abs() < 1e-9 && n >= 1.0) {
                    return Err(key_err(
                        path,
                        &text,
                        "output.truth_rate_hz",
                        Some("truth_rate_hz"),
                        format!("must divide the IMU rate {} Hz, got {r}", imu.rate_hz),
                    ));
                }
                n.round() as u64
            }
        };
        if let Some(v) = &file.vibration {
            v.validate()
                .map_err(|(k, m)| key_err(path, &text, &format!("vibration.{k}"), Some(&k), m))?;
        }
        if let Some(o) = &file.odometer {
            let ok = o.rate_hz.is_finite()
                && o.rate_hz > 0.0
                && o.rate_hz <= imu.rate_hz
                && o.meters_per_pulse.is_finite()
                && o.meters_per_pulse > 0.0
                && o.scale_error_ppm.is_finite()
                && o.scale_error_ppm.abs() < 1e5
                && o.speed_noise_mps.is_finite()
                && o.speed_noise_mps >= 0.0;
            if !ok {
                return Err(key_err(
                    path,
                    &text,
                    "odometer",
                    Some("[odometer]"),
                    "expected rate_hz in (0, imu.rate_hz], meters_per_pulse > 0, |scale_error_ppm| < 1e5, speed_noise_mps >= 0".into(),
                ));
            }
        }
        if let Some(g) = &file.gnss {
            g.validate(&trajectory).map_err(|(k, m)| {
                key_err(
                    path,
                    &text,
                    &format!("gnss.{k}"),
                    Some(k.split('.').next_back().unwrap_or(&k)),
                    m,
                )
            })?;
        }
        Ok(Scenario {
            file,
            path: path.to_path_buf(),
            text,
            trajectory,
            rig,
            imu,
            imu_grade,
            truth_every,
        })
    }

    /// Directory of the scenario file (relative paths inside it resolve here).
    pub fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }
}

fn default_imu() -> ImuSpec {
    toml::from_str("").expect("ImuSpec has defaults for every key")
}
