//! The backward (time-reversed) run of navfuse-core (`run_backward`) on simulated
//! drives with truth, against the forward run (`run`) on the same inputs: loose GNSS,
//! NHC + odometer + ZUPT, tight coupling (pseudorange + Doppler, pseudorange + TDCP),
//! barometer, GNSS-IMU time offset estimation, and the integrity monitor under a
//! spoofing attack. Both runs start from the truth with the configured uncertainty
//! (forward at the first IMU epoch, backward at the last); the figures are printed
//! (`cargo test --release -p navfuse-experiments --test backward -- --nocapture`).

use nalgebra::UnitQuaternion;
use navfuse_app::config::RunConfig;
use navfuse_core::attitude::euler_from_q_bn;
use navfuse_core::config::{NhcMode, RangeRate, TimeOffsetConfig};
use navfuse_core::earth::lla_diff_ned;
use navfuse_core::integrity::IntegrityState;
use navfuse_core::outage::{OutageSchedule, Window};
use navfuse_core::{
    run, run_backward, BackwardStart, ImuSample, Measurement, NavError, NavState, Navigator,
    RunSummary,
};
use navfuse_io::input::GnssFormat;
use navfuse_sim::scenario::Scenario;
use std::collections::HashMap;
use std::path::PathBuf;

const T0: f64 = 345_600.0;

/// A car drive of about 290 s (the seed scenarios' site, 21 N): standing 10 s, turns, a lane change, a stop
/// of 15 s in the middle, standing 10 s at the end; ADIS16405 at 100 Hz (turn-on
/// biases 180 deg/h, 5 mg), GNSS at 1 Hz. `gnss`: the rest of `[gnss]` (fixes or raw,
/// events); `extra`: more sections.
fn car(seed: u64, gnss: &str, extra: &str) -> String {
    format!(
        r#"seed = {seed}
description = "backward filter test drive"

[start]
gps_week = 2381
time_s = {T0}
position_deg_m = [21.0285, 105.8542, 15.0]
heading_deg = 30

[vehicle]
imu_mounting_deg = [0.0, 0.3, -0.4]
imu_to_reference_m = [-0.8, 0.0, 0.3]

[imu]
grade = "adis16405"
gyro_bias_degph = 180
accel_bias_mg = 5
rate_hz = 100

{extra}

[gnss]
rate_hz = 1
antenna_lever_arm_m = [0.3, 0.0, -1.0]
{gnss}

[[segment]]
type = "static"
duration_s = 10

[[segment]]
type = "accelerate"
accel_mps2 = 1.5
to_speed_mps = 12
ramp_s = 1

[[segment]]
type = "hold"
duration_s = 25

[[segment]]
type = "turn"
rate_dps = 12
angle_deg = 90
ramp_s = 1.5

[[segment]]
type = "hold"
duration_s = 20

[[segment]]
type = "lane_change"
width_m = 3.5
duration_s = 5

[[segment]]
type = "hold"
duration_s = 15

[[segment]]
type = "turn"
rate_dps = -10
angle_deg = -120
ramp_s = 1.5

[[segment]]
type = "accelerate"
accel_mps2 = -1.0
to_speed_mps = 0
ramp_s = 1

[[segment]]
type = "static"
duration_s = 15

[[segment]]
type = "accelerate"
accel_mps2 = 1.0
to_speed_mps = 10
ramp_s = 1

[[segment]]
type = "hold"
duration_s = 30

[[segment]]
type = "turn"
rate_dps = 9
angle_deg = 180
ramp_s = 2

[[segment]]
type = "hold"
duration_s = 40

[[segment]]
type = "turn"
rate_dps = -9
angle_deg = -90
ramp_s = 2

[[segment]]
type = "hold"
duration_s = 20

[[segment]]
type = "accelerate"
accel_mps2 = -1.0
to_speed_mps = 0
ramp_s = 1

[[segment]]
type = "static"
duration_s = 10
"#
    )
}

const FIXES: &str = "raw = false\n\n[gnss.fix]\nhorizontal_std_m = 1.5\nvertical_std_m = 3.0\ncorr_time_s = 30\nvelocity_std_mps = 0.05\n";
const RAW: &str = "raw = true\n\n[gnss.errors]\nsa_m = 0\n";

/// A scratch directory, removed at the end.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Simulated inputs with their truth.
struct Sim {
    cfg: RunConfig,
    imu: Vec<ImuSample>,
    meas: Vec<Measurement>,
    /// Truth by time key (ms).
    truth: HashMap<i64, NavState>,
}

fn key(t: f64) -> i64 {
    (t * 1000.0).round() as i64
}

/// Simulate `text` and read what the simulator wrote with its run.toml's
/// configuration (the files are removed afterwards).
fn simulate(name: &str, text: &str) -> Sim {
    let dir = std::env::temp_dir().join(format!("navfuse-backward-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let _scratch = Scratch(dir.clone());
    let sc = Scenario::from_text(&dir.join("scenario.toml"), text.to_string()).unwrap();
    navfuse_sim::generate::generate(&sc, &dir).unwrap();
    let cfg = navfuse_sim::run_config::run_config(&sc, &dir);
    let (imu, meas) = read_inputs(&cfg);
    let truth = navfuse_io::nav::read_nav(&dir.join("truth.nav"))
        .unwrap()
        .into_iter()
        .map(|(_, s)| (key(s.t), s))
        .collect();
    Sim {
        cfg,
        imu,
        meas,
        truth,
    }
}

/// The IMU samples and the merged measurements of `cfg` (as navfuse-app reads them).
fn read_inputs(cfg: &RunConfig) -> (Vec<ImuSample>, Vec<Measurement>) {
    let imu: Vec<ImuSample> = navfuse_io::imu::open_imu(&cfg.imu)
        .unwrap()
        .map(|r| r.unwrap())
        .collect();
    let (mut fixes, mut raw) = (Vec::new(), Vec::new());
    if let Some(src) = &cfg.gnss {
        match &src.format {
            GnssFormat::Rinex(r) => {
                raw = navfuse_app::gnss_input::load_rinex(src, r, &cfg.nav.gnss.systems)
                    .unwrap()
                    .raw
            }
            _ => fixes = navfuse_io::gnss::read_gnss(src).unwrap().fixes,
        }
    }
    let mut warnings = Vec::new();
    let odometer = match &cfg.odometer {
        Some(src) => navfuse_io::odometer::read_odometer_report(src, &mut warnings).unwrap(),
        None => Vec::new(),
    };
    let other = navfuse_io::input::read_aiding_inputs(cfg, &mut warnings).unwrap();
    let meas = navfuse_core::merge_more(
        navfuse_core::merge_raw_epochs(
            navfuse_core::merge_measurements(&fixes, &odometer, &[]),
            raw,
        ),
        other,
    );
    (imu, meas)
}

/// One run's output, per IMU epoch: (IMU time, GNSS time, state, integrity state).
struct Track {
    epochs: Vec<(f64, f64, NavState, IntegrityState)>,
    summary: RunSummary,
}

fn record(out: &mut Vec<(f64, f64, NavState, IntegrityState)>, n: &Navigator) {
    out.push((n.nav().t, n.time_gnss(), *n.nav(), n.integrity_state()));
}

fn forward(cfg: &RunConfig, imu: &[ImuSample], meas: &[Measurement]) -> Track {
    let mut epochs = Vec::new();
    let summary = run::<NavError>(
        &cfg.nav,
        imu.iter().map(|s| Ok(*s)),
        meas,
        None,
        |n| {
            record(&mut epochs, n);
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    Track { epochs, summary }
}

/// Backward from the truth at the last IMU epoch (`time_shift`: IMU time minus GPS
/// time), with the configuration's initial uncertainty and IMU errors.
fn backward(sim: &Sim, cfg: &RunConfig, imu: &[ImuSample], time_shift: f64) -> Track {
    let last = imu.last().unwrap().t;
    let truth = sim.truth[&key(last - time_shift)];
    let start = BackwardStart {
        t: last,
        lla: truth.lla,
        v_n: truth.v_n,
        rpy: euler_from_q_bn(&truth.q_bn),
    };
    let mut epochs = Vec::new();
    let summary = run_backward::<NavError>(
        &cfg.nav,
        |_, _| Vec::new(),
        start,
        imu.iter().rev().map(|s| Ok(*s)),
        &sim.meas,
        None,
        |n| {
            record(&mut epochs, n);
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    Track { epochs, summary }
}

/// RMS horizontal, vertical \[m\] and attitude \[deg\] errors over the epochs on whole
/// tenths of a second whose GPS time (IMU time - `time_shift`) is in \[a, b\], and
/// their count; every state must be finite.
fn rms(sim: &Sim, tr: &Track, time_shift: f64, a: f64, b: f64) -> (f64, f64, f64, usize) {
    let (mut h, mut v, mut att, mut n) = (0.0, 0.0, 0.0, 0usize);
    for (t_imu, _, s, _) in &tr.epochs {
        assert!(
            s.lla.iter().chain(s.v_n.iter()).all(|x| x.is_finite()),
            "not finite at {t_imu}"
        );
        let t = t_imu - time_shift;
        if t < a - 1e-6 || t > b + 1e-6 || key(t) % 100 != 0 {
            continue;
        }
        let Some(truth) = sim.truth.get(&key(t)) else {
            continue;
        };
        let d = lla_diff_ned(&s.lla, &truth.lla);
        let dq: UnitQuaternion<f64> = s.q_bn * truth.q_bn.inverse();
        h += d.xy().norm_squared();
        v += d.z * d.z;
        att += dq.angle().to_degrees().powi(2);
        n += 1;
    }
    let k = n.max(1) as f64;
    ((h / k).sqrt(), (v / k).sqrt(), (att / k).sqrt(), n)
}

type Rms = (f64, f64, f64);

/// Forward and backward over the same data: both to their ends, the backward one in
/// decreasing time, finite everywhere; the figures printed. Returns the RMS (h, v,
/// att) over `span` (GPS time; the whole run when None) and the two tracks.
fn compare(
    label: &str,
    sim: &Sim,
    cfg: &RunConfig,
    imu: &[ImuSample],
    time_shift: f64,
    span: Option<(f64, f64)>,
) -> (Rms, Rms, Track, Track) {
    let f = forward(cfg, imu, &sim.meas);
    let b = backward(sim, cfg, imu, time_shift);
    // The backward run reaches the first sample's lower end.
    let (first, last) = (imu[0], imu[imu.len() - 1]);
    assert!((f.epochs.last().unwrap().0 - last.t).abs() < 1e-6);
    assert!((b.epochs.last().unwrap().0 - (first.t - first.dt)).abs() < 1e-6);
    assert!(b.epochs.windows(2).all(|w| w[1].0 < w[0].0));
    // Forward has no record at the first epoch, backward none at the last.
    let (a, z) = span.unwrap_or((first.t - time_shift + 0.5, last.t - time_shift - 0.5));
    let rf = rms(sim, &f, time_shift, a, z);
    let rb = rms(sim, &b, time_shift, a, z);
    assert!(rf.3 > 10 && rb.3 == rf.3, "{} {} epochs", rf.3, rb.3);
    eprintln!(
        "{label}: RMS horizontal / vertical / attitude over {:.0}-{:.0} s ({} epochs): forward {:.3} m / {:.3} m / {:.4} deg, backward {:.3} m / {:.3} m / {:.4} deg",
        a - T0,
        z - T0,
        rf.3,
        rf.0,
        rf.1,
        rf.2,
        rb.0,
        rb.1,
        rb.2
    );
    ((rf.0, rf.1, rf.2), (rb.0, rb.1, rb.2), f, b)
}

fn used(s: &RunSummary, name: &str) -> usize {
    s.aiding_used.get(name).copied().unwrap_or(0)
}

fn outage(a: f64, b: f64) -> OutageSchedule {
    OutageSchedule {
        windows: vec![Window { start: a, end: b }],
        periodic: Vec::new(),
    }
}

/// Loose GNSS (fixes with velocity, Gauss-Markov fix errors) with a configured 30 s
/// outage in the middle of the drive (as much data before it either way), four
/// seeds: the backward run's errors are comparable to the forward run's (the RMS over
/// the seeds within 1.5x), the same fixes are withheld, and the errors inside the
/// outage are of the same order (which run does better varies with the seed).
#[test]
fn loose_gnss_backward_is_as_good_as_forward() {
    let (a, b) = (T0 + 128.0, T0 + 158.0);
    let mean_sq = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let (mut fh, mut bh, mut fo, mut bo) = (vec![], vec![], vec![], vec![]);
    for seed in 1..=4 {
        let sim = simulate(&format!("loose{seed}"), &car(seed, FIXES, ""));
        let mut cfg = sim.cfg.clone();
        cfg.nav.gnss.outages = outage(a, b);
        let label = format!("loose GNSS, seed {seed}");
        let (f, bw, ft, bt) = compare(&label, &sim, &cfg, &sim.imu, 0.0, None);
        assert_eq!(ft.summary.gnss_in_outage, 29);
        assert_eq!(bt.summary.gnss_in_outage, 29);
        assert!(bt.summary.gnss_used + 2 >= ft.summary.gnss_used);
        assert!(bw.1 <= 3.0 * f.1 + 0.3 && bw.2 <= 2.0 * f.2 + 0.1);
        let (fr, br) = (rms(&sim, &ft, 0.0, a, b), rms(&sim, &bt, 0.0, a, b));
        eprintln!(
            "  inside the 30 s outage: forward {:.3} m / {:.3} m, backward {:.3} m / {:.3} m (horizontal / vertical RMS); fixes used {} / {}",
            fr.0, fr.1, br.0, br.1, ft.summary.gnss_used, bt.summary.gnss_used
        );
        fh.push(f.0);
        bh.push(bw.0);
        fo.push(fr.0);
        bo.push(br.0);
    }
    let (fh, bh, fo, bo) = (mean_sq(&fh), mean_sq(&bh), mean_sq(&fo), mean_sq(&bo));
    eprintln!(
        "loose GNSS over 4 seeds: horizontal RMS forward {fh:.3} m, backward {bh:.3} m; in the outage forward {fo:.3} m, backward {bo:.3} m"
    );
    assert!(bh <= 1.5 * fh, "horizontal: backward {bh} forward {fh}");
    assert!(bo <= 2.0 * fo, "outage: backward {bo} forward {fo}");
}

/// NHC (always, 2 Hz), odometer with scale and mounting states, ZUPT at the stops,
/// GNSS out for 60 s: the backward run fuses each kind about as often, finds the
/// odometer scale, and keeps the outage errors of the same order.
#[test]
fn nhc_odometer_and_zupt_backward() {
    let odo = "[odometer]\nrate_hz = 10\nscale_error_ppm = 2000\n";
    let sim = simulate("nhc", &car(5, FIXES, odo));
    let mut cfg = sim.cfg.clone();
    cfg.nav.nhc.mode = NhcMode::Always;
    cfg.nav.nhc.rate_hz = 2.0;
    cfg.nav.zupt.enabled = true;
    // The ADIS16405's white noise at 100 Hz is above the default thresholds.
    cfg.nav.zupt.accel_std_max = 0.15;
    cfg.nav.zupt.gyro_max = 1.5f64.to_radians();
    let (a, b) = (T0 + 113.0, T0 + 173.0);
    cfg.nav.gnss.outages = outage(a, b);
    let (f, bw, ft, bt) = compare("NHC + odometer + ZUPT", &sim, &cfg, &sim.imu, 0.0, None);
    assert!(
        bw.0 <= 1.5 * f.0 + 0.05,
        "horizontal: backward {} forward {}",
        bw.0,
        f.0
    );
    let (fo, bo) = (rms(&sim, &ft, 0.0, a, b), rms(&sim, &bt, 0.0, a, b));
    eprintln!(
        "  inside the 60 s outage: forward {:.3} m, backward {:.3} m horizontal RMS",
        fo.0, bo.0
    );
    assert!(bo.0 < 3.0 * fo.0 + 0.5);
    for k in ["nhc", "odometer", "zupt"] {
        let (nf, nb) = (used(&ft.summary, k), used(&bt.summary, k));
        eprintln!("  {k}: forward {nf} used, backward {nb}");
        assert!(nf > 20 && nb as f64 > 0.8 * nf as f64 && (nb as f64) < 1.25 * nf as f64);
    }
    eprintln!(
        "  static: forward {:.1} s, backward {:.1} s; odometer scale forward {:?}, backward {:?} (true 2000 ppm)",
        ft.summary.static_s,
        bt.summary.static_s,
        ft.summary.odometer_scale,
        bt.summary.odometer_scale
    );
    assert!((bt.summary.static_s - ft.summary.static_s).abs() < 3.0);
    let (kb, sb) = bt.summary.odometer_scale.unwrap();
    assert!(
        (kb - 2e-3).abs() < 3.0 * sb + 5e-4,
        "backward odometer scale {kb} +- {sb}"
    );
}

/// Tight coupling on the raw observations, pseudorange + Doppler and pseudorange +
/// TDCP (the simulator's run.toml), with the receiver clock states.
#[test]
fn tight_coupling_backward() {
    let sim = simulate("tight", &car(7, RAW, ""));
    assert!(sim.cfg.nav.tight.enabled);
    for rr in [RangeRate::Doppler, RangeRate::Tdcp] {
        let mut cfg = sim.cfg.clone();
        cfg.nav.tight.range_rate = rr;
        let label = format!("tight, pseudorange + {rr:?}");
        let (f, bw, ft, bt) = compare(&label, &sim, &cfg, &sim.imu, 0.0, None);
        let kind = if rr == RangeRate::Tdcp {
            "tdcp"
        } else {
            "doppler"
        };
        let (nf, nb) = (used(&ft.summary, kind), used(&bt.summary, kind));
        let (pf, pb) = (
            used(&ft.summary, "pseudorange"),
            used(&bt.summary, "pseudorange"),
        );
        eprintln!("  {kind} rows used: forward {nf}, backward {nb}; pseudoranges {pf} / {pb}");
        assert!(
            nf > 1000 && nb as f64 > 0.8 * nf as f64,
            "{kind}: {nf} {nb}"
        );
        assert!(pb as f64 > 0.9 * pf as f64);
        assert!(
            bw.0 <= 1.5 * f.0 + 0.3,
            "horizontal: backward {} forward {}",
            bw.0,
            f.0
        );
        assert!(bw.1 <= 2.0 * f.1 + 0.5);
    }
}

/// The barometer (its bias state set from its first reading, a random walk) with
/// GNSS fixes and a 60 s outage: the vertical errors in the outage are of the same
/// order.
#[test]
fn barometer_backward() {
    let baro = "[baro]\nrate_hz = 10\nnoise_std_m = 0.3\nbias_m = 5\n";
    let sim = simulate("baro", &car(9, FIXES, baro));
    let mut cfg = sim.cfg.clone();
    assert!(cfg.nav.baro.enabled);
    let (a, b) = (T0 + 113.0, T0 + 173.0);
    cfg.nav.gnss.outages = outage(a, b);
    let (f, bw, ft, bt) = compare("barometer", &sim, &cfg, &sim.imu, 0.0, None);
    assert!(bw.0 <= 1.5 * f.0 + 0.05 && bw.1 <= 2.0 * f.1 + 0.1);
    let (fo, bo) = (rms(&sim, &ft, 0.0, a, b), rms(&sim, &bt, 0.0, a, b));
    let (nf, nb) = (used(&ft.summary, "baro"), used(&bt.summary, "baro"));
    let bias = |s: &RunSummary| s.source_states.first().map(|s| (s.value[0], s.std[0]));
    eprintln!(
        "  inside the 60 s outage: vertical RMS forward {:.3} m, backward {:.3} m; readings fused {nf} / {nb}; bias (value, std) forward {:?} (at the end), backward {:?} (at the start)",
        fo.1,
        bo.1,
        bias(&ft.summary),
        bias(&bt.summary)
    );
    assert!(nf > 2000 && nb as f64 > 0.9 * nf as f64);
    assert!(bo.1 < 3.0 * fo.1 + 0.5);
}

/// IMU time tags 80 ms late, the offset estimated (0.2 s std, no first pass): both
/// runs find it, the backward one from the end starting again from 0.
#[test]
fn time_offset_backward() {
    let sim = simulate("offset", &car(11, FIXES, ""));
    let shift = 0.08;
    let imu: Vec<ImuSample> = sim
        .imu
        .iter()
        .map(|s| ImuSample {
            t: s.t + shift,
            ..*s
        })
        .collect();
    let mut cfg = sim.cfg.clone();
    cfg.nav.start_time += shift;
    cfg.nav.filter.time_offset = Some(TimeOffsetConfig {
        std_s: 0.2,
        ..TimeOffsetConfig::default()
    });
    let first = imu[0].t - shift;
    let span = Some((first + 30.0, imu.last().unwrap().t - shift - 30.0));
    let (f, bw, ft, bt) = compare("time offset", &sim, &cfg, &imu, shift, span);
    let (of, ob) = (
        ft.summary.time_offset.unwrap(),
        bt.summary.time_offset.unwrap(),
    );
    eprintln!(
        "  offset estimate (true {shift} s): forward {:.4} +- {:.4} s (at the end), backward {:.4} +- {:.4} s (at the start)",
        of.0, of.1, ob.0, ob.1
    );
    assert!((of.0 - shift).abs() < 0.01 && (ob.0 - shift).abs() < 0.01);
    assert!(bw.0 <= 1.5 * f.0 + 0.05);
    // The records' GNSS time is the IMU time minus the estimate (mid-run here).
    let (t_imu, t_gnss, _, _) = bt.epochs[bt.epochs.len() / 2];
    eprintln!("  backward estimate mid-run: {:.4} s", t_imu - t_gnss);
    assert!((t_imu - t_gnss - shift).abs() < 0.025);
}

/// A drift spoofing attack (1.5 m/s east from 120 s to 200 s: 120 m off at its end),
/// the integrity monitor on, odometer + NHC: the forward run sees it grow, the
/// backward run sees it appear at its end (a jump); both flag the attacked epochs.
#[test]
fn integrity_monitor_flags_the_spoofed_epochs_backward() {
    let odo = "[odometer]\nrate_hz = 10\nscale_error_ppm = 1000\n";
    let spoof = format!(
        "{FIXES}\n[[gnss.event]]\ntype = \"spoof\"\nmode = \"drift\"\nstart_s = 120\nend_s = 200\nvelocity_mps = [0.0, 1.5, 0.0]\n"
    );
    let sim = simulate("spoof", &car(13, &spoof, odo));
    let mut cfg = sim.cfg.clone();
    cfg.nav.integrity.enabled = true;
    cfg.nav.integrity.gnss_corr_time_s = 30.0;
    cfg.nav.nhc.mode = NhcMode::Always;
    cfg.nav.nhc.rate_hz = 2.0;
    let (f, bw, ft, bt) = compare("spoofing + monitor", &sim, &cfg, &sim.imu, 0.0, None);
    // Integrity states at whole seconds inside the attack and outside it.
    let flags = |tr: &Track| -> (usize, usize, usize, usize) {
        let (mut inside, mut flagged_in, mut outside, mut flagged_out) = (0, 0, 0, 0);
        for (_, tg, _, st) in &tr.epochs {
            let t = tg - T0;
            if key(t) % 1000 != 0 {
                continue;
            }
            let bad = *st != IntegrityState::Trusted;
            // Left out: the first 15 s of the attack (what the window test needs to
            // see a drift forward) and 15 s around each end (re-admission).
            if t > 135.0 && t < 200.0 {
                inside += 1;
                flagged_in += usize::from(bad);
            } else if !(105.0..=215.0).contains(&t) {
                outside += 1;
                flagged_out += usize::from(bad);
            }
        }
        (inside, flagged_in, outside, flagged_out)
    };
    let (fi, ffi, fo, ffo) = flags(&ft);
    let (bi, bfi, bo, bfo) = flags(&bt);
    let first_alarm = |tr: &Track| {
        tr.summary
            .events
            .iter()
            .find_map(|e| match e {
                navfuse_core::Event::Integrity(t) if t.to != IntegrityState::Trusted => {
                    Some(format!("{:.0} s ({})", t.t - T0, t.detector.name()))
                }
                _ => None,
            })
            .unwrap_or_default()
    };
    eprintln!(
        "  attacked epochs flagged: forward {ffi}/{fi}, backward {bfi}/{bi}; flagged outside: forward {ffo}/{fo}, backward {bfo}/{bo}; first alarm forward {}, backward {}",
        first_alarm(&ft),
        first_alarm(&bt)
    );
    assert!(ffi as f64 >= 0.9 * fi as f64 && bfi as f64 >= 0.9 * bi as f64);
    assert!(ffo <= 2 && bfo <= 2);
    // The false track stays out of the solution both ways.
    assert!(f.0 < 5.0 && bw.0 < 5.0, "forward {} backward {}", f.0, bw.0);
}
