//! u-blox ESF-RAW / ESF-MEAS (IMU, wheel ticks, speed) and NAV-RELPOSNED (heading)
//! through the readers, on logs written by `ubx::synth` (no real log of these
//! messages is at hand): values back equal to their quantisation, the time mapping
//! and its latency bias, damage warned about and never a panic, clear errors.

use navfuse_io::imu::open_imu;
use navfuse_io::input::*;
use navfuse_io::odometer::read_odometer_report;
use navfuse_io::ubx::synth::{self, ImuRate, Stream};
use navfuse_io::ubx::{aiding, decode_ubx, esf};
use std::path::{Path, PathBuf};

fn tmp(name: &str, data: &[u8]) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("ubx_esf");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    p
}

fn imu_src(path: &Path, rate_hz: f64) -> ImuSource {
    ImuSource {
        path: path.to_path_buf(),
        format: ImuFormat::Ubx,
        rate_hz,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: GapPolicy::default(),
    }
}

/// The synthetic log's sample k at GPS time (s of week): tags count 1 ms from
/// ITOW0 - 0.5 s.
fn truth_t(k: u32) -> f64 {
    f64::from(synth::ITOW0_MS) * 1e-3 - 0.5 + 0.020 * f64::from(k)
}

#[test]
fn imu_increments_round_trip_to_the_quantisation() {
    let secs = 20;
    let p = tmp("imu.ubx", &synth::synthetic_esf_log(secs));
    let r = open_imu(&imu_src(&p, 50.0)).unwrap();
    assert_eq!(r.gps_week(), Some(synth::WEEK as u32));
    let mut r = r;
    let got: Vec<_> = r.by_ref().map(|s| s.unwrap()).collect();
    let rep = r.report().clone();
    println!("{rep}");
    assert!(rep.to_string().contains("ESF-RAW"), "{rep}");
    let n = secs * 50 + 25;
    // the first sample only seeds the trapezoid
    assert_eq!(got.len() as u32, n - 1);
    // The time map: 1 ms tick fitted; the anchors pair each epoch with the last
    // ESF-RAW output before its NAV message (40 ms late; batches of 5 at 20 ms
    // ending 20 ms before the epoch): every time 20 ms late, by construction.
    let bias: Vec<f64> = got
        .iter()
        .enumerate()
        .map(|(j, s)| s.t - truth_t(j as u32 + 1))
        .collect();
    let (bmin, bmax) = bias
        .iter()
        .fold((f64::MAX, f64::MIN), |a, &b| (a.0.min(b), a.1.max(b)));
    println!("time bias {:.6} .. {:.6} s", bmin, bmax);
    assert!((bmin - 0.020).abs() < 1e-6 && (bmax - 0.020).abs() < 1e-6);
    // Increments: the trapezoid of the quantised rates, equal to 1e-12; against the
    // unquantised rates within half a count x dt.
    let (mut eq_g, mut eq_a, mut q_g, mut q_a) = (0f64, 0f64, 0f64, 0f64);
    let deq = |x: f64, scale: f64| (x / scale).round() * scale;
    for (j, s) in got.iter().enumerate() {
        let (a, b) = (
            synth::synthetic_rate(j as u32),
            synth::synthetic_rate(j as u32 + 1),
        );
        assert!((s.dt - 0.020).abs() < 1e-9, "dt {}", s.dt);
        for k in 0..3 {
            let gq =
                |r: &ImuRate| deq(r.gyro[k].to_degrees(), esf::GYRO_DPS_PER_COUNT).to_radians();
            let aq = |r: &ImuRate| deq(r.accel[k], esf::ACCEL_MPS2_PER_COUNT);
            let want_g = 0.5 * (gq(&a) + gq(&b)) * s.dt;
            let want_a = 0.5 * (aq(&a) + aq(&b)) * s.dt;
            eq_g = eq_g.max((s.dtheta[k] - want_g).abs());
            eq_a = eq_a.max((s.dvel[k] - want_a).abs());
            q_g = q_g.max((s.dtheta[k] - 0.5 * (a.gyro[k] + b.gyro[k]) * s.dt).abs());
            q_a = q_a.max((s.dvel[k] - 0.5 * (a.accel[k] + b.accel[k]) * s.dt).abs());
        }
    }
    println!(
        "dtheta: vs quantised {eq_g:.2e} rad, vs true {q_g:.2e} rad (bound {:.2e}); dvel: {eq_a:.2e}, {q_a:.2e} m/s (bound {:.2e})",
        (0.5 * esf::GYRO_DPS_PER_COUNT).to_radians() * 0.02,
        0.5 * esf::ACCEL_MPS2_PER_COUNT * 0.02
    );
    assert!(eq_g < 1e-12 && eq_a < 1e-12);
    assert!(q_g <= (0.5 * esf::GYRO_DPS_PER_COUNT).to_radians() * 0.02 * (1.0 + 1e-9));
    assert!(q_a <= 0.5 * esf::ACCEL_MPS2_PER_COUNT * 0.02 * (1.0 + 1e-9));
}

#[test]
fn esf_meas_imu_when_there_is_no_esf_raw() {
    let mut st = Stream::default();
    for k in 0..600u32 {
        let s = synth::synthetic_rate(k);
        let f = synth::imu_fields(&s);
        // gyro and accel in two messages of the same time tag
        st.push(f64::from(k), synth::esf_meas(s.tag, &f[..3]));
        st.push(f64::from(k) + 0.1, synth::esf_meas(s.tag, &f[3..]));
        if k % 50 == 25 {
            st.push(
                f64::from(k) + 0.2,
                synth::nav_pvt(synth::ITOW0_MS + 20 * (k - 25)),
            );
        }
    }
    let p = tmp("meas.ubx", &st.finish());
    let mut r = open_imu(&imu_src(&p, 50.0)).unwrap();
    let got: Vec<_> = r.by_ref().map(|s| s.unwrap()).collect();
    assert_eq!(got.len(), 599);
    assert!(r.report().to_string().contains("ESF-MEAS"));
    // anchor: epoch ITOW0 + 20 (k - 25) ms paired with tag of sample k: no bias
    let t1 = f64::from(synth::ITOW0_MS) * 1e-3 + 0.020 * (1.0 - 25.0);
    assert!((got[0].t - t1).abs() < 1e-9, "{} {t1}", got[0].t);
}

#[test]
fn wheel_ticks_and_speed_round_trip() {
    let p = tmp("odo.ubx", &synth::synthetic_esf_log(10));
    let ticks = OdometerSource {
        path: p.clone(),
        format: OdometerFormat::Ubx(UbxOdometer::Ticks {
            meters_per_pulse: 0.02,
        }),
        skip_lines: None,
    };
    let mut w = Vec::new();
    let o = read_odometer_report(&ticks, &mut w).unwrap();
    assert_eq!(o.len(), 10 * 10 + 4);
    for s in &o {
        assert!((s.speed_mps - 10.0).abs() < 1e-9, "{s:?}");
        assert!((s.interval_s - 0.1).abs() < 1e-9);
    }
    let speed = OdometerSource {
        path: p,
        format: OdometerFormat::Ubx(UbxOdometer::Speed),
        skip_lines: None,
    };
    let o = read_odometer_report(&speed, &mut w).unwrap();
    assert_eq!(o.len(), 105);
    assert!(o.iter().all(|s| s.speed_mps == 10.0 && s.interval_s == 0.0));
    // ESF-MEAS epoch anchors: the last MEAS before each NAV (40 ms late) has the
    // tag of the epoch itself (10 Hz on whole tenths): no bias.
    let t0 = f64::from(synth::ITOW0_MS) * 1e-3 - 0.5;
    assert!((o[0].t - t0).abs() < 1e-9, "{}", o[0].t - t0);
}

#[test]
fn ticks_wrap_and_reverse() {
    assert_eq!(aiding::tick_delta(0x7F_FFF0, 0x10), 32.0);
    assert_eq!(aiding::tick_delta(100, 130 | 1 << 23), -30.0);
    // a counter counting down while reversing, direction bit set
    assert_eq!(aiding::tick_delta(130, 100 | 1 << 23), -30.0);
    // single ticks (type 10) at 10 Hz through the 23-bit wrap, the last second backwards
    let mut st = Stream::default();
    let mut count: u64 = (1 << 23) - 200;
    for k in 0..50u32 {
        let back = k >= 40;
        st.push(
            f64::from(k),
            synth::esf_meas(1000 + 100 * k, &[(10, synth::tick_field(count, back))]),
        );
        count += 37;
        if k % 10 == 0 {
            st.push(
                f64::from(k) + 0.5,
                synth::nav_pvt(synth::ITOW0_MS + 100 * k),
            );
        }
    }
    let p = tmp("wrap.ubx", &st.finish());
    let src = OdometerSource {
        path: p,
        format: OdometerFormat::Ubx(UbxOdometer::Ticks {
            meters_per_pulse: 0.01,
        }),
        skip_lines: None,
    };
    let o = read_odometer_report(&src, &mut Vec::new()).unwrap();
    assert_eq!(o.len(), 49);
    for (k, s) in o.iter().enumerate() {
        let want = if k + 1 >= 40 { -3.7 } else { 3.7 };
        assert!((s.speed_mps - want).abs() < 1e-9, "{k} {s:?}");
    }
}

#[test]
fn relposned_headings_v0_and_v1() {
    let p = tmp("hdg.ubx", &synth::synthetic_esf_log(8));
    let log = navfuse_io::ubx::read_ubx(&p).unwrap();
    assert_eq!(log.relpos.len(), 8);
    assert_eq!(log.relpos[1].version, 0);
    let mut w = Vec::new();
    let h = aiding::headings(&p, &log, UbxHeading { float_ok: false }, &mut w).unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(h.len(), 8);
    let mut worst = (0f64, 0f64);
    for (s, o) in h.iter().enumerate() {
        let want = (30.0 + 2.0 * s as f64).to_radians();
        assert!((o.t - (f64::from(synth::ITOW0_MS) * 1e-3 + s as f64)).abs() < 1e-9);
        let e = (o.heading_rad - want).abs().to_degrees();
        if s == 1 {
            worst.1 = e; // version 0: from N/E at 0.1 mm over 1.2 m
            assert!(e < 0.01, "{e}");
            let std = o.std_rad.to_degrees();
            // 4 mm on both axes over 1.2 m
            assert!((std - (0.004f64 / 1.2).to_degrees()).abs() < 1e-3, "{std}");
        } else {
            worst.0 = worst.0.max(e);
            assert!(e <= 0.5e-5 + 1e-12, "{e}");
            assert!((o.std_rad.to_degrees() - 0.3).abs() < 1e-9);
        }
    }
    println!(
        "heading round trip: v1 {:.1e} deg, v0 {:.1e} deg",
        worst.0, worst.1
    );
}

#[test]
fn relposned_flags_decide() {
    let mut st = Stream::default();
    let flags = [
        synth::RELPOS_OK,
        synth::RELPOS_OK & !synth::HEADING_VALID,
        synth::RELPOS_OK & !synth::GNSS_FIX_OK,
        (synth::RELPOS_OK & !synth::CARR_FIXED) | synth::CARR_FLOAT,
        synth::RELPOS_OK & !synth::CARR_FIXED,
        synth::RELPOS_OK,
    ];
    for (k, f) in flags.iter().enumerate() {
        st.push(
            k as f64,
            synth::relposned_v1(synth::ITOW0_MS + 1000 * k as u32, 10.0, 0.5, *f),
        );
    }
    // a repeated epoch
    st.push(
        9.0,
        synth::relposned_v1(synth::ITOW0_MS + 5000, 10.0, 0.5, synth::RELPOS_OK),
    );
    let p = tmp("flags.ubx", &st.finish());
    let log = navfuse_io::ubx::read_ubx(&p).unwrap();
    let mut w = Vec::new();
    let fixed = aiding::headings(&p, &log, UbxHeading { float_ok: false }, &mut w).unwrap();
    assert_eq!(fixed.len(), 2);
    assert!(
        w.iter()
            .any(|m| m.contains("field 'iTOW'") && m.contains("byte ")),
        "{w:?}"
    );
    let float = aiding::headings(&p, &log, UbxHeading { float_ok: true }, &mut w).unwrap();
    assert_eq!(float.len(), 3);
}

#[test]
fn damage_is_warned_never_a_panic() {
    let good = synth::synthetic_esf_log(12);
    // checksum damage in the middle, an incomplete sample, a duplicated and an
    // out-of-order sample, a malformed ESF-MEAS
    let mut d = good.clone();
    let mid = d.len() / 2;
    d[mid] ^= 0x55;
    let t = |k| synth::synthetic_rate(k);
    let mut a = synth::imu_fields(&t(2000)).to_vec();
    a.pop();
    let blocks: Vec<(u8, u32, u32)> = a.iter().map(|&(ty, f)| (ty, f, t(2000).tag)).collect();
    d.extend(synth::esf_raw_blocks(&blocks));
    d.extend(synth::esf_raw(&[t(2001)]));
    d.extend(synth::esf_raw(&[t(2001)]));
    d.extend(synth::esf_raw(&[t(1990)]));
    d.extend(synth::frame(0x10, 0x02, &[1, 2, 3, 4, 0, 0x10, 0, 0]));
    d.extend(synth::frame(0x01, 0x3C, &[7; 64]));
    let log = decode_ubx(&d, "damaged.ubx");
    for w in &log.warnings {
        println!("{w}");
    }
    let has = |s: &str| log.warnings.iter().any(|w| w.contains(s));
    assert!(has("UBX checksum error"));
    assert!(has("no data type [18]: sample dropped"));
    assert!(has("duplicated"));
    assert!(has("out of order"));
    assert!(has("ESF-MEAS: field 'numMeas'"));
    assert!(has("NAV-RELPOSNED: field 'version': 7"));
    assert!(log.esf.counts.dropped_imu >= 3);
    // every truncation of the log decodes
    for cut in (0..good.len()).step_by(97) {
        let l = decode_ubx(&good[..cut], "cut.ubx");
        let _ = l.summary();
    }
}

#[test]
fn clear_errors_without_the_messages() {
    // a NAV-PVT-only log: no IMU, no odometer, no heading
    let p = tmp("pvt_only.ubx", &synth::nav_pvt(synth::ITOW0_MS));
    let e = open_imu(&imu_src(&p, 50.0)).err().unwrap().to_string();
    assert!(
        e.contains("pvt_only.ubx")
            && e.contains("no IMU samples")
            && e.contains("ESF-RAW (0x10 0x03)"),
        "{e}"
    );
    let src = OdometerSource {
        path: p.clone(),
        format: OdometerFormat::Ubx(UbxOdometer::Speed),
        skip_lines: None,
    };
    let e = read_odometer_report(&src, &mut Vec::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("speed (data type 11)"), "{e}");
    let log = navfuse_io::ubx::read_ubx(&p).unwrap();
    let e = aiding::headings(&p, &log, UbxHeading { float_ok: false }, &mut Vec::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no NAV-RELPOSNED (0x01 0x3C)"), "{e}");
    // IMU data but no navigation epoch: the time cannot be mapped, refused
    let rates: Vec<ImuRate> = (0..10).map(synth::synthetic_rate).collect();
    let p = tmp("no_nav.ubx", &synth::esf_raw(&rates));
    let e = open_imu(&imu_src(&p, 50.0)).err().unwrap().to_string();
    assert!(
        e.contains("field 'sTtag'") && e.contains("cannot map the sensor time tags"),
        "{e}"
    );
}
