//! Loosely coupled GNSS: the receiver's fixes (position, velocity) into the
//! error-state filter, then the course over ground as heading when configured
//! (REFERENCES \[SYS\] §3a, §3c; models in gnss_position.rs, gnss_velocity.rs,
//! heading.rs).
//!
//! Policy (docs/ALGORITHMS.md "GNSS aiding", "GNSS fix errors"): the time-correlated share of each
//! fix's error is a Gauss-Markov block (`GnssBias`, fix_error.rs); each row is tested
//! on NIS / the robust innovation scale, never rejected within what the INS can have
//! drifted (the floor), IGG-III down-weighted beyond; rejected fixes that agree with
//! each other for `readmit_s` are re-admitted with the uncertainty widened. Under the
//! integrity monitor the monitor replaces the gate.

use super::gnss_integrity::GnssGuard;
use super::heading::HeadingAxis;
use super::source::{chi2_gate, AidingSource, Fuser, Handled};
use super::{Aiding, ReceiverClock};
use crate::chi2::chi2_threshold;
use crate::config::{GnssFusion, GnssOptions, HeadingOptions, NavConfig};
use crate::earth::lla_diff_ned;
use crate::events::Event;
use crate::fix_error::{igg3_factor, InnovationScale, RejectStreak};
use crate::integrity::IntegrityState;
use crate::nav::ins_filter::{BlockProcess, BlockSpec, Fused};
use crate::nav::timeline::TimeDirection;
use crate::state::{Block, POS, VEL};
use crate::types::{GnssFix, HeadingObs, Measurement};
use nalgebra::{DVector, Vector3};

/// Loosely coupled GNSS fixes as an aiding source (`\[gnss\]` with fixes).
pub struct GnssLoose {
    opt: GnssOptions,
    heading: HeadingOptions,
    /// The `GnssBias` block is in the filter.
    correlated: bool,
    guard: Option<GnssGuard>,
    /// The current run of gate-rejected fixes (fix_error.rs).
    fix_streak: Option<RejectStreak>,
    /// Steady-state sigma of the fix-error states, NED \[m\] (zero until the first fix).
    fix_bias_sigma_ned_m: Vector3<f64>,
    fix_pos_scale: InnovationScale,
    fix_vel_scale: InnovationScale,
    /// Previous fix (course from displacement when fixes carry no velocity).
    prev_fix: Option<GnssFix>,
}

impl GnssLoose {
    /// None under tight coupling or six-state fusion.
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        if cfg.tight.enabled || cfg.gnss.fusion != GnssFusion::ErrorState {
            return None;
        }
        let fe = &cfg.gnss.fix_error;
        Some(GnssLoose {
            opt: cfg.gnss.clone(),
            heading: cfg.heading.clone(),
            // Not under the integrity monitor, which carries its own Gauss-Markov
            // model (integrity.gnss_corr_time_s): the states would absorb a slow drift.
            correlated: fe.correlated() && !cfg.integrity.enabled,
            guard: GnssGuard::from_config(cfg),
            fix_streak: None,
            fix_bias_sigma_ned_m: Vector3::zeros(),
            fix_pos_scale: InnovationScale::new(fe.scale_window),
            fix_vel_scale: InnovationScale::new(fe.scale_window),
            prev_fix: None,
        })
    }

    /// Fuse and remember the correction for the monitor.
    fn fuse(&mut self, f: &mut Fuser, aiding: Aiding, gate: Option<f64>) -> Fused {
        let r = f.fuse(aiding, gate);
        if let Some(g) = self.guard.as_mut() {
            g.note(&r);
        }
        r
    }

    /// A fix row (position or velocity) with R = `r_share` x the reported variance,
    /// tested with NIS / `test_scale` (the robust innovation scale) on t = sqrt(NIS /
    /// dof) (fix_error.rs). Within `floor` (what the INS can plausibly have drifted)
    /// it is never rejected: full weight up to the gate k1, Huber weight (k1/t)²
    /// beyond. Beyond the floor: IGG-III between k0 and the gate k1, rejected beyond.
    /// Returns what was done, the NIS with the unweighted R, the innovation and the
    /// weight.
    fn fuse_fix_row(
        &mut self,
        f: &mut Fuser,
        aiding: Aiding,
        r_share: f64,
        test_scale: f64,
        gate_p: Option<f64>,
        floor: f64,
    ) -> (Fused, Option<f64>, Option<DVector<f64>>, f64) {
        f.flush_covariance();
        let mut ctx = f.context(ReceiverClock::default());
        // The fix-error states are this source's (module doc).
        if let [n, e, d] = *f.extra(Block::GnssBias) {
            ctx.gnss_bias_ned_m = Vector3::new(n, e, d);
        }
        let Some(mut lin) = aiding.linearize(&ctx) else {
            return (Fused::NotApplicable, None, None, 0.0);
        };
        lin.r *= r_share;
        let dof = lin.y.len();
        // Under adaptive noise, with the source's current scale (the update's own).
        let nis = f.nis_adapted(aiding.name(), &lin);
        let y = Some(lin.y.clone());
        // The gate on NIS / scale: the update's own test sees the scaled threshold.
        let gate = chi2_gate(dof, gate_p).map(|g| g * test_scale);
        let mut fused = None;
        if let (Some(g), Some(nis)) = (gate, nis) {
            let t = (nis / dof as f64).sqrt();
            let k1 = (g / dof as f64).sqrt();
            let k0 = self.opt.fix_error.robust_probability.map_or(k1, |p0| {
                (chi2_threshold(dof, p0) * test_scale / dof as f64).sqrt()
            });
            let w = if lin.y.amax() <= floor {
                // Plausible drift: full weight up to the gate, Huber beyond.
                if t > k1 {
                    (k1 / t).powi(2)
                } else {
                    1.0
                }
            } else if k0 < k1 {
                igg3_factor(t, k0, k1)
            } else if t < k1 {
                1.0
            } else {
                0.0
            };
            if w > 0.0 {
                lin.r /= w;
                // Down-weighted (or full weight), not rejected.
                fused = Some((f.fuse_linearized(&aiding, &lin, None, Some(nis)), w));
            }
        }
        let (r, w) = fused.unwrap_or_else(|| (f.fuse_linearized(&aiding, &lin, gate, nis), 1.0));
        if let Some(g) = self.guard.as_mut() {
            g.note(&r);
        }
        (r, nis, y, w)
    }

    /// The correlated share of this fix's variance drives the Gauss-Markov states; a
    /// much better fix (a new solution type) bounds them anew.
    fn set_fix_bias_sigma(&mut self, f: &mut Fuser, std_ned_m: &Vector3<f64>) {
        let Some(i) = f.layout().index(Block::GnssBias) else {
            return;
        };
        f.flush_covariance();
        let rho = self.opt.fix_error.corr_fraction;
        let sigma = std_ned_m * rho.sqrt();
        for k in 0..3 {
            let var = sigma[k].powi(2);
            let p = f.covariance()[(i + k, i + k)];
            if self.fix_bias_sigma_ned_m[k] == 0.0 || p > 2.0 * var {
                if p > 0.0 {
                    f.extra_mut(Block::GnssBias)[k] *= (var / p).sqrt();
                }
                f.reset_state(i + k, var);
            }
        }
        self.fix_bias_sigma_ned_m = sigma;
        f.set_process(
            Block::GnssBias,
            BlockProcess::GaussMarkov {
                corr_time_s: self.opt.fix_error.corr_time_s,
                sigma: sigma.as_slice().to_vec(),
            },
        );
    }

    fn update(&mut self, f: &mut Fuser, fix: &GnssFix) {
        let mut fx = *fix;
        let g = &self.opt;
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
        let use_vel = g.use_velocity;
        let fe = g.fix_error;
        // Elapsed times along the run (a backward run goes down in time).
        let dir = f.direction();
        let mut gate_p = g.gate_probability;
        if let Some(guard) = self.guard.as_mut() {
            // The monitor replaces the gate (and its re-admission, which would let a
            // spoofer in): position and (when fused) velocity jointly against the
            // INS/odometer prediction.
            let pos = Aiding::GnssPosition(&fx);
            let mut rows = vec![pos];
            if use_vel && fx.vel_ned.is_some() {
                rows.push(Aiding::GnssVelocity(&fx));
            }
            if !guard.check(f, fix.t, &rows, Some(pos), 0.0, ReceiverClock::default()) {
                f.record().gnss_rejected += 1;
                return;
            }
            gate_p = None;
        }
        if self.fix_bias_sigma_ned_m == Vector3::zeros() {
            // The first fix sizes the Gauss-Markov states; later ones once accepted.
            self.set_fix_bias_sigma(f, &fx.std_ned);
        }
        let white = if f.layout().index(Block::GnssBias).is_some() {
            1.0 - fe.corr_fraction
        } else {
            1.0
        };
        // Rejected fixes that have agreed with each other for readmit_s: the INS has
        // drifted (or the GNSS stepped for good); widen its uncertainty to take them.
        // A streak interrupted by a gap (an outage) is stale: it starts again.
        if self
            .fix_streak
            .is_some_and(|st| dir.elapsed(st.last_t(), fix.t) > self.opt.gate_timeout_s)
        {
            self.fix_streak = None;
        }
        if let (Some(st), Some(_)) = (self.fix_streak, gate_p) {
            if st.agreed_for(fe.readmit_s) {
                let y = st.last_innovation();
                let span = dir.elapsed(st.since, fix.t).max(1.0);
                f.widen(POS, y.component_mul(&y));
                f.widen(VEL, (y / span).component_mul(&(y / span)));
                f.push_event(Event::GnssReadmitted {
                    t: fix.t,
                    streak_s: dir.elapsed(st.since, fix.t),
                    offset_m: y.norm(),
                });
                self.fix_streak = None;
            }
        }
        let lambda = self.fix_pos_scale.scale();
        // What the INS can have drifted since the last fix used: 3 sigma of the fixes
        // plus half the plausible acceleration error over the time since.
        // High-rate fixes: at least one second's worth (a drift shows over time), and
        // the fix's 3 sigma at the spread the innovations really have.
        let since = dir.elapsed(f.shared_ref().last_gnss_used_t, fix.t).max(1.0);
        let a = fe.floor_accel_mps2;
        let floor = 3.0 * lambda.sqrt() * fx.std_ned.amax() + 0.5 * a * since * since;
        let (fused, nis, y, weight) =
            self.fuse_fix_row(f, Aiding::GnssPosition(&fx), white, lambda, gate_p, floor);
        if let Some(nis) = nis {
            self.fix_pos_scale.observe(nis, 3);
        }
        let used = fused.applied();
        // A fix fused with a tenth of its weight or less does not count as a trusted
        // one: the drift floor keeps growing, and no course update follows.
        let trusted = used && weight >= 0.1;
        if used {
            f.record().gnss_used += 1;
            f.shared().note_gnss_fused(fix.t);
        }
        if trusted {
            self.fix_streak = None;
            f.shared().last_gnss_used_t = fix.t;
            self.set_fix_bias_sigma(f, &fx.std_ned);
        } else if !used {
            f.record().gnss_rejected += 1;
            if let (Fused::Rejected, Some(y)) = (&fused, y) {
                let y = Vector3::new(y[0], y[1], y[2]);
                let vel_std = f.vel_std_ned_mps();
                match self.fix_streak.as_mut() {
                    Some(st) => st.push(fix.t, y, fx.std_ned, vel_std),
                    None => self.fix_streak = Some(RejectStreak::new(fix.t, y, fx.std_ned)),
                }
            }
        }
        if use_vel && fx.vel_ned.is_some() {
            let lambda = self.fix_vel_scale.scale();
            let floor = 3.0 * lambda.sqrt() * fx.vel_std_ned.map_or(0.0, |s| s.amax()) + a * since;
            let (_, nis, _, _) =
                self.fuse_fix_row(f, Aiding::GnssVelocity(&fx), 1.0, lambda, gate_p, floor);
            if let Some(nis) = nis {
                self.fix_vel_scale.observe(nis, 3);
            }
        }
        if self.heading.course_over_ground && trusted {
            if let Some(obs) = self.course_from(&fx, dir) {
                let g = chi2_gate(1, self.heading.gate_probability);
                self.fuse(f, Aiding::Heading(&obs, HeadingAxis::VehicleForward), g);
            }
        }
        self.prev_fix = Some(fx);
    }

    /// Course over ground from the fix velocity, or from the displacement since the
    /// previous fix (seed 001 eq. 11), when fast enough; its std grows as the speed
    /// falls: sqrt(floor² + (sigma_v / v)²). The previous fix is the later one in a
    /// backward run: the displacement over the signed time difference is the same
    /// velocity.
    fn course_from(&self, f: &GnssFix, dir: TimeDirection) -> Option<HeadingObs> {
        let c = &self.heading;
        let (v_ne, sigma_v) = match (f.vel_ned, f.vel_std_ned) {
            (Some(v), s) => (
                (v.x, v.y),
                s.map_or(0.1, |s| s.x.hypot(s.y) / std::f64::consts::SQRT_2),
            ),
            (None, _) => {
                let p = self.prev_fix?;
                let dt = f.t - p.t;
                let elapsed = dir.elapsed(p.t, f.t);
                if !(elapsed > 0.0 && elapsed <= 2.0) {
                    return None;
                }
                let d = lla_diff_ned(&f.lla, &p.lla);
                let sp = (f.std_ned.x.hypot(f.std_ned.y) + p.std_ned.x.hypot(p.std_ned.y)) / 2.0;
                ((d.x / dt, d.y / dt), sp / elapsed)
            }
        };
        let speed = v_ne.0.hypot(v_ne.1);
        if speed < c.course_min_speed_mps {
            return None;
        }
        Some(HeadingObs {
            t: f.t,
            heading_rad: v_ne.1.atan2(v_ne.0),
            std_rad: c.course_std_floor.hypot(sigma_v / speed),
        })
    }
}

impl AidingSource for GnssLoose {
    fn name(&self) -> &'static str {
        "gnss_loose"
    }

    fn blocks(&self) -> Vec<BlockSpec> {
        if !self.correlated {
            return Vec::new();
        }
        // Its variance is set from the first fix's std (set_fix_bias_sigma).
        vec![BlockSpec {
            block: Block::GnssBias,
            initial_variance: vec![0.0; 3],
            process: BlockProcess::GaussMarkov {
                corr_time_s: self.opt.fix_error.corr_time_s,
                sigma: vec![0.0; 3],
            },
        }]
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
