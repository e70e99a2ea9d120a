//! KF-GINS YAML configuration: the synthetic demo file, conversions, warnings, errors.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use navfuse_io::config::{load, load_kfgins_yaml, load_toml, parse_kfgins_yaml_str, ConfigError};
use navfuse_io::input::{GnssFormat, ImuFormat};

const D2R: f64 = PI / 180.0;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300)
}

#[track_caller]
fn assert_close3(v: &nalgebra::Vector3<f64>, expected: [f64; 3]) {
    for i in 0..3 {
        assert!(
            close(v[i], expected[i]),
            "element {i}: {} != {}",
            v[i],
            expected[i]
        );
    }
}

fn shared_data() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if p.is_dir() {
        Some(p)
    } else {
        println!("skipped: {} not found (shared data absent)", p.display());
        None
    }
}

fn tmp(name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("config_kfgins");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The synthetic demo file's content (section 4 values), for tests that must run
/// without /work/shared.
const DEMO: &str = r#"# KF-GINS configuration
imupath: "./IMU.txt"
gnsspath: "./GNSS.txt"
outputpath: "./out"
imudatalen: 7
imudatarate: 200
starttime: 456300
endtime: -1
initpos: [ 30.4447873701, 114.4718632047, 20.899 ]
initvel: [ 0.0, 0.0, 0.0 ]
initatt: [ 0.85421502, -2.03480295, 185.70235133 ]
initgyrbias: [ 0, 0, 0 ]
initaccbias: [ 0, 0, 0 ]
initgyrscale: [ 0, 0, 0 ]
initaccscale: [ 0, 0, 0 ]
initposstd: [ 0.005, 0.004, 0.008 ]
initvelstd: [ 0.003, 0.004, 0.004 ]
initattstd: [ 0.003, 0.003, 0.023 ]
imunoise:
  arw: [0.003, 0.003, 0.003]
  vrw: [0.03, 0.03, 0.03]
  gbstd: [0.027, 0.027, 0.027]
  abstd: [15.0, 15.0, 15.0]
  gsstd: [300.0, 300.0, 300.0]
  asstd: [300.0, 300.0, 300.0]
  corrtime: 4.0
antlever: [ 0.136, -0.301, -0.184 ]
"#;

fn check_demo(c: &navfuse_io::config::RunConfig, dir: &Path) {
    assert_eq!(c.imu.path, dir.join("./IMU.txt"));
    assert_eq!(c.imu.format, ImuFormat::KfGins);
    assert_eq!(c.imu.rate_hz, 200.0);
    assert_eq!(c.imu.sensor_to_body_rpy_deg, [0.0; 3]);
    let g = c.gnss.as_ref().unwrap();
    assert_eq!(g.path, dir.join("./GNSS.txt"));
    assert_eq!(g.format, GnssFormat::KfGins);
    assert_eq!((g.decimate_s, g.time_offset_s), (None, 0.0));
    assert_eq!(c.kfgins_output_path, Some(dir.join("./out")));
    assert_eq!(c.nav.start_time, 456300.0);
    assert_eq!(c.nav.end_time, None);

    let n = &c.nav.imu_noise;
    // ARW 0.003 deg/sqrt(h) = 0.003 * pi/180 / 60 rad/sqrt(s) = 8.7266e-7
    assert_close3(&n.arw, [0.003 * PI / 180.0 / 60.0; 3]);
    assert!((n.arw.x - 8.726646259971648e-7).abs() < 1e-20);
    assert_close3(&n.vrw, [0.0005; 3]);
    assert_close3(&n.gyro_bias_std, [0.027 * PI / 180.0 / 3600.0; 3]);
    // abstd 15 mGal = 1.5e-4 m/s^2
    assert_close3(&n.accel_bias_std, [1.5e-4; 3]);
    assert_close3(&n.gyro_scale_std, [3e-4; 3]);
    assert_close3(&n.accel_scale_std, [3e-4; 3]);
    // corrtime 4 h
    assert_eq!(n.corr_time_s, 14400.0);

    let i = &c.nav.initial;
    assert_close3(
        &i.lla.expect("initpos"),
        [30.4447873701 * D2R, 114.4718632047 * D2R, 20.899],
    );
    assert_close3(&i.v_n, [0.0; 3]);
    // initatt in radians
    let rpy = match i.attitude {
        navfuse_core::config::AttitudeInit::Given(r) => r,
        other => panic!("initatt must give the attitude, got {other:?}"),
    };
    assert_close3(
        &rpy,
        [
            0.85421502 * PI / 180.0,
            -2.03480295 * PI / 180.0,
            185.70235133 * PI / 180.0,
        ],
    );
    assert!((rpy.z - 3.2411).abs() < 1e-4);
    assert_close3(&i.pos_std, [0.005, 0.004, 0.008]);
    assert_close3(&i.vel_std, [0.003, 0.004, 0.004]);
    assert_close3(&i.att_std, [0.003 * D2R, 0.003 * D2R, 0.023 * D2R]);
    assert_eq!(i.imu_errors, Default::default());
    // initbgstd etc. absent: the noise values
    assert_eq!(i.imu_errors_std.gyro_bias, n.gyro_bias_std);
    assert_eq!(i.imu_errors_std.accel_bias, n.accel_bias_std);
    assert_eq!(i.imu_errors_std.gyro_scale, n.gyro_scale_std);
    assert_eq!(i.imu_errors_std.accel_scale, n.accel_scale_std);

    let go = &c.nav.gnss;
    assert_close3(&go.lever_arm_b, [0.136, -0.301, -0.184]);
    assert!(go.use_velocity);
    assert_eq!(go.gate_probability, None);
    assert_eq!(go.position_std_override, None);
    assert!(go.outages.is_empty());
    assert_eq!(
        c.nav.filter.covariance_period_s,
        navfuse_core::config::DEFAULT_COVARIANCE_PERIOD_S
    );
    assert_eq!(c.nav.filter.time_offset, None);
    assert_eq!(c.output.rate_hz, None);
    assert!(c.output.imu_err && c.output.std && !c.output.csv);
}

#[test]
fn synthetic_demo_yaml_loads_in_si() {
    let Some(data) = shared_data() else { return };
    let p = data.join("kf-gins/synthetic/kf-gins.yaml");
    let c = load_kfgins_yaml(&p).unwrap();
    check_demo(&c, p.parent().unwrap());
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    assert_eq!(load(&p).unwrap(), c);
}

#[test]
fn demo_values_without_shared_data() {
    let p = tmp("demo.yaml", DEMO);
    let c = load_kfgins_yaml(&p).unwrap();
    check_demo(&c, p.parent().unwrap());
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    let q = tmp("demo.yml", DEMO);
    check_demo(&load(&q).unwrap(), q.parent().unwrap());
}

#[test]
fn yaml_to_toml_round_trip() {
    let p = tmp("demo_rt.yaml", DEMO);
    let c = load_kfgins_yaml(&p).unwrap();
    let text = c.to_toml_string();
    let d = load_toml(&tmp("demo_rt.toml", &text)).unwrap_or_else(|e| panic!("{e}\n{text}"));
    check_demo(
        &navfuse_io::config::RunConfig {
            kfgins_output_path: c.kfgins_output_path.clone(),
            ..d
        },
        &std::path::absolute(p.parent().unwrap()).unwrap(),
    );
}

#[test]
fn optional_init_std_and_endtime() {
    let text = DEMO.replace("endtime: -1", "endtime: 459000.5").replace(
        "initattstd: [ 0.003, 0.003, 0.023 ]",
        "initattstd: [ 0.003, 0.003, 0.023 ]\ninitbgstd: [1, 2, 3]\ninitbastd: [100, 100, 100]\n\
         initsgstd: [1000, 1000, 1000]\ninitsastd: [2000, 2000, 2000]",
    );
    let c = parse_kfgins_yaml_str(&text, Path::new("/d/k.yaml")).unwrap();
    assert_eq!(c.nav.end_time, Some(459000.5));
    let s = &c.nav.initial.imu_errors_std;
    let dph = D2R / 3600.0;
    assert_close3(&s.gyro_bias, [dph, 2.0 * dph, 3.0 * dph]);
    assert_close3(&s.accel_bias, [1e-3; 3]);
    assert_close3(&s.gyro_scale, [1e-3; 3]);
    assert_close3(&s.accel_scale, [2e-3; 3]);
    assert_eq!(c.imu.path, PathBuf::from("/d/./IMU.txt"));
}

#[test]
fn unknown_keys_are_warnings() {
    let text = format!("{DEMO}odometer: true\nimunoise2: 3\n").replace(
        "  corrtime: 4.0",
        "  corrtime: 4.0\n  odostd: [0.1, 0.1, 0.1]",
    );
    let c = parse_kfgins_yaml_str(&text, Path::new("k.yaml")).unwrap();
    assert_eq!(c.warnings.len(), 3, "{:?}", c.warnings);
    assert!(c.warnings.iter().any(|w| w.contains("'odometer'")));
    assert!(c.warnings.iter().any(|w| w.contains("'imunoise2'")));
    assert!(c.warnings.iter().any(|w| w.contains("'imunoise.odostd'")));
    // a longer vector: first three used, with a warning
    let text = DEMO.replace(
        "initvel: [ 0.0, 0.0, 0.0 ]",
        "initvel: [ 1.0, 2.0, 3.0, 4.0 ]",
    );
    let c = parse_kfgins_yaml_str(&text, Path::new("k.yaml")).unwrap();
    assert_close3(&c.nav.initial.v_n, [1.0, 2.0, 3.0]);
    assert!(
        c.warnings.iter().any(|w| w.contains("initvel")),
        "{:?}",
        c.warnings
    );
}

fn yerr(text: &str) -> ConfigError {
    parse_kfgins_yaml_str(text, Path::new("dir/k.yaml")).expect_err("expected an error")
}

fn line_containing(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn errors_name_yaml_key_and_line() {
    // imudatalen < 7
    let text = DEMO.replace("imudatalen: 7", "imudatalen: 6");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("imudatalen"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "imudatalen")), "{e}");
    assert!(e.message.contains("at least 7"), "{e}");
    assert!(
        e.to_string()
            .starts_with("dir/k.yaml:5: key 'imudatalen': "),
        "{e}"
    );

    // short vector
    let text = DEMO.replace(
        "antlever: [ 0.136, -0.301, -0.184 ]",
        "antlever: [ 0.136, -0.301 ]",
    );
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("antlever"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "antlever")), "{e}");

    // zero std, nested key
    let text = DEMO.replace("abstd: [15.0, 15.0, 15.0]", "abstd: [15.0, 0.0, 15.0]");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("imunoise.abstd"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "abstd")), "{e}");
    assert!(e.message.contains("> 0"), "{e}");

    let text = DEMO.replace(
        "initposstd: [ 0.005, 0.004, 0.008 ]",
        "initposstd: [ 0.005, 0, 0.008 ]",
    );
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("initposstd"), "{e}");

    let text = DEMO.replace("corrtime: 4.0", "corrtime: 0");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("imunoise.corrtime"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "corrtime")), "{e}");

    // wrong type
    let text = DEMO.replace("imudatarate: 200", "imudatarate: fast");
    let e = yerr(&text);
    assert_eq!(e.line, Some(line_containing(&text, "imudatarate")), "{e}");
    assert_eq!(e.key.as_deref(), Some("imudatarate"), "{e}");

    let text = DEMO.replace("gbstd: [0.027, 0.027, 0.027]", "gbstd: [0.027, x, 0.027]");
    let e = yerr(&text);
    assert_eq!(e.line, Some(line_containing(&text, "gbstd")), "{e}");
    assert_eq!(e.key.as_deref(), Some("imunoise.gbstd"), "{e}");

    // missing key
    let text = DEMO.replace("initatt: [ 0.85421502, -2.03480295, 185.70235133 ]\n", "");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("initatt"), "{e}");
    let text = DEMO.replace("  vrw: [0.03, 0.03, 0.03]\n", "");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("imunoise.vrw"), "{e}");

    // latitude out of range
    let text = DEMO.replace("30.4447873701", "130.4447873701");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("initpos"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "initpos")), "{e}");

    // endtime before starttime
    let text = DEMO.replace("endtime: -1", "endtime: 1000");
    let e = yerr(&text);
    assert_eq!(e.key.as_deref(), Some("endtime"), "{e}");
}

#[test]
fn missing_yaml_file() {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join("config_kfgins/nope.yaml");
    let e = load_kfgins_yaml(&p).unwrap_err();
    assert_eq!(e.path, p);
    assert!(e.message.contains("cannot read"), "{e}");
}

#[test]
fn garbage_does_not_panic() {
    for t in [
        "",
        "[1, 2]",
        "imunoise: 3",
        ":\n  - {",
        "imupath: [1]\n",
        "\u{feff}x: y",
    ] {
        assert!(parse_kfgins_yaml_str(t, Path::new("k.yaml")).is_err());
    }
}
