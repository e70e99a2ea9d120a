//! The example configurations in examples/ load; checks that need the data files are
//! skipped when /work/shared is absent.

use std::path::{Path, PathBuf};

use navfuse_io::config::{load, load_kfgins_yaml, RunConfig};
use navfuse_io::input::{GnssFormat, ImuFormat};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn shared_data() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if p.is_dir() {
        Some(p)
    } else {
        println!(
            "skipped data checks: {} not found (shared data absent)",
            p.display()
        );
        None
    }
}

fn load_example(name: &str) -> RunConfig {
    let p = examples().join(name);
    load(&p).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_example_loads() {
    let mut n = 0;
    for entry in std::fs::read_dir(examples()).unwrap() {
        let p = entry.unwrap().path();
        if matches!(
            p.extension().and_then(|e| e.to_str()),
            Some("toml" | "yaml" | "yml")
        ) {
            let c = load(&p).unwrap_or_else(|e| panic!("{e}"));
            assert!(c.warnings.is_empty(), "{}: {:?}", p.display(), c.warnings);
            n += 1;
        }
    }
    assert!(n >= 3);
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

#[track_caller]
fn assert_nav_close(a: &navfuse_core::config::NavConfig, b: &navfuse_core::config::NavConfig) {
    // same values up to the last bit or two of the unit conversions
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(y.abs()).max(1e-300);
    let v = |x: &nalgebra::Vector3<f64>, y: &nalgebra::Vector3<f64>, what: &str| {
        for i in 0..3 {
            assert!(close(x[i], y[i]), "{what}[{i}]: {} != {}", x[i], y[i]);
        }
    };
    let (n, m) = (&a.imu_noise, &b.imu_noise);
    v(&n.arw, &m.arw, "arw");
    v(&n.vrw, &m.vrw, "vrw");
    v(&n.gyro_bias_std, &m.gyro_bias_std, "gbstd");
    v(&n.accel_bias_std, &m.accel_bias_std, "abstd");
    v(&n.gyro_scale_std, &m.gyro_scale_std, "gsstd");
    v(&n.accel_scale_std, &m.accel_scale_std, "asstd");
    assert_eq!(n.corr_time_s, m.corr_time_s);
    let (i, j) = (&a.initial, &b.initial);
    assert_eq!(i.lla.is_some(), j.lla.is_some(), "lla given in one only");
    if let (Some(x), Some(y)) = (&i.lla, &j.lla) {
        v(x, y, "lla");
    }
    v(&i.v_n, &j.v_n, "v_n");
    assert_eq!(i.attitude, j.attitude, "attitude");
    v(&i.pos_std, &j.pos_std, "pos_std");
    v(&i.vel_std, &j.vel_std, "vel_std");
    v(&i.att_std, &j.att_std, "att_std");
    assert_eq!(i.imu_errors, j.imu_errors);
    assert_eq!(i.imu_errors_std, j.imu_errors_std);
    v(&a.gnss.lever_arm_b, &b.gnss.lever_arm_b, "lever");
    assert_eq!(a.gnss.use_velocity, b.gnss.use_velocity);
    assert_eq!(a.gnss.gate_probability, b.gnss.gate_probability);
    let fe = |g: &navfuse_core::config::GnssOptions| {
        let f = g.fix_error;
        (f.correlated(), f.scale_window, f.robust_probability)
    };
    assert_eq!(fe(&a.gnss), fe(&b.gnss));
    assert_eq!(a.gnss.position_std_override, b.gnss.position_std_override);
    assert_eq!(a.filter, b.filter);
    assert_eq!((a.start_time, a.end_time), (b.start_time, b.end_time));
}

#[test]
fn kfgins_synthetic_matches_the_yaml() {
    let t = load_example("kfgins-synthetic.toml");
    assert_eq!(t.imu.format, ImuFormat::KfGins);
    assert_eq!(t.nav.start_time, 456300.0);
    assert!(t.nav.gnss.outages.is_empty());
    let Some(data) = shared_data() else { return };
    let y = load_kfgins_yaml(&data.join("kf-gins/synthetic/kf-gins.yaml")).unwrap();
    assert_nav_close(&t.nav, &y.nav);
    assert_eq!(t.output, y.output);
    assert!(
        same_file(&t.imu.path, &y.imu.path),
        "{:?} vs {:?}",
        t.imu.path,
        y.imu.path
    );
    let (tg, yg) = (t.gnss.as_ref().unwrap(), y.gnss.as_ref().unwrap());
    assert!(
        same_file(&tg.path, &yg.path),
        "{:?} vs {:?}",
        tg.path,
        yg.path
    );
    assert_eq!(
        (&tg.format, tg.decimate_s, tg.time_offset_s),
        (&yg.format, yg.decimate_s, yg.time_offset_s)
    );
    assert_eq!(t.imu.rate_hz, y.imu.rate_hz);
}

#[test]
fn kfgins_synthetic_outages_is_the_paper_protocol() {
    let base = load_example("kfgins-synthetic.toml");
    let c = load_example("kfgins-synthetic-outages.toml");
    let o = &c.nav.gnss.outages;
    assert_eq!(o.periodic.len(), 1);
    let w = o.windows_in(456300.0, 459662.0);
    assert_eq!(w.len(), 15);
    assert_eq!((w[0].start, w[0].end), (456900.0, 456960.0));
    assert_eq!(w[14].start, 459420.0);
    // otherwise the same run
    let mut c2 = c.clone();
    c2.nav.gnss.outages = Default::default();
    assert_eq!(c2.nav, base.nav);
    assert_eq!(
        (c2.imu, c2.gnss, c2.output),
        (base.imu, base.gnss, base.output)
    );
}

#[test]
fn drive_0708() {
    let c = load_example("drive_0708.toml");
    let ImuFormat::RtklibExplorer(o) = &c.imu.format else {
        panic!("{:?}", c.imu.format)
    };
    assert!(o.tag_path.ends_with("drive_0708/imu_1934.csv.tag"));
    assert_eq!(c.imu.rate_hz, 100.0);
    assert_eq!(c.imu.sensor_to_body_rpy_deg, [180.0, 0.0, 180.0]);
    let g = c.gnss.as_ref().unwrap();
    assert_eq!(g.format, GnssFormat::RtklibPos { quality: vec![1] });
    assert_eq!(g.decimate_s, Some(1.0));
    assert_eq!(
        c.nav.gnss.lever_arm_b,
        nalgebra::Vector3::new(0.0, -0.05, 0.0)
    );
    assert_eq!(c.nav.start_time, f64::NEG_INFINITY);
    let t = c.nav.filter.time_offset.unwrap();
    assert_eq!((t.initial_s, t.std_s), (0.0, 0.5));
    assert!(t.rate_std > 0.0, "the drive estimates the offset rate");
    // Effective noise of the roof-mounted MEMS (vibration): 1 deg/sqrt(h), 0.3 m/s/sqrt(h).
    let n = &c.nav.imu_noise;
    assert!(
        (n.arw.x - 1f64.to_radians() / 60.0).abs() < 1e-12,
        "ARW {}",
        n.arw.x
    );
    assert!((n.vrw.x - 0.3 / 60.0).abs() < 1e-12, "VRW {}", n.vrw.x);
    assert_eq!(n.corr_time_s, 3600.0);

    let Some(_) = shared_data() else { return };
    assert!(c.imu.path.is_file(), "{}", c.imu.path.display());
    assert!(o.tag_path.is_file(), "{}", o.tag_path.display());
    assert!(g.path.is_file(), "{}", g.path.display());
    // initial position = first Q=1 line of the .pos file
    let text = std::fs::read_to_string(&g.path).unwrap();
    let first = text
        .lines()
        .filter(|l| !l.starts_with('%'))
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .find(|f| f.len() > 5 && f[5].parse::<f64>().ok() == Some(1.0))
        .unwrap();
    let lla: Vec<f64> = first[2..5].iter().map(|x| x.parse().unwrap()).collect();
    // The drive example starts from the first GNSS fix (no position in the file)
    // and aligns in motion; the first Q=1 fix is where it starts.
    assert!(c.nav.initial.lla.is_none());
    assert!(matches!(
        c.nav.initial.attitude,
        navfuse_core::config::AttitudeInit::LevelAndGnssCourse { .. }
    ));
    assert!((lla[0] - 40.0966268).abs() < 1e-6 && (lla[1] + 105.1474483).abs() < 1e-6);
}

#[test]
fn kfgins_example_files_exist_when_data_present() {
    let Some(_) = shared_data() else { return };
    for name in ["kfgins-synthetic.toml", "kfgins-synthetic-outages.toml"] {
        let c = load_example(name);
        assert!(c.imu.path.is_file(), "{}", c.imu.path.display());
        assert!(c.gnss.unwrap().path.is_file());
    }
}
