//! GNSS simulation: constellation, raw L1 C/A measurements with an error budget,
//! DGPS corrections from a reference station, receiver fixes, dual-antenna heading,
//! and the events that disturb them (outages, blockage, spoofing, cycle slips).
//!
//! Pseudorange (SYSTEM.md §3b; seed 000 eq. 12):
//! `P = rho + c (dt_r - dt_s) + I + T + E_orbit + E_sa + E_clk + E_mp + eps`, where
//! rho is the geometric range with light time and Sagnac (navfuse_gnss::geometry),
//! dt_s the broadcast clock (with relativity, minus TGD), I and T the broadcast
//! Klobuchar and Saastamoinen model delays (when `model_delays`) plus their residual
//! errors. Each error source of seed 000 Table 1 is a time-correlated process with the
//! configured 1-sigma (docs/SIMULATOR.md lists the processes and their mappings).
//! Carrier phase: the same with the ionosphere sign reversed, its own small noise and
//! multipath, plus an integer ambiguity. Doppler: -(d/dt of the phase range)/lambda.

use std::collections::VecDeque;

use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla, lla_to_ecef};
use navfuse_gnss::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m, tropo_mapping};
use navfuse_gnss::ephemeris::{GpsEphemeris, SPEED_OF_LIGHT_MPS};
use navfuse_gnss::ephemeris_set::EphemerisSet;
use navfuse_gnss::geometry::{az_el, signal_path};
use navfuse_gnss::time::GpsTime;
use navfuse_io::rinex_obs::SatObs;
use serde::Deserialize;

use crate::random::{GaussMarkov, Stream};
use crate::trajectory::{Trajectory, TruthSample};

/// GPS L1 frequency [Hz] and wavelength [m].
pub const L1_HZ: f64 = 1_575.42e6;
pub const L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT_MPS / L1_HZ;
/// Ionosphere single-layer height [m] and mean Earth radius [m] for the obliquity.
const IONO_SHELL_M: f64 = 350e3;
const EARTH_RADIUS_M: f64 = 6_371e3;

// ---------------------------------------------------------------------------------
// Scenario tables

/// `[gnss]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GnssSpec {
    /// Epoch rate [Hz]; must divide the IMU rate.
    #[serde(default = "one")]
    pub rate_hz: f64,
    /// "nominal24" (bundled 24-slot GPS constellation), "seed000" (seed 000 Table 3's
    /// six satellites) or "rinex" (ephemerides from `rinex_nav`).
    #[serde(default = "nominal")]
    pub constellation: String,
    /// RINEX navigation file (relative to the scenario file) for `constellation = "rinex"`.
    pub rinex_nav: Option<String>,
    /// Elevation mask [deg].
    #[serde(default = "ten")]
    pub elevation_mask_deg: f64,
    /// Antenna phase centre from the IMU centre, IMU frame F-R-D [m].
    #[serde(default)]
    pub antenna_lever_arm_m: [f64; 3],
    /// Write obs.rnx / nav.rnx (raw measurements).
    #[serde(default = "yes")]
    pub raw: bool,
    #[serde(default)]
    pub errors: ErrorBudget,
    /// Receiver fixes for loose coupling (gnss.txt); absent = none.
    pub fix: Option<FixSpec>,
    /// Dual-antenna heading (heading.txt); absent = none.
    pub heading: Option<HeadingSpec>,
    /// DGPS reference station and corrections (dgps.csv); absent = none.
    pub dgps: Option<DgpsSpec>,
    /// Outages, blockage, spoofing, cycle slips, loss of lock.
    #[serde(default, rename = "event")]
    pub events: Vec<EventSpec>,
}

fn one() -> f64 {
    1.0
}
fn ten() -> f64 {
    10.0
}
fn yes() -> bool {
    true
}
fn nominal() -> String {
    "nominal24".into()
}

/// `[gnss.errors]`: 1-sigma of each source [m] and its correlation time [s]. Defaults:
/// seed 000 Table 1, GPS column (SA on). Ionosphere and troposphere are zenith values
/// (slant = mapping x zenith); multipath and receiver noise are zenith values scaled by
/// sqrt((1 + 1/sin² el) / 2).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorBudget {
    #[serde(default = "d_iono")]
    pub iono_m: f64,
    #[serde(default = "d_1800")]
    pub iono_tau_s: f64,
    #[serde(default = "d_tropo")]
    pub tropo_m: f64,
    #[serde(default = "d_3600")]
    pub tropo_tau_s: f64,
    #[serde(default = "d_clk")]
    pub sat_clock_m: f64,
    #[serde(default = "d_1800")]
    pub sat_clock_tau_s: f64,
    #[serde(default = "d_orbit")]
    pub orbit_m: f64,
    #[serde(default = "d_1800")]
    pub orbit_tau_s: f64,
    #[serde(default = "d_one")]
    pub multipath_m: f64,
    #[serde(default = "d_30")]
    pub multipath_tau_s: f64,
    #[serde(default = "d_one")]
    pub noise_m: f64,
    #[serde(default = "d_rxclk")]
    pub rx_clock_m: f64,
    #[serde(default = "d_600")]
    pub rx_clock_tau_s: f64,
    /// Selective Availability (seed 000 Table 1: 100 m); 0 = off (as since 2000).
    #[serde(default = "d_sa")]
    pub sa_m: f64,
    #[serde(default = "d_120")]
    pub sa_tau_s: f64,
    /// Carrier-phase white noise at zenith [m].
    #[serde(default = "d_phase_noise")]
    pub phase_noise_m: f64,
    /// Carrier-phase multipath at zenith [m] (tau = multipath_tau_s).
    #[serde(default = "d_phase_mp")]
    pub phase_multipath_m: f64,
    /// Doppler white noise at zenith [m/s].
    #[serde(default = "d_doppler")]
    pub doppler_noise_mps: f64,
    /// C/N0 at zenith [dB-Hz]; lower elevations lose 20 log10 of the noise scaling.
    #[serde(default = "d_cn0")]
    pub cn0_zenith_dbhz: f64,
    /// Put the broadcast Klobuchar and Saastamoinen delays into the measurements (so
    /// the ionosphere/troposphere errors above are the residuals of those models).
    #[serde(default = "yes")]
    pub model_delays: bool,
}

fn d_iono() -> f64 {
    5.0
}
fn d_tropo() -> f64 {
    1.5
}
fn d_clk() -> f64 {
    3.0
}
fn d_orbit() -> f64 {
    4.2
}
fn d_one() -> f64 {
    1.0
}
fn d_rxclk() -> f64 {
    5.0
}
fn d_sa() -> f64 {
    100.0
}
fn d_30() -> f64 {
    30.0
}
fn d_120() -> f64 {
    120.0
}
fn d_600() -> f64 {
    600.0
}
fn d_1800() -> f64 {
    1800.0
}
fn d_3600() -> f64 {
    3600.0
}
fn d_phase_noise() -> f64 {
    0.003
}
fn d_phase_mp() -> f64 {
    0.005
}
fn d_doppler() -> f64 {
    0.05
}
fn d_cn0() -> f64 {
    48.0
}

impl Default for ErrorBudget {
    fn default() -> Self {
        toml::from_str("").expect("defaults for every key")
    }
}

/// `[gnss.fix]`: receiver position/velocity fixes from a noise model.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixSpec {
    /// Horizontal (per axis) and vertical 1-sigma [m], also the reported std.
    #[serde(default = "d_fix_h")]
    pub horizontal_std_m: f64,
    #[serde(default = "d_fix_v")]
    pub vertical_std_m: f64,
    /// Correlation time of the position error [s]; 0 = white.
    #[serde(default = "d_fix_tau")]
    pub corr_time_s: f64,
    /// Velocity 1-sigma per axis [m/s] (white); also reported.
    #[serde(default = "d_fix_vel")]
    pub velocity_std_mps: f64,
    /// Minimum satellites above the mask for a fix (4 for a 3-D fix).
    #[serde(default = "d_four")]
    pub min_satellites: usize,
}

fn d_fix_h() -> f64 {
    1.5
}
fn d_fix_v() -> f64 {
    3.0
}
fn d_fix_tau() -> f64 {
    60.0
}
fn d_fix_vel() -> f64 {
    0.05
}
fn d_four() -> usize {
    4
}

/// `[gnss.heading]`: dual-antenna heading (SYSTEM.md §3c; seed 001 eq. 10).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadingSpec {
    /// Baseline from the primary to the secondary antenna, IMU frame [m].
    #[serde(default = "d_baseline")]
    pub baseline_m: [f64; 3],
    /// Heading 1-sigma [deg]; default 0.3 deg x 1.2 m / baseline length.
    pub std_deg: Option<f64>,
}

fn d_baseline() -> [f64; 3] {
    [1.2, 0.0, 0.0]
}

/// `[gnss.dgps]`: a reference station and its pseudorange corrections.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DgpsSpec {
    /// Distance [km] and bearing [deg] of the reference station from the start.
    #[serde(default = "d_dgps_b")]
    pub baseline_km: f64,
    #[serde(default = "d_45")]
    pub bearing_deg: f64,
    /// Corrections computed every `interval_s`, available `latency_s` later.
    #[serde(default = "one")]
    pub interval_s: f64,
    #[serde(default)]
    pub latency_s: f64,
    /// Spatially decorrelated residuals (zenith) at `residual_baseline_km`, growing
    /// linearly with the baseline. Defaults: seed 000 Table 1 DGPS column.
    #[serde(default = "d_res_iono")]
    pub iono_residual_m: f64,
    #[serde(default = "d_res_tropo")]
    pub tropo_residual_m: f64,
    #[serde(default = "d_res_orbit")]
    pub orbit_residual_m: f64,
    #[serde(default = "d_dgps_b")]
    pub residual_baseline_km: f64,
    /// The reference station's own multipath and noise at zenith [m].
    #[serde(default = "d_ref")]
    pub ref_multipath_m: f64,
    #[serde(default = "d_ref")]
    pub ref_noise_m: f64,
}

fn d_dgps_b() -> f64 {
    20.0
}
fn d_45() -> f64 {
    45.0
}
fn d_res_iono() -> f64 {
    0.5
}
fn d_res_tropo() -> f64 {
    0.2
}
fn d_res_orbit() -> f64 {
    0.3
}
fn d_ref() -> f64 {
    0.1
}

/// Spoofing modes.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SpoofMode {
    /// False position = truth + offset_m from start_s.
    Jump,
    /// False position = truth + velocity_mps (t - start_s).
    Drift,
    /// False position = the true track delay_s earlier, plus offset_m.
    Replay,
}

/// One `[[gnss.event]]`; times in seconds from the scenario start.
#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum EventSpec {
    /// No GNSS output at all for start_s < t < end_s.
    Outage { start_s: f64, end_s: f64 },
    /// Outages of length_s every period_s from from_s (until until_s).
    OutageEvery {
        length_s: f64,
        period_s: f64,
        from_s: f64,
        until_s: Option<f64>,
    },
    /// Partial sky blockage: only the `keep` highest satellites (or the listed PRNs)
    /// are tracked; no fix when fewer than the fix needs.
    Blockage {
        start_s: f64,
        end_s: f64,
        keep: Option<usize>,
        prns: Option<Vec<u8>>,
    },
    /// Spoofing of fixes and raw measurements, consistently.
    Spoof {
        mode: SpoofMode,
        start_s: f64,
        end_s: f64,
        #[serde(default)]
        offset_m: [f64; 3],
        #[serde(default)]
        velocity_mps: [f64; 3],
        #[serde(default)]
        delay_s: f64,
    },
    /// Cycle slip of `cycles` on one satellite at at_s.
    CycleSlip { prn: u8, at_s: f64, cycles: i64 },
    /// One satellite not tracked for start_s < t < end_s; reacquired with a new
    /// ambiguity and the loss-of-lock flag.
    LossOfLock { prn: u8, start_s: f64, end_s: f64 },
}

impl GnssSpec {
    /// Check values; Err((key, message)).
    pub fn validate(&self, traj: &Trajectory) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 100.0) {
            return bad(
                "rate_hz",
                format!("expected (0, 100] Hz, got {}", self.rate_hz),
            );
        }
        match self.constellation.as_str() {
            "nominal24" | "seed000" => {}
            "rinex" if self.rinex_nav.is_some() => {}
            "rinex" => {
                return bad(
                    "rinex_nav",
                    "constellation = \"rinex\" needs rinex_nav = \"FILE\"".into(),
                )
            }
            c => {
                return bad(
                    "constellation",
                    format!("expected \"nominal24\", \"seed000\" or \"rinex\", got \"{c}\""),
                )
            }
        }
        if !(0.0..=60.0).contains(&self.elevation_mask_deg) {
            return bad(
                "elevation_mask_deg",
                format!("expected [0, 60] deg, got {}", self.elevation_mask_deg),
            );
        }
        let e = &self.errors;
        let sig = [
            ("errors.iono_m", e.iono_m),
            ("errors.tropo_m", e.tropo_m),
            ("errors.sat_clock_m", e.sat_clock_m),
            ("errors.orbit_m", e.orbit_m),
            ("errors.multipath_m", e.multipath_m),
            ("errors.noise_m", e.noise_m),
            ("errors.rx_clock_m", e.rx_clock_m),
            ("errors.sa_m", e.sa_m),
            ("errors.phase_noise_m", e.phase_noise_m),
            ("errors.phase_multipath_m", e.phase_multipath_m),
            ("errors.doppler_noise_mps", e.doppler_noise_mps),
        ];
        for (k, v) in sig {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, format!("expected a finite value >= 0, got {v}"));
            }
        }
        let taus = [
            ("errors.iono_tau_s", e.iono_tau_s),
            ("errors.tropo_tau_s", e.tropo_tau_s),
            ("errors.sat_clock_tau_s", e.sat_clock_tau_s),
            ("errors.orbit_tau_s", e.orbit_tau_s),
            ("errors.multipath_tau_s", e.multipath_tau_s),
            ("errors.rx_clock_tau_s", e.rx_clock_tau_s),
            ("errors.sa_tau_s", e.sa_tau_s),
        ];
        for (k, v) in taus {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, format!("expected a correlation time > 0 s, got {v}"));
            }
        }
        if let Some(f) = &self.fix {
            if !(f.horizontal_std_m > 0.0
                && f.vertical_std_m > 0.0
                && f.velocity_std_mps > 0.0
                && f.corr_time_s >= 0.0)
            {
                return bad("fix", "std values must be > 0 and corr_time_s >= 0".into());
            }
        }
        if let Some(h) = &self.heading {
            let b = Vector3::from(h.baseline_m);
            if !(b.norm() > 0.05 && b.iter().all(|x| x.is_finite())) {
                return bad(
                    "heading.baseline_m",
                    format!(
                        "expected a baseline longer than 5 cm, got {:?}",
                        h.baseline_m
                    ),
                );
            }
            if let Some(s) = h.std_deg {
                if !(s.is_finite() && s > 0.0) {
                    return bad("heading.std_deg", format!("expected > 0, got {s}"));
                }
            }
        }
        if let Some(d) = &self.dgps {
            if !(d.baseline_km >= 0.0
                && d.interval_s > 0.0
                && d.latency_s >= 0.0
                && d.residual_baseline_km > 0.0)
            {
                return bad("dgps", "expected baseline_km >= 0, interval_s > 0, latency_s >= 0, residual_baseline_km > 0".into());
            }
        }
        let dur = traj.duration();
        for (k, ev) in self.events.iter().enumerate() {
            let key = format!("event[{}]", k + 1);
            let window = |a: f64, b: f64| -> Result<(), (String, String)> {
                if a.is_finite() && b.is_finite() && a >= 0.0 && b > a {
                    Ok(())
                } else {
                    Err((
                        key.clone(),
                        format!("expected 0 <= start < end, got {a}..{b}"),
                    ))
                }
            };
            match ev {
                EventSpec::Outage { start_s, end_s } => window(*start_s, *end_s)?,
                EventSpec::OutageEvery {
                    length_s,
                    period_s,
                    from_s,
                    ..
                } => {
                    if !(*length_s > 0.0 && period_s > length_s && *from_s >= 0.0) {
                        return Err((
                            key,
                            "expected length_s > 0, period_s > length_s, from_s >= 0".into(),
                        ));
                    }
                }
                EventSpec::Blockage {
                    start_s,
                    end_s,
                    keep,
                    prns,
                } => {
                    window(*start_s, *end_s)?;
                    if keep.is_some() == prns.is_some() {
                        return Err((key, "give exactly one of keep and prns".into()));
                    }
                }
                EventSpec::Spoof {
                    start_s,
                    end_s,
                    mode,
                    delay_s,
                    offset_m,
                    velocity_mps,
                } => {
                    window(*start_s, *end_s)?;
                    let vals = offset_m.iter().chain(velocity_mps).chain([delay_s]);
                    if let Some(v) = vals.into_iter().find(|v| !v.is_finite()) {
                        return Err((
                            key,
                            format!("offset_m, velocity_mps and delay_s must be finite, got {v}"),
                        ));
                    }
                    if *mode == SpoofMode::Replay && !(*delay_s > 0.0 && *delay_s <= *start_s) {
                        return Err((
                            key,
                            format!("replay needs 0 < delay_s <= start_s, got {delay_s}"),
                        ));
                    }
                }
                EventSpec::CycleSlip { at_s, .. } => {
                    if !(*at_s >= 0.0 && *at_s <= dur) {
                        return Err((
                            key,
                            format!("at_s must be within the run (0..{dur}), got {at_s}"),
                        ));
                    }
                }
                EventSpec::LossOfLock { start_s, end_s, .. } => window(*start_s, *end_s)?,
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------
// Random processes

/// A smooth (differentiable) Gauss-Markov process: a first-order GM x with time
/// constant tau, low-passed once more, y' = (x - y) / tau. Stationary: var(x) = 2
/// sigma², cov(x, y) = var(y) = sigma². The rate y' exists, so Doppler is consistent.
/// Exact discretisation: Phi = e^{-dt/tau} [[1, 0], [dt/tau, 1]], Q = P - Phi P Phi^T.
#[derive(Clone, Debug)]
pub struct SmoothGm {
    tau: f64,
    sigma: f64,
    x: f64,
    y: f64,
}

impl SmoothGm {
    pub fn new(sigma: f64, tau: f64, rng: &mut Stream) -> Self {
        // Draw (x, y) from the stationary covariance [[2s², s²], [s², s²]].
        let (a, b) = (rng.normal(), rng.normal());
        let y = sigma * a;
        let x = y + sigma * b;
        SmoothGm { tau, sigma, x, y }
    }

    pub fn step(&mut self, dt: f64, rng: &mut Stream) {
        if self.sigma == 0.0 {
            return;
        }
        let e = (-dt / self.tau).exp();
        let r = dt / self.tau;
        let s2 = self.sigma * self.sigma;
        // P = s² [[2, 1], [1, 1]]; Phi = e [[1, 0], [r, 1]].
        let (p11, p12, p22) = (2.0 * s2, s2, s2);
        let (f11, f21, f22) = (e, e * r, e);
        let q11 = p11 - f11 * f11 * p11;
        let q12 = p12 - f11 * (f21 * p11 + f22 * p12);
        let q22 = p22 - (f21 * f21 * p11 + 2.0 * f21 * f22 * p12 + f22 * f22 * p22);
        let l11 = q11.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { q12 / l11 } else { 0.0 };
        let l22 = (q22 - l21 * l21).max(0.0).sqrt();
        let (w1, w2) = (rng.normal(), rng.normal());
        let (x, y) = (self.x, self.y);
        self.x = f11 * x + l11 * w1;
        self.y = f21 * x + f22 * y + l21 * w1 + l22 * w2;
    }

    pub fn value(&self) -> f64 {
        self.y
    }

    pub fn rate(&self) -> f64 {
        if self.sigma == 0.0 {
            0.0
        } else {
            (self.x - self.y) / self.tau
        }
    }
}

/// Noise/multipath scaling with elevation, 1 at zenith.
pub fn elevation_scale(el_rad: f64) -> f64 {
    let s = el_rad.sin().max(0.05);
    ((1.0 + 1.0 / (s * s)) / 2.0).sqrt()
}

/// Single-layer ionosphere obliquity factor.
pub fn iono_obliquity(el_rad: f64) -> f64 {
    let k = EARTH_RADIUS_M * el_rad.cos() / (EARTH_RADIUS_M + IONO_SHELL_M);
    1.0 / (1.0 - k * k).sqrt()
}

// ---------------------------------------------------------------------------------
// Simulator state

/// Per-satellite processes.
struct SatProc {
    iono_common: SmoothGm,
    iono_diff: SmoothGm,
    sat_clock: SmoothGm,
    orbit_common: SmoothGm,
    orbit_diff: SmoothGm,
    sa: SmoothGm,
    multipath: GaussMarkov,
    phase_multipath: GaussMarkov,
    ref_multipath: GaussMarkov,
    rng: Stream,
    ambiguity: i64,
    /// Tracked at the previous epoch.
    tracked: bool,
    /// Loss-of-lock indicator for the next output.
    lli_pending: bool,
}

/// Error components of one pseudorange [m] (slant), for gnss_errors.csv.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorParts {
    pub iono: f64,
    pub tropo: f64,
    pub sat_clock: f64,
    pub orbit: f64,
    pub multipath: f64,
    pub noise: f64,
    pub rx_clock: f64,
    pub sa: f64,
}

impl ErrorParts {
    pub fn total(&self) -> f64 {
        self.iono
            + self.tropo
            + self.sat_clock
            + self.orbit
            + self.multipath
            + self.noise
            + self.rx_clock
            + self.sa
    }
}

/// One satellite at one epoch, with its truth.
#[derive(Clone, Debug)]
pub struct SatEpoch {
    pub obs: SatObs,
    pub el_rad: f64,
    pub az_rad: f64,
    /// Errors in the pseudorange (excluding the broadcast model delays).
    pub errors: ErrorParts,
    /// Residual of each source after the DGPS correction (None without DGPS or
    /// without a correction for this satellite).
    pub dgps_residual: Option<ErrorParts>,
    pub dgps_age_s: Option<f64>,
    /// Spoofing-induced range change [m] (0 when not spoofed).
    pub spoof_range_m: f64,
}

/// A DGPS correction (RTCM-style PRC/RRC) for one satellite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DgpsCorrection {
    /// Time the correction refers to (GPS s of week).
    pub t: f64,
    pub prn: u8,
    /// Add to the measured pseudorange [m].
    pub prc_m: f64,
    /// Its rate [m/s]: correction at t' = prc + rrc (t' - t).
    pub rrc_mps: f64,
    pub iode: u16,
    /// Per-source parts of -prc (what the reference station saw), for the residuals.
    parts: ErrorParts,
    parts_rate: ErrorParts,
}

/// A receiver fix (antenna), possibly spoofed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fix {
    pub t: f64,
    pub lla: Vector3<f64>,
    pub std_ned: Vector3<f64>,
    pub vel_ned: Vector3<f64>,
    pub vel_std: f64,
    pub spoofed: bool,
}

/// Everything produced at one GNSS epoch.
#[derive(Clone, Debug, Default)]
pub struct GnssEpoch {
    pub t: f64,
    /// Visible and tracked satellites (empty during an outage).
    pub sats: Vec<SatEpoch>,
    pub fix: Option<Fix>,
    /// Dual-antenna heading [rad] and its std [rad].
    pub heading: Option<(f64, f64)>,
    /// Corrections computed at this epoch (written to dgps.csv).
    pub corrections: Vec<DgpsCorrection>,
    /// Receiver clock bias [m] (truth).
    pub rx_clock_m: f64,
    /// Active spoofing offset of the antenna position (NED, m), if any.
    pub spoof_offset_ned: Option<Vector3<f64>>,
    /// Outage in force (nothing output).
    pub outage: bool,
}

/// The GNSS simulator.
pub struct GnssSim {
    spec: GnssSpec,
    ephs: EphemerisSet,
    iono_alpha: [f64; 4],
    iono_beta: [f64; 4],
    week: i32,
    t0: f64,
    lever_b: Vector3<f64>,
    procs: Vec<Option<SatProc>>,
    tropo_common: SmoothGm,
    tropo_diff: SmoothGm,
    rx_clock: SmoothGm,
    rng_tropo: Stream,
    rng_rx: Stream,
    fix_err: [GaussMarkov; 3],
    rng_fix: Stream,
    rng_heading: Stream,
    ref_lla: Option<Vector3<f64>>,
    /// Latest corrections available to the rover, per PRN.
    latest: Vec<Option<DgpsCorrection>>,
    /// Corrections waiting for their latency.
    pending: VecDeque<DgpsCorrection>,
    last_dgps_t: f64,
    /// Antenna truth history for replay spoofing (t, lla, vel_ned).
    history: VecDeque<(f64, Vector3<f64>, Vector3<f64>)>,
    last_t: Option<f64>,
}

/// Broadcast Klobuchar coefficients used when the navigation source has none (a
/// typical set; written to nav.rnx so users can apply the same model).
pub const DEFAULT_IONO_ALPHA: [f64; 4] = [1.1176e-8, 7.4506e-9, -5.9605e-8, -5.9605e-8];
pub const DEFAULT_IONO_BETA: [f64; 4] = [9.0112e4, 3.2768e4, -1.9661e5, -6.5536e4];

impl GnssSim {
    /// `ephs`: the constellation; `iono`: Klobuchar coefficients if known.
    pub fn new(
        spec: &GnssSpec,
        ephs: Vec<GpsEphemeris>,
        iono: Option<([f64; 4], [f64; 4])>,
        seed: u64,
        week: u32,
        t0: f64,
        start_lla: &Vector3<f64>,
    ) -> Self {
        let e = &spec.errors;
        let mut procs: Vec<Option<SatProc>> = (0..=32).map(|_| None).collect();
        let ephs = EphemerisSet::new(ephs);
        let (res_scale, ref_mp, iono_res, tropo_res, orbit_res) = match &spec.dgps {
            Some(d) => (
                d.baseline_km / d.residual_baseline_km,
                d.ref_multipath_m,
                d.iono_residual_m,
                d.tropo_residual_m,
                d.orbit_residual_m,
            ),
            None => (0.0, 0.0, 0.0, 0.0, 0.0),
        };
        // Split each spatially correlated source so that common² + diff² = sigma².
        let split = |sigma: f64, diff: f64| -> (f64, f64) {
            let d = diff.min(sigma);
            ((sigma * sigma - d * d).sqrt(), d)
        };
        let (iono_c, iono_d) = split(e.iono_m, iono_res * res_scale);
        let (tropo_c, tropo_d) = split(e.tropo_m, tropo_res * res_scale);
        let (orbit_c, orbit_d) = split(e.orbit_m, orbit_res * res_scale);
        for prn in ephs.prns() {
            if prn == 0 || prn > 32 {
                continue;
            }
            let mut rng = Stream::new(seed, &format!("gnss.sat.G{prn:02}"));
            let p = SatProc {
                iono_common: SmoothGm::new(iono_c, e.iono_tau_s, &mut rng),
                iono_diff: SmoothGm::new(iono_d, e.iono_tau_s, &mut rng),
                sat_clock: SmoothGm::new(e.sat_clock_m, e.sat_clock_tau_s, &mut rng),
                orbit_common: SmoothGm::new(orbit_c, e.orbit_tau_s, &mut rng),
                orbit_diff: SmoothGm::new(orbit_d, e.orbit_tau_s, &mut rng),
                sa: SmoothGm::new(e.sa_m, e.sa_tau_s, &mut rng),
                multipath: GaussMarkov::new(e.multipath_m, e.multipath_tau_s, &mut rng),
                phase_multipath: GaussMarkov::new(e.phase_multipath_m, e.multipath_tau_s, &mut rng),
                ref_multipath: GaussMarkov::new(ref_mp, e.multipath_tau_s, &mut rng),
                ambiguity: (rng.uniform_range(-1e5, 1e5)).round() as i64,
                tracked: false,
                lli_pending: false,
                rng,
            };
            procs[prn as usize] = Some(p);
        }
        let mut rng_tropo = Stream::new(seed, "gnss.tropo");
        let mut rng_rx = Stream::new(seed, "gnss.rx_clock");
        let mut rng_fix = Stream::new(seed, "gnss.fix");
        let (fh, fv, ftau) = match &spec.fix {
            Some(f) => (
                f.horizontal_std_m,
                f.vertical_std_m,
                if f.corr_time_s > 0.0 {
                    f.corr_time_s
                } else {
                    1e-9
                },
            ),
            None => (0.0, 0.0, 1.0),
        };
        let ref_lla = spec.dgps.as_ref().map(|d| {
            let b = d.bearing_deg.to_radians();
            let ned = Vector3::new(b.cos(), b.sin(), 0.0) * d.baseline_km * 1e3;
            let r = lla_to_ecef(start_lla) + c_ne(start_lla.x, start_lla.y) * ned;
            // Same ellipsoidal height as the start.
            let mut lla = ecef_to_lla(&r);
            lla.z = start_lla.z;
            lla
        });
        let (alpha, beta) = iono.unwrap_or((DEFAULT_IONO_ALPHA, DEFAULT_IONO_BETA));
        GnssSim {
            spec: spec.clone(),
            ephs,
            iono_alpha: alpha,
            iono_beta: beta,
            week: week as i32,
            t0,
            lever_b: Vector3::from(spec.antenna_lever_arm_m),
            procs,
            tropo_common: SmoothGm::new(tropo_c, e.tropo_tau_s, &mut rng_tropo),
            tropo_diff: SmoothGm::new(tropo_d, e.tropo_tau_s, &mut rng_tropo),
            rx_clock: SmoothGm::new(e.rx_clock_m, e.rx_clock_tau_s, &mut rng_rx),
            rng_tropo,
            rng_rx,
            fix_err: [
                GaussMarkov::new(fh, ftau, &mut rng_fix),
                GaussMarkov::new(fh, ftau, &mut rng_fix),
                GaussMarkov::new(fv, ftau, &mut rng_fix),
            ],
            rng_fix,
            rng_heading: Stream::new(seed, "gnss.heading"),
            ref_lla,
            latest: vec![None; 33],
            pending: VecDeque::new(),
            last_dgps_t: f64::NEG_INFINITY,
            history: VecDeque::new(),
            last_t: None,
        }
    }

    /// Klobuchar coefficients in use.
    pub fn iono_coefficients(&self) -> ([f64; 4], [f64; 4]) {
        (self.iono_alpha, self.iono_beta)
    }

    /// Reference station position (lat, lon rad, h m), when DGPS is on.
    pub fn reference_lla(&self) -> Option<Vector3<f64>> {
        self.ref_lla
    }

    fn in_outage(&self, rel: f64) -> bool {
        self.spec.events.iter().any(|e| match *e {
            EventSpec::Outage { start_s, end_s } => rel > start_s && rel < end_s,
            EventSpec::OutageEvery {
                length_s,
                period_s,
                from_s,
                until_s,
            } => {
                if rel <= from_s {
                    return false;
                }
                let k = ((rel - from_s) / period_s).floor();
                let s = from_s + k * period_s;
                if until_s.is_some_and(|u| s >= u) {
                    return false;
                }
                rel > s && rel < s + length_s
            }
            _ => false,
        })
    }

    fn spoof_at(&self, rel: f64) -> Option<&EventSpec> {
        self.spec.events.iter().find(|e| match e {
            EventSpec::Spoof { start_s, end_s, .. } => rel >= *start_s && rel < *end_s,
            _ => false,
        })
    }

    /// The antenna position and NED velocity the receiver reports (true or false).
    fn antenna_track(
        &self,
        rel: f64,
        lla: Vector3<f64>,
        vel: Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>, Option<Vector3<f64>>) {
        let Some(EventSpec::Spoof {
            mode,
            start_s,
            offset_m,
            velocity_mps,
            delay_s,
            ..
        }) = self.spoof_at(rel)
        else {
            return (lla, vel, None);
        };
        let to_lla = |base: &Vector3<f64>, d_ned: &Vector3<f64>| -> Vector3<f64> {
            ecef_to_lla(&(lla_to_ecef(base) + c_ne(base.x, base.y) * d_ned))
        };
        match mode {
            SpoofMode::Jump => {
                let d = Vector3::from(*offset_m);
                (to_lla(&lla, &d), vel, Some(d))
            }
            SpoofMode::Drift => {
                let v = Vector3::from(*velocity_mps);
                let d = v * (rel - start_s);
                (to_lla(&lla, &d), vel + v, Some(d))
            }
            SpoofMode::Replay => {
                let t_old = self.t0 + rel - delay_s;
                let old = self
                    .history
                    .iter()
                    .min_by(|a, b| (a.0 - t_old).abs().total_cmp(&(b.0 - t_old).abs()))
                    .copied();
                match old {
                    Some((_, old_lla, old_vel)) => {
                        let p = to_lla(&old_lla, &Vector3::from(*offset_m));
                        let d = navfuse_core::earth::lla_diff_ned(&p, &lla);
                        (p, old_vel, Some(d))
                    }
                    None => (lla, vel, None),
                }
            }
        }
    }

    /// Simulate the epoch at the truth sample `truth` (time truth.t).
    pub fn epoch(&mut self, truth: &TruthSample) -> GnssEpoch {
        let t = truth.t;
        let rel = t - self.t0;
        let dt = self.last_t.map_or(0.0, |lt| t - lt);
        self.last_t = Some(t);
        let e = self.spec.errors.clone();
        // Advance the processes (also through outages: the errors keep evolving).
        if dt > 0.0 {
            self.tropo_common.step(dt, &mut self.rng_tropo);
            self.tropo_diff.step(dt, &mut self.rng_tropo);
            self.rx_clock.step(dt, &mut self.rng_rx);
            for p in self.procs.iter_mut().flatten() {
                let r = &mut p.rng;
                p.iono_common.step(dt, r);
                p.iono_diff.step(dt, r);
                p.sat_clock.step(dt, r);
                p.orbit_common.step(dt, r);
                p.orbit_diff.step(dt, r);
                p.sa.step(dt, r);
                p.multipath.step(dt, r);
                p.phase_multipath.step(dt, r);
                p.ref_multipath.step(dt, r);
            }
            for g in self.fix_err.iter_mut() {
                g.step(dt, &mut self.rng_fix);
            }
        }
        let gt = GpsTime::new(self.week, t);
        let ant_lla = {
            let d = truth.c_bn * self.lever_b;
            ecef_to_lla(&(lla_to_ecef(&truth.lla) + c_ne(truth.lla.x, truth.lla.y) * d))
        };
        let ant_vel = truth.velocity_at(&self.lever_b);
        self.history.push_back((t, ant_lla, ant_vel));
        let max_delay = self
            .spec
            .events
            .iter()
            .map(|e| match e {
                EventSpec::Spoof { delay_s, .. } => *delay_s,
                _ => 0.0,
            })
            .fold(0.0, f64::max);
        while self
            .history
            .front()
            .is_some_and(|h| h.0 < t - max_delay - 2.0)
        {
            self.history.pop_front();
        }

        // DGPS: the reference station's corrections at this epoch (before the rover
        // uses them, so latency 0 means "this epoch's corrections").
        let mut out = GnssEpoch {
            t,
            rx_clock_m: self.rx_clock.value(),
            ..Default::default()
        };
        if let (Some(d), Some(ref_lla)) = (self.spec.dgps.clone(), self.ref_lla) {
            if t - self.last_dgps_t >= d.interval_s - 1e-6 {
                self.last_dgps_t = t;
                let corr = self.reference_corrections(gt, &ref_lla, &d);
                out.corrections = corr.clone();
                self.pending.extend(corr);
            }
            while self
                .pending
                .front()
                .is_some_and(|c| c.t + d.latency_s <= t + 1e-9)
            {
                let c = self.pending.pop_front().expect("checked");
                self.latest[c.prn as usize] = Some(c);
            }
        }

        out.outage = self.in_outage(rel);
        if out.outage {
            for p in self.procs.iter_mut().flatten() {
                if p.tracked {
                    p.lli_pending = true;
                }
                p.tracked = false;
            }
            return out;
        }
        let (rx_lla, rx_vel_ned, spoof) = self.antenna_track(rel, ant_lla, ant_vel);
        out.spoof_offset_ned = spoof;
        let rx_ecef = lla_to_ecef(&rx_lla);
        let rx_vel_ecef = c_ne(rx_lla.x, rx_lla.y) * rx_vel_ned;
        // Geometry is that of the (possibly false) position: the spoofer synthesises
        // consistent signals. The true antenna sees the spoofer's signals only.
        let true_ecef = lla_to_ecef(&ant_lla);
        let mask = self.spec.elevation_mask_deg.to_radians();
        let mut visible: Vec<(u8, f64)> = Vec::new();
        let prns = self.ephs.prns();
        let mut paths = Vec::new();
        for &prn in &prns {
            let Some(eph) = self.ephs.select(prn, gt) else {
                continue;
            };
            let path = signal_path(eph, &rx_ecef, &rx_vel_ecef, gt);
            let (az, el) = az_el(&rx_lla, &path.los_unit);
            if el < mask {
                continue;
            }
            if self.blocked(rel, prn, el, &mut visible) {
                continue;
            }
            let lost = self.spec.events.iter().any(|e| matches!(*e, EventSpec::LossOfLock { prn: p, start_s, end_s } if p == prn && rel > start_s && rel < end_s));
            if lost {
                continue;
            }
            paths.push((prn, (eph.tgd_s, eph.iode), path, az, el));
        }
        // Blockage by count: keep the highest satellites.
        if let Some(keep) = self.blockage_keep(rel) {
            paths.sort_by(|a, b| b.4.total_cmp(&a.4));
            paths.truncate(keep);
            paths.sort_by_key(|p| p.0);
        }
        let tracked: Vec<u8> = paths.iter().map(|p| p.0).collect();
        for (prn, p) in self.procs.iter_mut().enumerate() {
            if let Some(p) = p {
                let now = tracked.contains(&(prn as u8));
                if !now && p.tracked {
                    // Lost: a new ambiguity on reacquisition.
                    p.ambiguity = (p.rng.uniform_range(-1e5, 1e5)).round() as i64;
                }
                if now && !p.tracked {
                    p.lli_pending = true;
                }
                p.tracked = now;
            }
        }
        for (prn, (tgd_s, iode), path, az, el) in paths {
            let Some(p) = self.procs[prn as usize].as_mut() else {
                continue;
            };
            for ev in &self.spec.events {
                if let EventSpec::CycleSlip {
                    prn: sp,
                    at_s,
                    cycles,
                } = *ev
                {
                    if sp == prn && at_s > rel - dt && at_s <= rel {
                        p.ambiguity += cycles;
                        p.lli_pending = true;
                    }
                }
            }
            let obl = iono_obliquity(el);
            let mt = tropo_mapping(el);
            let sc = elevation_scale(el);
            let noise = e.noise_m * sc * p.rng.normal();
            let parts = ErrorParts {
                iono: obl * (p.iono_common.value() + p.iono_diff.value()),
                tropo: mt * (self.tropo_common.value() + self.tropo_diff.value()),
                sat_clock: p.sat_clock.value(),
                orbit: p.orbit_common.value() + p.orbit_diff.value(),
                multipath: sc * p.multipath.value(),
                noise,
                rx_clock: self.rx_clock.value(),
                sa: p.sa.value(),
            };
            let rates = obl * (p.iono_common.rate() + p.iono_diff.rate());
            let tropo_rate = mt * (self.tropo_common.rate() + self.tropo_diff.rate());
            let common_rate = tropo_rate
                + p.sat_clock.rate()
                + p.orbit_common.rate()
                + p.orbit_diff.rate()
                + p.sa.rate()
                + self.rx_clock.rate();
            let (model_iono, model_tropo) = if e.model_delays {
                (
                    klobuchar_l1_delay_m(
                        &self.iono_alpha,
                        &self.iono_beta,
                        rx_lla.x,
                        rx_lla.y,
                        az,
                        el,
                        t,
                    ),
                    saastamoinen_slant_m(rx_lla.x, rx_lla.z, el),
                )
            } else {
                (0.0, 0.0)
            };
            // Satellite clock as an L1 C/A user applies it (IS-GPS-200 20.3.3.3.3.2).
            let dts_m = (path.sat_clock_bias_s - tgd_s) * SPEED_OF_LIGHT_MPS;
            let dts_rate = path.sat_clock_drift_s_per_s * SPEED_OF_LIGHT_MPS;
            let range = path.geometric_range_m;
            let pr = range - dts_m + model_iono + model_tropo + parts.total();
            let nondisp = parts.tropo + parts.sat_clock + parts.orbit + parts.rx_clock + parts.sa;
            let phase_m = range - dts_m - model_iono + model_tropo - parts.iono
                + nondisp
                + sc * p.phase_multipath.value()
                + e.phase_noise_m * sc * p.rng.normal();
            let carrier = phase_m / L1_WAVELENGTH_M + p.ambiguity as f64;
            let range_rate = path.range_rate_mps - dts_rate + common_rate - rates;
            let doppler =
                -(range_rate + e.doppler_noise_mps * sc * p.rng.normal()) / L1_WAVELENGTH_M;
            let cn0 = e.cn0_zenith_dbhz - 20.0 * sc.log10() + 0.5 * p.rng.normal();
            let lli = if p.lli_pending { 1 } else { 0 };
            p.lli_pending = false;
            let spoof_range_m = if spoof.is_some() {
                range - (path.sat_pos_ecef_m - true_ecef).norm()
            } else {
                0.0
            };
            let (dgps_residual, dgps_age_s) = match self.latest[prn as usize] {
                Some(c) if c.iode == iode => {
                    let age = t - c.t;
                    let r = |rover: f64, refv: f64, rate: f64| rover - refv - rate * age;
                    let (a, b) = (c.parts, c.parts_rate);
                    (
                        Some(ErrorParts {
                            iono: r(parts.iono, a.iono, b.iono),
                            tropo: r(parts.tropo, a.tropo, b.tropo),
                            sat_clock: r(parts.sat_clock, a.sat_clock, b.sat_clock),
                            orbit: r(parts.orbit, a.orbit, b.orbit),
                            multipath: r(parts.multipath, a.multipath, b.multipath),
                            noise: r(parts.noise, a.noise, b.noise),
                            rx_clock: parts.rx_clock,
                            sa: r(parts.sa, a.sa, b.sa),
                        }),
                        Some(age),
                    )
                }
                _ => (None, None),
            };
            out.sats.push(SatEpoch {
                obs: SatObs {
                    prn,
                    pseudorange_m: Some(pr),
                    carrier_cycles: Some(carrier),
                    doppler_hz: Some(doppler),
                    cn0_dbhz: Some(cn0),
                    lli,
                },
                el_rad: el,
                az_rad: az,
                errors: parts,
                dgps_residual,
                dgps_age_s,
                spoof_range_m,
            });
        }

        // Receiver fix from the noise model (at the reported, possibly false, position).
        if let Some(f) = &self.spec.fix {
            if out.sats.len() >= f.min_satellites {
                let err = Vector3::new(
                    self.fix_err[0].value(),
                    self.fix_err[1].value(),
                    self.fix_err[2].value(),
                );
                let lla = ecef_to_lla(&(rx_ecef + c_ne(rx_lla.x, rx_lla.y) * err));
                let vn = Vector3::new(
                    self.rng_fix.normal(),
                    self.rng_fix.normal(),
                    self.rng_fix.normal(),
                ) * f.velocity_std_mps;
                out.fix = Some(Fix {
                    t,
                    lla,
                    std_ned: Vector3::new(f.horizontal_std_m, f.horizontal_std_m, f.vertical_std_m),
                    vel_ned: rx_vel_ned + vn,
                    vel_std: f.velocity_std_mps,
                    spoofed: spoof.is_some(),
                });
            }
        }
        // Dual-antenna heading (SYSTEM.md §3c): azimuth of the baseline in NED.
        if let Some(h) = &self.spec.heading {
            if out.sats.len() >= 4 {
                let b = Vector3::from(h.baseline_m);
                let std = h.std_deg.unwrap_or(0.3 * 1.2 / b.norm()).to_radians();
                let b_n = truth.c_bn * b;
                let psi = b_n.y.atan2(b_n.x) + std * self.rng_heading.normal();
                out.heading = Some((navfuse_core::attitude::wrap_2pi(psi), std));
            }
        }
        out
    }

    fn blockage_keep(&self, rel: f64) -> Option<usize> {
        self.spec.events.iter().find_map(|e| match e {
            EventSpec::Blockage {
                start_s,
                end_s,
                keep: Some(k),
                ..
            } if rel > *start_s && rel < *end_s => Some(*k),
            _ => None,
        })
    }

    /// Blockage by PRN list.
    fn blocked(&self, rel: f64, prn: u8, _el: f64, _vis: &mut Vec<(u8, f64)>) -> bool {
        self.spec.events.iter().any(|e| match e {
            EventSpec::Blockage {
                start_s,
                end_s,
                prns: Some(list),
                ..
            } => rel > *start_s && rel < *end_s && !list.contains(&prn),
            _ => false,
        })
    }

    /// Corrections from the reference station at `gt` (RTCM convention: the station
    /// removes its own clock, so PRC = -(common errors + model delays + own noise)).
    fn reference_corrections(
        &mut self,
        gt: GpsTime,
        ref_lla: &Vector3<f64>,
        d: &DgpsSpec,
    ) -> Vec<DgpsCorrection> {
        let e = &self.spec.errors;
        let ref_ecef = lla_to_ecef(ref_lla);
        let mask = self.spec.elevation_mask_deg.to_radians();
        let mut out = Vec::new();
        for prn in self.ephs.prns() {
            let Some(eph) = self.ephs.select(prn, gt) else {
                continue;
            };
            let Some(p) = self.procs[prn as usize].as_mut() else {
                continue;
            };
            let path = signal_path(eph, &ref_ecef, &Vector3::zeros(), gt);
            let (az, el) = az_el(ref_lla, &path.los_unit);
            if el < mask {
                continue;
            }
            let obl = iono_obliquity(el);
            let mt = tropo_mapping(el);
            let sc = elevation_scale(el);
            let parts = ErrorParts {
                iono: obl * p.iono_common.value(),
                tropo: mt * self.tropo_common.value(),
                sat_clock: p.sat_clock.value(),
                orbit: p.orbit_common.value(),
                multipath: sc * p.ref_multipath.value(),
                noise: d.ref_noise_m * sc * p.rng.normal(),
                rx_clock: 0.0,
                sa: p.sa.value(),
            };
            let rates = ErrorParts {
                iono: obl * p.iono_common.rate(),
                tropo: mt * self.tropo_common.rate(),
                sat_clock: p.sat_clock.rate(),
                orbit: p.orbit_common.rate(),
                multipath: 0.0,
                noise: 0.0,
                rx_clock: 0.0,
                sa: p.sa.rate(),
            };
            let (mi, mtr) = if e.model_delays {
                (
                    klobuchar_l1_delay_m(
                        &self.iono_alpha,
                        &self.iono_beta,
                        ref_lla.x,
                        ref_lla.y,
                        az,
                        el,
                        gt.sow,
                    ),
                    saastamoinen_slant_m(ref_lla.x, ref_lla.z, el),
                )
            } else {
                (0.0, 0.0)
            };
            out.push(DgpsCorrection {
                t: gt.sow,
                prn,
                prc_m: -(parts.total() + mi + mtr),
                rrc_mps: -(rates.total()),
                iode: eph.iode,
                parts,
                parts_rate: rates,
            });
        }
        out
    }
}
