//! Tests of the backward (time-reversed) run: the mechanization integrated backward
//! returns to where the forward integration started, the time line cuts the
//! intervals at the measurement times going down, the Gauss-Markov states stay
//! stable, and the cadence-driven sources keep their rates.

use super::backward::{run_backward, BackwardStart};
use super::navigator::{NavError, Navigator};
use super::run::run;
use crate::aiding::baro::BaroSample;
use crate::aiding::source::{AidingSource, Fuser, Handled};
use crate::attitude::{euler_from_q_bn, q_bn_from_euler};
use crate::config::{
    AttitudeInit, FixErrorOptions, GnssFusion, ImuNoise, InitialState, NavConfig, NhcMode,
};
use crate::earth::{gravity_normal, lla_diff_ned, omega_ie_n};
use crate::mechanization::Mechanizer;
use crate::state::{BG, SA};
use crate::types::{ImuErrors, ImuSample, Measurement, NavState};
use nalgebra::{UnitQuaternion, Vector3};
use std::sync::{Arc, Mutex};

/// Sinusoids (amplitude, angular frequency, phase) plus a constant.
type Signal<'a> = (&'a [(f64, f64, f64)], f64);

/// Exact integral over (t0, t1] of sum_k a_k sin(w_k t + p_k) + c.
fn integral(terms: &[(f64, f64, f64)], c: f64, t0: f64, t1: f64) -> f64 {
    terms
        .iter()
        .map(|&(a, w, p)| a / w * ((w * t0 + p).cos() - (w * t1 + p).cos()))
        .sum::<f64>()
        + c * (t1 - t0)
}

/// A manoeuvring IMU: smooth rates (turns, pitching, rolling up to ~10 deg/s) and
/// specific force (accelerating and braking, lateral force), increments integrated
/// exactly over each interval of `dt` from `t0`.
fn manoeuvring_imu(t0: f64, dt: f64, n: usize) -> Vec<ImuSample> {
    let w: [Signal; 3] = [
        (&[(0.10, 0.50, 0.3), (0.03, 1.70, 1.0)], 1e-5),
        (&[(0.05, 0.30, 1.1), (0.02, 2.30, 0.2)], -2e-5),
        (&[(0.20, 0.10, 0.0), (0.05, 0.90, 2.0)], 4e-5),
    ];
    let f: [Signal; 3] = [
        (&[(1.0, 0.20, 0.0), (0.3, 3.10, 0.5)], 0.2),
        (&[(0.5, 0.40, 1.0), (0.2, 2.70, 0.1)], 0.0),
        (&[(0.2, 1.00, 0.7), (0.1, 5.30, 0.4)], -9.806),
    ];
    (1..=n)
        .map(|k| {
            let (a, b) = (t0 + (k - 1) as f64 * dt, t0 + k as f64 * dt);
            ImuSample {
                t: b,
                dt: b - a,
                dtheta: Vector3::from_fn(|i, _| integral(w[i].0, w[i].1, a, b)),
                dvel: Vector3::from_fn(|i, _| integral(f[i].0, f[i].1, a, b)),
            }
        })
        .collect()
}

/// The same interval, time-reversed as the backward mechanization takes it.
fn reversed(s: &ImuSample) -> ImuSample {
    ImuSample {
        t: s.t - s.dt,
        dt: -s.dt,
        dtheta: -s.dtheta,
        dvel: -s.dvel,
    }
}

fn start_state(t: f64) -> NavState {
    NavState {
        t,
        lla: Vector3::new(45f64.to_radians(), 7f64.to_radians(), 300.0),
        v_n: Vector3::new(12.0, -9.0, 0.4),
        q_bn: q_bn_from_euler(&Vector3::new(0.05, -0.02, 2.0)),
    }
}

/// (position error [m], velocity error [m/s], attitude error [rad]) of b against a.
fn difference(a: &NavState, b: &NavState) -> (f64, f64, f64) {
    let dq: UnitQuaternion<f64> = b.q_bn * a.q_bn.inverse();
    (
        lla_diff_ned(&b.lla, &a.lla).norm(),
        (b.v_n - a.v_n).norm(),
        dq.angle(),
    )
}

/// Forward from A to B over 60 s at 100 Hz at 45 deg latitude, moving at 15 m/s and
/// manoeuvring; then backward from B over the same samples reversed: back at A.
#[test]
fn mechanization_integrated_backward_returns_to_the_start() {
    let imu = manoeuvring_imu(1000.0, 0.01, 6000);
    let a = start_state(1000.0);
    let mut mech = Mechanizer::new();
    let mut nav = a;
    for s in &imu {
        nav = mech.step(&nav, s).0;
    }
    let b = nav;
    let (moved, _, _) = difference(&a, &b);
    assert!(moved > 500.0, "the trajectory moves ({moved} m)");
    let mut mech = Mechanizer::new();
    for s in imu.iter().rev() {
        nav = mech.step(&nav, &reversed(s)).0;
    }
    assert!((nav.t - a.t).abs() < 1e-9, "time {}", nav.t);
    let (dp, dv, da) = difference(&a, &nav);
    eprintln!(
        "mechanization A -> B ({moved:.0} m) -> A: position {dp:.3e} m, velocity {dv:.3e} m/s, attitude {da:.3e} rad"
    );
    assert!(dp < 1e-3, "position {dp} m");
    assert!(dv < 1e-5, "velocity {dv} m/s");
    assert!(da < 1e-6, "attitude {da} rad");
    // The reversal is not trivially exact: integrating the reversed samples forward
    // in time (dt > 0) goes somewhere else entirely.
    let mut mech = Mechanizer::new();
    let mut wrong = b;
    for s in imu.iter().rev() {
        let mut r = reversed(s);
        r.dt = s.dt;
        wrong = mech.step(&wrong, &r).0;
    }
    assert!(difference(&a, &wrong).0 > 100.0);
}

fn noise() -> ImuNoise {
    ImuNoise {
        arw: Vector3::repeat(1e-5),
        vrw: Vector3::repeat(1e-4),
        gyro_bias_std: Vector3::repeat(1e-5),
        accel_bias_std: Vector3::repeat(1e-3),
        gyro_scale_std: Vector3::repeat(1e-4),
        accel_scale_std: Vector3::repeat(1e-4),
        corr_time_s: 100.0,
    }
}

fn cfg() -> NavConfig {
    let n = noise();
    let mut c = NavConfig::new(
        n.clone(),
        InitialState::new(
            Vector3::repeat(0.1),
            Vector3::repeat(0.01),
            Vector3::repeat(0.001),
            &n,
        ),
    );
    c.gnss.fix_error = FixErrorOptions::white();
    c
}

/// Collects what the navigator does at each output and what a source sees.
#[derive(Default)]
struct Seen {
    /// nav().t at each measurement handed to the probe source.
    at_measurement: Vec<(f64, f64)>,
}

struct Probe(Arc<Mutex<Seen>>);

impl AidingSource for Probe {
    fn name(&self) -> &'static str {
        "probe"
    }
    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        self.0
            .lock()
            .unwrap()
            .at_measurement
            .push((m.t(), f.nav().t));
        Handled::No
    }
}

fn start_of(n: &NavState) -> BackwardStart {
    BackwardStart {
        t: n.t,
        lla: n.lla,
        v_n: n.v_n,
        rpy: euler_from_q_bn(&n.q_bn),
    }
}

/// A barometer reading (the barometer is off: it only cuts the interval).
fn cut_at(t: f64) -> Measurement {
    Measurement::Baro(BaroSample { t, height_m: 0.0 })
}

/// The whole backward run without aiding: from the forward run's last state over
/// the reversed IMU stream, with measurement times inside intervals, on samples and
/// just off them: each measurement is seen at its own time, every increment is
/// integrated once, the outputs come at each epoch reached in decreasing time, and the
/// state returns to the forward start.
#[test]
fn backward_run_without_aiding_returns_to_the_forward_start() {
    let mut c = cfg();
    let a = start_state(500.0);
    let rpy = euler_from_q_bn(&a.q_bn);
    c.initial.lla = Some(a.lla);
    c.initial.v_n = a.v_n;
    c.initial.attitude = AttitudeInit::Given(rpy);
    // The first sample fixes the forward start (its interval is not integrated).
    let mut imu = manoeuvring_imu(500.0 - 0.005, 0.005, 4001);
    // One long interval in the middle (two samples merged): cut in it too.
    let (i, j) = (1500, 1501);
    let merged = ImuSample {
        t: imu[j].t,
        dt: imu[i].dt + imu[j].dt,
        dtheta: imu[i].dtheta + imu[j].dtheta,
        dvel: imu[i].dvel + imu[j].dvel,
    };
    imu.splice(i..=j, [merged]);
    let times = [
        503.0037,
        505.0,
        505.0,
        507.5 + 4e-10,
        509.2 - 3e-10,
        507.5031,
        502.0,
    ];
    let mut meas: Vec<Measurement> = times.iter().map(|&t| cut_at(t)).collect();
    meas.push(cut_at(imu[i].t - 0.003));
    meas.sort_by(|a, b| a.t().total_cmp(&b.t()));
    let mut last = None;
    run::<NavError>(
        &c,
        imu.iter().map(|s| Ok(*s)),
        &meas,
        None,
        |n| {
            last = Some(*n.nav());
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    let b = last.unwrap();
    assert!((b.t - 520.0).abs() < 1e-9);

    let seen = Arc::new(Mutex::new(Seen::default()));
    let probe = seen.clone();
    let mut outputs: Vec<(f64, NavState)> = Vec::new();
    let mut integrated = None;
    let summary = run_backward::<NavError>(
        &c,
        move |_, _| vec![Box::new(Probe(probe)) as Box<dyn AidingSource>],
        start_of(&b),
        imu.iter().rev().map(|s| Ok(*s)),
        &meas,
        None,
        |n: &Navigator| {
            outputs.push((n.time_gnss(), *n.nav()));
            integrated = Some(n.integrated());
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    // Down to the first sample's lower end: one epoch past the forward start.
    let first = imu[0];
    assert_eq!(outputs.len(), imu.len());
    assert!((outputs.last().unwrap().0 - (first.t - first.dt)).abs() < 1e-9);
    assert!(outputs.windows(2).all(|w| w[1].0 < w[0].0));
    for (k, (t, _)) in outputs.iter().enumerate() {
        let s = imu[imu.len() - 1 - k];
        assert!((t - (s.t - s.dt)).abs() < 1e-9, "output {k} at {t}");
    }
    assert_eq!(summary.imu_samples, imu.len());
    // Every increment once (negated: integrated time-reversed).
    let (sum_dt, sum_th, sum_dv) = integrated.unwrap();
    let total = imu
        .iter()
        .fold((0.0, Vector3::zeros(), Vector3::zeros()), |a, s| {
            (a.0 + s.dt, a.1 + s.dtheta, a.2 + s.dvel)
        });
    assert!((sum_dt + total.0).abs() < 1e-9, "{sum_dt} {}", total.0);
    assert!((sum_th + total.1).norm() < 1e-12);
    assert!((sum_dv + total.2).norm() < 1e-9);
    // Each measurement was seen at its own time, the latest first.
    let at = &seen.lock().unwrap().at_measurement;
    assert_eq!(at.len(), meas.len());
    assert!(at.windows(2).all(|w| w[1].0 <= w[0].0));
    for (tm, tn) in at {
        assert!((tm - tn).abs() < 2e-9, "measurement at {tm} seen at {tn}");
    }
    // Back at the forward start (the state at the epoch of the first sample).
    let at_start = outputs
        .iter()
        .find(|(t, _)| (t - a.t).abs() < 1e-9)
        .expect("an output at the forward start")
        .1;
    let (dp, dv, da) = difference(&a, &at_start);
    eprintln!(
        "navigator without aiding, 20 s at 200 Hz with 8 cuts: back at the start within {dp:.3e} m, {dv:.3e} m/s, {da:.3e} rad"
    );
    assert!(dp < 1e-4 && dv < 1e-5 && da < 1e-7, "{dp} {dv} {da}");
}

/// Outputs at a period: the first epoch at or before each multiple, going down.
#[test]
fn backward_output_period() {
    let mut c = cfg();
    let a = start_state(100.0);
    c.initial.lla = Some(a.lla);
    let imu = manoeuvring_imu(100.0, 0.01, 1000);
    let b = imu.last().unwrap().t;
    let mut times = Vec::new();
    let mut st = start_of(&a);
    st.t = b;
    run_backward::<NavError>(
        &c,
        |_, _| Vec::new(),
        st,
        imu.iter().rev().map(|s| Ok(*s)),
        &[],
        Some(0.5),
        |n| {
            times.push(n.time_gnss());
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    let want: Vec<f64> = (0..20).rev().map(|k| 100.0 + 0.5 * k as f64).collect();
    assert_eq!(times.len(), want.len(), "{times:?}");
    for (t, w) in times.iter().zip(&want) {
        assert!((t - w).abs() < 1e-6, "{times:?}");
    }
}

/// Stationary IMU (gravity and Earth rate exactly) at `lla`, attitude `rpy`.
fn static_imu(
    lla: &Vector3<f64>,
    rpy: &Vector3<f64>,
    t0: f64,
    dt: f64,
    n: usize,
) -> Vec<ImuSample> {
    let c_nb = crate::attitude::c_bn_from_euler(rpy).transpose();
    let f_b = c_nb * Vector3::new(0.0, 0.0, -gravity_normal(lla.x, lla.z));
    let w_b = c_nb * omega_ie_n(lla.x);
    (1..=n)
        .map(|k| ImuSample {
            t: t0 + k as f64 * dt,
            dt,
            dtheta: w_b * dt,
            dvel: f_b * dt,
        })
        .collect()
}

/// Backward, the IMU errors' Gauss-Markov states decay with |dt| (their std stays at
/// the steady-state sigma); I + F dt with dt < 0 would grow them by e^(|t|/T).
#[test]
fn gauss_markov_states_stay_stable_backward() {
    let c = cfg();
    let lla = Vector3::new(0.7, 0.2, 100.0);
    let rpy = Vector3::new(0.0, 0.0, 1.0);
    let imu = static_imu(&lla, &rpy, 0.0, 0.01, 30_000);
    let mut std = None;
    run_backward::<NavError>(
        &c,
        |_, _| Vec::new(),
        BackwardStart {
            t: imu.last().unwrap().t,
            lla,
            v_n: Vector3::zeros(),
            rpy,
        },
        imu.iter().rev().map(|s| Ok(*s)),
        &[],
        None,
        |n| {
            std = Some(n.std21());
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    let std = std.unwrap();
    let sigma = c.initial.imu_errors_std;
    let want = [
        sigma.gyro_bias,
        sigma.accel_bias,
        sigma.gyro_scale,
        sigma.accel_scale,
    ];
    for i in BG..SA + 3 {
        let s0 = want[(i - BG) / 3][(i - BG) % 3];
        assert!(
            (std[i] / s0 - 1.0).abs() < 1e-3,
            "state {i}: {} against {s0} after 300 s = 3 T",
            std[i]
        );
    }
    // The position uncertainty grows as forward.
    assert!(std[0] > 1.0);
}

/// Counts of the cadence-driven sources over the same data, forward and backward:
/// the ZUPT at rest (5 Hz), the NHC while moving (2 Hz, NHC on always).
#[test]
fn cadences_and_standstill_work_backward() {
    // At rest: static detection and ZUPTs.
    let mut c = cfg();
    let lla = Vector3::new(0.7, 0.2, 100.0);
    let rpy = Vector3::new(0.0, 0.0, 1.0);
    c.initial.lla = Some(lla);
    c.initial.attitude = AttitudeInit::Given(rpy);
    c.zupt.enabled = true;
    let imu = static_imu(&lla, &rpy, 0.0, 0.01, 2001);
    let fwd = run::<NavError>(
        &c,
        imu.iter().map(|s| Ok(*s)),
        &[],
        None,
        |_| Ok(()),
        |_| {},
    )
    .unwrap();
    let start = BackwardStart {
        t: imu.last().unwrap().t,
        lla,
        v_n: Vector3::zeros(),
        rpy,
    };
    let bwd = run_backward::<NavError>(
        &c,
        |_, _| Vec::new(),
        start,
        imu.iter().rev().map(|s| Ok(*s)),
        &[],
        None,
        |_| Ok(()),
        |_| {},
    )
    .unwrap();
    let zupts = |s: &crate::RunSummary| s.aiding_used.get("zupt").copied().unwrap_or(0);
    eprintln!(
        "ZUPT over 20 s at rest: forward {} backward {}, static {} s / {} s",
        zupts(&fwd),
        zupts(&bwd),
        fwd.static_s,
        bwd.static_s
    );
    assert!(zupts(&fwd) >= 90);
    assert!(
        zupts(&bwd).abs_diff(zupts(&fwd)) <= 1,
        "{} {}",
        zupts(&bwd),
        zupts(&fwd)
    );

    // Moving: the NHC at its rate (whatever its verdicts on this synthetic motion).
    let mut c = cfg();
    let a = start_state(0.0);
    c.initial.lla = Some(a.lla);
    c.initial.v_n = a.v_n;
    c.initial.attitude = AttitudeInit::Given(euler_from_q_bn(&a.q_bn));
    c.nhc.mode = NhcMode::Always;
    c.nhc.rate_hz = 2.0;
    c.nhc.gate_probability = None;
    let imu = manoeuvring_imu(0.0, 0.01, 2001);
    let mut last = None;
    let fwd = run::<NavError>(
        &c,
        imu.iter().map(|s| Ok(*s)),
        &[],
        None,
        |n| {
            last = Some(*n.nav());
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    let bwd = run_backward::<NavError>(
        &c,
        |_, _| Vec::new(),
        start_of(&last.unwrap()),
        imu.iter().rev().map(|s| Ok(*s)),
        &[],
        None,
        |_| Ok(()),
        |_| {},
    )
    .unwrap();
    let nhc = |s: &crate::RunSummary| s.aiding_used.get("nhc").copied().unwrap_or(0);
    assert_eq!(nhc(&fwd), 40);
    assert_eq!(
        nhc(&bwd),
        41,
        "from the start at 20 s down to 0 s, both ends"
    );
}

#[test]
fn six_state_fusion_is_refused_backward() {
    let mut c = cfg();
    c.gnss.fusion = GnssFusion::SixState {
        every: std::num::NonZeroU32::new(1).unwrap(),
    };
    let imu = manoeuvring_imu(0.0, 0.01, 10);
    let r = run_backward::<NavError>(
        &c,
        |_, _| Vec::new(),
        start_of(&start_state(0.1)),
        imu.iter().rev().map(|s| Ok(*s)),
        &[],
        None,
        |_| Ok(()),
        |_| {},
    );
    assert!(r.unwrap_err().0.contains("six_state"));
}

/// The compensation is linear: the reversed raw sample compensates to the reversed
/// compensated sample (what the backward INS integrates).
#[test]
fn compensation_commutes_with_the_reversal() {
    let e = ImuErrors {
        gyro_bias: Vector3::new(1e-4, -2e-4, 3e-4),
        accel_bias: Vector3::new(0.01, -0.02, 0.03),
        gyro_scale: Vector3::new(1e-3, -2e-3, 5e-4),
        accel_scale: Vector3::new(-1e-3, 2e-3, 1e-4),
    };
    let s = manoeuvring_imu(3.0, 0.01, 1)[0];
    let a = reversed(&e.compensate(&s));
    let b = e.compensate(&reversed(&s));
    assert!((a.dtheta - b.dtheta).norm() < 1e-18 && (a.dvel - b.dvel).norm() < 1e-15);
}

/// `start_time` bounds the run (it stops before a sample reaching below it), samples
/// after the start (or after `end_time`) are skipped, and a sample straddling the
/// start is integrated from the start only.
#[test]
fn backward_run_is_bounded_by_the_start_and_the_configured_times() {
    let imu = manoeuvring_imu(100.0, 0.01, 1000);
    let a = start_state(100.0);
    let run_from = |c: &NavConfig, t_start: f64| {
        let mut st = start_of(&a);
        st.t = t_start;
        let mut times = Vec::new();
        let mut total = 0.0;
        let s = run_backward::<NavError>(
            c,
            |_, _| Vec::new(),
            st,
            imu.iter().rev().map(|s| Ok(*s)),
            &[],
            None,
            |n| {
                times.push(n.nav().t);
                total = -n.integrated().0;
                Ok(())
            },
            |_| {},
        )
        .unwrap();
        (times, total, s)
    };
    let mut c = cfg();
    c.start_time = 105.0;
    let (times, total, s) = run_from(&c, 110.0);
    assert_eq!(times.len(), 500);
    assert!((times[times.len() - 1] - 105.0).abs() < 1e-9 && s.imu_samples == 500);
    assert!((total - 5.0).abs() < 1e-9);
    // Starting between two samples: the straddling one from the start down.
    let c = cfg();
    let (times, total, _) = run_from(&c, 107.004);
    assert!((times[0] - 107.0).abs() < 1e-9, "{}", times[0]);
    assert!((total - 7.004).abs() < 1e-9, "{total}");
    // end_time below the start: the samples after it are skipped.
    let mut c = cfg();
    c.end_time = Some(108.0);
    let (times, _, _) = run_from(&c, 108.0);
    assert!((times[0] - 107.99).abs() < 1e-9 && times.len() == 800);
}
