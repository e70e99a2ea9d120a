//! The run configuration for what [`generate`](crate::generate::generate) writes:
//! built as a [`RunConfig`] value and written by the configuration's writer as
//! run.toml (no second copy of the schema).

use std::path::Path;

use nalgebra::Vector3;
use navfuse_core::aiding::baro::BaroOptions;
use navfuse_core::config::{
    AttitudeInit, GnssOptions, ImuNoise, InitialState, NavConfig, RangeRate, VehicleOptions,
};
use navfuse_io::baro::{BaroQuantity, BaroSource};
use navfuse_io::config::{units, RunConfig, TomlStyle};
use navfuse_io::input::{
    Coupling, CsvImuOptions, GapPolicy, GnssFormat, GnssSource, HeadingSource, ImuFormat,
    ImuQuantity, ImuSource, OdometerFormat, OdometerSource, OutputSpec, RateSampling, RinexGnss,
};

use crate::imu_model::ImuOutput;
use crate::scenario::Scenario;
use crate::trajectory::TruthGenerator;

/// The text of run.toml: [`run_config`] written with the configuration's writer
/// (paths relative to `dir`, defaults left out but for the coupling and the
/// mounting), under a comment naming the scenario.
pub fn run_config_text(sc: &Scenario, dir: &Path) -> String {
    // Written although they are the defaults: the choices a reader (and whoever
    // edits the file) looks for.
    let keep = ["gnss.coupling", "vehicle.mounting_rpy_deg"];
    let body = run_config(sc, dir).to_toml_with(&TomlStyle {
        relative_to: Some(dir.to_path_buf()),
        omit_defaults: true,
        keep: keep.map(String::from).to_vec(),
    });
    format!(
        "# Written by `navfuse sim` for {}: run with `navfuse run run.toml --out DIR`.\n\
         # Initial state = the truth at the start; IMU noise = the simulated grade ({}).\n\n{body}",
        sc.path.display(),
        sc.imu_grade.name,
    )
}

/// The navfuse run configuration for the files [`generate`](crate::generate::generate)
/// writes into `dir` (loose
/// coupling on gnss.txt when there are fixes, tight coupling on obs.rnx with raw
/// observations only, pure inertial otherwise), initialised from the truth, with the
/// IMU noise model of the simulated grade. With an odometer: odometer.txt with the
/// nominal K_OD (its speed column when the scenario adds speed noise), the scenario's
/// lever arm to the reference point and the mounting
/// estimated from zero (1 deg); with dual-antenna heading: heading.txt with the
/// scenario's baseline. NHC and ZUPT stay off. Numbers the file gives in its own
/// units (degrees, deg/h, mGal, ppm, hours) are chosen in those units and converted
/// as loading them does (`navfuse_io::config::units`), so `load` of run.toml gives
/// this value.
pub fn run_config(sc: &Scenario, dir: &Path) -> RunConfig {
    let t0 = sc.trajectory.t_start();
    let mut g = TruthGenerator::new(&sc.trajectory, sc.rig, sc.imu.rate_hz);
    let s0 = g.current();
    let _ = g.step();
    let e = s0.euler();
    let grade = &sc.imu_grade;
    const RAD_TO_DEG: f64 = 180.0 / std::f64::consts::PI;
    let tiny = |x: f64, floor: f64| if x > floor { x } else { floor };
    let arw = tiny(grade.gyro.white_noise_density * RAD_TO_DEG * 60.0, 1e-5);
    let vrw = tiny(grade.accel.white_noise_density * 60.0, 1e-5);
    let gb = tiny(
        grade.gyro.turn_on_bias_sigma.hypot(grade.gyro.gm_sigma()) * RAD_TO_DEG * 3600.0,
        1e-4,
    );
    let ab = tiny(
        grade.accel.turn_on_bias_sigma.hypot(grade.accel.gm_sigma()) * 1e5,
        1e-2,
    );
    let gs = tiny(grade.gyro.scale_sigma * 1e6, 1.0);
    let asc = tiny(grade.accel.scale_sigma * 1e6, 1.0);
    // One Gauss-Markov state per bias carries both the turn-on bias (a constant) and
    // the in-run instability, so its correlation time is at least 1 h (as in
    // `navfuse reproduce`): a short one would let the filter forget the turn-on bias
    // it has learnt within that time whenever the aiding is weak.
    let tau_h = {
        let t = grade.gyro.bias_corr_time_s;
        if t.is_finite() && t > 3600.0 {
            t / 3600.0
        } else {
            1.0
        }
    };
    let imu_noise = ImuNoise {
        arw: Vector3::repeat(units::ARW.si(arw)),
        vrw: Vector3::repeat(units::VRW.si(vrw)),
        gyro_bias_std: Vector3::repeat(units::DEGPH.si(gb)),
        accel_bias_std: Vector3::repeat(units::MGAL.si(ab)),
        gyro_scale_std: Vector3::repeat(units::PPM.si(gs)),
        accel_scale_std: Vector3::repeat(units::PPM.si(asc)),
        corr_time_s: units::HOURS.si(tau_h),
    };
    let imu = ImuSource {
        path: dir.join(match sc.imu.output {
            ImuOutput::Increments => "imu.txt",
            ImuOutput::Rates => "imu.csv",
        }),
        format: match sc.imu.output {
            ImuOutput::Increments => ImuFormat::KfGins,
            // t_gps, t, gyro x y z, accel x y z (imu_model.rs), one header line
            ImuOutput::Rates => ImuFormat::Csv(CsvImuOptions {
                skip_lines: 1,
                time_col: 1,
                gyro_cols: [2, 3, 4],
                accel_cols: [5, 6, 7],
                quantity: ImuQuantity::Rate,
                rate_sampling: RateSampling::IntervalMean,
                ..CsvImuOptions::default()
            }),
        },
        rate_hz: sc.imu.rate_hz,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: GapPolicy::default(),
    };
    // The truth start (rounded as run.toml always wrote it); with raw measurements
    // only (tight coupling) its uncertainty is what the pseudoranges can confirm, not
    // 1 cm: with a 1 cm prior the first single point fix, 10-25 m off with broadcast
    // errors, is a (correct) integrity alarm.
    let raw_only = sc
        .file
        .gnss
        .as_ref()
        .is_some_and(|g| g.fix.is_none() && g.raw);
    let (pos_std, vel_std) = if raw_only { (10.0, 0.1) } else { (0.01, 0.001) };
    let round = |x: f64, decimals: usize| -> f64 { format!("{x:.decimals$}").parse().unwrap_or(x) };
    let deg = |rad: f64, decimals: usize| units::DEG.si(round(rad.to_degrees(), decimals));
    let initial = InitialState {
        lla: Some(Vector3::new(
            deg(s0.lla.x, 12),
            deg(s0.lla.y, 12),
            round(s0.lla.z, 6),
        )),
        v_n: s0.v_n.map(|v| round(v, 9)),
        attitude: AttitudeInit::Given(e.map(|a| deg(a, 9))),
        ..InitialState::new(
            Vector3::repeat(pos_std),
            Vector3::repeat(vel_std),
            Vector3::repeat(units::DEG.si(0.01)),
            &imu_noise,
        )
    };
    let mut nav = NavConfig::new(imu_noise, initial);
    // The IMU clock runs `[gnss] time_offset_s` ahead of GPS time (generate.rs): the
    // run starts at that IMU time and estimates the offset (from the default prior).
    let tau = sc.file.gnss.as_ref().map_or(0.0, |g| g.time_offset_s);
    nav.start_time = t0 + tau;
    if tau != 0.0 {
        nav.filter.time_offset = Some(Default::default());
    }
    let mut gnss = None;
    let mut heading = None;
    if let Some(gs_) = &sc.file.gnss {
        nav.gnss.lever_arm_b = Vector3::from(gs_.antenna_lever_arm_m);
        if let Some(fix) = &gs_.fix {
            // The fix errors are Gauss-Markov with the reported std (gnss_sim.rs):
            // the filter's shaping states with that correlation time, nearly all of
            // the variance correlated.
            let (tau, share) = if fix.corr_time_s > 0.0 {
                (fix.corr_time_s, 0.95)
            } else {
                (0.0, 0.0)
            };
            nav.gnss.fix_error.corr_time_s = tau;
            nav.gnss.fix_error.corr_fraction = share;
            gnss = Some(GnssSource {
                path: dir.join("gnss.txt"),
                format: GnssFormat::KfGins,
                decimate_s: None,
                time_offset_s: 0.0,
                skip_lines: None,
            });
        } else if gs_.raw {
            // Raw observations only: tight coupling on them, with every system
            // simulated.
            nav.tight.enabled = true;
            nav.gnss.systems = crate::gnss_sim::systems_of(gs_);
            nav.tight.range_rate = RangeRate::Tdcp;
            gnss = Some(GnssSource {
                path: dir.join("obs.rnx"),
                format: GnssFormat::Rinex(RinexGnss {
                    nav_path: dir.join("nav.rnx"),
                    coupling: Coupling::Tight,
                    elevation_mask_deg: gs_.elevation_mask_deg,
                    fde: true,
                    dgps: None,
                    signals: Vec::new(),
                    dual_frequency: false,
                    orbits: Default::default(),
                    cn0_weighting: None,
                }),
                decimate_s: None,
                time_offset_s: 0.0,
                skip_lines: None,
            });
        }
        if let Some(h) = &gs_.heading {
            nav.heading.baseline_b = Some(Vector3::from(h.baseline_m));
            heading = Some(HeadingSource {
                path: dir.join("heading.txt"),
                nmea: None,
                skip_lines: None,
                ubx: None,
            });
        }
    }
    if gnss.is_none() {
        // what loading a configuration without [gnss] gives: nothing to gate
        nav.gnss = GnssOptions {
            gate_probability: None,
            ..GnssOptions::default()
        };
    }
    let mut odometer = None;
    if let Some(o) = &sc.file.odometer {
        nav.odometer.enabled = true;
        // With speed noise the speed column carries it (the pulse count is exact):
        // read that column, with its noise and the pulse quantisation of a differenced
        // count, K_OD rate / sqrt(6), in the std (the default when that is larger).
        let format = if o.speed_noise_mps > 0.0 {
            let quantisation = o.meters_per_pulse * o.rate_hz / 6f64.sqrt();
            nav.odometer.std_mps = nav
                .odometer
                .std_mps
                .max(o.speed_noise_mps.hypot(quantisation));
            OdometerFormat::NavfuseSpeed
        } else {
            OdometerFormat::Navfuse {
                meters_per_pulse: o.meters_per_pulse,
            }
        };
        odometer = Some(OdometerSource {
            path: dir.join("odometer.txt"),
            format,
            skip_lines: None,
        });
        nav.vehicle = VehicleOptions {
            mounting_rpy: Vector3::zeros(),
            lever_arm_b: Vector3::from(sc.file.vehicle.imu_to_reference_m),
            mounting_std: units::DEG.si(1.0),
        };
    }
    // Barometer: baro.txt (pressure in Pa); the filter's bias walk covers the
    // simulated drift and the slow error (amplitude A over a quarter period P/4).
    let baro = sc.file.baro.as_ref().map(|b| {
        let slow = if b.slow_period_s > 0.0 {
            b.slow_amplitude_m.powi(2) / (b.slow_period_s / 4.0)
        } else {
            0.0
        };
        let walk_si = ((b.bias_drift_m_per_sqrth / 60.0).powi(2) + slow).sqrt();
        nav.baro = BaroOptions {
            enabled: true,
            std_m: b.noise_std_m.max(0.05),
            bias_random_walk: units::VRW.si(units::VRW.user(walk_si)),
            ..BaroOptions::default()
        };
        BaroSource {
            path: dir.join("baro.txt"),
            quantity: BaroQuantity::PressurePa,
            reference_pressure_pa: b.reference_pressure_pa,
            delay_s: b.delay_s,
            format: Default::default(),
            skip_lines: None,
        }
    });
    RunConfig {
        nav,
        baro,
        imu,
        gnss,
        odometer,
        heading,
        // The 1-sigma (std.txt) for consistency checks and the report's bands.
        output: OutputSpec {
            imu_err: false,
            std: true,
            ..OutputSpec::default()
        },
        source_path: dir.join("run.toml"),
        kfgins_output_path: None,
        warnings: Vec::new(),
        smoother: Default::default(),
        tuning: Default::default(),
        relative_outages: Vec::new(),
        defaulted: Vec::new(),
    }
}
