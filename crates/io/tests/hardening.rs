//! The hardening rules (issue "Trustworthy on data nobody here tuned"): values checked
//! after conversion to SI, a cut last line dropped with a warning, IMU gaps bridged,
//! line length bounded, DGPS times, config round trips of every example.

use navfuse_io::config::{load, parse_toml_str, RunConfig, TomlStyle};
use navfuse_io::gnss::read_gnss;
use navfuse_io::heading::read_heading;
use navfuse_io::imu::open_imu;
use navfuse_io::input::*;
use std::path::{Path, PathBuf};

fn write(name: &str, data: &[u8]) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse-hardening-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, data).unwrap();
    p
}

fn kf_imu(p: &Path, gap_policy: GapPolicy) -> ImuSource {
    ImuSource {
        path: p.to_path_buf(),
        format: ImuFormat::KfGins,
        rate_hz: 100.0,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy,
    }
}

fn gnss(p: &Path) -> GnssSource {
    GnssSource {
        path: p.to_path_buf(),
        format: GnssFormat::KfGins,
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    }
}

#[test]
fn tiny_and_huge_stds_rejected_after_conversion() {
    for (v, name) in [("1e-300", "a"), ("1e300", "b"), ("5e-324", "c")] {
        let p = write(
            &format!("std-{name}.txt"),
            format!("1 30 114 20 {v} 0.1 0.1\n").as_bytes(),
        );
        let e = read_gnss(&gnss(&p)).unwrap_err().to_string();
        assert!(e.contains(":1: field 'std_n': std "), "{e}");
        assert!(
            e.contains("out of range: expected 1e-150 to 1e150 in SI"),
            "{e}"
        );
    }
    // 1e-149 deg is 1.7e-151 rad: fine in degrees, not in SI.
    let p = write("heading.txt", b"1 10 1e-147\n2 10 1e-149\n");
    let e = read_heading(&p).unwrap_err().to_string();
    assert!(e.contains(":2: field 'std': std 1e-149 (1.7453"), "{e}");
}

#[test]
fn accelerations_overflowing_after_scaling_rejected() {
    let o = CsvImuOptions {
        rate_sampling: RateSampling::IntervalMean,
        gyro_unit: GyroUnit::Deg,
        accel_unit: AccelUnit::G,
        ..Default::default()
    };
    let p = write(
        "g.csv",
        b"1.00,0,0,0,0,0,1\n1.01,0,0,0,1e308,0,1\n1.02,0,0,0,0,0,1\n",
    );
    let mut s = kf_imu(&p, GapPolicy::default());
    s.format = ImuFormat::Csv(o);
    let r: Vec<_> = open_imu(&s).unwrap().collect();
    let e = r.last().unwrap().as_ref().unwrap_err().to_string();
    assert!(e.contains(":2: field 'accel_x': 1e308 overflows"), "{e}");
    assert!(
        e.contains("overflows to inf after conversion to SI units"),
        "{e}"
    );
}

#[test]
fn cut_last_line_is_a_warning_mid_file_damage_an_error() {
    let good = "1 30 114 20 0.1 0.1 0.2\n2 30 114 20 0.1 0.1 0.2\n";
    let p = write("cut.txt", format!("{good}3 30 114 2").as_bytes());
    let d = read_gnss(&gnss(&p)).unwrap();
    assert_eq!(d.fixes.len(), 2);
    assert_eq!(d.warnings.len(), 1);
    assert!(
        d.warnings[0].contains(
            "cut.txt:3: damaged last line dropped (file cut mid-write?): expected 7 or 13 columns"
        ),
        "{:?}",
        d.warnings
    );
    // The same line in the middle, or a complete last line, is an error.
    let p = write("mid.txt", format!("3 30 114 2\n{good}").as_bytes());
    assert!(read_gnss(&gnss(&p)).is_err());
    let p = write("end.txt", format!("{good}3 30 114 2\n").as_bytes());
    assert!(read_gnss(&gnss(&p)).is_err());

    // IMU: the cut sample is dropped and reported.
    let p = write(
        "imu_cut.txt",
        b"1.00 0 0 0 0 0 0.1\n1.01 0 0 0 0 0 0.1\n1.02 0 0 0 0",
    );
    let mut r = open_imu(&kf_imu(&p, GapPolicy::default())).unwrap();
    let read: Vec<_> = r.by_ref().collect::<Result<_, _>>().unwrap();
    assert_eq!(read.len(), 2);
    let w = &r.report().warnings;
    assert!(
        w.len() == 1 && w[0].contains("imu_cut.txt:3: damaged last line"),
        "{w:?}"
    );
    assert!(r.report().to_string().contains("warning: "));
}

#[test]
fn imu_gap_bridged_over_its_real_length() {
    // 100 Hz increments with a 30 s gap before t = 31.01.
    let p = write(
        "gap.txt",
        b"1.00 0.001 0 0 0.05 0 0\n1.01 0.001 0 0 0.05 0 0\n31.01 0.001 0 0 0.05 0 0\n",
    );
    let out: Vec<_> = open_imu(&kf_imu(&p, GapPolicy::default()))
        .unwrap()
        .map(|s| s.unwrap())
        .collect();
    let s = &out[2];
    assert!((s.dt - 30.0).abs() < 1e-9, "{}", s.dt);
    // The increment (one nominal interval's worth) held over the 30 s: x 3000.
    assert!((s.dtheta.x - 3.0).abs() < 1e-9 && (s.dvel.x - 150.0).abs() < 1e-6);
    let mut r = open_imu(&kf_imu(&p, GapPolicy::default())).unwrap();
    r.by_ref().for_each(drop);
    let w = r.report().warnings.join("\n");
    assert!(w.contains("1 gaps longer than 0.1 s bridged"), "{w}");
    assert!(w.contains("30.000 s from t = 1.010"), "{w}");
    // Nominal: the KF-GINS rule.
    let out: Vec<_> = open_imu(&kf_imu(&p, GapPolicy::Nominal))
        .unwrap()
        .map(|s| s.unwrap())
        .collect();
    assert!((out[2].dt - 0.01).abs() < 1e-12 && (out[2].dtheta.x - 0.001).abs() < 1e-15);
    // A gap over max_bridge_s is an error suggesting to split the run.
    let r: Vec<_> = open_imu(&kf_imu(&p, GapPolicy::Bridge { max_s: Some(10.0) }))
        .unwrap()
        .collect();
    let e = r.last().unwrap().as_ref().unwrap_err().to_string();
    assert!(e.contains(":3: field 'time': gap of 30"), "{e}");
    assert!(
        e.contains("longer than imu.max_bridge_s = 10 s: split the run"),
        "{e}"
    );
}

#[test]
fn line_longer_than_1_mib_is_an_error() {
    let mut big = b"1 30 114 20 0.1 0.1 0.2\n".to_vec();
    big.extend(std::iter::repeat_n(b'7', (1 << 20) + 10));
    let p = write("long.txt", &big);
    let e = read_gnss(&gnss(&p)).unwrap_err().to_string();
    assert!(
        e.contains("long.txt:2: line longer than 1048576 bytes (1 MiB)"),
        "{e}"
    );
}

#[test]
fn dgps_time_above_a_week_rejected() {
    let p = write(
        "dgps.csv",
        b"t_s,prn,prc_m,rrc_mps,iode\n10,5,1,0,1\n1e12,5,1,0,1\n",
    );
    let e = navfuse_io::dgps::read_dgps_file(&p)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            ":3: field 't_s': expected GPS seconds of week in [0, 604800), found 1000000000000"
        ),
        "{e}"
    );
}

#[test]
fn config_overflowing_on_conversion_rejected() {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/kfgins-synthetic.toml"),
    )
    .unwrap();
    let p = Path::new("x.toml");
    let text = base.replace("corr_time_h = 4", "corr_time_h = 1e308");
    assert_ne!(text, base, "the example sets corr_time_h = 4");
    let e = parse_toml_str(&text, p).unwrap_err().to_string();
    assert!(e.contains("key 'imu_noise.corr_time_h'"), "{e}");
    assert!(
        e.contains("out of range: expected 1e-150 to 1e150 in SI"),
        "{e}"
    );
}

/// Every example config loads and round-trips through `to_toml_string`.
#[test]
fn example_configs_round_trip() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in ["examples", "examples/demo", "scenarios"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml" || x == "yaml") {
                files.push(p);
            }
        }
    }
    files.push(root.join("crates/io/tests/data/fuzz/kfgins.yaml"));
    let mut loaded = 0;
    for p in &files {
        // scenarios/ holds simulator scenarios, not run configs: those do not load.
        let Ok(c) = load(p) else { continue };
        loaded += 1;
        let s1 = c.to_toml_string();
        let c2 = parse_toml_str(&s1, p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let body = |s: &str| -> String {
            s.lines()
                .skip_while(|l| l.starts_with('#'))
                .collect::<Vec<_>>()
                .join("\n")
        };
        assert_eq!(body(&s1), body(&c2.to_toml_string()), "{}", p.display());
        assert_eq!(c2.imu, c.imu, "{}", p.display());
        assert_eq!(c2.gnss, c.gnss, "{}", p.display());
    }
    assert!(loaded >= 7, "only {loaded} configs loaded");
}

/// Heading and odometer files cut mid-write: the report readers (what `navfuse run`
/// uses) drop the damaged last line with a warning naming file and line; the strict
/// readers refuse it; damage mid-file stays an error for both.
#[test]
fn heading_and_odometer_cut_last_line() {
    use navfuse_io::heading::read_heading_report;
    use navfuse_io::odometer::{read_odometer, read_odometer_report};
    let h = write(
        "cut_heading.txt",
        b"100.0 10.0 0.5\n101.0 11.0 0.5\n102.0 1",
    );
    let mut w = Vec::new();
    let r = read_heading_report(&h, None, &mut w).unwrap();
    assert_eq!(r.len(), 2);
    assert!(
        w.len() == 1 && w[0].contains("cut_heading.txt:3: damaged last line dropped"),
        "{w:?}"
    );
    assert!(read_heading(&h).is_err());
    let mid = write(
        "mid_heading.txt",
        b"100.0 10.0 0.5\n101.0 x 0.5\n102.0 12.0 0.5\n",
    );
    assert!(read_heading_report(&mid, None, &mut Vec::new()).is_err());
    let o = write("cut_odometer.txt", b"10.0 1.5\n10.1 1.6\n10.2 ");
    let src = OdometerSource {
        path: o,
        format: OdometerFormat::Speed {
            speed_is_mean: true,
        },
        skip_lines: None,
    };
    let whole = OdometerSource {
        path: write("whole_odometer.txt", b"10.0 1.5\n10.1 1.6\n"),
        format: src.format,
        skip_lines: None,
    };
    let mut w = Vec::new();
    assert_eq!(
        read_odometer_report(&src, &mut w).unwrap(),
        read_odometer(&whole).unwrap()
    );
    assert!(
        w.len() == 1 && w[0].contains("cut_odometer.txt:3: damaged last line dropped"),
        "{w:?}"
    );
    assert!(read_odometer(&src).is_err());
}

/// Every example config written with the defaults left out and paths relative to its
/// directory loads to the same configuration, bit for bit; and writing every key is
/// exact too: a second load gives the same values.
#[test]
fn example_configs_written_minimal_and_exact_load_the_same() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let bits = |c: &RunConfig| {
        format!(
            "{:?}",
            RunConfig {
                source_path: PathBuf::new(),
                kfgins_output_path: None,
                warnings: Vec::new(),
                ..c.clone()
            }
        )
    };
    let mut n = 0;
    for dir in ["examples", "examples/demo"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if !p.extension().is_some_and(|x| x == "toml" || x == "yaml") {
                continue;
            }
            let c = load(&p).unwrap_or_else(|e| panic!("{e}"));
            let style = TomlStyle {
                relative_to: p.parent().map(Path::to_path_buf),
                omit_defaults: true,
                keep: Vec::new(),
            };
            let text = c.to_toml_with(&style);
            let d = parse_toml_str(&text, &p).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(bits(&d), bits(&c), "{}\n{text}", p.display());
            let full = parse_toml_str(&c.to_toml_string(), &p).unwrap();
            assert_eq!(bits(&full), bits(&c), "{}", p.display());
            n += 1;
        }
    }
    assert!(n >= 6, "only {n} configs");
}
