//! `GnssFusion::SixState` (REFERENCES \[SYS\] §5; seed 004 §3): the fixes go to a
//! six-state position/velocity filter (six_state.rs) that follows the dead reckoning,
//! never to the error-state filter, which dead-reckons with the vehicle aiding.
//!
//! Policy: every N-th fix is fused (the others are neither used nor counted as
//! rejected), moved to the IMU centre with the dead reckoning's attitude, position
//! and (when `use_velocity`) velocity, with the std overrides and the innovation gate
//! and its timeout of `\[gnss\]`; under the integrity monitor the monitor replaces the
//! gate.

use super::gnss_integrity::GnssGuard;
use super::source::{chi2_gate, AidingSource, Fuser, Handled};
use crate::config::{GnssFusion, GnssOptions, NavConfig};
use crate::earth::lla_diff_ned;
use crate::events::Event;
use crate::integrity::{EpochCheck, IntegrityReference, IntegrityState, StepInput};
use crate::six_state::{ImuFix, SixState, SixStateOutcome};
use crate::state::POS;
use crate::types::{GnssFix, Measurement, NavState};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Six-state GNSS fusion as an aiding source.
pub struct GnssSixState {
    opt: GnssOptions,
    reference: IntegrityReference,
    guard: Option<GnssGuard>,
    /// Time of the first of the current run of gate-rejected fixes.
    reject_streak_since: Option<f64>,
}

/// The six-state filter for `GnssFusion::SixState` with loose coupling, started at
/// the dead reckoning's initial state with its position/velocity uncertainty; None
/// otherwise (and when the start is not finite: the run reports that).
pub(crate) fn new_six_state(
    cfg: &NavConfig,
    nav: &NavState,
    p_dr: &DMatrix<f64>,
) -> Option<SixState> {
    let GnssFusion::SixState { every } = cfg.gnss.fusion else {
        return None;
    };
    if cfg.tight.enabled {
        return None;
    }
    let ini = &cfg.initial;
    let mut p0 = nalgebra::Matrix6::zeros();
    for k in 0..3 {
        p0[(k, k)] = ini.pos_std[k].powi(2);
        p0[(3 + k, 3 + k)] = ini.vel_std[k].powi(2);
    }
    let mut six = SixState::new(nav, p0, every).ok()?;
    six.track_dr_covariance(p_dr).then_some(six)
}

impl GnssSixState {
    /// None unless the fusion is six-state (loose coupling only).
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        if cfg.tight.enabled || !matches!(cfg.gnss.fusion, GnssFusion::SixState { .. }) {
            return None;
        }
        Some(GnssSixState {
            opt: cfg.gnss.clone(),
            reference: cfg.integrity.reference,
            guard: GnssGuard::from_config(cfg),
            reject_streak_since: None,
        })
    }

    fn update(&mut self, f: &mut Fuser, fix: &GnssFix) {
        let g = &self.opt;
        let mut fx = *fix;
        if let Some(s) = g.position_std_override {
            fx.std_ned = s;
        }
        if let (Some(s), true) = (g.velocity_std_override, fx.vel_ned.is_some()) {
            fx.vel_std_ned = Some(s);
        }
        // The scales apply to the reported or overridden stds alike.
        fx.std_ned *= g.position_std_scale;
        if let Some(v) = fx.vel_std_ned.as_mut() {
            *v *= g.velocity_std_scale;
        }
        if !g.use_velocity {
            fx.vel_ned = None;
            fx.vel_std_ned = None;
        }
        let (lever_arm_b, gate_p, timeout_s) =
            (g.lever_arm_b, g.gate_probability, g.gate_timeout_s);
        // Bring the six-state covariance and state to the fix time.
        f.flush_covariance();
        f.six_state_follow_dr();
        let nav = *f.nav();
        let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
        let imu_fix = ImuFix::from_antenna(&fx, &c_bn, &f.w_ib_b(), &lever_arm_b, &nav.v_n);
        let ins = &mut *f.ins;
        let Some(six) = ins.six_state.as_mut() else {
            return;
        };
        if !six.next_epoch_due() {
            six.update(&imu_fix, None);
            return;
        }
        let dr_increment_var_ned_m2 = six.predict_covariance_from_dr(&ins.filter.p);
        if let Some(guard) = self.guard.as_mut() {
            // The fix against the six-state prediction (position and, when the fix has
            // one, velocity), or against the dead reckoning itself (seed 004's
            // r_INS/OD, which GNSS never corrects; position only): distance and NIS.
            // The displacement window is against the dead reckoning.
            let pos_var = imu_fix.pos_std_ned_m.map(|x| x * x);
            let innovation = match self.reference {
                IntegrityReference::Prediction => six.innovation(&imu_fix),
                IntegrityReference::DeadReckoning => {
                    let p_rr = ins.filter.p.fixed_view::<3, 3>(POS, POS).into_owned();
                    let y = lla_diff_ned(&imu_fix.lla, &nav.lla);
                    let s = p_rr + Matrix3::from_diagonal(&pos_var);
                    Some((
                        DVector::from_column_slice(y.as_slice()),
                        DMatrix::from_column_slice(3, 3, s.as_slice()),
                    ))
                }
            };
            // A fix that is not finite goes on to the update, which reports it.
            if let Some((y, s_mat)) = innovation {
                let nis = s_mat
                    .clone()
                    .cholesky()
                    .map_or(f64::NAN, |c| y.dot(&c.solve(&y)));
                let ref_pos_var: f64 = (0..3).map(|k| s_mat[(k, k)] - pos_var[k]).sum();
                let check = EpochCheck {
                    t: fix.t,
                    distance_m: y.rows(0, 2).norm(),
                    nis,
                    dof: y.len(),
                    distance_floor_m: 0.0,
                    ref_pos_std_m: ref_pos_var.max(0.0).sqrt(),
                    step: Some(StepInput {
                        innovation_ned_m: lla_diff_ned(&nav.lla, &imu_fix.lla),
                        fix_std_ned_m: imu_fix.pos_std_ned_m,
                        vel_std_ned_mps: f.vel_std_ned_mps(),
                        gnss_correction_ned_m: Vector3::zeros(),
                        ref_increment_var_ned_m2: dr_increment_var_ned_m2,
                    }),
                };
                if !guard.verdict(f, &check) {
                    f.record().gnss_rejected += 1;
                    return;
                }
            }
        }
        // The monitor, when on, replaces the gate and its timeout.
        let mut gate = chi2_gate(imu_fix.dof(), gate_p).filter(|_| self.guard.is_none());
        if let (Some(t0), Some(_)) = (self.reject_streak_since, gate) {
            if fix.t - t0 >= timeout_s {
                gate = None;
                f.push_event(Event::GateBypassed {
                    t: fix.t,
                    streak_s: fix.t - t0,
                });
            }
        }
        let Some(six) = f.six_state() else {
            return;
        };
        let outcome = six.update(&imu_fix, gate);
        f.six_state_refresh();
        if matches!(outcome, SixStateOutcome::Applied { .. }) {
            f.shared().note_gnss_fused(fix.t);
        }
        const SOURCE: &str = "gnss_six_state";
        let rec = f.record();
        match outcome {
            SixStateOutcome::Applied { .. } => {
                rec.gnss_used += 1;
                *rec.aiding_used.entry(SOURCE).or_default() += 1;
                self.reject_streak_since = None;
            }
            SixStateOutcome::Rejected { nis, threshold } => {
                rec.gnss_rejected += 1;
                *rec.aiding_rejected.entry(SOURCE).or_default() += 1;
                self.reject_streak_since.get_or_insert(fix.t);
                rec.events.push(Event::Rejected {
                    t: fix.t,
                    source: SOURCE,
                    nis,
                    threshold,
                });
            }
            SixStateOutcome::Invalid => {
                rec.gnss_rejected += 1;
                *rec.aiding_rejected.entry(SOURCE).or_default() += 1;
                rec.events.push(Event::Singular {
                    t: fix.t,
                    source: SOURCE,
                });
            }
            SixStateOutcome::Skipped => {}
        }
    }
}

impl AidingSource for GnssSixState {
    fn name(&self) -> &'static str {
        "gnss_six_state"
    }

    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        let Measurement::Gnss(fix) = m else {
            return Handled::No;
        };
        self.update(f, fix);
        Handled::Yes
    }

    fn integrity_state(&self) -> Option<IntegrityState> {
        self.guard.as_ref().map(|g| g.state())
    }
}
