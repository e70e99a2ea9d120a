//! The navigator configurations the experiments build on the simulator's run.toml:
//! noise model from the simulated grade, start as a user would, seed 000's GNSS,
//! seed 004's odometer.

use std::path::Path;

use nalgebra::Vector3;
use navfuse_core::config::{AttitudeInit, NhcMode};
use navfuse_io::config::RunConfig;
use navfuse_io::gnss_csv::CsvGnssOptions;
use navfuse_io::input::{Coupling, DgpsKind, DgpsSource, GnssFormat, GnssSource, RinexGnss};
use navfuse_sim::imu_model::ImuGrade;
use navfuse_sim::scenario::Scenario;

/// The navigator's IMU noise model for a simulated grade. The filter has one
/// Gauss-Markov process per bias; the simulated bias is a turn-on constant plus a
/// fast (100 s) Gauss-Markov wander. Modelled as one slow process (1 h) whose std is
/// the total (turn-on and wander): the constant part is then not forgotten after a
/// correlation time, and the driving noise 2 sigma² / T stays near the wander's.
pub(crate) fn realistic_noise(cfg: &mut RunConfig, grade: &ImuGrade) {
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
pub(crate) fn vehicle_installation(cfg: &mut RunConfig, sc: &Scenario) {
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
pub(crate) fn seed001_start(cfg: &mut RunConfig, sc: &Scenario) {
    user_start(cfg, sc);
    cfg.nav.gnss.use_velocity = false;
}

/// Seed 001's receiver output as its eq. 11 reads it: the fixes' position and std
/// only (the simulator's gnss.txt read as CSV without its velocity columns), so the
/// course over ground comes from the displacement between consecutive fixes and the
/// alignment sees positions only.
pub(crate) fn fixes_without_velocity(cfg: &mut RunConfig) {
    if let Some(g) = cfg.gnss.as_mut() {
        // gnss.txt: t, lat, lon [deg], h [m], std N E D [m], velocity and its std.
        let mut csv = CsvGnssOptions::lla(0, [1, 2, 3]);
        csv.pos_std_cols = Some([4, 5, 6]);
        g.format = GnssFormat::Csv(csv);
    }
}

/// Seed 002's NHC: v_y = v_z = 0 with 0.1 m/s (its eq. 12 and Fig. 4), always, at
/// 2 Hz (6.7 in docs/RESULTS.md); the lever arm to the rear axle known, the mounting
/// estimated.
pub(crate) fn seed002_nhc(cfg: &mut RunConfig, sc: &Scenario) {
    vehicle_installation(cfg, sc);
    cfg.nav.nhc.mode = NhcMode::Always;
    cfg.nav.nhc.rate_hz = 2.0;
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
        skip_lines: None,
    });
    cfg.nav.odometer.enabled = true;
    cfg.nav.odometer.with_nhc = true;
    cfg.nav.odometer.scale_std = 0.01;
    cfg.nav.vehicle.lever_arm_b = sc.rig.lever_b;
    cfg.nav.vehicle.mounting_std = 1.0_f64.to_radians();
}

/// Seed 000's GNSS as the GNSS layer sees it: the simulator's RINEX observations and
/// navigation file, 10 deg mask, optionally the DGPS corrections file.
pub(crate) fn seed000_gnss(cfg: &mut RunConfig, coupling: Coupling, dgps: bool) {
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
            signals: Vec::new(),
            dual_frequency: false,
            orbits: Default::default(),
            cn0_weighting: None,
        }),
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
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
pub(crate) fn seed000_start(cfg: &mut RunConfig, sc: &Scenario) {
    realistic_noise(cfg, &sc.imu_grade);
    cfg.output.rate_hz = Some(1.0);
    cfg.output.imu_err = false;
    cfg.output.std = false;
    cfg.output.csv = false;
}

/// The simulator's dual-antenna heading file beside its GNSS file.
pub(crate) fn heading_source(gnss_path: &Path) -> navfuse_io::input::HeadingSource {
    navfuse_io::input::HeadingSource {
        path: gnss_path.with_file_name("heading.txt"),
        nmea: None,
        skip_lines: None,
        ubx: None,
    }
}
