//! navfuse TOML: alignment modes, [vehicle], [nhc], [odometer], [heading], [zupt]
//! (docs/CONFIG.md): defaults equal to the core's, unit conversions, round trips
//! through `to_toml_string`, and errors naming file, line and key.

use std::path::{Path, PathBuf};

use navfuse_core::config::{
    AttitudeInit, HeadingOptions, NhcMode, NhcOptions, OdometerOptions, VehicleOptions, ZuptOptions,
};
use navfuse_io::config::{load_toml, ConfigError, RunConfig};
use navfuse_io::input::OdometerFormat;

const D2R: f64 = std::f64::consts::PI / 180.0;

fn tmp(name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("config_aiding");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Required keys only, and no initial attitude at all.
const BASE: &str = r#"
[imu]
file = "IMU.txt"
format = "kf-gins"
rate_hz = 200

[initial]
position_std_m = 1.0
velocity_std_mps = 0.1
attitude_std_deg = [1, 1, 5]

[imu_noise]
arw_deg_sqrth = 0.2
vrw_mps_sqrth = 0.05
gyro_bias_std_degph = 20
accel_bias_std_mgal = 300
gyro_scale_std_ppm = 1000
accel_scale_std_ppm = 1000
corr_time_h = 1
"#;

fn with(extra: &str) -> String {
    format!("{BASE}\n{extra}\n")
}

fn ok(name: &str, text: &str) -> RunConfig {
    let p = tmp(name, text);
    load_toml(&p).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Load, write back as TOML, load again: the same configuration.
fn round_trip(name: &str, c: &RunConfig) -> RunConfig {
    let text = c.to_toml_string();
    let d = ok(&format!("{name}_rt.toml"), &text);
    assert_eq!(d.nav, c.nav, "{text}");
    assert_eq!(d.odometer, c.odometer, "{text}");
    assert_eq!(d.heading, c.heading, "{text}");
    d
}

fn err(name: &str, text: &str) -> ConfigError {
    let p = tmp(name, text);
    let e = load_toml(&p).expect_err("expected an error");
    let shown = e.to_string();
    assert!(shown.starts_with(&p.display().to_string()), "{shown}");
    if let (Some(line), Some(key)) = (e.line, &e.key) {
        assert!(
            shown.contains(&format!(":{line}: key '{key}': ")),
            "{shown}"
        );
    }
    e
}

fn line_containing(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// `extra` appended to BASE must fail on `key`, at the line holding `needle`, with a
/// message containing `expect`.
#[track_caller]
fn check_err(name: &str, extra: &str, key: &str, needle: &str, expect: &str) {
    let text = with(extra);
    let e = err(name, &text);
    assert_eq!(e.key.as_deref(), Some(key), "{e}");
    // the needle is looked for in the appended part only
    let skip = BASE.lines().count();
    assert_eq!(
        e.line,
        Some(
            skip + line_containing(
                &text.lines().skip(skip).collect::<Vec<_>>().join("\n"),
                needle
            )
        ),
        "{e}"
    );
    assert!(e.message.contains(expect), "{e}");
}

#[test]
fn defaults_are_the_core_defaults() {
    let c = ok("defaults.toml", BASE);
    assert_eq!(c.nav.vehicle, VehicleOptions::default());
    assert_eq!(c.nav.nhc, NhcOptions::default());
    assert_eq!(c.nav.odometer, OdometerOptions::default());
    assert_eq!(c.nav.heading, HeadingOptions::default());
    assert_eq!(c.nav.zupt, ZuptOptions::default());
    assert_eq!((c.odometer.as_ref(), c.heading.as_ref()), (None, None));
    // empty sections: the same defaults
    let c2 = ok(
        "empty_sections.toml",
        &with("[vehicle]\n[nhc]\n[heading]\n[zupt]\n"),
    );
    assert_eq!(c2.nav, c.nav);
    assert_eq!(c2.heading, None);
    round_trip("defaults", &c);
}

#[test]
fn no_initial_attitude_means_auto_alignment() {
    let c = ok("auto.toml", BASE);
    assert_eq!(
        c.nav.initial.attitude,
        AttitudeInit::Auto {
            level_window_s: 10.0,
            min_speed_mps: 3.0,
            gyrocompass: false
        }
    );
    round_trip("auto", &c);
}

#[test]
fn alignment_modes() {
    let align = |name: &str, body: &str| {
        let text = BASE.replace(
            "[imu_noise]",
            &format!("[initial.alignment]\n{body}\n\n[imu_noise]"),
        );
        let c = ok(name, &text);
        round_trip(name, &c);
        c.nav.initial.attitude
    };
    // no mode: the original level-and-course alignment (back-compatible)
    assert_eq!(
        align("al_none.toml", "level_window_s = 20"),
        AttitudeInit::LevelAndGnssCourse {
            level_window_s: 20.0,
            min_speed_mps: 3.0
        }
    );
    assert_eq!(
        align("al_empty.toml", ""),
        AttitudeInit::LevelAndGnssCourse {
            level_window_s: 10.0,
            min_speed_mps: 3.0
        }
    );
    assert_eq!(
        align(
            "al_lc.toml",
            "mode = \"level_and_course\"\nmin_speed_mps = 5"
        ),
        AttitudeInit::LevelAndGnssCourse {
            level_window_s: 10.0,
            min_speed_mps: 5.0
        }
    );
    assert_eq!(
        align(
            "al_gc.toml",
            "mode = \"static_gyrocompass\"\nlevel_window_s = 60"
        ),
        AttitudeInit::StaticGyrocompass {
            level_window_s: 60.0
        }
    );
    assert_eq!(
        align("al_im.toml", "mode = \"in_motion\"\nmin_speed_mps = 2"),
        AttitudeInit::InMotion { min_speed_mps: 2.0 }
    );
    assert_eq!(
        align("al_im_default.toml", "mode = \"in_motion\""),
        AttitudeInit::InMotion { min_speed_mps: 3.0 }
    );
    assert_eq!(
        align(
            "al_auto.toml",
            "mode = \"auto\"\nlevel_window_s = 5\nmin_speed_mps = 4\ngyrocompass = true"
        ),
        AttitudeInit::Auto {
            level_window_s: 5.0,
            min_speed_mps: 4.0,
            gyrocompass: true
        }
    );
}

#[test]
fn alignment_errors() {
    let align = |body: &str| {
        BASE.replace(
            "[imu_noise]",
            &format!("[initial.alignment]\n{body}\n\n[imu_noise]"),
        )
    };
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            "mode = \"in_motion\"\nlevel_window_s = 5",
            "initial.alignment.level_window_s",
            "level_window_s",
            "in_motion",
        ),
        (
            "mode = \"static_gyrocompass\"\nmin_speed_mps = 5",
            "initial.alignment.min_speed_mps",
            "min_speed_mps",
            "static_gyrocompass",
        ),
        (
            "mode = \"level_and_course\"\ngyrocompass = true",
            "initial.alignment.gyrocompass",
            "gyrocompass",
            "auto",
        ),
        (
            "gyrocompass = false",
            "initial.alignment.gyrocompass",
            "gyrocompass",
            "auto",
        ),
        (
            "mode = \"auto\"\nlevel_window_s = 0",
            "initial.alignment.level_window_s",
            "level_window_s",
            "> 0",
        ),
        (
            "mode = \"auto\"\nmin_speed_mps = -1",
            "initial.alignment.min_speed_mps",
            "min_speed_mps",
            "> 0",
        ),
        (
            "mode = \"gyro\"",
            "initial.alignment.mode",
            "mode",
            "static_gyrocompass",
        ),
    ];
    for (i, (body, key, needle, expect)) in cases.iter().enumerate() {
        let text = align(body);
        let e = err(&format!("al_err{i}.toml"), &text);
        assert_eq!(e.key.as_deref(), Some(*key), "{e}");
        assert_eq!(e.line, Some(line_containing(&text, needle)), "{e}");
        assert!(e.message.contains(expect), "{e}");
    }
    // attitude_deg and an alignment table: still an error
    let text = align("mode = \"auto\"").replace(
        "position_std_m = 1.0",
        "attitude_deg = [0, 0, 0]\nposition_std_m = 1.0",
    );
    let e = err("al_both.toml", &text);
    assert_eq!(e.key.as_deref(), Some("initial.alignment"), "{e}");
    assert!(e.message.contains("not both"), "{e}");
}

#[test]
fn vehicle_and_nhc() {
    let c = ok(
        "veh.toml",
        &with(
            "[vehicle]\nmounting_rpy_deg = [0, 1.5, -3]\nlever_arm_m = [-1.5, 0.2, 0.9]\nmounting_std_deg = 1\n\
             [nhc]\nmode = \"always\"\nstd_mps = 0.05\ngate_probability = false\n",
        ),
    );
    let v = &c.nav.vehicle;
    assert_eq!(
        v.mounting_rpy,
        nalgebra::Vector3::new(0.0, 1.5 * D2R, -3.0 * D2R)
    );
    assert_eq!(v.lever_arm_b, nalgebra::Vector3::new(-1.5, 0.2, 0.9));
    assert_eq!(v.mounting_std, D2R);
    let n = &c.nav.nhc;
    assert_eq!(n.mode, NhcMode::Always);
    assert_eq!(n.std_mps, [0.05, 0.05]);
    assert_eq!(n.gate_probability, None);
    assert_eq!(n.rate_hz, NhcOptions::default().rate_hz);
    round_trip("veh", &c);
    let c = ok(
        "nhc_off.toml",
        &with("[nhc]\nmode = \"off\"\nstd_mps = [0.3, 0.2]"),
    );
    assert_eq!(c.nav.nhc.mode, NhcMode::Off);
    assert_eq!(c.nav.nhc.std_mps, [0.3, 0.2]);
    round_trip("nhc_off", &c);

    check_err(
        "veh_e0.toml",
        "[vehicle]\nmounting_rpy_deg = [0, 95, 0]",
        "vehicle.mounting_rpy_deg",
        "mounting_rpy_deg",
        "pitch",
    );
    check_err(
        "veh_e1.toml",
        "[vehicle]\nlever_arm_m = [1, 2]",
        "vehicle.lever_arm_m",
        "lever_arm_m",
        "3 numbers",
    );
    check_err(
        "veh_e2.toml",
        "[vehicle]\nmounting_std_deg = -1",
        "vehicle.mounting_std_deg",
        "mounting_std_deg",
        ">= 0",
    );
    check_err(
        "veh_e3.toml",
        "[vehicle]\nlever = [1, 2, 3]",
        "vehicle.lever",
        "lever =",
        "unknown field",
    );
    check_err(
        "nhc_e0.toml",
        "[nhc]\nmode = \"during_outage\"",
        "nhc.mode",
        "mode",
        "outage",
    );
    check_err(
        "nhc_e1.toml",
        "[nhc]\nstd_mps = [0.1, 0.1, 0.1]",
        "nhc.std_mps",
        "std_mps",
        "2 numbers",
    );
    check_err(
        "nhc_e2.toml",
        "[nhc]\nstd_mps = [0.1, 0]",
        "nhc.std_mps",
        "std_mps",
        "> 0",
    );
    check_err(
        "nhc_e3.toml",
        "[nhc]\nstd_mps = 0",
        "nhc.std_mps",
        "std_mps",
        "> 0",
    );
    check_err(
        "nhc_e4.toml",
        "[nhc]\nrate_hz = 0",
        "nhc.rate_hz",
        "rate_hz",
        "> 0",
    );
    check_err(
        "nhc_e5.toml",
        "[nhc]\noutage_after_s = -1",
        "nhc.outage_after_s",
        "outage_after_s",
        ">= 0",
    );
    check_err(
        "nhc_e6.toml",
        "[nhc]\ngate_probability = 0.7",
        "nhc.gate_probability",
        "gate_probability",
        "[1e-15, 0.5)",
    );
    check_err(
        "nhc_e7.toml",
        "[nhc]\ngate_probability = true",
        "nhc.gate_probability",
        "gate_probability",
        "false",
    );
    check_err(
        "nhc_e8.toml",
        "[nhc]\ngate_probability = 0",
        "nhc.gate_probability",
        "gate_probability",
        "probability",
    );
    check_err(
        "nhc_e9.toml",
        "[nhc]\nmin_speed_mps = nan",
        "nhc.min_speed_mps",
        "min_speed_mps",
        ">= 0",
    );
    check_err(
        "nhc_e10.toml",
        "[nhc]\nstd_mps = \"0.1\"",
        "nhc.std_mps",
        "std_mps",
        "2 numbers",
    );
}

#[test]
fn odometer_formats() {
    let odo = |name: &str, body: &str| {
        ok(
            name,
            &with(&format!("[odometer]\nfile = \"odo.txt\"\n{body}")),
        )
    };
    let c = odo("odo_speed.toml", "format = \"speed\"");
    let src = c.odometer.clone().unwrap();
    assert_eq!(src.path, tmp("x", "").parent().unwrap().join("odo.txt"));
    assert_eq!(
        src.format,
        OdometerFormat::Speed {
            speed_is_mean: true
        }
    );
    // presence of the section with a file switches the odometer on; the rest are the
    // core defaults
    assert_eq!(
        c.nav.odometer,
        OdometerOptions {
            enabled: true,
            ..OdometerOptions::default()
        }
    );
    round_trip("odo_speed", &c);
    let c = odo("odo_inst.toml", "format = \"speed\"\nspeed_is_mean = false");
    assert_eq!(
        c.odometer.as_ref().unwrap().format,
        OdometerFormat::Speed {
            speed_is_mean: false
        }
    );
    round_trip("odo_inst", &c);
    let c = odo(
        "odo_nav.toml",
        "format = \"navfuse\"\nmeters_per_pulse = 0.00324\nscale_std_ppm = 0\nscale_ppm = -250\ngate_probability = 1e-6",
    );
    assert_eq!(
        c.odometer.as_ref().unwrap().format,
        OdometerFormat::Navfuse {
            meters_per_pulse: 0.00324
        }
    );
    assert_eq!(c.nav.odometer.scale_std, 0.0);
    assert!((c.nav.odometer.scale_initial + 250e-6).abs() < 1e-18);
    assert_eq!(c.nav.odometer.gate_probability, Some(1e-6));
    round_trip("odo_nav", &c);
}

#[test]
fn odometer_errors() {
    let o = |body: &str| format!("[odometer]\nfile = \"odo.txt\"\n{body}");
    check_err(
        "odo_e0.toml",
        &o("format = \"pulses\""),
        "odometer.meters_per_pulse",
        "[odometer]",
        "required",
    );
    check_err(
        "odo_e1.toml",
        &o("format = \"navfuse\"\nmeters_per_pulse = 0"),
        "odometer.meters_per_pulse",
        "meters_per_pulse",
        "> 0",
    );
    check_err(
        "odo_e2.toml",
        &o("format = \"speed\"\nmeters_per_pulse = 0.003"),
        "odometer.meters_per_pulse",
        "meters_per_pulse",
        "pulses",
    );
    check_err(
        "odo_e3.toml",
        &o("format = \"pulses\"\nmeters_per_pulse = 0.003\nspeed_is_mean = true"),
        "odometer.speed_is_mean",
        "speed_is_mean",
        "speed",
    );
    check_err(
        "odo_e4.toml",
        &o("format = \"speed\"\nstd_mps = 0"),
        "odometer.std_mps",
        "std_mps",
        "> 0",
    );
    check_err(
        "odo_e5.toml",
        &o("format = \"speed\"\nscale_std_ppm = -1"),
        "odometer.scale_std_ppm",
        "scale_std_ppm",
        ">= 0",
    );
    check_err(
        "odo_e6.toml",
        &o("format = \"speed\"\nscale_ppm = inf"),
        "odometer.scale_ppm",
        "scale_ppm",
        "finite",
    );
    check_err(
        "odo_e7.toml",
        &o("format = \"speed\"\nscale_random_walk_ppm_per_sqrth = -5"),
        "odometer.scale_random_walk_ppm_per_sqrth",
        "scale_random_walk",
        ">= 0",
    );
    check_err(
        "odo_e8.toml",
        &o("format = \"speed\"\ngate_probability = 1"),
        "odometer.gate_probability",
        "gate_probability",
        "[1e-15, 0.5)",
    );
    check_err(
        "odo_e9.toml",
        &o("format = \"wheel\""),
        "odometer.format",
        "format",
        "navfuse",
    );
    check_err(
        "odo_e10.toml",
        &o("format = \"speed\"\nwith_nhc = 1"),
        "odometer.with_nhc",
        "with_nhc",
        "bool",
    );
    let e = err("odo_e11.toml", &with("[odometer]\nformat = \"speed\""));
    assert_eq!(e.key.as_deref(), Some("odometer.file"), "{e}");
    let e = err("odo_e12.toml", &with("[odometer]\nfile = \"o.txt\""));
    assert_eq!(e.key.as_deref(), Some("odometer.format"), "{e}");
    check_err(
        "odo_e13.toml",
        "[odometer]\nfile = \" \"\nformat = \"speed\"",
        "odometer.file",
        "file",
        "file path",
    );
}

#[test]
fn heading_and_zupt() {
    let c = ok(
        "head.toml",
        &with("[heading]\nfile = \"heading.txt\"\nbaseline_m = [1.2, 0, 0]\n"),
    );
    assert_eq!(
        c.heading.as_ref().unwrap().path,
        tmp("x", "").parent().unwrap().join("heading.txt")
    );
    assert_eq!(
        c.nav.heading,
        HeadingOptions {
            baseline_b: Some(nalgebra::Vector3::new(1.2, 0.0, 0.0)),
            ..HeadingOptions::default()
        }
    );
    round_trip("head", &c);
    // course over ground alone: no file needed
    let c = ok(
        "cog.toml",
        &with("[heading]\ncourse_over_ground = true\ncourse_min_speed_mps = 8\ngate_probability = false"),
    );
    assert!(c.heading.is_none() && c.nav.heading.baseline_b.is_none());
    assert!(c.nav.heading.course_over_ground);
    assert_eq!(c.nav.heading.course_min_speed_mps, 8.0);
    assert_eq!(c.nav.heading.gate_probability, None);
    round_trip("cog", &c);

    let c = ok(
        "zupt.toml",
        &with("[zupt]\nenabled = true\ngyro_max_dps = 0.2\nangular_rate_std_dps = 0.05"),
    );
    let z = &c.nav.zupt;
    assert!(z.enabled);
    assert_eq!(z.gyro_max, 0.2 * D2R);
    assert_eq!(z.angular_rate_std, 0.05 * D2R);
    assert_eq!(z.window_s, ZuptOptions::default().window_s);
    round_trip("zupt", &c);

    let h = |body: &str| format!("[heading]\n{body}");
    check_err(
        "head_e0.toml",
        &h("file = \"h.txt\""),
        "heading.baseline_m",
        "[heading]",
        "required",
    );
    check_err(
        "head_e1.toml",
        &h("baseline_m = [1, 0, 0]"),
        "heading.baseline_m",
        "baseline_m",
        "heading.file",
    );
    check_err(
        "head_e2.toml",
        &h("std_deg = 0.5"),
        "heading.std_deg",
        "std_deg",
        "heading.file",
    );
    check_err(
        "head_e3.toml",
        &h("file = \"h.txt\"\nbaseline_m = [0, 0, 0]"),
        "heading.baseline_m",
        "baseline_m",
        "non-zero",
    );
    check_err(
        "head_e4.toml",
        &h("file = \"h.txt\"\nbaseline_m = [1, 0, 0]\nstd_deg = 0"),
        "heading.std_deg",
        "std_deg",
        "> 0",
    );
    check_err(
        "head_e5.toml",
        &h("course_min_speed_mps = 0"),
        "heading.course_min_speed_mps",
        "course_min_speed_mps",
        "> 0",
    );
    check_err(
        "head_e6.toml",
        &h("course_std_floor_deg = -1"),
        "heading.course_std_floor_deg",
        "course_std_floor_deg",
        "> 0",
    );
    check_err(
        "head_e7.toml",
        &h("gate_probability = 1e-20"),
        "heading.gate_probability",
        "gate_probability",
        "[1e-15, 0.5)",
    );
    check_err(
        "head_e8.toml",
        &h("format = \"nmea\""),
        "heading.format",
        "format",
        // heading.format exists (NMEA heading), but only with heading.file.
        "applies only with heading.file",
    );

    let z = |body: &str| format!("[zupt]\n{body}");
    check_err(
        "zupt_e0.toml",
        &z("window_s = 0"),
        "zupt.window_s",
        "window_s",
        "> 0",
    );
    check_err(
        "zupt_e1.toml",
        &z("accel_std_max_mps2 = -0.1"),
        "zupt.accel_std_max_mps2",
        "accel_std_max_mps2",
        "> 0",
    );
    check_err(
        "zupt_e2.toml",
        &z("gyro_max_dps = 0"),
        "zupt.gyro_max_dps",
        "gyro_max_dps",
        "> 0",
    );
    check_err(
        "zupt_e3.toml",
        &z("rate_hz = -5"),
        "zupt.rate_hz",
        "rate_hz",
        "> 0",
    );
    check_err(
        "zupt_e4.toml",
        &z("velocity_std_mps = 0"),
        "zupt.velocity_std_mps",
        "velocity_std_mps",
        "> 0",
    );
    check_err(
        "zupt_e5.toml",
        &z("angular_rate_std_dps = -1"),
        "zupt.angular_rate_std_dps",
        "angular_rate_std_dps",
        ">= 0",
    );
    check_err(
        "zupt_e6.toml",
        &z("enabled = \"yes\""),
        "zupt.enabled",
        "enabled",
        "bool",
    );
}

#[test]
fn written_toml_spells_out_the_new_sections() {
    let c = ok(
        "spell.toml",
        &with(
            "[odometer]\nfile = \"odo.txt\"\nformat = \"navfuse\"\nmeters_per_pulse = 0.00324\n\
               [heading]\nfile = \"heading.txt\"\nbaseline_m = [1.2, 0, 0]\n",
        ),
    );
    let text = c.to_toml_string();
    for needle in [
        "[odometer]",
        "format = \"navfuse\"",
        "meters_per_pulse = 0.00324",
        "scale_std_ppm = 10000",
        "[heading]",
        "baseline_m = [",
        "[vehicle]",
        "mounting_std_deg = 0",
        "[nhc]",
        "mode = \"off\"",
        "[zupt]",
        "enabled = false",
        "[initial.alignment]",
        "mode = \"auto\"",
        "gyrocompass = false",
    ] {
        assert!(text.contains(needle), "{needle} missing in\n{text}");
    }
    println!("{text}");
}

/// `[gnss] systems` and the multi-system keys of `[gnss.tight]`: defaults (GPS only,
/// factors 1: the GNSS layer applies RTKLIB's), letters, partial factor tables, round trips, and errors
/// naming the key.
#[test]
fn gnss_systems_and_inter_system_bias_keys() {
    use navfuse_core::config::PerSystem;
    use navfuse_core::sat::System;
    let rinex = "[gnss]\nfile = \"obs.rnx\"\nformat = \"rinex\"\nnav = \"nav.rnx\"\n";
    let c = ok("systems_default.toml", &with(rinex));
    assert_eq!(c.nav.gnss.systems, vec![System::Gps]);
    assert_eq!(c.nav.tight.sigma_scale, PerSystem::ONES);
    assert_eq!(c.nav.tight.sigma_scale.get(System::Glonass), 1.0);
    round_trip("systems_default", &c);

    let text = with(&format!(
        "{rinex}systems = [\"G\", \"E\", \"C\", \"R\", \"J\"]\n\n[gnss.tight]\nsigma_scale = {{ R = 2.0, E = 1.2 }}\nisb_psd_sqrt = 0.02\nisb_init_sigma_m = 50\n"
    ));
    let c = ok("systems_multi.toml", &text);
    use System::*;
    assert_eq!(
        c.nav.gnss.systems,
        vec![Gps, Galileo, BeiDou, Glonass, Qzss]
    );
    let s = c.nav.tight.sigma_scale;
    assert_eq!(
        (s.get(Glonass), s.get(Galileo), s.get(Gps)),
        (2.0, 1.2, 1.0)
    );
    assert_eq!(s.get(Sbas), 1.0);
    assert_eq!(c.nav.tight.isb_psd_sqrt, 0.02);
    assert_eq!(c.nav.tight.isb_init_sigma_m, 50.0);
    let d = round_trip("systems_multi", &c);
    assert_eq!(d.nav.gnss.systems, c.nav.gnss.systems);

    // As users type them: names or lower case, or one string.
    for (name, v) in [
        ("systems_names.toml", "[\"gps\", \"Galileo\", \"c\"]"),
        ("systems_string.toml", "\"G, galileo,C\""),
    ] {
        let c = ok(name, &with(&format!("{rinex}systems = {v}\n")));
        assert_eq!(c.nav.gnss.systems, vec![Gps, Galileo, BeiDou], "{v}");
    }
    check_err(
        "systems_bad.toml",
        &format!("{rinex}systems = [\"G\", \"X\"]\n"),
        "gnss.systems",
        "systems",
        "expected a system letter",
    );
    check_err(
        "systems_twice.toml",
        &format!("{rinex}systems = [\"E\", \"E\"]\n"),
        "gnss.systems",
        "systems",
        "listed twice",
    );
    check_err(
        "systems_empty.toml",
        &format!("{rinex}systems = []\n"),
        "gnss.systems",
        "systems",
        "at least one",
    );
    check_err(
        "sigma_scale_bad.toml",
        &format!("{rinex}\n[gnss.tight]\nsigma_scale = {{ Q = 2.0 }}\n"),
        "gnss.tight.sigma_scale",
        "sigma_scale",
        "\"Q\"",
    );
    check_err(
        "sigma_scale_neg.toml",
        &format!("{rinex}\n[gnss.tight]\nsigma_scale = {{ R = -1 }}\n"),
        "gnss.tight.sigma_scale.R",
        "sigma_scale",
        "> 0",
    );
    // Loose coupling of fixes has no satellites to choose.
    check_err(
        "systems_kfgins.toml",
        "[gnss]\nfile = \"gnss.txt\"\nformat = \"kf-gins\"\nsystems = [\"G\"]\n",
        "gnss.systems",
        "systems",
        "rinex",
    );
}

/// `[gnss] signals`, `dual_frequency`, `orbits`, `sp3`, `clk`: parsed, written back,
/// and refused with the key named.
#[test]
fn gnss_signals_and_orbits_keys() {
    use navfuse_io::input::{GnssFormat, Orbits};
    let rinex = "[gnss]\nfile = \"obs.rnx\"\nformat = \"rinex\"\nnav = \"nav.rnx\"\n";
    let rinex_of = |c: &RunConfig| match &c.gnss.as_ref().unwrap().format {
        GnssFormat::Rinex(r) => r.clone(),
        f => panic!("{f:?}"),
    };
    let r = rinex_of(&ok("signals_default.toml", &with(rinex)));
    assert!(r.signals.is_empty() && !r.dual_frequency);
    assert_eq!(r.orbits, Orbits::Broadcast);
    let text = with(&format!(
        "{rinex}signals = {{ R = [\"C1P\", \"C1C\"], E = [\"C1X\"] }}\ndual_frequency = true\n\
         orbits = \"sp3\"\nsp3 = [\"a.sp3\", \"b.sp3\"]\nclk = [\"a.clk\"]\n"
    ));
    let c = ok("signals_multi.toml", &text);
    let r = rinex_of(&c);
    let codes: Vec<String> = r
        .signals
        .iter()
        .map(|(s, c)| {
            format!(
                "{}:{}",
                s.letter(),
                c.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join("+")
            )
        })
        .collect();
    assert_eq!(codes, vec!["E:C1X", "R:C1P+C1C"]);
    assert!(r.dual_frequency);
    match &r.orbits {
        Orbits::Sp3 { sp3, clk } => {
            assert_eq!((sp3.len(), clk.len()), (2, 1));
            assert!(sp3[1].ends_with("b.sp3"));
        }
        o => panic!("{o:?}"),
    }
    let back = c.to_toml_string();
    let d = ok("signals_multi_rt.toml", &back);
    assert_eq!(rinex_of(&d), r, "{back}");
    // A single code as a string; systems by name or in lower case.
    let c = ok(
        "signals_lenient.toml",
        &with(&format!(
            "{rinex}signals = {{ r = \"C1P\", Galileo = [\"C1X\"] }}\n"
        )),
    );
    let got: Vec<(char, Vec<String>)> = rinex_of(&c)
        .signals
        .iter()
        .map(|(s, c)| (s.letter(), c.iter().map(|x| x.to_string()).collect()))
        .collect();
    assert_eq!(
        got,
        vec![
            ('E', vec!["C1X".to_string()]),
            ('R', vec!["C1P".to_string()])
        ]
    );
    check_err(
        "signals_bad.toml",
        &format!("{rinex}signals = {{ R = [\"L1P\"] }}\n"),
        "gnss.signals",
        "signals",
        "not a RINEX 3 code observation",
    );
    check_err(
        "orbits_bad.toml",
        &format!("{rinex}orbits = \"precise\"\n"),
        "gnss.orbits",
        "orbits",
        "expected \"broadcast\" or \"sp3\"",
    );
    check_err(
        "sp3_missing.toml",
        &format!("{rinex}orbits = \"sp3\"\n"),
        "gnss.orbits",
        "orbits",
        "needs sp3",
    );
}

#[test]
fn ubx_imu_odometer_and_heading() {
    use navfuse_io::input::{ImuFormat, UbxHeading, UbxOdometer};
    let text = with(
        "[odometer]\nfile = \"rx.ubx\"\nformat = \"ubx\"\nmeters_per_pulse = 0.0125\n\n\
         [heading]\nfile = \"rx.ubx\"\nformat = \"ubx\"\nubx_carrier = \"float\"\nbaseline_m = [1.2, 0, 0]\n",
    )
    .replace("format = \"kf-gins\"", "format = \"ubx\"");
    let c = ok("ubx_all.toml", &text);
    assert_eq!(c.imu.format, ImuFormat::Ubx);
    assert_eq!(
        c.odometer.as_ref().unwrap().format,
        OdometerFormat::Ubx(UbxOdometer::Ticks {
            meters_per_pulse: 0.0125
        })
    );
    let h = c.heading.as_ref().unwrap();
    assert_eq!(h.ubx, Some(UbxHeading { float_ok: true }));
    assert!(h.nmea.is_none());
    let d = round_trip("ubx_all", &c);
    assert_eq!(d.imu.format, ImuFormat::Ubx);
    let c = ok(
        "ubx_speed.toml",
        &with("[odometer]\nfile = \"rx.ubx\"\nformat = \"ubx\"\nubx_measurement = \"speed\"\n\n[heading]\nfile = \"rx.ubx\"\nformat = \"ubx\"\nbaseline_m = [1, 0, 0]"),
    );
    assert_eq!(
        c.odometer.as_ref().unwrap().format,
        OdometerFormat::Ubx(UbxOdometer::Speed)
    );
    assert_eq!(
        c.heading.as_ref().unwrap().ubx,
        Some(UbxHeading { float_ok: false })
    );
    round_trip("ubx_speed", &c);
    let o = |body: &str| format!("[odometer]\nfile = \"rx.ubx\"\n{body}");
    check_err(
        "ubx_e0.toml",
        &o("format = \"ubx\""),
        "odometer.meters_per_pulse",
        "[odometer]",
        "required for UBX wheel ticks",
    );
    check_err(
        "ubx_e1.toml",
        &o("format = \"ubx\"\nubx_measurement = \"speed\"\nmeters_per_pulse = 0.01"),
        "odometer.meters_per_pulse",
        "meters_per_pulse",
        "not to the UBX speed",
    );
    check_err(
        "ubx_e2.toml",
        &o("format = \"speed\"\nubx_measurement = \"speed\""),
        "odometer.ubx_measurement",
        "ubx_measurement",
        "applies only to odometer.format = \"ubx\"",
    );
    check_err(
        "ubx_e3.toml",
        "[heading]\nfile = \"h.txt\"\nubx_carrier = \"fixed\"\nbaseline_m = [1, 0, 0]",
        "heading.ubx_carrier",
        "ubx_carrier",
        "applies only to heading.format = \"ubx\"",
    );
}
