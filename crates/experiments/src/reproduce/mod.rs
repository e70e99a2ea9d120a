//! `navfuse reproduce SEED`: the papers' experiments on the simulator (SYSTEM.md §7).
//!
//! For each random seed: simulate the experiment's scenario (scenarios/*.toml, built
//! into the binary), run every variant of the navigator on the same data with
//! `navfuse_app::run_job`, score it against the simulated truth, and print the mean and
//! spread over seeds beside the paper's figures. Improvements follow seed 002 eq. 18:
//! (RMSE_base - RMSE_variant) / RMSE_base.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use nalgebra::Vector3;
use navfuse_core::config::{AttitudeInit, NhcMode, RangeRate};
use navfuse_core::eval::{evaluate, EvalOptions, EvalReport, TrajPoint};
use navfuse_io::config::RunConfig;
use navfuse_io::input::{Coupling, DgpsKind, DgpsSource, GnssFormat, GnssSource, RinexGnss};
use navfuse_sim::generate::generate;
use navfuse_sim::imu_model::ImuGrade;
use navfuse_sim::scenario::Scenario;
use serde_json::{json, Value};

use crate::track::load_nav;
use navfuse_app::run_job;

/// One navigator configuration of an experiment.
pub(crate) struct Variant {
    pub name: &'static str,
    /// What it adds, for the table.
    pub label: &'static str,
    pub apply: fn(&mut RunConfig, &Scenario),
}

/// A figure the paper reports, for the side-by-side table.
struct PaperFigure {
    metric: &'static str,
    variant: &'static str,
    value: f64,
}

struct Experiment {
    id: &'static str,
    title: &'static str,
    scenario_name: &'static str,
    scenario_text: &'static str,
    variants: Vec<Variant>,
    paper: Vec<PaperFigure>,
    /// Improvement checks: (metric, base variant, variant, claimed fraction).
    claims: Vec<(&'static str, &'static str, &'static str, f64)>,
    /// Metrics shown (METRICS, CLOSED_LOOP_METRICS).
    metrics: &'static [&'static str],
}

/// Accuracy of one run: RMSE of position N, E, D, 3D [m] and attitude roll, pitch,
/// yaw, 3D [deg], and for closed-loop experiments the final errors.
#[derive(Clone, Debug, Default)]
struct Metrics {
    values: Vec<(&'static str, f64)>,
}

impl Metrics {
    fn get(&self, k: &str) -> Option<f64> {
        self.values.iter().find(|(n, _)| *n == k).map(|(_, v)| *v)
    }
}

const METRICS: [&str; 8] = [
    "rmse_n_m",
    "rmse_e_m",
    "rmse_d_m",
    "rmse_3d_m",
    "rmse_roll_deg",
    "rmse_pitch_deg",
    "rmse_yaw_deg",
    "rmse_att3d_deg",
];

/// Seed 004: error at the end of the closed loop (return to start), in metres and in
/// % of the distance driven, and the error 6 min after the start.
const CLOSED_LOOP_METRICS: [&str; 5] = [
    "end_error_m",
    "end_error_pct_distance",
    "error_6min_m",
    "rmse_3d_m",
    "rmse_yaw_deg",
];

/// Horizontal error [m] of the solution at time `t` (nearest solution epoch at or
/// before t) against the truth at the same epoch.
fn horizontal_error_at(sol: &[TrajPoint], truth: &[TrajPoint], t: f64) -> Option<f64> {
    let i = sol.partition_point(|p| p.t <= t + 1e-6).checked_sub(1)?;
    let s = &sol[i];
    let j = truth.partition_point(|p| p.t < s.t - 1e-6);
    let r = truth.get(j).filter(|r| (r.t - s.t).abs() < 1e-3)?;
    let d = navfuse_core::earth::lla_diff_ned(&s.lla, &r.lla);
    Some(d.x.hypot(d.y))
}

fn closed_loop_metrics(m: &mut Metrics, sol: &[TrajPoint], truth: &[TrajPoint], distance_m: f64) {
    let (Some(first), Some(last)) = (sol.first(), sol.last()) else {
        return;
    };
    if let Some(e) = horizontal_error_at(sol, truth, last.t) {
        m.values.push(("end_error_m", e));
        m.values
            .push(("end_error_pct_distance", 100.0 * e / distance_m));
    }
    if let Some(e) = horizontal_error_at(sol, truth, first.t + 360.0) {
        m.values.push(("error_6min_m", e));
    }
}

fn metrics_of(rep: &EvalReport) -> Metrics {
    let att = rep.att.unwrap_or_default();
    let d = |s: &navfuse_core::eval::Stat| s.rms.to_degrees();
    let a3 = (d(&att[0]).powi(2) + d(&att[1]).powi(2) + d(&att[2]).powi(2)).sqrt();
    Metrics {
        values: vec![
            ("rmse_n_m", rep.north.rms),
            ("rmse_e_m", rep.east.rms),
            ("rmse_d_m", rep.down.rms),
            ("rmse_3d_m", rep.pos_3d.rms),
            ("rmse_roll_deg", d(&att[0])),
            ("rmse_pitch_deg", d(&att[1])),
            ("rmse_yaw_deg", d(&att[2])),
            ("rmse_att3d_deg", a3),
        ],
    }
}

/// The navigator's IMU noise model for a simulated grade. The filter has one
/// Gauss-Markov process per bias; the simulated bias is a turn-on constant plus a
/// fast (100 s) Gauss-Markov wander. Modelled as one slow process (1 h) whose std is
/// the total (turn-on and wander): the constant part is then not forgotten after a
/// correlation time, and the driving noise 2 sigma² / T stays near the wander's.
fn realistic_noise(cfg: &mut RunConfig, grade: &ImuGrade) {
    let n = &mut cfg.nav.imu_noise;
    let floor = |x: f64, f: f64| if x > f { x } else { f };
    let gyro_bias = floor(
        grade.gyro.turn_on_bias_sigma.hypot(grade.gyro.gm_sigma()),
        1e-8,
    );
    let accel_bias = floor(
        grade.accel.turn_on_bias_sigma.hypot(grade.accel.gm_sigma()),
        1e-6,
    );
    n.arw = Vector3::repeat(floor(grade.gyro.white_noise_density, 1e-7));
    n.vrw = Vector3::repeat(floor(grade.accel.white_noise_density, 1e-6));
    n.gyro_bias_std = Vector3::repeat(gyro_bias);
    n.accel_bias_std = Vector3::repeat(accel_bias);
    n.gyro_scale_std = Vector3::repeat(floor(grade.gyro.scale_sigma, 1e-6));
    n.accel_scale_std = Vector3::repeat(floor(grade.accel.scale_sigma, 1e-6));
    n.corr_time_s = 3600.0;
    let i = &mut cfg.nav.initial;
    i.imu_errors_std.gyro_bias = n.gyro_bias_std;
    i.imu_errors_std.accel_bias = n.accel_bias_std;
    i.imu_errors_std.gyro_scale = n.gyro_scale_std;
    i.imu_errors_std.accel_scale = n.accel_scale_std;
}

/// The vehicle installation as a user knows it: the lever arm to the rear axle is
/// measured with a tape; the IMU mounting angles are not known and are estimated
/// (pitch and yaw, 2 deg initial sigma).
fn vehicle_installation(cfg: &mut RunConfig, sc: &Scenario) {
    cfg.nav.vehicle.lever_arm_b = sc.rig.lever_b;
    cfg.nav.vehicle.mounting_rpy = Vector3::zeros();
    cfg.nav.vehicle.mounting_std = 2.0_f64.to_radians();
}

/// Start as a user would: position from the first fix, attitude from alignment
/// (static levelling + first GNSS course), realistic initial uncertainty.
pub(crate) fn user_start(cfg: &mut RunConfig, sc: &Scenario) {
    realistic_noise(cfg, &sc.imu_grade);
    // The simulator's run.toml uses every sensor it wrote; each variant adds its own.
    cfg.heading = None;
    cfg.odometer = None;
    cfg.nav.heading = Default::default();
    cfg.nav.odometer = Default::default();
    cfg.nav.vehicle = Default::default();
    cfg.nav.nhc = Default::default();
    let i = &mut cfg.nav.initial;
    i.lla = None;
    i.v_n = Vector3::zeros();
    i.attitude = AttitudeInit::Auto {
        level_window_s: 30.0,
        min_speed_mps: 5.0,
        gyrocompass: false,
    };
    i.pos_std = Vector3::new(2.0, 2.0, 4.0);
    i.vel_std = Vector3::repeat(0.1);
    i.att_std = Vector3::new(2.0, 2.0, 5.0).map(f64::to_radians);
    cfg.nav.gnss.use_velocity = true;
    // Zero-velocity / zero-rate updates while static (the gyro bias is learnt there).
    cfg.nav.zupt.enabled = true;
    cfg.nav.zupt.accel_std_max = 0.1;
    cfg.nav.zupt.gyro_max = 1.0_f64.to_radians();
    cfg.output.rate_hz = Some(10.0);
    cfg.output.imu_err = false;
    cfg.output.std = false;
    cfg.output.csv = false;
}

/// Seed 001's loose filter fuses GNSS positions only; its heading aid is the motion
/// vector of consecutive fixes (eq. 11).
fn seed001_start(cfg: &mut RunConfig, sc: &Scenario) {
    user_start(cfg, sc);
    cfg.nav.gnss.use_velocity = false;
}

fn seed001() -> Experiment {
    Experiment {
        id: "seed001",
        title: "Seed 001: car, ADIS16405 50 Hz + GNSS 1 Hz, loose EKF vs + heading from GNSS",
        scenario_name: "scenarios/seed001_car.toml",
        scenario_text: include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/seed001_car.toml"
        )),
        variants: vec![
            Variant {
                name: "loose",
                label: "loose EKF (GNSS position only, as the paper)",
                apply: |c, sc| seed001_start(c, sc),
            },
            Variant {
                name: "course",
                label: "+ heading from GNSS motion (consecutive fixes, eq. 11)",
                apply: |c, sc| {
                    seed001_start(c, sc);
                    c.nav.heading.course_over_ground = true;
                },
            },
            Variant {
                name: "loose_vel",
                label: "loose EKF with GNSS velocity too (for reference)",
                apply: |c, sc| user_start(c, sc),
            },
            Variant {
                name: "dual_antenna",
                label: "+ dual-antenna heading, 1.2 m baseline (eq. 10)",
                apply: |c, sc| {
                    seed001_start(c, sc);
                    let b = sc
                        .file
                        .gnss
                        .as_ref()
                        .and_then(|g| g.heading.as_ref())
                        .map(|h| Vector3::from(h.baseline_m));
                    c.nav.heading.baseline_b = b;
                    c.heading = c.gnss.as_ref().map(|g| heading_source(&g.path));
                },
            },
        ],
        paper: vec![
            pf("rmse_e_m", "loose", 1.669),
            pf("rmse_e_m", "course", 1.616),
            pf("rmse_n_m", "loose", 1.647),
            pf("rmse_n_m", "course", 1.435),
            pf("rmse_d_m", "loose", 5.294),
            pf("rmse_d_m", "course", 3.791),
            pf("rmse_3d_m", "loose", 5.790),
            pf("rmse_3d_m", "course", 4.364),
            pf("rmse_roll_deg", "loose", 0.385),
            pf("rmse_roll_deg", "course", 0.170),
            pf("rmse_pitch_deg", "loose", 0.744),
            pf("rmse_pitch_deg", "course", 0.354),
            pf("rmse_yaw_deg", "loose", 3.472),
            pf("rmse_yaw_deg", "course", 0.596),
        ],
        claims: vec![
            ("rmse_3d_m", "loose", "course", 0.25),
            ("rmse_yaw_deg", "loose", "course", 0.83),
        ],
        metrics: &METRICS,
    }
}

fn seed002() -> Experiment {
    Experiment {
        id: "seed002",
        title: "Seed 002: car, ADIS16405 50 Hz + GNSS 1 Hz with 30 s and 60 s outages, loose EKF vs + NHC",
        scenario_name: "scenarios/seed002_car.toml",
        scenario_text: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/seed002_car.toml")),
        variants: vec![
            Variant {
                name: "loose",
                label: "loose EKF (GNSS position + velocity)",
                apply: |c, sc| user_start(c, sc),
            },
            Variant {
                name: "nhc",
                label: "+ NHC (0.1 m/s, always)",
                apply: |c, sc| {
                    user_start(c, sc);
                    vehicle_installation(c, sc);
                    c.nav.nhc.mode = NhcMode::Always;
                    c.nav.nhc.rate_hz = 2.0;
                },
            },
            Variant {
                name: "nhc_outage",
                label: "+ NHC only during GNSS outages",
                apply: |c, sc| {
                    user_start(c, sc);
                    vehicle_installation(c, sc);
                    c.nav.nhc.mode = NhcMode::DuringOutage;
                },
            },
        ],
        paper: vec![
            pf("rmse_e_m", "loose", 1.08),
            pf("rmse_e_m", "nhc", 1.02),
            pf("rmse_n_m", "loose", 0.76),
            pf("rmse_n_m", "nhc", 0.28),
            pf("rmse_d_m", "loose", 1.35),
            pf("rmse_d_m", "nhc", 0.49),
            pf("rmse_3d_m", "loose", 1.89),
            pf("rmse_3d_m", "nhc", 1.17),
            pf("rmse_roll_deg", "loose", 0.16),
            pf("rmse_roll_deg", "nhc", 0.06),
            pf("rmse_pitch_deg", "loose", 0.47),
            pf("rmse_pitch_deg", "nhc", 0.43),
            pf("rmse_yaw_deg", "loose", 1.31),
            pf("rmse_yaw_deg", "nhc", 0.27),
            pf("rmse_att3d_deg", "loose", 1.34),
            pf("rmse_att3d_deg", "nhc", 0.51),
        ],
        claims: vec![
            ("rmse_3d_m", "loose", "nhc", 0.38),
            ("rmse_att3d_deg", "loose", "nhc", 0.62),
        ],
        metrics: &METRICS,
    }
}

/// Seed 004 without GNSS: surveyed start position (the truth), static alignment by
/// levelling and gyrocompassing (IMU500: 0.1 deg/h), zero-velocity updates while
/// static.
pub(crate) fn seed004_start(cfg: &mut RunConfig, sc: &Scenario) {
    let lla = cfg.nav.initial.lla;
    user_start(cfg, sc);
    cfg.gnss = None;
    cfg.nav.initial.lla = lla;
    cfg.nav.initial.attitude = AttitudeInit::StaticGyrocompass {
        level_window_s: 50.0,
    };
    cfg.nav.initial.pos_std = Vector3::repeat(0.05);
    cfg.nav.initial.vel_std = Vector3::repeat(0.01);
    cfg.nav.initial.att_std = Vector3::new(0.05, 0.05, 1.0).map(f64::to_radians);
}

/// The odometer as seed 004 uses it: pulses with K_OD, scale-factor and mounting
/// states, and v^m = [v 0 0] (the NHC rows) in one update (seed 004 eq. 1-7).
pub(crate) fn seed004_odometer(cfg: &mut RunConfig, sc: &Scenario) {
    let k_od = sc
        .file
        .odometer
        .as_ref()
        .map_or(0.00324, |o| o.meters_per_pulse);
    let dir = cfg
        .imu
        .path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    cfg.odometer = Some(navfuse_io::input::OdometerSource {
        path: dir.join("odometer.txt"),
        format: navfuse_io::input::OdometerFormat::Navfuse {
            meters_per_pulse: k_od,
        },
    });
    cfg.nav.odometer.enabled = true;
    cfg.nav.odometer.with_nhc = true;
    cfg.nav.odometer.scale_std = 0.01;
    cfg.nav.vehicle.lever_arm_b = sc.rig.lever_b;
    cfg.nav.vehicle.mounting_std = 1.0_f64.to_radians();
}

fn seed004() -> Experiment {
    Experiment {
        id: "seed004",
        title: "Seed 004: car, IMU500 + odometer, no GNSS, 3010 m closed loop",
        scenario_name: "scenarios/seed004_loop.toml",
        scenario_text: include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/seed004_loop.toml"
        )),
        variants: vec![
            Variant {
                name: "ins",
                label: "INS alone (static alignment, ZUPT while static)",
                apply: |c, sc| seed004_start(c, sc),
            },
            Variant {
                name: "ins_odo",
                label: "INS + odometer with seed 004's states dk, dalpha_y, dalpha_p (24 states)",
                apply: |c, sc| {
                    seed004_start(c, sc);
                    seed004_odometer(c, sc);
                },
            },
        ],
        paper: vec![
            pf("end_error_m", "ins_odo", 6.32),
            pf("end_error_pct_distance", "ins_odo", 0.21),
            pf("error_6min_m", "ins_odo", 3.1),
            pf("error_6min_m", "ins", 72.0),
        ],
        claims: vec![],
        metrics: &CLOSED_LOOP_METRICS,
    }
}

/// Seed 000 Table 4's epochs [s after the start].
const TABLE4_TIMES_S: [f64; 11] = [
    0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 100.0, 200.0, 300.0, 400.0, 500.0,
];
/// Seed 000: 3D position error at the Table 4 epochs and its mean over the run.
const TABLE4_METRICS: [&str; 12] = [
    "err_3d_0s_m",
    "err_3d_10s_m",
    "err_3d_20s_m",
    "err_3d_30s_m",
    "err_3d_40s_m",
    "err_3d_50s_m",
    "err_3d_100s_m",
    "err_3d_200s_m",
    "err_3d_300s_m",
    "err_3d_400s_m",
    "err_3d_500s_m",
    "mean_3d_m",
];

/// The variant that is not a navigator run: single point positioning alone.
const GNSS_ONLY: &str = "gps_only";

/// 3D error [m] of the solution epoch nearest to `t` (within 0.6 s) against the truth
/// at that epoch.
fn error_3d_at(sol: &[TrajPoint], truth: &[TrajPoint], t: f64) -> Option<f64> {
    let i = sol.partition_point(|p| p.t < t);
    let s = [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter_map(|k| sol.get(k))
        .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
        .filter(|s| (s.t - t).abs() <= 0.6)?;
    // GNSS fixes are valid at the true time (tag - receiver clock): a few us off.
    let j = truth.partition_point(|p| p.t < s.t);
    let r = [j.checked_sub(1), Some(j)]
        .into_iter()
        .flatten()
        .filter_map(|k| truth.get(k))
        .find(|r| (r.t - s.t).abs() < 1e-3)?;
    Some(navfuse_core::earth::lla_diff_ned(&s.lla, &r.lla).norm())
}

/// Table 4 metrics: the 3D error at each Table 4 epoch, and the mean 3D error over
/// every whole second of the run.
fn table4_metrics(m: &mut Metrics, sol: &[TrajPoint], truth: &[TrajPoint]) {
    let Some(t0) = truth.first().map(|p| p.t) else {
        return;
    };
    for (k, dt) in TABLE4_TIMES_S.iter().enumerate() {
        if let Some(e) = error_3d_at(sol, truth, t0 + dt) {
            m.values.push((TABLE4_METRICS[k], e));
        }
    }
    let end = truth.last().map_or(t0, |p| p.t);
    let errs: Vec<f64> = (0..=((end - t0).floor() as usize))
        .filter_map(|k| error_3d_at(sol, truth, t0 + k as f64))
        .collect();
    if !errs.is_empty() {
        m.values
            .push(("mean_3d_m", errs.iter().sum::<f64>() / errs.len() as f64));
    }
}

/// Seed 000's GNSS as the GNSS layer sees it: the simulator's RINEX observations and
/// navigation file, 10 deg mask, optionally the DGPS corrections file.
fn seed000_gnss(cfg: &mut RunConfig, coupling: Coupling, dgps: bool) {
    let dir = cfg
        .imu
        .path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    cfg.gnss = Some(GnssSource {
        path: dir.join("obs.rnx"),
        format: GnssFormat::Rinex(RinexGnss {
            nav_path: dir.join("nav.rnx"),
            coupling,
            elevation_mask_deg: 10.0,
            // With SA the broadcast error model is 30x too small: no residual test.
            fde: false,
            dgps: dgps.then(|| DgpsSource {
                kind: DgpsKind::Corrections(dir.join("dgps.csv")),
                max_age_s: 30.0,
            }),
        }),
        decimate_s: None,
        time_offset_s: 0.0,
    });
    cfg.nav.gnss.lever_arm_b = Vector3::zeros();
    cfg.nav.tight.enabled = coupling == Coupling::Tight;
    // The error budget the designer knows (seed 000 Table 1): with SA the
    // pseudoranges are good to ~100 m and their rates to ~1 m/s (SA: 100 m, 120 s);
    // with DGPS to ~1.5 m, and the time-differenced carrier to ~1 cm/s.
    let t = &mut cfg.nav.tight;
    if dgps {
        t.pseudorange_sigma_floor_m = 1.5;
        t.range_rate_sigma_floor_mps = 0.01;
    } else {
        t.pseudorange_sigma_floor_m = 100.0;
        t.range_rate_sigma_floor_mps = 1.0;
    }
    // Loose: the SPP fixes with SA's size as their std (its own std assumes no SA).
    cfg.nav.gnss.position_std_override = (!dgps).then(|| Vector3::new(50.0, 50.0, 80.0));
    cfg.nav.gnss.velocity_std_override = (!dgps).then(|| Vector3::new(1.0, 1.0, 2.0));
}

/// Seed 000 starts at rest with the attitude known (its Table 4 has zero error at
/// 0 s): the initial state is the truth; the filter's noise model is the HG1700's.
fn seed000_start(cfg: &mut RunConfig, sc: &Scenario) {
    realistic_noise(cfg, &sc.imu_grade);
    cfg.output.rate_hz = Some(1.0);
    cfg.output.imu_err = false;
    cfg.output.std = false;
    cfg.output.csv = false;
}

fn seed000() -> Experiment {
    let v = |name, label, apply| Variant { name, label, apply };
    Experiment {
        id: "seed000",
        title: "Seed 000: UAV, HG1700 100 Hz + GPS 1 Hz (Table 3 satellites, Table 1 errors with SA), loose vs tight vs tight + TDCP + DGPS",
        scenario_name: "scenarios/seed000_uav.toml",
        scenario_text: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/seed000_uav.toml")),
        variants: vec![
            v("ins", "INS only", |c, sc| {
                seed000_start(c, sc);
                c.gnss = None;
            }),
            v(GNSS_ONLY, "GPS only: single point positioning", |c, sc| {
                seed000_start(c, sc);
                seed000_gnss(c, Coupling::Loose, false);
            }),
            v("loose", "loose: SPP position + Doppler velocity fixes", |c, sc| {
                seed000_start(c, sc);
                seed000_gnss(c, Coupling::Loose, false);
            }),
            v("tight_doppler", "tight: pseudorange + Doppler", |c, sc| {
                seed000_start(c, sc);
                seed000_gnss(c, Coupling::Tight, false);
                c.nav.tight.range_rate = RangeRate::Doppler;
            }),
            v("tight_tdcp", "tight: pseudorange + TDCP", |c, sc| {
                seed000_start(c, sc);
                seed000_gnss(c, Coupling::Tight, false);
                c.nav.tight.range_rate = RangeRate::Tdcp;
            }),
            v("tight_tdcp_dgps", "tight: DGPS pseudorange + TDCP (proposed)", |c, sc| {
                seed000_start(c, sc);
                seed000_gnss(c, Coupling::Tight, true);
                c.nav.tight.range_rate = RangeRate::Tdcp;
            }),
        ],
        paper: {
            // Table 4: INS, GPS, loose, tight, proposed at 0, 10, ... 500 s; mean.
            let rows: [[f64; 5]; 11] = [
                [0.0, 115.0, 0.0, 0.0, 0.0],
                [2.05, 12.0, 40.0, 24.1, 1.80],
                [7.155, 193.0, 113.0, 20.2, 7.74],
                [15.79, 187.0, 47.0, 17.9, 1.04],
                [27.72, 50.0, 99.0, 25.9, 5.96],
                [43.03, 33.0, 37.0, 17.8, 9.55],
                [61.37, 187.0, 241.0, 41.4, 6.88],
                [659.0, 181.0, 9.0, 8.5, 8.13],
                [1540.0, 56.0, 21.0, 44.9, 4.26],
                [2690.0, 15.0, 34.0, 21.1, 2.12],
                [3718.0, 20.0, 30.0, 12.3, 8.93],
            ];
            let cols = ["ins", GNSS_ONLY, "loose", "tight_doppler", "tight_tdcp_dgps"];
            let mut p = Vec::new();
            for (k, row) in rows.iter().enumerate() {
                for (c, v) in cols.iter().zip(row) {
                    p.push(pf(TABLE4_METRICS[k], c, *v));
                }
            }
            for (c, v) in cols[1..].iter().zip([99.52, 65.66, 34.52, 6.568]) {
                p.push(pf("mean_3d_m", c, v));
            }
            p
        },
        claims: vec![
            ("mean_3d_m", "tight_doppler", "tight_tdcp_dgps", 0.80),
            ("mean_3d_m", "loose", "tight_tdcp", 0.50),
        ],
        metrics: &TABLE4_METRICS,
    }
}

fn pf(metric: &'static str, variant: &'static str, value: f64) -> PaperFigure {
    PaperFigure {
        metric,
        variant,
        value,
    }
}

/// The simulator's dual-antenna heading file beside its GNSS file.
fn heading_source(gnss_path: &Path) -> navfuse_io::input::HeadingSource {
    navfuse_io::input::HeadingSource {
        path: gnss_path.with_file_name("heading.txt"),
    }
}

fn experiment(id: &str) -> Result<Experiment> {
    Ok(match id {
        "seed000" => seed000(),
        "seed001" => seed001(),
        "seed002" => seed002(),
        "seed004" => seed004(),
        other => {
            bail!("unknown experiment '{other}': expected seed000, seed001, seed002 or seed004")
        }
    })
}

/// The single point fixes of the configuration's RINEX input, as a track.
fn gnss_only_track(cfg: &RunConfig) -> Result<Vec<TrajPoint>> {
    let Some(
        src @ GnssSource {
            format: GnssFormat::Rinex(r),
            ..
        },
    ) = &cfg.gnss
    else {
        bail!("the GNSS-only variant needs a RINEX input");
    };
    let g = navfuse_app::gnss_input::load_rinex(src, r)?;
    Ok(g.fixes
        .iter()
        .map(|f| TrajPoint {
            t: f.t,
            lla: f.lla,
            v_n: f.vel_ned,
            rpy: None,
        })
        .collect())
}

/// Per variant, per seed: the metrics.
struct Results {
    seeds: Vec<u64>,
    per_variant: Vec<(&'static str, Vec<Metrics>)>,
}

fn run_experiment(ex: &Experiment, seeds: &[u64], work: &Path, quiet: bool) -> Result<Results> {
    let mut per_variant: Vec<(&'static str, Vec<Metrics>)> =
        ex.variants.iter().map(|v| (v.name, Vec::new())).collect();
    for &seed in seeds {
        let mut sc = Scenario::from_text(Path::new(ex.scenario_name), ex.scenario_text.to_string())
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        sc.file.seed = seed;
        let dir = work.join(format!("{}_seed{seed}", ex.id));
        let sim = generate(&sc, &dir).map_err(|e| anyhow::anyhow!("{e}"))?;
        let truth = load_nav(&dir.join("truth.nav"))?;
        for (k, v) in ex.variants.iter().enumerate() {
            let mut cfg = navfuse_io::config::load(&dir.join("run.toml"))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            (v.apply)(&mut cfg, &sc);
            let out = dir.join(v.name);
            let t_run = std::time::Instant::now();
            let sol = if v.name == GNSS_ONLY {
                gnss_only_track(&cfg)?
            } else {
                run_job(cfg, &out, false)
                    .with_context(|| format!("{} seed {seed}: variant {}", ex.id, v.name))?;
                load_nav(&out.join("solution.nav"))?.points
            };
            let wall = t_run.elapsed();
            let rep = evaluate(&sol, &truth.points, &EvalOptions::default());
            let mut m = metrics_of(&rep);
            closed_loop_metrics(&mut m, &sol, &truth.points, sim.distance_m);
            table4_metrics(&mut m, &sol, &truth.points);
            if !quiet {
                eprintln!(
                    "  {} seed {seed} {:<16} 3D RMSE {:8.3} m  mean {:8.3} m  yaw {:6.3} deg  ({:.1} s sim, {:.2} s run)",
                    ex.id,
                    v.name,
                    m.get("rmse_3d_m").unwrap_or(f64::NAN),
                    m.get("mean_3d_m").unwrap_or(f64::NAN),
                    m.get("rmse_yaw_deg").unwrap_or(f64::NAN),
                    sim.t_end - sim.t_start,
                    wall.as_secs_f64()
                );
            }
            per_variant[k].1.push(m);
        }
    }
    Ok(Results {
        seeds: seeds.to_vec(),
        per_variant,
    })
}

/// Mean, min and max over seeds.
pub(crate) fn spread(xs: &[f64]) -> (f64, f64, f64) {
    let mean = xs.iter().sum::<f64>() / xs.len().max(1) as f64;
    let min = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let max = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (mean, min, max)
}

fn values(r: &Results, variant: &str, metric: &str) -> Vec<f64> {
    r.per_variant
        .iter()
        .find(|(n, _)| *n == variant)
        .map(|(_, ms)| ms.iter().filter_map(|m| m.get(metric)).collect())
        .unwrap_or_default()
}

/// Improvement of the mean (seed 002 eq. 18) and its per-seed range.
fn improvement(r: &Results, metric: &str, base: &str, new: &str) -> (f64, f64, f64) {
    let b = values(r, base, metric);
    let n = values(r, new, metric);
    let (mb, _, _) = spread(&b);
    let (mn, _, _) = spread(&n);
    let per: Vec<f64> = b.iter().zip(&n).map(|(b, n)| (b - n) / b).collect();
    let (_, lo, hi) = spread(&per);
    ((mb - mn) / mb, lo, hi)
}

fn to_text(ex: &Experiment, r: &Results) -> String {
    let mut s = format!("{}\n", ex.title);
    s.push_str(&format!(
        "scenario {}, seeds {:?}; RMSE over the whole run, mean [min, max] over seeds\n\n",
        ex.scenario_name, r.seeds
    ));
    for v in &ex.variants {
        s.push_str(&format!("  {:<14} {}\n", v.name, v.label));
    }
    s.push_str(&format!("\n{:<24}", "metric"));
    for v in &ex.variants {
        s.push_str(&format!("{:>26}", v.name));
    }
    s.push_str("   paper\n");
    for &m in ex.metrics {
        s.push_str(&format!("{m:<24}"));
        for v in &ex.variants {
            let xs = values(r, v.name, m);
            let cell = if xs.is_empty() {
                "n/a".to_string()
            } else {
                let (mean, lo, hi) = spread(&xs);
                format!("{mean:.3} [{lo:.3}, {hi:.3}]")
            };
            s.push_str(&format!("{cell:>26}"));
        }
        let paper: Vec<String> = ex
            .paper
            .iter()
            .filter(|p| p.metric == m)
            .map(|p| format!("{} {}", p.variant, p.value))
            .collect();
        s.push_str(&format!("   {}\n", paper.join(", ")));
    }
    s.push_str("\nimprovement (seed 002 eq. 18), ours vs the paper's claim:\n");
    for (metric, base, new) in improvement_rows(ex) {
        let (imp, lo, hi) = improvement(r, metric, base, new);
        let claim = ex
            .claims
            .iter()
            .find(|c| c.0 == metric && c.1 == base && c.2 == new)
            .map(|c| {
                format!(
                    "  claim >= {:.0} %: {}",
                    c.3 * 100.0,
                    if imp >= c.3 { "met" } else { "NOT met" }
                )
            })
            .unwrap_or_default();
        s.push_str(&format!(
            "  {metric:<16} {base} -> {new}: {:6.1} % (per seed {:.1} .. {:.1} %){claim}\n",
            imp * 100.0,
            lo * 100.0,
            hi * 100.0
        ));
    }
    s
}

/// The claims, then every metric for every variant against the first (base) variant.
fn improvement_rows(ex: &Experiment) -> Vec<(&'static str, &'static str, &'static str)> {
    let base = ex.variants[0].name;
    let mut rows: Vec<_> = ex.claims.iter().map(|c| (c.0, c.1, c.2)).collect();
    for v in &ex.variants[1..] {
        for m in [
            "rmse_3d_m",
            "rmse_yaw_deg",
            "rmse_att3d_deg",
            "end_error_m",
            "mean_3d_m",
        ] {
            if ex.metrics.contains(&m) && !rows.contains(&(m, base, v.name)) {
                rows.push((m, base, v.name));
            }
        }
    }
    rows
}

fn to_json(ex: &Experiment, r: &Results) -> Value {
    let variants: Vec<Value> = ex
        .variants
        .iter()
        .map(|v| {
            let mut metrics = serde_json::Map::new();
            for &m in ex.metrics {
                let xs = values(r, v.name, m);
                let (mean, min, max) = spread(&xs);
                metrics.insert(
                    m.to_string(),
                    json!({"mean": mean, "min": min, "max": max, "per_seed": xs}),
                );
            }
            json!({"name": v.name, "label": v.label, "metrics": metrics})
        })
        .collect();
    let claims: Vec<Value> = ex
        .claims
        .iter()
        .map(|(m, b, n, c)| {
            let (imp, lo, hi) = improvement(r, m, b, n);
            json!({"metric": m, "base": b, "variant": n, "claimed": c, "measured": imp,
                   "per_seed_min": lo, "per_seed_max": hi, "met": imp >= *c})
        })
        .collect();
    let paper: Vec<Value> = ex
        .paper
        .iter()
        .map(|p| json!({"metric": p.metric, "variant": p.variant, "value": p.value}))
        .collect();
    json!({"experiment": ex.id, "title": ex.title, "scenario": ex.scenario_name,
           "seeds": r.seeds, "variants": variants, "claims": claims, "paper": paper})
}

pub fn main(
    id: &str,
    seeds: u64,
    first_seed: u64,
    json_out: bool,
    keep: Option<PathBuf>,
    quiet: bool,
) -> Result<()> {
    let ex = experiment(id)?;
    if seeds == 0 {
        bail!("--seeds must be at least 1");
    }
    let seed_list: Vec<u64> = (first_seed..first_seed + seeds).collect();
    let (work, temp) = match keep {
        Some(d) => (d, false),
        None => (
            std::env::temp_dir().join(format!("navfuse-reproduce-{}-{}", id, std::process::id())),
            true,
        ),
    };
    std::fs::create_dir_all(&work).with_context(|| format!("{}: cannot create", work.display()))?;
    let result = run_experiment(&ex, &seed_list, &work, quiet);
    if temp {
        let _ = std::fs::remove_dir_all(&work);
    }
    let r = result?;
    if json_out {
        println!("{}", serde_json::to_string_pretty(&to_json(&ex, &r))?);
    } else {
        print!("{}", to_text(&ex, &r));
    }
    Ok(())
}
