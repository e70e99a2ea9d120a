//! Bad inputs: each error names the file, the line and (where it applies) the field,
//! and nothing panics. Inputs are written to a fresh temporary directory.

use navfuse_io::gnss::read_gnss;
use navfuse_io::imu::{open_imu, ImuReader};
use navfuse_io::input::{
    AccelUnit, CsvImuOptions, GnssFormat, GnssSource, GyroUnit, ImuFormat, ImuQuantity, ImuSource,
    RateSampling, RtklibExplorerImuOptions, TimeScale, TimeUnit,
};
use navfuse_io::nav::read_nav;
use navfuse_io::timetag::read_timetag;
use navfuse_io::InputError;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// Write `text` to a new file in a per-process temporary directory.
fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("navfuse-formats-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    let p = dir.join(format!("{k}-{name}"));
    std::fs::write(&p, text).unwrap();
    p
}

fn imu(path: PathBuf, format: ImuFormat) -> ImuSource {
    ImuSource {
        path,
        format,
        rate_hz: 200.0,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: Default::default(),
    }
}

fn kfgins_imu(text: &str) -> (PathBuf, ImuSource) {
    let p = write("imu.txt", text);
    (p.clone(), imu(p, ImuFormat::KfGins))
}

fn gnss(text: &str, name: &str, format: GnssFormat) -> (PathBuf, GnssSource) {
    let p = write(name, text);
    (
        p.clone(),
        GnssSource {
            path: p,
            format,
            decimate_s: None,
            time_offset_s: 0.0,
            skip_lines: None,
        },
    )
}

/// Drain a reader; the error it ends with.
fn imu_error(r: ImuReader) -> InputError {
    let mut last = None;
    for s in r {
        if let Err(e) = s {
            last = Some(e);
        }
    }
    last.expect("expected an error")
}

/// The message names the file and line (and field), in the Display form.
fn check(e: &InputError, path: &PathBuf, line: Option<usize>, field: Option<&str>, msg: &str) {
    let s = e.to_string();
    assert_eq!(&e.path, path, "{s}");
    assert_eq!(e.line, line, "{s}");
    assert_eq!(e.field.as_deref(), field, "{s}");
    assert!(s.starts_with(&path.display().to_string()), "{s}");
    if let Some(l) = line {
        assert!(s.contains(&format!(":{l}: ")), "{s}");
    }
    if let Some(f) = field {
        assert!(s.contains(&format!("field '{f}': ")), "{s}");
    }
    assert!(s.contains(msg), "expected {msg:?} in: {s}");
    println!("{s}");
}

const GOOD_IMU: &str = "456300.000 0.1 0.2 0.3 0.4 0.5 0.6\n";

#[test]
fn missing_files() {
    let p = std::env::temp_dir().join("navfuse-no-such-dir/none.txt");
    let e = open_imu(&imu(p.clone(), ImuFormat::KfGins)).err().unwrap();
    check(&e, &p, None, None, "cannot open: No such file or directory");
    assert_eq!(
        e.to_string(),
        format!("{}: cannot open: No such file or directory", p.display())
    );
    let e = read_gnss(&GnssSource {
        path: p.clone(),
        format: GnssFormat::KfGins,
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap_err();
    check(&e, &p, None, None, "cannot open: No such file or directory");
    let e = read_nav(&p).unwrap_err();
    check(&e, &p, None, None, "cannot open: No such file or directory");
    let e = read_timetag(&p).unwrap_err();
    check(&e, &p, None, None, "cannot open: No such file or directory");
    // The CSV exists but its tag file does not: the error names the tag file.
    let csv = write("imu.csv", "0,0,1,0,0,0,100\n0,0,1,0,0,0,110\n");
    let e = open_imu(&imu(
        csv,
        ImuFormat::RtklibExplorer(RtklibExplorerImuOptions {
            tag_path: p.clone(),
        }),
    ))
    .err()
    .unwrap();
    check(&e, &p, None, None, "cannot open: No such file or directory");
}

#[test]
fn wrong_column_count() {
    let (p, s) = kfgins_imu(&format!("{GOOD_IMU}456300.005 0.1 0.2 0.3 0.4\n"));
    let e = imu_error(open_imu(&s).unwrap());
    check(
        &e,
        &p,
        Some(2),
        None,
        "expected 7 columns (t, dtheta x y z, dvel x y z), found 5",
    );

    let (p, s) = gnss("1 30 114 20 0.1 0.1\n", "gnss.txt", GnssFormat::KfGins);
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(1), None, "expected 7 or 13 columns");
    assert!(e.to_string().contains("found 6"));

    let pos = "% header\n2025/07/08 19:34:18.499 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0\n";
    let (p, s) = gnss(pos, "a.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(2), None, "expected 15 or 24 columns");

    let p = write("a.nav", "0 1 30 114 20 0 0 0 0 0\n");
    let e = read_nav(&p).unwrap_err();
    check(&e, &p, Some(1), None, "expected 11 columns");

    let opts = CsvImuOptions {
        skip_lines: 1,
        time_col: 0,
        gyro_cols: [1, 2, 3],
        accel_cols: [4, 5, 9],
        time_unit: TimeUnit::Seconds,
        time_scale: TimeScale::GpsSecondsOfWeek,
        quantity: ImuQuantity::Rate,
        rate_sampling: RateSampling::Instant,
        gyro_unit: GyroUnit::Deg,
        accel_unit: AccelUnit::G,
    };
    let p = write("imu.csv", "header\n1,0,0,0,0,0,1\n");
    let e = imu_error(open_imu(&imu(p.clone(), ImuFormat::Csv(opts))).unwrap());
    check(&e, &p, Some(2), None, "expected at least 10 columns");
    assert!(e.to_string().contains("found 7"));

    // rtklibexplorer: a short line in the middle (not first or last) is an error.
    let tag = write("imu.csv.tag", "");
    let mut b = vec![0u8; 60];
    b[..7].copy_from_slice(b"TIMETAG");
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&1_750_000_000u32.to_le_bytes());
    b.extend_from_slice(&0.25f64.to_le_bytes());
    b.extend_from_slice(&[0u8; 8]);
    b.extend_from_slice(&30u32.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    std::fs::write(&tag, b).unwrap();
    let csv = write(
        "raw.csv",
        "0,0,1,0,0\n0,0,1,0,0,0,100\n0,0,1,0,0,110\n0,0,1,0,0,0,120\n0,0,1\n",
    );
    let e = imu_error(
        open_imu(&imu(
            csv.clone(),
            ImuFormat::RtklibExplorer(RtklibExplorerImuOptions { tag_path: tag }),
        ))
        .unwrap(),
    );
    check(&e, &csv, Some(3), None, "expected 7 columns (ax ay az [g]");
    assert!(e.to_string().contains("found 6"));
}

#[test]
fn non_numeric_field() {
    let (p, s) = kfgins_imu(&format!("{GOOD_IMU}456300.005 0.1 abc 0.3 0.4 0.5 0.6\n"));
    let e = imu_error(open_imu(&s).unwrap());
    check(
        &e,
        &p,
        Some(2),
        Some("dtheta_y"),
        "expected a number, found \"abc\"",
    );

    let (p, s) = gnss("1 30 114 20 0.1 x 0.2\n", "gnss.txt", GnssFormat::KfGins);
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("std_e"),
        "expected a number, found \"x\"",
    );

    let pos = "2025/07/08 19:34:18.499 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1..2\n";
    let (p, s) = gnss(pos, "a.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("ratio"),
        "expected a number, found \"1..2\"",
    );

    let pos = "2025/07/08 19:3x:18.499 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1\n";
    let (p, s) = gnss(pos, "b.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("time"),
        "expected a time of day HH:MM:SS.sss",
    );

    let pos = "2025/02/30 19:30:18.499 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1\n";
    let (p, s) = gnss(pos, "c.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(1), Some("date"), "expected a valid GPST date");

    let p = write("a.nav", "0 1 30 114 20 0 0 0 0 0 -\n");
    let e = read_nav(&p).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("yaw"),
        "expected a number, found \"-\"",
    );

    // Invalid UTF-8 does not panic either.
    let p = write("bin.txt", "");
    std::fs::write(&p, b"456300 \xff\xfe 0 0 0 0 0\n").unwrap();
    let e = imu_error(open_imu(&imu(p.clone(), ImuFormat::KfGins)).unwrap());
    check(
        &e,
        &p,
        Some(1),
        Some("dtheta_x"),
        "expected a number, found",
    );
}

#[test]
fn nan_and_infinity() {
    let (p, s) = kfgins_imu(&format!("{GOOD_IMU}456300.005 0.1 0.2 0.3 NaN 0.5 0.6\n"));
    let e = imu_error(open_imu(&s).unwrap());
    check(&e, &p, Some(2), Some("dvel_x"), "NaN is not allowed");

    let (p, s) = kfgins_imu("inf 0.1 0.2 0.3 0.4 0.5 0.6\n");
    let e = imu_error(open_imu(&s).unwrap());
    check(&e, &p, Some(1), Some("t"), "infinity is not allowed");

    let (p, s) = gnss("1 nan 114 20 0.1 0.1 0.2\n", "gnss.txt", GnssFormat::KfGins);
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(1), Some("lat"), "NaN is not allowed");

    let p = write("a.nav", "0 1 30 114 NaN 0 0 0 0 0 0\n");
    let e = read_nav(&p).unwrap_err();
    check(&e, &p, Some(1), Some("h"), "NaN is not allowed");
}

#[test]
fn time_going_backwards() {
    let (p, s) =
        kfgins_imu("456300.000 0 0 0 0 0 0\n456300.010 0 0 0 0 0 0\n456300.005 0 0 0 0 0 0\n");
    let e = imu_error(open_imu(&s).unwrap());
    check(
        &e,
        &p,
        Some(3),
        Some("time"),
        "time 456300.005 goes backwards (previous 456300.01)",
    );

    let (p, s) = gnss(
        "2 30 114 20 0.1 0.1 0.2\n1 30 114 20 0.1 0.1 0.2\n",
        "gnss.txt",
        GnssFormat::KfGins,
    );
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(2),
        Some("time"),
        "time 1 goes backwards (previous 2)",
    );

    let pos = "2025/07/08 19:34:18.499 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1\n\
               2025/07/08 19:34:18.249 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1\n";
    let (p, s) = gnss(pos, "a.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(2), Some("time"), "goes backwards");

    let p = write(
        "a.nav",
        "0 2 30 114 20 0 0 0 0 0 0\n0 1 30 114 20 0 0 0 0 0 0\n",
    );
    let e = read_nav(&p).unwrap_err();
    check(
        &e,
        &p,
        Some(2),
        Some("t"),
        "time 1 goes backwards (previous 2)",
    );
}

#[test]
fn duplicate_samples() {
    // IMU: dropped and reported, not an error.
    let (_, s) = kfgins_imu(
        "456300.000 0 0 0 0 0 0\n456300.005 0 0 0 0 0 0\n456300.005 1 1 1 1 1 1\n\
         456300.010 0 0 0 0 0 0\n456300.010 0 0 0 0 0 0\n456300.015 0 0 0 0 0 0\n",
    );
    let mut r = open_imu(&s).unwrap();
    let out: Vec<_> = r.by_ref().collect::<Result<Vec<_>, _>>().unwrap();
    assert_eq!(out.len(), 4);
    assert!(
        out.iter().all(|s| s.dtheta.x == 0.0),
        "the first of equal tags is kept"
    );
    let rep = r.report();
    assert_eq!(rep.duplicates, 2);
    assert_eq!(rep.duplicate_times, vec![456300.005, 456300.010]);
    assert_eq!(rep.samples, 4);
    assert_eq!(rep.lines, 6);
    let msg = rep.to_string();
    println!("{msg}");
    assert!(
        msg.contains(
            "2 samples with a repeated time tag dropped (first at 456300.005, 456300.010 s)"
        ),
        "{msg}"
    );

    // GNSS: an error.
    let (p, s) = gnss(
        "1 30 114 20 0.1 0.1 0.2\n1 30 114 20 0.1 0.1 0.2\n",
        "gnss.txt",
        GnssFormat::KfGins,
    );
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(2),
        Some("time"),
        "duplicate epoch: time 1 repeats the previous epoch",
    );

    let pos = "%  GPST  latitude(deg) longitude(deg) height(m)\n\
               2374 100.5 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1\n\
               2374 100.5 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1\n";
    let (p, s) = gnss(pos, "a.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(3), Some("time"), "duplicate epoch");
}

#[test]
fn zero_or_negative_std() {
    let (p, s) = gnss("1 30 114 20 0.1 0.1 0\n", "gnss.txt", GnssFormat::KfGins);
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(1), Some("std_d"), "std must be > 0, found 0");

    let (p, s) = gnss(
        "1 30 114 20 0.1 0.1 0.2 1 2 3 0.1 -0.1 0.1\n",
        "gnss13.txt",
        GnssFormat::KfGins,
    );
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("vel_std_e"),
        "std must be > 0, found -0.1",
    );

    let pos = "2025/07/08 19:34:18.499 40 -105 1600 1 21 -0.01 0.01 0.02 0 0 0 0 1\n";
    let (p, s) = gnss(pos, "a.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(1), Some("sdn"), "std must be > 0, found -0.01");

    let pos = "2025/07/08 19:34:18.499 40 -105 1600 1 21 0.01 0.01 0.02 0 0 0 0 1 \
               1 2 3 0.05 0.05 0 0 0 0\n";
    let (p, s) = gnss(pos, "b.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(&e, &p, Some(1), Some("sdvu"), "std must be > 0, found 0");
}

#[test]
fn out_of_range_values() {
    let (p, s) = gnss("1 91 114 20 0.1 0.1 0.2\n", "gnss.txt", GnssFormat::KfGins);
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("lat"),
        "expected a latitude in [-90, 90] deg, found 91",
    );

    let pos = "2025/07/08 19:34:18.499 40 -105 1600 1.5 21 0.01 0.01 0.02 0 0 0 0 1\n";
    let (p, s) = gnss(pos, "a.pos", GnssFormat::RtklibPos { quality: vec![1] });
    let e = read_gnss(&s).unwrap_err();
    check(
        &e,
        &p,
        Some(1),
        Some("Q"),
        "expected an integer quality flag",
    );

    let (p, mut s) = kfgins_imu(GOOD_IMU);
    s.rate_hz = 0.0;
    let e = open_imu(&s).err().unwrap();
    check(
        &e,
        &p,
        None,
        Some("rate_hz"),
        "rate_hz must be > 0, found 0",
    );
}

#[test]
fn garbage_never_panics() {
    // Assorted junk through every reader: errors or empty results, never a panic.
    let junk: [&[u8]; 10] = [
        b"",
        b"\n\n\n",
        b",,,,,,\n",
        b"1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24\n",
        b"% only a header\n",
        b"\xff\xff\xff\xff\n\x00\x00",
        b"2025/07/08 99:99:99.999 1 2 3 4 5 6 7 8 9 10 11 12 13\n",
        b"-1e400 1e400 1 1 1 1 1\n",
        b"1e308 1 1 1 1 1 1\n-1e308 1 1 1 1 1 1\n",
        b"4294967296 0 0 0 0 0 0 0 0 0 0\n",
    ];
    for (k, bytes) in junk.iter().enumerate() {
        let p = write(&format!("junk{k}"), "");
        std::fs::write(&p, bytes).unwrap();
        let _ = open_imu(&imu(p.clone(), ImuFormat::KfGins)).map(|r| r.count());
        for format in [
            GnssFormat::KfGins,
            GnssFormat::RtklibPos { quality: vec![] },
        ] {
            let _ = read_gnss(&GnssSource {
                path: p.clone(),
                format,
                decimate_s: Some(1.0),
                time_offset_s: 0.0,
                skip_lines: None,
            });
        }
        let _ = read_nav(&p);
        let _ = read_timetag(&p);
        let tagged = ImuFormat::RtklibExplorer(RtklibExplorerImuOptions {
            tag_path: p.clone(),
        });
        let _ = open_imu(&imu(p.clone(), tagged)).map(|r| r.count());
        let csv = ImuFormat::Csv(CsvImuOptions {
            skip_lines: 0,
            time_col: 6,
            gyro_cols: [0, 1, 2],
            accel_cols: [3, 4, 5],
            time_unit: TimeUnit::Nanoseconds,
            time_scale: TimeScale::GpstUnix,
            quantity: ImuQuantity::Rate,
            rate_sampling: RateSampling::Instant,
            gyro_unit: GyroUnit::Rad,
            accel_unit: AccelUnit::Metre,
        });
        let _ = open_imu(&imu(p.clone(), csv)).map(|r| r.count());
    }
}
