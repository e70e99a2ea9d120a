//! Issue 30 part A: the rows of one epoch linearised together (TDCP) fused one-shot
//! or one at a time give the same state, and the per-row bookkeeping agrees; the old
//! way (each row re-linearised with the displacement fixed at the epoch's start)
//! applies the velocity correction again. Random geometry, covariance, lever arm,
//! interval and number of rows.

use super::source::{EpochUpdate, Fuser, Shared};
use super::tdcp::{Interval, TdcpPrevious};
use super::{Aiding, Linearized, ReceiverClock};
use crate::earth::{c_ne, lla_diff_ned, lla_to_ecef};
use crate::events::{AidStatus, RunSummary};
use crate::nav::ins_filter::{BlockProcess, BlockSpec, Fused, InsFilter};
use crate::nav::tests::cfg;
use crate::sat::SatId;
use crate::state::{Block, ATT, POS, VEL};
use crate::types::SatMeasurement;
use nalgebra::{DMatrix, DVector, Vector3};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;

/// One epoch of TDCP rows with its truth.
struct Scene {
    lla: Vector3<f64>,
    rpy: Vector3<f64>,
    v_n: Vector3<f64>,
    lever_arm_b: Vector3<f64>,
    p: DMatrix<f64>,
    sats: Vec<SatMeasurement>,
    prevs: Vec<TdcpPrevious>,
    interval: Interval,
    drift_mps: f64,
}

fn normal(rng: &mut Pcg64) -> f64 {
    StandardNormal.sample(rng)
}

/// Log-uniform in [a, b].
fn log_uniform(rng: &mut Pcg64, a: f64, b: f64) -> f64 {
    (a.ln() + rng.random::<f64>() * (b / a).ln()).exp()
}

fn blocks() -> Vec<BlockSpec> {
    [Block::ClockBias, Block::ClockDrift]
        .into_iter()
        .map(|block| BlockSpec {
            block,
            initial_variance: vec![1.0],
            process: BlockProcess::RandomWalk(0.0),
        })
        .collect()
}

/// A random covariance of the layout's size: per-state sigmas (log-uniform over the
/// plausible range of each kind of state) times a random correlation matrix.
fn random_covariance(rng: &mut Pcg64, ins: &InsFilter) -> DMatrix<f64> {
    let n = ins.layout.len();
    let mut sigma = DVector::zeros(n);
    let range = |i: usize| match i {
        0..=2 => (0.3, 30.0),    // position [m]
        3..=5 => (0.01, 3.0),    // velocity [m/s]
        6..=8 => (1e-4, 3e-2),   // attitude [rad]
        9..=11 => (1e-7, 1e-4),  // gyro bias [rad/s]
        12..=14 => (1e-4, 3e-2), // accelerometer bias [m/s²]
        15..=20 => (1e-5, 1e-3), // scale factors
        21 => (0.1, 30.0),       // clock bias [m]
        _ => (0.01, 3.0),        // clock drift [m/s]
    };
    for i in 0..n {
        let (a, b) = range(i);
        sigma[i] = log_uniform(rng, a, b);
    }
    let b = DMatrix::from_fn(n, n, |_, _| normal(rng));
    let mut c = &b * b.transpose() + DMatrix::identity(n, n) * (0.2 * n as f64);
    let d = c.diagonal().map(|x| 1.0 / x.sqrt());
    for i in 0..n {
        for j in 0..n {
            c[(i, j)] *= d[i] * d[j] * sigma[i] * sigma[j];
        }
    }
    c
}

/// A random site (|lat| <= 80 deg, any longitude), motion, lever arm, satellites
/// (5-85 deg elevation, any azimuth), interval, and an INS with velocity error
/// `dv_n` (its displacement over the interval is the true one plus dv dt).
fn scene(rng: &mut Pcg64, m: usize, dv_n: Vector3<f64>) -> Scene {
    let lla = Vector3::new(
        rng.random_range(-80.0f64..80.0).to_radians(),
        rng.random_range(-180.0f64..180.0).to_radians(),
        rng.random_range(-50.0..3000.0),
    );
    let rpy = Vector3::new(
        rng.random_range(-0.3..0.3),
        rng.random_range(-0.3..0.3),
        rng.random_range(-3.1..3.1),
    );
    let v_true = Vector3::new(normal(rng), normal(rng), 0.1 * normal(rng)) * 10.0;
    let lever_arm_b = Vector3::new(normal(rng), normal(rng), normal(rng)) * 0.7;
    let dt = rng.random_range(0.2..2.0);
    let drift_mps = 100.0 * normal(rng);
    let cne = c_ne(lla.x, lla.y);
    let c_bn = crate::attitude::c_bn_from_euler(&rpy);
    let r_ant = lla_to_ecef(&lla) + cne * c_bn * lever_arm_b;
    // The INS velocity is v_true + dv (no rotation: the antenna moves with the IMU).
    let v_ins = v_true + dv_n;
    let d_true = cne * v_true * dt;
    let interval = Interval {
        antenna_displacement_ecef_m: cne * v_ins * dt,
        dt_s: dt,
    };
    let mut sats = Vec::new();
    let mut prevs = Vec::new();
    for k in 0..m {
        let (az, el) = (
            rng.random_range(0.0..std::f64::consts::TAU),
            rng.random_range(5.0f64..85.0).to_radians(),
        );
        let u_n = Vector3::new(az.cos() * el.cos(), az.sin() * el.cos(), -el.sin());
        let s_k = r_ant + cne * u_n * rng.random_range(2.0e7..2.6e7);
        let v_sat = Vector3::new(normal(rng), normal(rng), normal(rng)).normalize() * 3.9e3;
        let s_prev = s_k - v_sat * dt;
        let carrier_std_m = log_uniform(rng, 1e-3, 5e-3);
        // Carrier change: the true range change, the clock drift, noise.
        let dphi = (s_k - r_ant).norm() - (s_prev - (r_ant - d_true)).norm()
            + drift_mps * dt
            + carrier_std_m * std::f64::consts::SQRT_2 * normal(rng);
        let carrier_prev = 1e3 * normal(rng);
        sats.push(SatMeasurement {
            sat: SatId::gps(k as u8 + 1),
            sat_pos_ecef_m: s_k,
            sat_vel_ecef_mps: v_sat,
            elevation_rad: el,
            pseudorange_m: None,
            pseudorange_std_m: 3.0,
            range_rate_mps: None,
            range_rate_std_mps: 0.1,
            carrier_m: Some(carrier_prev + dphi),
            carrier_std_m,
            lost_lock: false,
            dgps: false,
        });
        prevs.push(TdcpPrevious {
            t: -dt,
            sat_pos_ecef_m: s_prev,
            carrier_m: carrier_prev,
            carrier_std_m,
        });
    }
    let mut sc = Scene {
        lla,
        rpy,
        v_n: v_ins,
        lever_arm_b,
        p: DMatrix::zeros(0, 0),
        sats,
        prevs,
        interval,
        drift_mps,
    };
    let ins = filter(&sc);
    sc.p = random_covariance(rng, &ins);
    sc
}

/// The INS of the scene (before any update), logging innovations.
fn filter(sc: &Scene) -> InsFilter {
    let mut c = cfg();
    c.tight.enabled = true;
    c.gnss.lever_arm_b = sc.lever_arm_b;
    let mut ins = InsFilter::new(&c, 0.0, sc.lla, sc.rpy, sc.v_n, &blocks(), true);
    if sc.p.nrows() == ins.layout.len() {
        ins.filter.p = sc.p.clone();
    }
    ins.extra_mut(Block::ClockDrift)[0] = sc.drift_mps;
    ins.innovations = Some(Vec::new());
    ins
}

fn clock(f: &Fuser) -> ReceiverClock {
    ReceiverClock {
        bias_m: f.extra(Block::ClockBias)[0],
        drift_mps: f.extra(Block::ClockDrift)[0],
        ..ReceiverClock::default()
    }
}

/// `apply` with a fuser on `ins`; what it returned and the run's record.
fn with_fuser<R>(ins: &mut InsFilter, apply: impl FnOnce(&mut Fuser) -> R) -> (R, RunSummary) {
    let mut record = RunSummary::default();
    let mut shared = Shared {
        last_gnss_used_t: 0.0,
        is_static: false,
        gnss_fused_t: None,
        gnss_interval_s: None,
        vehicle_fused_t: None,
    };
    let mut status = AidStatus::default();
    let mut f = Fuser {
        ins,
        record: &mut record,
        shared: &mut shared,
        status: &mut status,
    };
    (apply(&mut f), record)
}

/// The scene's TDCP rows linearised at the current state.
fn rows(sc: &Scene, f: &Fuser) -> Vec<(&'static str, Linearized)> {
    let ctx = f.context(clock(f));
    sc.sats
        .iter()
        .zip(&sc.prevs)
        .map(|(s, p)| {
            let a = Aiding::Tdcp(s, *p, sc.interval);
            (a.name(), a.linearize(&ctx).expect("tdcp row"))
        })
        .collect()
}

/// The scene's rows fused with `how`: the filter after, the correction, the record.
fn fused(sc: &Scene, how: EpochUpdate) -> (InsFilter, DVector<f64>, RunSummary) {
    let mut ins = filter(sc);
    let (r, record) = with_fuser(&mut ins, |f| {
        let rows = rows(sc, f);
        let refs: Vec<(&'static str, &Linearized)> = rows.iter().map(|(n, l)| (*n, l)).collect();
        f.fuse_epoch(&refs, how)
    });
    let Fused::Applied(dx) = r else {
        panic!("not applied: {r:?}")
    };
    (ins, dx, record)
}

/// The old way: each row fused alone, re-linearised at the state the previous left,
/// with the displacement fixed at the epoch's start.
fn fused_row_by_row(sc: &Scene) -> InsFilter {
    let mut ins = filter(sc);
    with_fuser(&mut ins, |f| {
        for (s, p) in sc.sats.iter().zip(&sc.prevs) {
            let c = clock(f);
            f.fuse_with_clock(Aiding::Tdcp(s, *p, sc.interval), None, c);
        }
    });
    ins
}

#[test]
fn one_shot_and_sequential_fusion_give_the_same_state() {
    let mut rng = Pcg64::seed_from_u64(30);
    let mut worst: f64 = 0.0;
    for trial in 0..300 {
        let m = rng.random_range(1..=14);
        let dv = Vector3::new(normal(&mut rng), normal(&mut rng), normal(&mut rng))
            * log_uniform(&mut rng, 1e-3, 2.0);
        let sc = scene(&mut rng, m, dv);
        let (a, dx_a, rec_a) = fused(&sc, EpochUpdate::OneShot { gate: None });
        let (b, dx_b, rec_b) = fused(&sc, EpochUpdate::Sequential { row_gate: None });
        let n = a.layout.len();
        let sigma = sc.p.diagonal().map(f64::sqrt);
        // "The same state to 1e-9": each correction (and each state after the
        // feedback, in m, m/s, rad) to 1e-9 in SI units, relative to the prior sigma or
        // the correction where those exceed 1 (a 30 m position sigma). Relative to a
        // small sigma alone the floor is the rounding of S (condition up to ~1e8 here:
        // a 1 mm/s row against a 3 m/s velocity sigma): 1e-8 of it.
        let tol = |i: usize| 1e-9 * (sigma[i] + dx_a[i].abs()).max(1.0);
        for i in 0..n {
            let d = (dx_a[i] - dx_b[i]).abs();
            worst = worst.max(d / tol(i) * 1e-9);
            assert!(
                d < tol(i),
                "trial {trial} ({m} rows) state {i}: {} vs {}",
                dx_a[i],
                dx_b[i]
            );
        }
        let tol3 = |k: usize| (0..3).map(|j| tol(k + j)).fold(0.0, f64::max);
        let d_pos = lla_diff_ned(&a.nav.lla, &b.nav.lla).norm();
        let d_vel = (a.nav.v_n - b.nav.v_n).norm();
        let d_att = a.nav.q_bn.angle_to(&b.nav.q_bn);
        let i_drift = a.layout.index(Block::ClockDrift).unwrap();
        let d_drift = (a.extra(Block::ClockDrift)[0] - b.extra(Block::ClockDrift)[0]).abs();
        assert!(
            d_pos < 2.0 * tol3(POS)
                && d_vel < 2.0 * tol3(VEL)
                && d_att < 2.0 * tol3(ATT)
                && d_drift < tol(i_drift),
            "trial {trial}: {d_pos:e} m {d_vel:e} m/s {d_att:e} rad {d_drift:e} m/s"
        );
        // The covariances, likewise.
        for i in 0..n {
            for j in 0..n {
                let d = (a.filter.p[(i, j)] - b.filter.p[(i, j)]).abs();
                assert!(
                    d < 1e-9 * (sigma[i] * sigma[j]).max(1.0),
                    "trial {trial} P[{i},{j}]"
                );
            }
        }
        // The bookkeeping: one innovations.csv row per satellite, the same in both,
        // the NIS shares summing to the joint NIS. A late row's variance s_i is small
        // against the prior's H P H^T (the rows before it took most of it), so its
        // sequential value carries cancellation: the NIS agree to 1e-6.
        let (log_a, log_b) = (
            a.innovations.as_ref().unwrap(),
            b.innovations.as_ref().unwrap(),
        );
        assert_eq!(log_a.len(), m);
        assert_eq!(log_b.len(), m);
        for (x, y) in log_a.iter().zip(log_b) {
            assert_eq!((x.source, x.rows, x.outcome), ("tdcp", 1, y.outcome));
            assert!(
                (x.innovation[0] - y.innovation[0]).abs() < 1e-9 * (1.0 + y.innovation[0].abs())
            );
            assert!(
                (x.nis - y.nis).abs() < 1e-6 * (1.0 + y.nis),
                "trial {trial}: nis {} vs {}, e {} vs {}",
                x.nis,
                y.nis,
                x.innovation[0],
                y.innovation[0]
            );
        }
        let joint = {
            let ins = filter(&sc);
            let mut ins = ins;
            let (v, _) = with_fuser(&mut ins, |f| {
                let rows = rows(&sc, f);
                let lins: Vec<&Linearized> = rows.iter().map(|(_, l)| l).collect();
                let st = super::source::stack_rows(&lins, n).unwrap();
                f.nis(&st).unwrap()
            });
            v
        };
        let sum: f64 = log_a.iter().map(|r| r.nis).sum();
        assert!(
            (sum - joint).abs() < 1e-6 * (1.0 + joint),
            "trial {trial}: {sum} vs {joint}"
        );
        for rec in [&rec_a, &rec_b] {
            assert_eq!(rec.aiding_used.get("tdcp"), Some(&m));
            let (s, k) = rec.aiding_nis["tdcp"];
            assert_eq!(k, m);
            assert!((s - joint).abs() < 1e-6 * (1.0 + joint));
        }
    }
    eprintln!("one-shot vs sequential: largest difference of a correction {worst:.1e} (SI units, or relative above 1)");
}

/// A row gated alone in the sequential update: the others as one-shot without it.
#[test]
fn sequential_row_gate_drops_the_row_alone() {
    let mut rng = Pcg64::seed_from_u64(7);
    for _ in 0..50 {
        let m = rng.random_range(3..=10);
        let mut sc = scene(&mut rng, m, Vector3::zeros());
        // A 100 m carrier jump on one satellite: beyond any prior here.
        let bad = rng.random_range(0..m);
        *sc.sats[bad].carrier_m.as_mut().unwrap() += 100.0;
        let gate = crate::chi2::chi2_threshold(1, 1e-6);
        let (b, dx_b, rec) = fused(
            &sc,
            EpochUpdate::Sequential {
                row_gate: Some(gate),
            },
        );
        let log = b.innovations.as_ref().unwrap();
        let rejected: Vec<usize> = (0..m)
            .filter(|&i| log[i].outcome == crate::events::UpdateKind::Rejected)
            .collect();
        assert_eq!(
            rejected,
            vec![bad],
            "{:?}",
            log.iter().map(|r| r.nis).collect::<Vec<_>>()
        );
        assert_eq!(log[bad].gate, Some(gate));
        assert_eq!(rec.aiding_rejected.get("tdcp"), Some(&1));
        assert_eq!(rec.aiding_used.get("tdcp"), Some(&(m - 1)));
        let mut clean = sc;
        clean.sats.remove(bad);
        clean.prevs.remove(bad);
        let (_, dx_a, _) = fused(&clean, EpochUpdate::OneShot { gate: None });
        let sigma = clean.p.diagonal().map(f64::sqrt);
        for i in 0..dx_a.len() {
            assert!(
                (dx_a[i] - dx_b[i]).abs() < 1e-9 * (sigma[i] + dx_a[i].abs()),
                "state {i}"
            );
        }
    }
}

/// The defect: with an INS velocity error and consistent carriers, one joint update
/// removes most of it; the rows fused one after another, each re-linearised with the
/// same displacement, correct the velocity again and again (the prediction does not
/// move with the velocity state).
#[test]
fn row_by_row_with_a_fixed_displacement_overcorrects() {
    let mut rng = Pcg64::seed_from_u64(11);
    let (mut worse, mut trials) = (0, 0);
    for _ in 0..40 {
        let dv = Vector3::new(normal(&mut rng), normal(&mut rng), 0.3 * normal(&mut rng)) * 0.5;
        let mut sc = scene(&mut rng, 8, dv);
        // A consistent prior: 1 m position, 1 m/s velocity, small attitude error.
        let n = sc.p.nrows();
        let mut p = DMatrix::identity(n, n) * 1e-10;
        for k in 0..3 {
            p[(POS + k, POS + k)] = 1.0;
            p[(VEL + k, VEL + k)] = 1.0;
            p[(ATT + k, ATT + k)] = 1e-6;
        }
        p[(n - 2, n - 2)] = 100.0;
        p[(n - 1, n - 1)] = 0.01;
        sc.p = p;
        let v_true = sc.v_n - dv;
        let (joint, _, _) = fused(&sc, EpochUpdate::OneShot { gate: None });
        let old = fused_row_by_row(&sc);
        let err_joint = (joint.nav.v_n - v_true).norm();
        let err_old = (old.nav.v_n - v_true).norm();
        assert!(
            err_joint < 0.1 * dv.norm(),
            "joint: {err_joint:.3} m/s left of {:.3}",
            dv.norm()
        );
        trials += 1;
        worse += usize::from(err_old > 2.0 * err_joint);
    }
    // Not every geometry shows it strongly; most do.
    assert!(worse * 4 >= trials * 3, "{worse} of {trials}");
}

/// The tight source's carrier policy, epoch by epoch, on a receiver at rest (no IMU
/// propagation between the epochs: the INS displacement is zero, as it is at rest).
mod policy {
    use super::*;
    use crate::aiding::source::AidingSource;
    use crate::aiding::tight::TightGnss;
    use crate::config::RangeRate;
    use crate::events::Event;
    use crate::types::{GnssRawEpoch, Measurement};
    use std::sync::Arc;

    /// Six satellites (azimuth, elevation deg) 22,000 km from the antenna.
    const SKY: [(f64, f64); 6] = [
        (10.0, 70.0),
        (80.0, 30.0),
        (150.0, 45.0),
        (220.0, 20.0),
        (280.0, 55.0),
        (330.0, 25.0),
    ];
    const CLOCK_M: f64 = 150.0;

    struct Rig {
        ins: InsFilter,
        src: TightGnss,
        sats: Vec<(SatId, Vector3<f64>)>,
        r_ant: Vector3<f64>,
    }

    fn rig() -> Rig {
        let mut c = cfg();
        c.tight.enabled = true;
        c.tight.range_rate = RangeRate::Tdcp;
        c.gnss.lever_arm_b = Vector3::zeros();
        let src = TightGnss::from_config(&c).unwrap();
        let lla = c.initial.lla.unwrap();
        let crate::config::AttitudeInit::Given(rpy) = c.initial.attitude else {
            unreachable!()
        };
        let ins = InsFilter::new(&c, 0.0, lla, rpy, Vector3::zeros(), &src.blocks(), true);
        let r_ant = lla_to_ecef(&lla);
        let cne = c_ne(lla.x, lla.y);
        let sats = SKY
            .iter()
            .enumerate()
            .map(|(k, &(az, el))| {
                let (az, el) = (az.to_radians(), el.to_radians());
                let u_n = Vector3::new(az.cos() * el.cos(), az.sin() * el.cos(), -el.sin());
                (SatId::gps(k as u8 + 1), r_ant + cne * u_n * 2.2e7)
            })
            .collect();
        Rig {
            ins,
            src,
            sats,
            r_ant,
        }
    }

    impl Rig {
        /// One epoch at `t`: each satellite's carrier (range + clock + an ambiguity +
        /// `offset(k)`), lock flag `lost(k)`, pseudorange and Doppler (the truth: at
        /// rest, clock drift 0). Returns the record of the epoch.
        fn epoch(
            &mut self,
            t: f64,
            offset: impl Fn(usize) -> f64,
            lost: impl Fn(usize) -> bool,
        ) -> RunSummary {
            let sats = self
                .sats
                .iter()
                .enumerate()
                .map(|(k, &(sat, pos))| {
                    let range = (pos - self.r_ant).norm();
                    SatMeasurement {
                        sat,
                        sat_pos_ecef_m: pos,
                        sat_vel_ecef_mps: Vector3::zeros(),
                        elevation_rad: 0.5,
                        pseudorange_m: Some(range + CLOCK_M),
                        pseudorange_std_m: 1.0,
                        range_rate_mps: Some(0.0),
                        range_rate_std_mps: 0.2,
                        carrier_m: Some(range + CLOCK_M + 1000.0 * k as f64 + offset(k)),
                        carrier_std_m: 0.003,
                        lost_lock: lost(k),
                        dgps: false,
                    }
                })
                .collect();
            let m = Measurement::GnssRaw(Arc::new(GnssRawEpoch { t, sats, fix: None }));
            let src = &mut self.src;
            with_fuser(&mut self.ins, |f| {
                src.on_measurement(&m, f);
            })
            .1
        }
    }

    fn count(rec: &RunSummary, name: &str) -> usize {
        rec.aiding_used.get(name).copied().unwrap_or(0)
    }

    /// The first epoch (nothing to difference), a loss of lock on every satellite, a
    /// slip on one: the satellites without a TDCP row give their Doppler.
    #[test]
    fn doppler_stands_in_per_satellite() {
        let mut r = rig();
        let none = |_: usize| 0.0;
        let e1 = r.epoch(0.0, none, |_| false);
        assert_eq!((count(&e1, "tdcp"), count(&e1, "doppler")), (0, 6));
        let e2 = r.epoch(1.0, none, |_| false);
        assert_eq!((count(&e2, "tdcp"), count(&e2, "doppler")), (6, 0));
        // Every carrier flagged lost: all Doppler.
        let e3 = r.epoch(2.0, none, |_| true);
        assert_eq!((count(&e3, "tdcp"), count(&e3, "doppler")), (0, 6));
        let e4 = r.epoch(3.0, none, |_| false);
        assert_eq!((count(&e4, "tdcp"), count(&e4, "doppler")), (6, 0));
        // A 5 m slip on satellite 3: the slip, five TDCP rows and its Doppler.
        let e5 = r.epoch(4.0, |k| if k == 3 { 5.0 } else { 0.0 }, |_| false);
        let slips: Vec<&Event> = e5
            .events
            .iter()
            .filter(|e| matches!(e, Event::CycleSlip { .. }))
            .collect();
        assert!(
            matches!(slips[..], [Event::CycleSlip { sat, .. }] if *sat == SatId::gps(4)),
            "{slips:?}"
        );
        assert_eq!((count(&e5, "tdcp"), count(&e5, "doppler")), (5, 1));
        // Its carrier restarts from there: six rows again.
        let e6 = r.epoch(5.0, |k| if k == 3 { 5.0 } else { 0.0 }, |_| false);
        assert_eq!((count(&e6, "tdcp"), count(&e6, "doppler")), (6, 0));
    }

    /// Every carrier moved as if the receiver had moved 2 m (the INS says it did not,
    /// and its velocity sigma is 1 cm/s): they disagree with the INS at once, TDCP
    /// pauses (Doppler stands in); at the next epoch they agree again and TDCP
    /// resumes at once (it used to wait 5 s).
    #[test]
    fn carriers_readmitted_at_the_first_epoch_they_agree() {
        let mut r = rig();
        let none = |_: usize| 0.0;
        r.epoch(0.0, none, |_| false);
        r.epoch(1.0, none, |_| false);
        let d_n = Vector3::new(1.6, -1.2, 0.0);
        let lla = r.ins.nav.lla;
        let cne = c_ne(lla.x, lla.y);
        let moved: Vec<f64> = r
            .sats
            .iter()
            .map(|(_, pos)| -((pos - r.r_ant).normalize().dot(&(cne * d_n))))
            .collect();
        let storm = r.epoch(2.0, |k| moved[k], |_| false);
        let distrusted = storm
            .events
            .iter()
            .any(|e| matches!(e, Event::CarriersDistrusted { .. }));
        assert!(distrusted, "{:?}", storm.events);
        assert_eq!((count(&storm, "tdcp"), count(&storm, "doppler")), (0, 6));
        // At rest again: the carriers of epoch 3 equal epoch 2's.
        let back = r.epoch(3.0, |k| moved[k], |_| false);
        let trusted: Vec<&Event> = back
            .events
            .iter()
            .filter(|e| matches!(e, Event::CarriersTrusted { .. }))
            .collect();
        assert!(
            matches!(trusted[..], [Event::CarriersTrusted { after_s, .. }] if *after_s == 1.0),
            "{:?}",
            back.events
        );
        assert_eq!((count(&back, "tdcp"), count(&back, "doppler")), (6, 0));
    }
}
