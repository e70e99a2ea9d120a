//! PX4 ULog reader (docs/FORMATS.md "PX4 ULog"): the two shared logs (skipped with a
//! message when ../shared/data is missing) and damaged input, which must give errors
//! or warnings with byte offsets and never panic.

mod shared_data;

use navfuse_io::baro::{read_baro, BaroFormat, BaroQuantity, BaroSource};
use navfuse_io::gnss::read_gnss;
use navfuse_io::imu::open_imu;
use navfuse_io::input::{GapPolicy, GnssFormat, GnssSource, ImuFormat, ImuSource};
use navfuse_io::trajectory::{detect_format, read_trajectory, TrajFormat};
use navfuse_io::ulog::{self, Ulog};
use std::path::PathBuf;

fn data(rel: &str) -> Option<PathBuf> {
    shared_data::data(&format!("px4/{rel}"))
}

fn imu_src(path: PathBuf) -> ImuSource {
    ImuSource {
        path,
        format: ImuFormat::Ulog { multi_id: 0 },
        rate_hz: 250.0,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: GapPolicy::default(),
    }
}

/// Parse a shared log and print its topics' record counts.
fn load(p: &std::path::Path) -> Ulog {
    let u = Ulog::parse(std::fs::read(p).unwrap()).unwrap();
    for (n, m, c) in u.topic_counts() {
        println!("topic {n}/{m}: {c}");
    }
    println!("version {}, warnings {:?}", u.version, u.warnings);
    u
}

fn count(u: &Ulog, name: &str) -> usize {
    u.topic(name, 0).map_or(0, |t| t.len())
}

/// (first, last) boot seconds of a topic's records.
fn span(u: &Ulog, name: &str) -> (f64, f64) {
    let t = u.topic(name, 0).unwrap();
    let a = t.timestamp_us(0).unwrap() as f64 * 1e-6;
    let b = t.timestamp_us(t.len() - 1).unwrap() as f64 * 1e-6;
    (a, b)
}

#[test]
fn sitl_log_topics_times_and_inputs() {
    let Some(p) = data("sample_px4_events.ulg") else {
        return;
    };
    let u = load(&p);
    let (a, b) = span(&u, "sensor_combined");
    let n = count(&u, "sensor_combined");
    let rate = (n - 1) as f64 / (b - a);
    println!("sensor_combined {n} records, {a:.3}..{b:.3} s boot, {rate:.1} Hz");
    assert!((200.0..300.0).contains(&rate), "{rate}");
    assert!(b - a > 25.0 && b - a < 40.0, "{a} {b}");
    let gps = ulog::GPS_TOPICS.iter().map(|t| count(&u, t)).max().unwrap();
    assert!(gps > 20, "{gps}");
    assert!(count(&u, "vehicle_attitude") > 100);
    assert!(count(&u, "vehicle_global_position") > 20);
    // Inputs, on the GPS time scale.
    let map = ulog::TimeMap::of(&u);
    println!("time map {map:?}");
    assert!(map.week.is_some_and(|w| w > 1000));
    let mut r = open_imu(&imu_src(p.clone())).unwrap();
    let samples: Vec<_> = r.by_ref().map(|s| s.unwrap()).collect();
    let rep = r.report();
    println!(
        "IMU {} samples {:.3}..{:.3} s of week {:?}, warnings {:?}",
        samples.len(),
        samples[0].t,
        samples.last().unwrap().t,
        r.gps_week(),
        rep.warnings
    );
    assert!(samples.len() + 2 >= n);
    // Hovering/flying: the mean specific force is about g.
    let f: f64 = samples.iter().map(|s| s.dvel.norm() / s.dt).sum::<f64>() / samples.len() as f64;
    assert!((8.0..11.5).contains(&f), "{f}");
    let g = read_gnss(&GnssSource {
        path: p.clone(),
        format: GnssFormat::Ulog { multi_id: 0 },
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap();
    let f0 = g.fixes[0];
    println!(
        "GNSS {} fixes {:.3}..{:.3} s week {:?}, first {:.7} {:.7} {:.2} std {:?} vel {:?}",
        g.fixes.len(),
        f0.t,
        g.fixes.last().unwrap().t,
        g.gps_week,
        f0.lla.x.to_degrees(),
        f0.lla.y.to_degrees(),
        f0.lla.z,
        f0.std_ned,
        f0.vel_ned
    );
    assert_eq!(g.gps_week, r.gps_week());
    assert!(g.fixes.len() > 20);
    assert!(f0.vel_ned.is_some());
    // The GNSS fixes lie within the IMU's span.
    assert!(
        f0.t >= samples[0].t - 1.0 && g.fixes.last().unwrap().t <= samples.last().unwrap().t + 1.0
    );
    let mut w = Vec::new();
    let baro = read_baro(
        &BaroSource {
            path: p.clone(),
            quantity: BaroQuantity::PressurePa,
            reference_pressure_pa: 101_325.0,
            delay_s: 0.0,
            format: BaroFormat::Ulog { multi_id: 0 },
            skip_lines: None,
        },
        &mut w,
    )
    .unwrap();
    println!(
        "baro {} samples {:.3}..{:.3} s, first height {:.2} m",
        baro.len(),
        baro[0].t,
        baro.last().unwrap().t,
        baro[0].height_m
    );
    assert!(baro.len() > 100);
    // EKF2's track.
    assert_eq!(detect_format(&p).unwrap(), TrajFormat::Ulog);
    let tr = read_trajectory(&p, None, &[]).unwrap();
    let with_att = tr.points.iter().filter(|p| p.rpy.is_some()).count();
    let with_vel = tr.points.iter().filter(|p| p.v_n.is_some()).count();
    println!(
        "EKF2 track {} points, {} with attitude, {} with velocity, week {}, warnings {:?}",
        tr.points.len(),
        with_att,
        with_vel,
        tr.week,
        tr.warnings
    );
    assert_eq!(tr.week, g.gps_week.unwrap());
    assert!(with_att * 10 >= tr.points.len() * 9);
}

#[test]
fn hardware_log_imu_only_on_boot_time() {
    let Some(p) = data("sample.ulg") else {
        return;
    };
    let u = load(&p);
    let n = count(&u, "sensor_combined");
    let (a, b) = span(&u, "sensor_combined");
    let rate = (n - 1) as f64 / (b - a);
    println!("sensor_combined {n} records, {a:.3}..{b:.3} s boot, {rate:.1} Hz");
    assert!(b - a > 60.0 && b - a < 75.0);
    assert!(count(&u, "vehicle_attitude") > 100);
    assert!(ulog::GPS_TOPICS.iter().all(|t| count(&u, t) == 0));
    assert_eq!(ulog::TimeMap::of(&u).week, None);
    let mut r = open_imu(&imu_src(p.clone())).unwrap();
    let samples: Vec<_> = r.by_ref().map(|s| s.unwrap()).collect();
    assert_eq!(r.gps_week(), None);
    // Boot seconds.
    assert!((samples[0].t - a).abs() < 0.1, "{} {a}", samples[0].t);
    assert!(samples.len() + 2 >= n);
    let g = read_gnss(&GnssSource {
        path: p,
        format: GnssFormat::Ulog { multi_id: 0 },
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap_err()
    .to_string();
    assert!(g.contains("no GPS topic"), "{g}");
}

#[test]
fn synthetic_log_every_message_type() {
    let bytes = ulog::synth::synthetic_ulog(10);
    let u = Ulog::parse(bytes.clone()).unwrap();
    assert!(u.warnings.is_empty(), "{:?}", u.warnings);
    assert_eq!(u.info["sys_name"], "synthetic");
    assert_eq!(u.params["EKF2_GPS_DELAY"], 110.0);
    assert_eq!(u.dropouts, (1, 25));
    assert_eq!(u.log_messages.len(), 1);
    assert_eq!(count(&u, "sensor_combined"), 1001);
    assert_eq!(u.topic("sensor_baro", 1).unwrap().len(), 101);
    let att = u.topic("vehicle_attitude", 0).unwrap();
    assert!(att.has("delta.z") && att.has("q[3]") && !att.has("_padding0[0]"));
    // GPS time: boot + 2024-03-18 00:00 UTC + 18 s = GPS week 2306, Monday. The
    // GPS records' time_utc_usec is their publication time here, so the log's
    // EKF2_GPS_DELAY (110 ms) puts the IMU 0.11 s later and the fixes 0.11 s
    // before their timestamps.
    let map = ulog::TimeMap::of(&u);
    assert_eq!(map.week, Some(2306));
    assert_eq!(map.gps_delay_us, 110_000);
    let t0 = map.t(ulog::synth::T0_US);
    assert!((t0 - (86_400.0 + 18.0 + 20.0 + 0.11)).abs() < 1e-6, "{t0}");
    assert!((map.fix_t(ulog::synth::T0_US) - (86_400.0 + 18.0 + 20.0)).abs() < 1e-6);
    let dir = std::env::temp_dir().join(format!("navfuse-ulog-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("synthetic.ulg");
    std::fs::write(&p, &bytes).unwrap();
    let mut r = open_imu(&ImuSource {
        rate_hz: 100.0,
        ..imu_src(p.clone())
    })
    .unwrap();
    let s: Vec<_> = r.by_ref().map(|s| s.unwrap()).collect();
    assert_eq!(s.len(), 1001);
    assert!((s[1].dt - 0.01).abs() < 1e-9);
    assert!((s[1].dvel.z + 0.0981).abs() < 1e-6, "{}", s[1].dvel);
    assert!((s[1].dtheta.x - 1e-5).abs() < 1e-9);
    let tr = read_trajectory(&p, Some(TrajFormat::Ulog), &[]).unwrap();
    let yaw = tr.points[3].rpy.unwrap().z.to_degrees();
    assert!((yaw - 90.0).abs() < 1e-4, "{yaw}");
    assert!((tr.points[0].lla.z - 500.0).abs() < 1e-3);
}

/// A log with `sensor_gyro` + `sensor_accel` and no `sensor_combined` (the accel
/// sampled 4 ms after the gyro) gives the increments of the combined log.
#[test]
fn separate_gyro_and_accel_topics_give_the_combined_imu() {
    let dir = std::env::temp_dir().join(format!("navfuse-ulog-sep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let read = |name: &str, bytes: Vec<u8>| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        let mut r = open_imu(&ImuSource {
            rate_hz: 100.0,
            ..imu_src(p)
        })
        .unwrap();
        let s: Vec<_> = r.by_ref().map(|s| s.unwrap()).collect();
        (s, r.report().warnings.clone())
    };
    let (combined, _) = read("combined.ulg", ulog::synth::synthetic_ulog(3));
    let (separate, warnings) = read("separate.ulg", ulog::synth::synthetic_ulog_separate_imu(3));
    // The first gyro sample has no accelerometer sample before it: left out, and said
    // so; the next only starts the intervals (instantaneous rates).
    assert_eq!(separate.len() + 2, combined.len());
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("sensor_gyro + sensor_accel: 1 records left out")),
        "{warnings:?}"
    );
    // The same times from the third gyro sample on (the combined log's first
    // interval is the nominal one).
    for (a, b) in combined.iter().skip(2).zip(&separate) {
        assert!((a.t - b.t).abs() < 1e-9, "{} {}", a.t, b.t);
        assert!(
            (a.dtheta - b.dtheta).norm() < 1e-12,
            "{} {}",
            a.dtheta,
            b.dtheta
        );
        assert!((a.dvel - b.dvel).norm() < 1e-9, "{} {}", a.dvel, b.dvel);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The SITL log's own `sensor_gyro` / `sensor_accel` records (logged at about 1 Hz,
/// too slow to be the IMU: refused, saying so) against the `sensor_combined` record
/// nearest in time: the same units and frame (SITL: calibration near identity).
#[test]
fn sitl_log_separate_topics_agree_with_sensor_combined() {
    let Some(p) = data("sample_px4_events.ulg") else {
        return;
    };
    let u = load(&p);
    let map = ulog::TimeMap::of(&u);
    let e = ulog::separate_imu(&p, &u, 0, &map).unwrap_err().to_string();
    println!("{e}");
    assert!(e.contains("sensor_gyro") && e.contains("Hz"), "{e}");
    let comb = u.topic("sensor_combined", 0).unwrap();
    let ct: Vec<f64> = (0..comb.len())
        .map(|k| comb.timestamp_us(k).unwrap() as f64)
        .collect();
    for (name, base, tol) in [
        ("sensor_gyro", "gyro_rad", 0.02),
        ("sensor_accel", "accelerometer_m_s2", 0.3),
    ] {
        let t = u.topic(name, 0).unwrap();
        let xyz = ["x", "y", "z"].map(|n| t.field(n).unwrap().clone());
        let ts = t.field("timestamp_sample").unwrap().clone();
        let cf = [0, 1, 2].map(|i| comb.field(&format!("{base}[{i}]")).unwrap().clone());
        let mut diffs = Vec::new();
        for k in 0..t.len() {
            let tk = t.value(k, &ts);
            let j = ct.partition_point(|&c| c < tk).min(ct.len() - 1);
            if (ct[j] - tk).abs() > 5_000.0 {
                continue;
            }
            for i in 0..3 {
                diffs.push((t.value(k, &xyz[i]) - comb.value(j, &cf[i])).abs());
            }
        }
        diffs.sort_by(f64::total_cmp);
        let med = diffs[diffs.len() / 2];
        println!(
            "{name}: {} axis values matched, median |difference| {med:.4}",
            diffs.len()
        );
        assert!(diffs.len() >= 60, "{}", diffs.len());
        assert!(med < tol, "{name}: median difference {med}");
    }
}

/// Damaged input: errors or warnings with byte offsets, never a panic.
#[test]
fn damaged_logs_give_byte_offsets() {
    let good = ulog::synth::synthetic_ulog(2);
    // Truncated inside the last message: a warning, the rest kept.
    let cut = &good[..good.len() - 5];
    let u = Ulog::parse(cut.to_vec()).unwrap();
    assert_eq!(u.warnings.len(), 1);
    assert!(
        u.warnings[0].contains("cut by the end of the file at byte"),
        "{:?}",
        u.warnings
    );
    // Cut inside a message header.
    let n = good.len();
    for k in 1..3 {
        let u = Ulog::parse(good[..n - 21 - k].to_vec()).unwrap();
        assert!(u.warnings[0].starts_with("byte "), "{:?}", u.warnings);
    }
    // Bad magic.
    let mut bad = good.clone();
    bad[1] = b'X';
    let e = Ulog::parse(bad).unwrap_err();
    assert_eq!(e.offset, 0);
    assert!(e.to_string().contains("not a ULog file"), "{e}");
    let e = Ulog::parse(b"ULog".to_vec()).unwrap_err();
    assert!(e.to_string().contains("shorter than the 16-byte"), "{e}");
    // A corrupted message size: the next "message" starts in the middle of data.
    let first_data = find_first(&good, b'D');
    let mut bad = good.clone();
    bad[first_data] = bad[first_data].wrapping_add(7);
    let e = Ulog::parse(bad).unwrap_err();
    assert!(e.offset > first_data, "{e}");
    println!("corrupted size: {e}");
    // A data message too short for its format.
    let mut bad = good.clone();
    bad[first_data] -= 8;
    let e = Ulog::parse(bad).unwrap_err();
    assert_eq!(e.offset, first_data);
    assert!(e.to_string().contains("its format needs"), "{e}");
    // Every cut and a sweep of single-byte corruptions: no panic.
    for k in (0..good.len()).step_by(7) {
        let _ = Ulog::parse(good[..k].to_vec());
        let mut b = good.clone();
        b[k] ^= 0xA5;
        let _ = Ulog::parse(b);
    }
    // Through the readers: the file's path and the byte offset.
    let dir = std::env::temp_dir().join(format!("navfuse-ulog-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.ulg");
    let mut bad = good.clone();
    bad[first_data] -= 8;
    std::fs::write(&p, &bad).unwrap();
    let e = open_imu(&imu_src(p.clone())).err().unwrap().to_string();
    assert!(
        e.contains("bad.ulg") && e.contains(&format!("byte {first_data}")),
        "{e}"
    );
    std::fs::write(&p, cut).unwrap();
    let mut r = open_imu(&imu_src(p.clone())).unwrap();
    for s in r.by_ref() {
        s.unwrap();
    }
    assert!(
        r.report()
            .warnings
            .iter()
            .any(|w| w.contains("bad.ulg: byte ")),
        "{:?}",
        r.report().warnings
    );
}

/// Offset of the first message of type `ty` (walking the message headers).
fn find_first(b: &[u8], ty: u8) -> usize {
    let mut pos = 16;
    loop {
        let size = u16::from_le_bytes([b[pos], b[pos + 1]]) as usize;
        if b[pos + 2] == ty {
            return pos;
        }
        pos += 3 + size;
    }
}

/// Fuzz findings: timestamps beyond i64 (a GPS record's 2^63, an IMU record's
/// u64::MAX) wrapped the time mapping (times going backwards, an overflow panic).
#[test]
fn huge_timestamps_do_not_wrap() {
    let good = ulog::synth::synthetic_ulog(2);
    let dir = std::env::temp_dir().join(format!("navfuse-ulog-huge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (msg_id, ts) in [
        (1u16, 1u64 << 63),
        (1, u64::MAX),
        (0, u64::MAX),
        (0, (1 << 63) - 1),
    ] {
        // The second data record of msg_id: its timestamp follows msg_id.
        let mut b = good.clone();
        let mut pos = 16;
        let mut seen = 0;
        while pos + 3 < b.len() {
            let size = u16::from_le_bytes([b[pos], b[pos + 1]]) as usize;
            if b[pos + 2] == b'D' && u16::from_le_bytes([b[pos + 3], b[pos + 4]]) == msg_id {
                seen += 1;
                if seen == 2 {
                    b[pos + 5..pos + 13].copy_from_slice(&ts.to_le_bytes());
                    break;
                }
            }
            pos += 3 + size;
        }
        let p = dir.join("huge.ulg");
        std::fs::write(&p, &b).unwrap();
        if let Ok(g) = read_gnss(&GnssSource {
            path: p.clone(),
            format: GnssFormat::Ulog { multi_id: 0 },
            decimate_s: None,
            time_offset_s: 0.0,
            skip_lines: None,
        }) {
            assert!(g.fixes.windows(2).all(|w| w[1].t > w[0].t));
        }
        if let Ok(r) = open_imu(&imu_src(p.clone())) {
            for s in r {
                if s.is_err() {
                    break;
                }
            }
        }
    }
}

fn ulog_msg(out: &mut Vec<u8>, ty: u8, payload: &[u8]) {
    out.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    out.push(ty);
    out.extend_from_slice(payload);
}

fn ulog_header() -> Vec<u8> {
    let mut out = ulog::MAGIC.to_vec();
    out.push(1);
    out.extend_from_slice(&0u64.to_le_bytes());
    out
}

/// An empty type in big nested arrays (no bytes, so no size guard) is refused at
/// once instead of looping 65535^depth times.
#[test]
fn empty_nested_type_is_refused_not_looped() {
    let mut b = ulog_header();
    ulog_msg(&mut b, b'F', b"z:");
    ulog_msg(&mut b, b'F', b"y:z[65535] a;");
    ulog_msg(&mut b, b'F', b"t:uint64_t timestamp;y[65535] a;");
    ulog_msg(&mut b, b'A', b"\x00\x00\x00t");
    let start = std::time::Instant::now();
    let e = Ulog::parse(b).unwrap_err().to_string();
    assert!(e.contains("has no bytes"), "{e}");
    assert!(start.elapsed().as_secs_f64() < 1.0);
}

/// A msg_id added again for another topic: the first topic keeps its records.
#[test]
fn reused_msg_id_keeps_the_earlier_records() {
    let mut b = ulog_header();
    ulog_msg(&mut b, b'F', b"a:uint64_t timestamp;float x;");
    ulog_msg(&mut b, b'F', b"b:uint64_t timestamp;float y;");
    ulog_msg(&mut b, b'A', b"\x00\x05\x00a");
    let rec = |ts: u64, v: f32| {
        [
            5u16.to_le_bytes().as_slice(),
            &ts.to_le_bytes(),
            &v.to_le_bytes(),
        ]
        .concat()
    };
    ulog_msg(&mut b, b'D', &rec(10, 1.0));
    ulog_msg(&mut b, b'D', &rec(20, 2.0));
    ulog_msg(&mut b, b'A', b"\x00\x05\x00b");
    ulog_msg(&mut b, b'D', &rec(30, 3.0));
    let u = Ulog::parse(b).unwrap();
    assert_eq!(u.topic("a", 0).unwrap().len(), 2);
    let t = u.topic("b", 0).unwrap();
    assert_eq!(t.len(), 1);
    assert_eq!(t.value(0, t.field("y").unwrap()), 3.0);
}
