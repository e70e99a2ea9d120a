//! Tests of the IMU readers.

use super::*;
use crate::input::{AccelUnit, CsvImuOptions, GyroUnit, RtklibExplorerImuOptions, TimeUnit};

fn tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("navfuse-imu-unit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn csv_opts(quantity: ImuQuantity, sampling: RateSampling) -> CsvImuOptions {
    CsvImuOptions {
        skip_lines: 1,
        time_col: 0,
        gyro_cols: [1, 2, 3],
        accel_cols: [4, 5, 6],
        time_unit: TimeUnit::Seconds,
        time_scale: TimeScale::GpsSecondsOfWeek,
        quantity,
        rate_sampling: sampling,
        gyro_unit: GyroUnit::Rad,
        accel_unit: AccelUnit::Metre,
    }
}

fn src(path: PathBuf, format: ImuFormat, rate: f64) -> ImuSource {
    ImuSource {
        path,
        format,
        rate_hz: rate,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: GapPolicy::Nominal,
    }
}

/// A rate growing linearly in time, w(t) = c0 + c1 t, sampled instantaneously at
/// uneven tags, must integrate exactly with the trapezoid over each (t_{k-1}, t_k],
/// with no half-interval shift.
#[test]
fn instant_rates_integrate_linear_rate_exactly() {
    let tags = [100.0, 100.01, 100.018, 100.029, 100.04, 100.05];
    let w = |t: f64| 0.3 + 2.0 * (t - 100.0);
    let mut text = String::from("t,gx,gy,gz,ax,ay,az\n");
    for &t in &tags {
        text += &format!(
            "{t},{},{},{},{},{},{}\n",
            w(t),
            -w(t),
            0.0,
            9.0 * w(t),
            0.0,
            1.0
        );
    }
    let p = tmp("linear.csv", &text);
    let s = src(
        p,
        ImuFormat::Csv(csv_opts(ImuQuantity::Rate, RateSampling::Instant)),
        100.0,
    );
    let out: Vec<ImuSample> = open_imu(&s).unwrap().map(|r| r.unwrap()).collect();
    assert_eq!(out.len(), tags.len() - 1, "first sample only seeds");
    for (k, smp) in out.iter().enumerate() {
        let (t0, t1) = (tags[k], tags[k + 1]);
        // Exact integral of w over (t0, t1].
        let exact = 0.3 * (t1 - t0) + ((t1 - 100.0).powi(2) - (t0 - 100.0).powi(2));
        assert_eq!(smp.t, t1);
        assert!((smp.dt - (t1 - t0)).abs() < 1e-12);
        assert!((smp.dtheta.x - exact).abs() < 1e-12, "{k}");
        assert!((smp.dtheta.y + exact).abs() < 1e-12);
        assert!((smp.dvel.x - 9.0 * exact).abs() < 1e-12);
        assert!((smp.dvel.z - (t1 - t0)).abs() < 1e-12);
    }
}

#[test]
fn interval_mean_and_units() {
    let text = "# header\n1.000,10,0,0,0,0,1\n1.010,10,0,0,0,0,1\n";
    let p = tmp("mean.csv", text);
    let mut o = csv_opts(ImuQuantity::Rate, RateSampling::IntervalMean);
    o.gyro_unit = GyroUnit::Deg;
    o.accel_unit = AccelUnit::G;
    let out: Vec<ImuSample> = open_imu(&src(p, ImuFormat::Csv(o), 100.0))
        .unwrap()
        .map(|r| r.unwrap())
        .collect();
    assert_eq!(out.len(), 2);
    for s in &out {
        assert!((s.dt - 0.01).abs() < 1e-12);
        assert!((s.dtheta.x - 10f64.to_radians() * 0.01).abs() < 1e-15);
        assert!((s.dvel.z - STANDARD_GRAVITY * 0.01).abs() < 1e-15);
    }
}

#[test]
fn rotation_gaps_and_dt_rule() {
    // KF-GINS increments; roll 180 deg flips y and z.
    let text = "10.00 0.1 0.2 0.3 1 2 3\n10.01 0.1 0.2 0.3 1 2 3\n10.03 0.1 0.2 0.3 1 2 3\n\
                10.50 0.1 0.2 0.3 1 2 3\n10.50 9 9 9 9 9 9\n10.51 0.1 0.2 0.3 1 2 3\n";
    let p = tmp("kf.txt", text);
    let mut s = src(p, ImuFormat::KfGins, 100.0);
    s.sensor_to_body_rpy_deg = [180.0, 0.0, 0.0];
    s.time_offset_s = 0.5;
    let mut r = open_imu(&s).unwrap();
    assert_eq!(r.gps_week(), None);
    let out: Vec<ImuSample> = r.by_ref().map(|x| x.unwrap()).collect();
    let dts: Vec<f64> = out.iter().map(|s| s.dt).collect();
    let want = [0.01, 0.01, 0.02, 0.01, 0.01];
    assert_eq!(out.len(), want.len());
    for (a, b) in dts.iter().zip(want) {
        assert!((a - b).abs() < 1e-9, "{dts:?}");
    }
    assert!((out[0].t - 10.5).abs() < 1e-12);
    assert!((out[0].dtheta - Vector3::new(0.1, -0.2, -0.3)).norm() < 1e-12);
    assert!((out[0].dvel - Vector3::new(1.0, -2.0, -3.0)).norm() < 1e-12);
    let rep = r.report();
    assert_eq!(rep.duplicates, 1);
    assert_eq!(rep.gaps.len(), 2);
    assert_eq!(rep.samples, 5);
    assert_eq!(rep.lines, 6);
    let msg = rep.to_string();
    assert!(
        msg.contains("1 samples with a repeated time tag dropped"),
        "{msg}"
    );
}

#[test]
fn gpst_unix_csv_time_and_week() {
    // Week 2374 starts at Unix-GPST 315964800 + 2374*604800; put samples 1 ms
    // before the end of the week and across it, in nanoseconds.
    let base = (315_964_800i64 + 2374 * 604_800) * 1_000_000_000;
    let end = base + 604_800 * 1_000_000_000;
    let mut text = String::from("h\n");
    for k in -2i64..3 {
        let t = end + k * 5_000_000; // 200 Hz
        text += &format!("{t} 0 0 0 0 0 0\n");
    }
    let p = tmp("ns.csv", &text);
    let mut o = csv_opts(ImuQuantity::Increment, RateSampling::Instant);
    o.time_unit = TimeUnit::Nanoseconds;
    o.time_scale = TimeScale::GpstUnix;
    let mut r = open_imu(&src(p, ImuFormat::Csv(o), 200.0)).unwrap();
    assert_eq!(r.gps_week(), Some(2374));
    let ts: Vec<f64> = r.by_ref().map(|s| s.unwrap().t).collect();
    assert_eq!(
        ts,
        vec![604_799.99, 604_799.995, 604_800.0, 604_800.005, 604_800.01]
    );
}

#[test]
fn rtk_truncated_lines_and_mapping() {
    let dir = std::env::temp_dir().join(format!("navfuse-imu-unit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = "1.0,0.0,0.0,0.0,0.0,100\n\
               0,0,1,0,0,0,1000\n0,0,1,0,0,0,1010\n0,0,1,0,0,0,1010\n0,0,1,0,0,0,1020\n\
               0,0,1,0,0,0\n";
    let p = tmp("rtk.csv", csv);
    // Tag: start at week 2374 sow 1000.5, last tick 40 ms (the counter spans 20).
    let mut tag = vec![0u8; 60];
    tag[..7].copy_from_slice(b"TIMETAG");
    tag.extend_from_slice(&0u32.to_le_bytes());
    let whole = (315_964_800i64 + 2374 * 604_800 + 1000) as u32;
    tag.extend_from_slice(&whole.to_le_bytes());
    tag.extend_from_slice(&0.5f64.to_le_bytes());
    for t in [0u32, 40] {
        tag.extend_from_slice(&t.to_le_bytes());
        tag.extend_from_slice(&0u32.to_le_bytes());
    }
    let tp = dir.join("rtk.csv.tag");
    std::fs::write(&tp, tag).unwrap();
    let fmt = ImuFormat::RtklibExplorer(RtklibExplorerImuOptions { tag_path: tp });
    let mut r = open_imu(&src(p.clone(), fmt.clone(), 100.0)).unwrap();
    assert_eq!(r.gps_week(), Some(2374));
    let out: Vec<ImuSample> = r.by_ref().map(|x| x.unwrap()).collect();
    assert_eq!(out.len(), 2);
    assert!((out[0].t - 1000.52).abs() < 1e-9);
    assert!((out[1].t - 1000.54).abs() < 1e-9);
    assert!((out[1].dvel.z - STANDARD_GRAVITY * 0.02).abs() < 1e-12);
    assert_eq!(r.report().truncated_lines, 2);
    assert_eq!(r.report().duplicates, 1);

    // A short line in the middle is an error naming the line.
    let csv = "0,0,1,0,0,0,1000\n0,0,1,0,0,1010\n0,0,1,0,0,0,1020\n";
    std::fs::write(&p, csv).unwrap();
    let errs: Vec<_> = open_imu(&src(p, fmt, 100.0)).unwrap().collect();
    let e = errs.last().unwrap().as_ref().unwrap_err().to_string();
    assert!(e.contains("rtk.csv:2: expected 7 columns"), "{e}");
}
