//! navfuse TOML configuration: every key, unit conversions, defaults, errors.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use navfuse_core::config::NhcMode;
use navfuse_io::config::{load, load_toml, parse_toml_str, ConfigError, RunConfig};
use navfuse_io::input::{
    AccelUnit, Coupling, GnssFormat, GyroUnit, ImuFormat, ImuQuantity, OdometerFormat,
    RateSampling, TimeScale, TimeUnit, UbxGnss,
};

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

fn tmp(name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("config_toml");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Every key of the format, csv IMU, rtklib-pos GNSS.
const FULL: &str = r#"
[imu]
file = "data/imu.csv"
format = "csv"
rate_hz = 100
sensor_to_body_rpy_deg = [180, 0, 90]
time_offset_s = -0.125

[imu.csv]
skip_lines = 2
time_col = 6
gyro_cols = [3, 4, 5]
accel_cols = [0, 1, 2]
time_unit = "ms"
time_scale = "gpst_unix"
quantity = "increment"
rate_sampling = "interval_mean"
gyro_unit = "deg"
accel_unit = "g"

[gnss]
file = "/abs/gnss.pos"
format = "rtklib-pos"
quality = [1, 2]
decimate_s = 1.0
time_offset_s = 0.01
time_snap_s = 0.001
lever_arm_m = [0.1, -0.05, -0.2]
use_velocity = false
position_std_m = [0.02, 0.03, 0.05]
velocity_std_mps = 0.1
gate_probability = 1e-4
outages = [[100.0, 160.0], [300, 330]]
outage_every = { length_s = 60, period_s = 180, from = 456900, until = 459500 }

[odometer]
file = "odo/odometer.txt"
format = "pulses"
meters_per_pulse = 0.00324
std_mps = 0.08
scale_ppm = 500
scale_std_ppm = 2000
scale_random_walk_ppm_per_sqrth = 30
with_nhc = true
gate_probability = false

[heading]
file = "heading.txt"
baseline_m = [0.0, 1.5, 0.0]
std_deg = 0.25
course_over_ground = true
course_min_speed_mps = 4
course_std_floor_deg = 2
gate_probability = 1e-3

[vehicle]
mounting_rpy_deg = [0.5, -1.0, 2.0]
lever_arm_m = [-1.2, 0.0, 0.8]
mounting_std_deg = 1.5

[nhc]
mode = "outage"
std_mps = [0.2, 0.1]
rate_hz = 20
outage_after_s = 2.5
gate_probability = 1e-3
min_speed_mps = 1.0

[zupt]
enabled = true
window_s = 0.5
accel_std_max_mps2 = 0.1
gyro_max_dps = 1
rate_hz = 2
velocity_std_mps = 0.02
angular_rate_std_dps = 0

[time]
start = 456300.5
end = 459000

[initial]
position_deg_m = [30.4447873701, 114.4718632047, 20.899]
velocity_mps = [1.0, -2.0, 0.5]
attitude_deg = [0.85421502, -2.03480295, 185.70235133]
position_std_m = [0.005, 0.004, 0.008]
velocity_std_mps = [0.003, 0.004, 0.004]
attitude_std_deg = [0.003, 0.003, 0.023]
gyro_bias_degph = [1, 2, 3]
accel_bias_mgal = [10, 20, 30]
gyro_scale_ppm = 100
accel_scale_ppm = [-100, 0, 100]
gyro_bias_std_degph = 5
accel_bias_std_mgal = [50, 60, 70]
gyro_scale_std_ppm = 1000
accel_scale_std_ppm = 2000

[imu_noise]
arw_deg_sqrth = 0.003
vrw_mps_sqrth = [0.03, 0.03, 0.04]
gyro_bias_std_degph = 0.027
accel_bias_std_mgal = 15
gyro_scale_std_ppm = 300
accel_scale_std_ppm = 300
corr_time_h = 4

[filter]
covariance_period_s = 0.1
time_offset = { estimate = true, initial_s = 0.02, std_s = 0.3, random_walk = 1e-6 }

[output]
rate_hz = 10
imu_err = false
std = false
csv = true
"#;

/// Minimal file: required keys only.
const MINIMAL: &str = r#"
[imu]
file = "IMU.txt"
format = "kf-gins"
rate_hz = 200

[initial]
position_deg_m = [30.0, 114.0, 20.0]
attitude_deg = [0, 0, 90]
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

fn check_full(c: &RunConfig, base: &Path) {
    // [imu]
    assert_eq!(c.imu.path, base.join("data/imu.csv"));
    assert_eq!(c.imu.rate_hz, 100.0);
    assert_eq!(c.imu.sensor_to_body_rpy_deg, [180.0, 0.0, 90.0]);
    assert_eq!(c.imu.time_offset_s, -0.125);
    let ImuFormat::Csv(o) = &c.imu.format else {
        panic!("csv expected: {:?}", c.imu.format)
    };
    assert_eq!(o.skip_lines, 2);
    assert_eq!(o.time_col, 6);
    assert_eq!(o.gyro_cols, [3, 4, 5]);
    assert_eq!(o.accel_cols, [0, 1, 2]);
    assert_eq!(o.time_unit, TimeUnit::Milliseconds);
    assert_eq!(o.time_scale, TimeScale::GpstUnix);
    assert_eq!(o.quantity, ImuQuantity::Increment);
    assert_eq!(o.rate_sampling, RateSampling::IntervalMean);
    assert_eq!(o.gyro_unit, GyroUnit::Deg);
    assert_eq!(o.accel_unit, AccelUnit::G);

    // [gnss]
    let g = c.gnss.as_ref().unwrap();
    assert_eq!(g.path, PathBuf::from("/abs/gnss.pos"));
    assert_eq!(
        g.format,
        GnssFormat::RtklibPos {
            quality: vec![1, 2]
        }
    );
    assert_eq!(g.decimate_s, Some(1.0));
    assert_eq!(g.time_offset_s, 0.01);
    let go = &c.nav.gnss;
    assert_eq!(go.time_snap_s, 0.001);
    assert_close3(&go.lever_arm_b, [0.1, -0.05, -0.2]);
    assert!(!go.use_velocity);
    assert_close3(
        go.position_std_override.as_ref().unwrap(),
        [0.02, 0.03, 0.05],
    );
    assert_close3(go.velocity_std_override.as_ref().unwrap(), [0.1; 3]);
    assert_eq!(go.gate_probability, Some(1e-4));
    assert_eq!(go.outages.windows.len(), 2);
    assert_eq!(
        (go.outages.windows[1].start, go.outages.windows[1].end),
        (300.0, 330.0)
    );
    assert_eq!(go.outages.periodic.len(), 1);
    let p = go.outages.periodic[0];
    assert_eq!(
        (p.length, p.period, p.from, p.until),
        (60.0, 180.0, 456900.0, Some(459500.0))
    );
    assert!(c.relative_outages.is_empty());

    // [time]
    assert_eq!(c.nav.start_time, 456300.5);
    assert_eq!(c.nav.end_time, Some(459000.0));

    // [initial]
    let i = &c.nav.initial;
    assert_close3(
        &i.lla.expect("position"),
        [30.4447873701 * D2R, 114.4718632047 * D2R, 20.899],
    );
    assert_close3(&i.v_n, [1.0, -2.0, 0.5]);
    let navfuse_core::config::AttitudeInit::Given(rpy) = i.attitude else {
        panic!("attitude_deg must give the attitude");
    };
    assert_close3(
        &rpy,
        [0.85421502 * D2R, -2.03480295 * D2R, 185.70235133 * D2R],
    );
    assert_close3(&i.pos_std, [0.005, 0.004, 0.008]);
    assert_close3(&i.vel_std, [0.003, 0.004, 0.004]);
    assert_close3(&i.att_std, [0.003 * D2R, 0.003 * D2R, 0.023 * D2R]);
    let dph = D2R / 3600.0;
    assert_close3(&i.imu_errors.gyro_bias, [dph, 2.0 * dph, 3.0 * dph]);
    assert_close3(&i.imu_errors.accel_bias, [10e-5, 20e-5, 30e-5]);
    assert_close3(&i.imu_errors.gyro_scale, [100e-6; 3]);
    assert_close3(&i.imu_errors.accel_scale, [-100e-6, 0.0, 100e-6]);
    assert_close3(&i.imu_errors_std.gyro_bias, [5.0 * dph; 3]);
    assert_close3(&i.imu_errors_std.accel_bias, [50e-5, 60e-5, 70e-5]);
    assert_close3(&i.imu_errors_std.gyro_scale, [1000e-6; 3]);
    assert_close3(&i.imu_errors_std.accel_scale, [2000e-6; 3]);

    // [imu_noise]
    let n = &c.nav.imu_noise;
    assert_close3(&n.arw, [0.003 * D2R / 60.0; 3]);
    assert_close3(&n.vrw, [0.03 / 60.0, 0.03 / 60.0, 0.04 / 60.0]);
    assert_close3(&n.gyro_bias_std, [0.027 * dph; 3]);
    assert_close3(&n.accel_bias_std, [15e-5; 3]);
    assert_close3(&n.gyro_scale_std, [300e-6; 3]);
    assert_close3(&n.accel_scale_std, [300e-6; 3]);
    assert_eq!(n.corr_time_s, 4.0 * 3600.0);

    // [filter]
    assert_eq!(c.nav.filter.covariance_period_s, 0.1);
    let t = c.nav.filter.time_offset.unwrap();
    assert_eq!((t.initial_s, t.std_s, t.random_walk), (0.02, 0.3, 1e-6));

    // [odometer]
    let o = c.odometer.as_ref().expect("odometer source");
    assert_eq!(o.path, base.join("odo/odometer.txt"));
    assert_eq!(
        o.format,
        OdometerFormat::Pulses {
            meters_per_pulse: 0.00324
        }
    );
    let od = &c.nav.odometer;
    assert!(od.enabled && od.with_nhc);
    assert_eq!(od.std_mps, 0.08);
    assert!(close(od.scale_initial, 500e-6));
    assert!(close(od.scale_std, 2000e-6));
    assert!(close(od.scale_random_walk, (30e-6_f64).powi(2) / 3600.0));
    assert_eq!(od.gate_probability, None);

    // [heading]
    let h = c.heading.as_ref().expect("heading source");
    assert_eq!(h.path, base.join("heading.txt"));
    let hd = &c.nav.heading;
    assert_close3(hd.baseline_b.as_ref().unwrap(), [0.0, 1.5, 0.0]);
    assert!(close(hd.dual_antenna_std_override.unwrap(), 0.25 * D2R));
    assert!(hd.course_over_ground);
    assert_eq!(hd.course_min_speed_mps, 4.0);
    assert!(close(hd.course_std_floor, 2.0 * D2R));
    assert_eq!(hd.gate_probability, Some(1e-3));

    // [vehicle]
    let v = &c.nav.vehicle;
    assert_close3(&v.mounting_rpy, [0.5 * D2R, -D2R, 2.0 * D2R]);
    assert_close3(&v.lever_arm_b, [-1.2, 0.0, 0.8]);
    assert!(close(v.mounting_std, 1.5 * D2R));

    // [nhc]
    let n = &c.nav.nhc;
    assert_eq!(n.mode, NhcMode::DuringOutage);
    assert_eq!(n.std_mps, [0.2, 0.1]);
    assert_eq!((n.rate_hz, n.outage_after_s), (20.0, 2.5));
    assert_eq!(n.gate_probability, Some(1e-3));
    assert_eq!(n.min_speed_mps, 1.0);

    // [zupt]
    let z = &c.nav.zupt;
    assert!(z.enabled);
    assert_eq!((z.window_s, z.accel_std_max, z.rate_hz), (0.5, 0.1, 2.0));
    assert!(close(z.gyro_max, D2R));
    assert_eq!((z.velocity_std_mps, z.angular_rate_std), (0.02, 0.0));

    // [output]
    assert_eq!(c.output.rate_hz, Some(10.0));
    assert!(!c.output.imu_err && !c.output.std && c.output.csv);
    assert!(c.warnings.is_empty());
    assert_eq!(c.kfgins_output_path, None);
}

#[test]
fn every_key_is_read_and_converted() {
    let p = tmp("full.toml", FULL);
    let c = load_toml(&p).unwrap();
    assert_eq!(c.source_path, p);
    check_full(&c, p.parent().unwrap());
    // dispatch by extension
    assert_eq!(load(&p).unwrap(), c);
}

#[test]
fn to_toml_round_trip_keeps_every_key() {
    let p = tmp("full_rt_src.toml", FULL);
    let c = load_toml(&p).unwrap();
    let text = c.to_toml_string();
    let q = tmp("full_rt.toml", &text);
    let d = load_toml(&q).unwrap_or_else(|e| panic!("{e}\n{text}"));
    check_full(&d, p.parent().unwrap());
    assert_eq!(d.imu, c.imu);
    assert_eq!(d.gnss, c.gnss);
    assert_eq!(d.odometer, c.odometer);
    assert_eq!(d.heading, c.heading);
    assert_eq!(d.output, c.output);
    // the vehicle and aiding options come back bit for bit
    assert_eq!(d.nav.vehicle, c.nav.vehicle);
    assert_eq!(d.nav.nhc, c.nav.nhc);
    assert_eq!(d.nav.odometer, c.nav.odometer);
    assert_eq!(d.nav.heading, c.nav.heading);
    assert_eq!(d.nav.zupt, c.nav.zupt);
    // and once more: the text is a fixed point up to rounding
    let e = load_toml(&tmp("full_rt2.toml", &d.to_toml_string())).unwrap();
    check_full(&e, p.parent().unwrap());
}

#[test]
fn defaults() {
    let p = tmp("minimal.toml", MINIMAL);
    let c = load_toml(&p).unwrap();
    assert_eq!(c.imu.format, ImuFormat::KfGins);
    assert_eq!(c.imu.sensor_to_body_rpy_deg, [0.0; 3]);
    assert_eq!(c.imu.time_offset_s, 0.0);
    assert!(c.gnss.is_none());
    assert_eq!(c.nav.start_time, f64::NEG_INFINITY);
    assert_eq!(c.nav.end_time, None);
    let i = &c.nav.initial;
    assert_eq!(i.v_n, nalgebra::Vector3::zeros());
    assert_eq!(i.imu_errors, Default::default());
    // *_std default to the imu_noise values, as in KF-GINS
    assert_eq!(i.imu_errors_std.gyro_bias, c.nav.imu_noise.gyro_bias_std);
    assert_eq!(i.imu_errors_std.accel_bias, c.nav.imu_noise.accel_bias_std);
    assert_eq!(i.imu_errors_std.gyro_scale, c.nav.imu_noise.gyro_scale_std);
    assert_eq!(
        i.imu_errors_std.accel_scale,
        c.nav.imu_noise.accel_scale_std
    );
    assert_eq!(
        c.nav.filter.covariance_period_s,
        navfuse_core::config::DEFAULT_COVARIANCE_PERIOD_S
    );
    assert_eq!(c.nav.filter.time_offset, None);
    assert_eq!(c.output.rate_hz, None);
    assert!(c.output.imu_err && c.output.std && !c.output.csv);
    let g = &c.nav.gnss;
    assert!(g.use_velocity && g.gate_probability.is_none() && g.outages.is_empty());

    // gnss defaults
    let text = format!("{MINIMAL}\n[gnss]\nfile = \"g.pos\"\nformat = \"rtklib-pos\"\n");
    let c = load_toml(&tmp("gnss_defaults.toml", &text)).unwrap();
    let g = c.gnss.unwrap();
    assert_eq!(g.format, GnssFormat::RtklibPos { quality: vec![1] });
    assert_eq!((g.decimate_s, g.time_offset_s), (None, 0.0));
    assert_eq!(c.nav.gnss.lever_arm_b, nalgebra::Vector3::zeros());

    // csv defaults
    let text = MINIMAL.replace(
        "format = \"kf-gins\"",
        "format = \"csv\"\ncsv = { time_col = 0, gyro_cols = [1, 2, 3], accel_cols = [4, 5, 6] }",
    );
    let c = load_toml(&tmp("csv_defaults.toml", &text)).unwrap();
    let ImuFormat::Csv(o) = c.imu.format else {
        panic!()
    };
    assert_eq!(o.skip_lines, 0);
    assert_eq!(o.time_unit, TimeUnit::Seconds);
    assert_eq!(o.time_scale, TimeScale::GpsSecondsOfWeek);
    assert_eq!(o.quantity, ImuQuantity::Rate);
    assert_eq!(o.rate_sampling, RateSampling::Instant);
    assert_eq!(o.gyro_unit, GyroUnit::Rad);
    assert_eq!(o.accel_unit, AccelUnit::Metre);

    // time offset table with defaults only
    let text = format!("{MINIMAL}\n[filter]\ntime_offset = {{}}\n");
    let c = load_toml(&tmp("toff_defaults.toml", &text)).unwrap();
    let t = c.nav.filter.time_offset.unwrap();
    assert_eq!((t.initial_s, t.std_s, t.random_walk), (0.0, 0.5, 0.0));
    // estimate = false: a known offset (and rate), applied but not estimated.
    let text = format!(
        "{MINIMAL}\n[filter]\ntime_offset = {{ estimate = false, initial_s = 0.25, initial_rate_ppm = 300 }}\n"
    );
    let c = load_toml(&tmp("toff_off.toml", &text)).unwrap();
    let t = c.nav.filter.time_offset.unwrap();
    assert_eq!((t.initial_s, t.std_s, t.rate_std), (0.25, 0.0, 0.0));
    assert!((t.initial_rate - 300e-6).abs() < 1e-15);
}

#[test]
fn rtklibexplorer_tag_file() {
    let text = MINIMAL.replace("format = \"kf-gins\"", "format = \"rtklibexplorer\"");
    let text = text.replace("file = \"IMU.txt\"", "file = \"drive/imu_1934.csv\"");
    let p = tmp("rtkx.toml", &text);
    let c = load_toml(&p).unwrap();
    let dir = p.parent().unwrap();
    let ImuFormat::RtklibExplorer(o) = &c.imu.format else {
        panic!()
    };
    assert_eq!(o.tag_path, dir.join("drive/imu_1934.csv.tag"));
    let text = text.replace("rate_hz = 200", "rate_hz = 100\ntag_file = \"other.tag\"");
    let c = load_toml(&tmp("rtkx2.toml", &text)).unwrap();
    let ImuFormat::RtklibExplorer(o) = &c.imu.format else {
        panic!()
    };
    assert_eq!(o.tag_path, dir.join("other.tag"));
    let rt = load_toml(&tmp("rtkx_rt.toml", &c.to_toml_string())).unwrap();
    assert_eq!(rt.imu, c.imu);
}

#[test]
fn relative_outages() {
    let gnss = "\n[gnss]\nfile = \"g.txt\"\nformat = \"kf-gins\"\n\
                outage_every = { length_s = 60, period_s = 180, from_start_s = 600, until_start_s = 3200 }\n";
    // no [time] start: kept until the CLI knows the run start
    let mut c = load_toml(&tmp("rel.toml", &format!("{MINIMAL}{gnss}"))).unwrap();
    assert!(c.nav.gnss.outages.periodic.is_empty());
    assert_eq!(c.relative_outages.len(), 1);
    let rt = load_toml(&tmp("rel_rt.toml", &c.to_toml_string())).unwrap();
    assert_eq!(rt.relative_outages, c.relative_outages);
    c.resolve_relative_outages(456300.0);
    c.resolve_relative_outages(1.0); // second call: no-op
    assert!(c.relative_outages.is_empty());
    let p = c.nav.gnss.outages.periodic.clone();
    assert_eq!(p.len(), 1);
    assert_eq!(
        (p[0].from, p[0].until, p[0].length),
        (456900.0, Some(459500.0), 60.0)
    );

    // with [time] start: resolved at load
    let text = format!("{MINIMAL}{gnss}\n[time]\nstart = 456300\n");
    let c = load_toml(&tmp("rel_start.toml", &text)).unwrap();
    assert!(c.relative_outages.is_empty());
    assert_eq!(c.nav.gnss.outages.periodic[0].from, 456900.0);
    assert_eq!(c.nav.gnss.outages.periodic[0].until, Some(459500.0));

    // array of tables
    let text = format!(
        "{MINIMAL}\n[gnss]\nfile = \"g.txt\"\nformat = \"kf-gins\"\n\
         [[gnss.outage_every]]\nlength_s = 10\nperiod_s = 100\nfrom = 5\n\
         [[gnss.outage_every]]\nlength_s = 20\nperiod_s = 200\nfrom = 7\n"
    );
    let c = load_toml(&tmp("every_many.toml", &text)).unwrap();
    assert_eq!(c.nav.gnss.outages.periodic.len(), 2);
    let rt = load_toml(&tmp("every_many_rt.toml", &c.to_toml_string())).unwrap();
    assert_eq!(rt.nav.gnss.outages, c.nav.gnss.outages);
}

// ----------------------------------------------------------------------------- errors

fn err(name: &str, text: &str) -> ConfigError {
    let p = tmp(name, text);
    let e = load_toml(&p).expect_err("expected an error");
    let shown = e.to_string();
    assert!(shown.starts_with(&p.display().to_string()), "{shown}");
    e
}

fn line_containing(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn unknown_key_names_key_and_line() {
    let text = MINIMAL.replace("corr_time_h = 1", "corr_time_h = 1\ncorrtime = 4");
    let e = err("unknown.toml", &text);
    assert_eq!(e.key.as_deref(), Some("imu_noise.corrtime"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "corrtime =")), "{e}");
    assert!(
        e.message.contains("unknown field") && e.message.contains("corr_time_h"),
        "{e}"
    );
    let shown = e.to_string();
    assert!(
        shown.contains(&format!(":{}: key 'imu_noise.corrtime': ", e.line.unwrap())),
        "{shown}"
    );

    // unknown section
    let text = format!("{MINIMAL}\n[wheel]\nscale = 1\n");
    let e = err("unknown_section.toml", &text);
    assert_eq!(e.key.as_deref(), Some("wheel"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "[wheel]")), "{e}");

    // unknown key in a new section
    let text = format!("{MINIMAL}\n[odometer]\nfile = \"o.txt\"\nformat = \"speed\"\nscale = 1\n");
    let e = err("unknown_odo_key.toml", &text);
    assert_eq!(e.key.as_deref(), Some("odometer.scale"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "scale = 1")), "{e}");
    assert!(e.message.contains("scale_ppm"), "{e}");

    // unknown key in an inline table
    let text = format!("{MINIMAL}\n[filter]\ntime_offset = {{ estimate = true, sigma = 1 }}\n");
    let e = err("unknown_inline.toml", &text);
    assert_eq!(e.key.as_deref(), Some("filter.time_offset.sigma"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "sigma")), "{e}");
}

#[test]
fn wrong_type_and_length() {
    // string instead of number
    let text = MINIMAL.replace("rate_hz = 200", "rate_hz = \"200\"");
    let e = err("type.toml", &text);
    assert_eq!(e.key.as_deref(), Some("imu.rate_hz"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "rate_hz")));
    assert!(e.message.contains("expected"), "{e}");

    // 2-vector
    let text = MINIMAL.replace("attitude_deg = [0, 0, 90]", "attitude_deg = [0, 90]");
    let e = err("len.toml", &text);
    assert_eq!(e.key.as_deref(), Some("initial.attitude_deg"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "attitude_deg")));
    assert!(
        e.message.contains("3 numbers") && e.message.contains("got 2"),
        "{e}"
    );

    // scalar-or-vector with 4 elements
    let text = MINIMAL.replace(
        "arw_deg_sqrth = 0.2",
        "arw_deg_sqrth = [0.2, 0.2, 0.2, 0.2]",
    );
    let e = err("len4.toml", &text);
    assert_eq!(e.key.as_deref(), Some("imu_noise.arw_deg_sqrth"), "{e}");
    assert_eq!(e.line, Some(line_containing(&text, "arw_deg_sqrth")));

    // string in a vector
    let text = MINIMAL.replace("attitude_deg = [0, 0, 90]", "attitude_deg = [0, \"x\", 90]");
    let e = err("elem.toml", &text);
    assert_eq!(
        e.key
            .as_deref()
            .map(|k| k.starts_with("initial.attitude_deg")),
        Some(true),
        "{e}"
    );
    assert_eq!(e.line, Some(line_containing(&text, "attitude_deg")));

    // bad enum value
    let text = MINIMAL.replace("format = \"kf-gins\"", "format = \"kfgins-txt\"");
    let e = err("enum.toml", &text);
    assert_eq!(e.key.as_deref(), Some("imu.format"), "{e}");
    assert!(
        e.message.contains("kf-gins") && e.message.contains("rtklibexplorer"),
        "{e}"
    );

    // a noise key left out takes its documented default and is listed as defaulted
    // (docs/CONFIG.md "[imu_noise]"; `navfuse tune` estimates it)
    let text = MINIMAL.replace("corr_time_h = 1\n", "");
    let c = load_toml(&tmp("missing.toml", &text)).unwrap();
    assert_eq!(c.defaulted, vec!["imu_noise.corr_time_h"]);
    assert_eq!(c.nav.imu_noise.corr_time_s, 3600.0);

    // missing required key
    let text = MINIMAL.replace("file = \"IMU.txt\"\n", "");
    let e = err("missing_file.toml", &text);
    assert_eq!(e.key.as_deref(), Some("imu.file"), "{e}");

    // missing section
    let text = MINIMAL.replace("[imu_noise]", "[imu_noise_]");
    let e = err("missing_section.toml", &text);
    assert!(
        e.key.as_deref().is_some_and(|k| k.starts_with("imu_noise")),
        "{e}"
    );

    // a TOML syntax error still gives a line
    let text = MINIMAL.replace("rate_hz = 200", "rate_hz = = 200");
    let e = err("syntax.toml", &text);
    assert_eq!(e.line, Some(line_containing(&text, "rate_hz")), "{e}");
}

#[test]
fn range_errors_name_key_and_expectation() {
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            "position_std_m = 1.0",
            "position_std_m = 0.0",
            "initial.position_std_m",
            "> 0",
        ),
        (
            "gyro_bias_std_degph = 20",
            "gyro_bias_std_degph = [20, 0, 20]",
            "imu_noise.gyro_bias_std_degph",
            "> 0",
        ),
        (
            "corr_time_h = 1",
            "corr_time_h = 0",
            "imu_noise.corr_time_h",
            "> 0",
        ),
        ("rate_hz = 200", "rate_hz = -200", "imu.rate_hz", "> 0"),
        ("rate_hz = 200", "rate_hz = nan", "imu.rate_hz", "> 0"),
        (
            "[30.0, 114.0, 20.0]",
            "[91.0, 114.0, 20.0]",
            "initial.position_deg_m",
            "[-90, 90]",
        ),
        (
            "attitude_deg = [0, 0, 90]",
            "attitude_deg = [0, 95, 90]",
            "initial.attitude_deg",
            "pitch",
        ),
        (
            "attitude_deg = [0, 0, 90]",
            "attitude_deg = [0, inf, 90]",
            "initial.attitude_deg",
            "finite",
        ),
    ];
    for (i, (from, to, key, expect)) in cases.iter().enumerate() {
        let text = MINIMAL.replace(from, to);
        assert_ne!(text, MINIMAL);
        let e = err(&format!("range{i}.toml"), &text);
        assert_eq!(e.key.as_deref(), Some(*key), "{e}");
        assert!(e.message.contains(expect), "{e}");
        let needle = to.split('=').next().unwrap().trim();
        assert_eq!(e.line, Some(line_containing(&text, needle)), "{e}");
    }

    let with = |extra: &str| format!("{MINIMAL}\n{extra}\n");
    let cases: &[(&str, &str, &str)] = &[
        ("[output]\nrate_hz = 0", "output.rate_hz", "> 0"),
        ("[time]\nstart = 10\nend = 5", "time.end", "after"),
        ("[filter]\ncovariance_period_s = -1", "filter.covariance_period_s", ">= 0"),
        ("[filter]\ntime_offset = { std_s = 0 }", "filter.time_offset.std_s", "> 0"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\ngate_probability = 0.7", "gnss.gate_probability", "[1e-15, 0.5)"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\nquality = [1]", "gnss.quality", "rtklib-pos"),
        ("[gnss]\nfile = \"g\"\nformat = \"rtklib-pos\"\nquality = []", "gnss.quality", "non-empty"),
        ("[gnss]\nfile = \"g\"\nformat = \"rtklib-pos\"\nquality = [9]", "gnss.quality", "1..=6"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\ndecimate_s = 0", "gnss.decimate_s", "> 0"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\ntime_snap_s = -0.001", "gnss.time_snap_s", "[0, 0.05]"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\ntime_snap_s = nan", "gnss.time_snap_s", "[0, 0.05]"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\nposition_std_m = [1, 1]", "gnss.position_std_m", "3 numbers"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\noutages = [[1, 2], [5, 3]]", "gnss.outages[1]", "end > start"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\noutages = [[1, 2, 3]]", "gnss.outages[0]", "[start, end]"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\noutage_every = { length_s = 60, period_s = 50, from = 0 }", "gnss.outage_every.period_s", "> length_s"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\noutage_every = { length_s = 60, period_s = 180 }", "gnss.outage_every", "from_start_s"),
        ("[gnss]\nfile = \"g\"\nformat = \"kf-gins\"\noutage_every = { length_s = 60, period_s = 180, from = 1, from_start_s = 1 }", "gnss.outage_every.from_start_s", "not both"),
        ("[gnss]\nfile = \"\"\nformat = \"kf-gins\"", "gnss.file", "file path"),
    ];
    for (i, (extra, key, expect)) in cases.iter().enumerate() {
        let text = with(extra);
        let e = err(&format!("range_extra{i}.toml"), &text);
        assert_eq!(e.key.as_deref(), Some(*key), "{e}");
        assert!(e.message.contains(expect), "{e}");
        assert!(e.line.is_some(), "{e}");
    }

    // csv table checks
    let csv = |t: &str| MINIMAL.replace("format = \"kf-gins\"", &format!("format = \"csv\"\n{t}"));
    let e = err("csv_missing.toml", &csv(""));
    assert_eq!(e.key.as_deref(), Some("imu.csv"), "{e}");
    let e = err(
        "csv_dup.toml",
        &csv("csv = { time_col = 0, gyro_cols = [1, 2, 3], accel_cols = [3, 4, 5] }"),
    );
    assert_eq!(e.key.as_deref(), Some("imu.csv.accel_cols"), "{e}");
    assert!(e.message.contains("distinct"), "{e}");
    let e = err(
        "csv_len.toml",
        &csv("csv = { time_col = 0, gyro_cols = [1, 2], accel_cols = [3, 4, 5] }"),
    );
    assert_eq!(e.key.as_deref(), Some("imu.csv.gyro_cols"), "{e}");
    let e = err(
        "csv_neg.toml",
        &csv("csv = { time_col = -1, gyro_cols = [1, 2, 3], accel_cols = [4, 5, 6] }"),
    );
    assert_eq!(e.key.as_deref(), Some("imu.csv.time_col"), "{e}");
    let e = err(
        "csv_unit.toml",
        &csv("csv = { time_col = 0, gyro_cols = [1, 2, 3], accel_cols = [4, 5, 6], time_unit = \"min\" }"),
    );
    assert_eq!(e.key.as_deref(), Some("imu.csv.time_unit"), "{e}");
    let e = err(
        "tag_wrong_format.toml",
        &MINIMAL.replace("rate_hz = 200", "rate_hz = 200\ntag_file = \"x.tag\""),
    );
    assert_eq!(e.key.as_deref(), Some("imu.tag_file"), "{e}");
}

#[test]
fn missing_file_and_bad_extension() {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join("config_toml/does-not-exist.toml");
    let e = load_toml(&p).unwrap_err();
    assert_eq!(e.path, p);
    assert_eq!((e.line, e.key.as_deref()), (None, None));
    assert!(e.message.contains("cannot read"), "{e}");
    let e = load(&p).unwrap_err();
    assert!(e.message.contains("cannot read"), "{e}");
    let e = load(Path::new("run.json")).unwrap_err();
    assert!(e.message.contains(".toml"), "{e}");
}

#[test]
fn relative_paths_resolve_against_the_config_directory() {
    let c = parse_toml_str(MINIMAL, Path::new("/some/dir/run.toml")).unwrap();
    assert_eq!(c.imu.path, PathBuf::from("/some/dir/IMU.txt"));
    let c = parse_toml_str(MINIMAL, Path::new("run.toml")).unwrap();
    assert_eq!(c.imu.path, PathBuf::from("IMU.txt"));
    let text = MINIMAL.replace("file = \"IMU.txt\"", "file = \"/data/IMU.txt\"");
    let c = parse_toml_str(&text, Path::new("/some/dir/run.toml")).unwrap();
    assert_eq!(c.imu.path, PathBuf::from("/data/IMU.txt"));
}

#[test]
fn never_panics_on_garbage() {
    let inputs = [
        "",
        "imu = 3",
        "[imu]\nfile = 3",
        "[[imu]]\nfile = \"x\"",
        "[initial]\nposition_deg_m = [[1], 2, 3]",
        "\u{0}\u{1}[",
        "[imu_noise]\narw_deg_sqrth = {}",
        "[gnss]\noutage_every = 5",
        "[gnss]\noutages = [1, 2]",
    ];
    for (i, t) in inputs.iter().enumerate() {
        let text = format!("{MINIMAL}\n{t}");
        let _ = parse_toml_str(&text, Path::new("x.toml"));
        let _ = parse_toml_str(t, Path::new("x.toml"));
        let _ = i;
    }
}

#[test]
fn converts_into_input_error() {
    let e = err(
        "into.toml",
        &MINIMAL.replace("corr_time_h = 1", "corr_time_h = -1"),
    );
    let shown = e.to_string();
    let i: navfuse_io::InputError = e.clone().into();
    assert_eq!((i.line, i.field.as_deref()), (e.line, e.key.as_deref()));
    assert_eq!(i.to_string(), shown.replace("key '", "field '"));
}

fn load_extra(extra: &str) -> Result<RunConfig, String> {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join("run.toml");
    parse_toml_str(&format!("{MINIMAL}{extra}"), &p).map_err(|e| e.to_string())
}

/// MINIMAL plus `extra`: load, write back, load again: the same configuration.
fn round_trip_extra(extra: &str) -> RunConfig {
    let c = load_extra(extra).unwrap();
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join("run.toml");
    let again = parse_toml_str(&c.to_toml_string(), &p).unwrap();
    assert_eq!(again.gnss, c.gnss);
    assert_eq!(again.heading, c.heading);
    c
}

#[test]
fn config_keys_nmea_csv_and_heading() {
    let c = round_trip_extra(
        "[gnss]\nfile = \"r.nmea\"\nformat = \"nmea\"\ndate = \"2025-07-08\"\nposition_std_m = [1, 1, 2]\n\
         [heading]\nfile = \"r.nmea\"\nformat = \"nmea\"\nbaseline_m = [1, 0, 0]\n",
    );
    let g = c.gnss.unwrap();
    assert_eq!(
        g.format,
        GnssFormat::Nmea(navfuse_io::nmea::NmeaOptions {
            date: Some((2025, 7, 8)),
            position_std_m: Some([1.0, 1.0, 2.0]),
        })
    );
    // The NMEA reader's fallback, not an override of GST.
    assert_eq!(c.nav.gnss.position_std_override, None);
    assert!(c.heading.unwrap().nmea.is_some());

    let c = round_trip_extra(
        "[gnss]\nfile = \"f.csv\"\nformat = \"csv\"\nposition_std_m = 2.0\n\
         [gnss.csv]\ntime_col = 1\nweek_col = 0\necef_cols = [2, 3, 4]\ndelimiter = \";\"\nskip_lines = 1\n",
    );
    let GnssFormat::Csv(o) = c.gnss.unwrap().format else {
        panic!()
    };
    assert_eq!(
        o.position,
        navfuse_io::gnss_csv::CsvPosition::Ecef([2, 3, 4])
    );
    assert_eq!(
        (o.week_col, o.delimiter, o.skip_lines),
        (Some(0), Some(b';'), Some(1))
    );

    for (extra, key) in [
        ("[gnss]\nfile = \"f.csv\"\nformat = \"csv\"\n", "gnss.csv"),
        (
            "[gnss]\nfile = \"f.csv\"\nformat = \"csv\"\n[gnss.csv]\ntime_col = 0\nlla_cols = [1, 2, 3]\n",
            "gnss.csv.pos_std_cols",
        ),
        (
            "[gnss]\nfile = \"f.csv\"\nformat = \"csv\"\nposition_std_m = 1\n[gnss.csv]\ntime_col = 1\nlla_cols = [1, 2, 3]\n",
            "gnss.csv",
        ),
        ("[gnss]\nfile = \"f.txt\"\nformat = \"kf-gins\"\ndate = \"2025-01-01\"\n", "gnss.date"),
        ("[gnss]\nfile = \"f.nmea\"\nformat = \"nmea\"\ndate = \"2025-02-30\"\n", "gnss.date"),
    ] {
        let e = load_extra(extra).unwrap_err();
        assert!(e.contains(key), "{key}: {e}");
    }
}

// `[gnss] format = "ubx"`: the raw and pvt sources, their keys, errors, and the
// round trip through the config writer.

fn parse_ubx(gnss: &str) -> Result<navfuse_io::config::RunConfig, String> {
    parse_toml_str(
        &format!("[gnss]\n{gnss}\n{MINIMAL}"),
        Path::new("/d/run.toml"),
    )
    .map_err(|e| e.to_string())
}

fn round_trip_gnss(c: &navfuse_io::config::RunConfig) {
    let text = c.to_toml_string();
    let back = parse_toml_str(&text, Path::new("/d/run.toml")).unwrap();
    assert_eq!(back.gnss, c.gnss, "{text}");
    assert_eq!(back.nav.tight, c.nav.tight);
}

#[test]
fn raw_source_takes_the_rinex_keys() {
    let c = parse_ubx(
        "file = \"g.ubx\"\nformat = \"ubx\"\ncoupling = \"loose\"\nelevation_mask_deg = 15",
    )
    .unwrap();
    let g = c.gnss.as_ref().unwrap();
    let GnssFormat::Ubx(u @ UbxGnss::Raw(r)) = &g.format else {
        panic!("{:?}", g.format)
    };
    assert_eq!(r.coupling, Coupling::Loose);
    assert_eq!(r.elevation_mask_deg, 15.0);
    assert_eq!(u.extra_nav(), None);
    assert!(!c.nav.tight.enabled);
    round_trip_gnss(&c);
    // Tight by default, with an extra navigation file.
    let c = parse_ubx("file = \"g.ubx\"\nformat = \"ubx\"\nubx_source = \"raw\"\nnav = \"b.nav\"")
        .unwrap();
    let GnssFormat::Ubx(u) = &c.gnss.as_ref().unwrap().format else {
        panic!()
    };
    assert_eq!(
        u.extra_nav(),
        Some(std::path::PathBuf::from("/d/b.nav").as_path())
    );
    assert!(c.nav.tight.enabled);
    round_trip_gnss(&c);
}

#[test]
fn pvt_source_is_fixes() {
    let c = parse_ubx("file = \"g.ubx\"\nformat = \"ubx\"\nubx_source = \"pvt\"\ndecimate_s = 1.0")
        .unwrap();
    let g = c.gnss.as_ref().unwrap();
    assert_eq!(g.format, GnssFormat::Ubx(UbxGnss::Pvt));
    assert!(!c.nav.tight.enabled);
    round_trip_gnss(&c);
}

#[test]
fn ubx_key_errors() {
    let e =
        parse_ubx("file = \"g.ubx\"\nformat = \"ubx\"\nubx_source = \"pvt\"\ncoupling = \"tight\"")
            .unwrap_err();
    assert!(
        e.contains("gnss.coupling") && e.contains("ubx_source"),
        "{e}"
    );
    let e =
        parse_ubx("file = \"g.pos\"\nformat = \"rtklib-pos\"\nubx_source = \"pvt\"").unwrap_err();
    assert!(
        e.contains("gnss.ubx_source") && e.contains("applies only to gnss.format = \"ubx\""),
        "{e}"
    );
    let e = parse_ubx("file = \"g.ubx\"\nformat = \"ubx\"\nubx_source = \"nmea\"").unwrap_err();
    assert!(e.contains("ubx_source") || e.contains("nmea"), "{e}");
}

#[test]
fn input_sections_alone_read_as_in_a_run_configuration() {
    let p = Path::new("/data/<reader keys>");
    let (imu, gnss) = navfuse_io::config::parse_input_sections(
        "[imu]\nfile = \"IMU.txt\"\nformat = \"kf-gins\"\nrate_hz = 200\n\n[gnss]\nfile = \"GNSS.txt\"\nformat = \"kf-gins\"\n",
        p,
    )
    .unwrap();
    let imu = imu.unwrap();
    assert_eq!(imu.path, Path::new("/data/IMU.txt"));
    let (g, opts) = gnss.unwrap();
    assert_eq!(g.path, Path::new("/data/GNSS.txt"));
    assert!(!opts.systems.is_empty());
    // A run configuration's other sections are not input sections.
    let e = navfuse_io::config::parse_input_sections("[initial]\nvelocity_mps = [0, 0, 0]\n", p)
        .unwrap_err();
    assert!(e.to_string().contains("initial"), "{e}");
    let e = navfuse_io::config::parse_input_sections("[imu]\nfile = \"a\"\nfromat = 1\n", p)
        .unwrap_err();
    assert_eq!(
        (e.line, e.key.as_deref()),
        (Some(3), Some("imu.fromat")),
        "{e}"
    );
}
