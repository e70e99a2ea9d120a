//! The GNSS integrity monitor (spoofing detection, integrity.rs) as the GNSS sources
//! use it: each epoch is tested against the INS (or dead-reckoning) prediction
//! before anything of it is fused, and the sum of the position corrections GNSS has
//! made is kept so the monitor can remove them from its reference.

use super::source::{stack_rows, Fuser};
use super::{Aiding, Linearized, ReceiverClock};
use crate::config::NavConfig;
use crate::events::Event;
use crate::integrity::{Detector, EpochCheck, IntegrityMonitor, IntegrityState, StepInput};
use crate::nav::ins_filter::Fused;
use crate::state::{POS, VEL};
use nalgebra::Vector3;

/// The monitor of one GNSS source.
pub struct GnssGuard {
    monitor: IntegrityMonitor,
    readmit_drift_mps: f64,
    /// Sum of the position corrections made by this source's updates, NED \[m\].
    correction_ned_m: Vector3<f64>,
}

impl GnssGuard {
    /// None when the monitor is off (`\[spoofing\]`).
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        cfg.integrity.enabled.then(|| GnssGuard {
            monitor: IntegrityMonitor::new(cfg.integrity.clone()),
            readmit_drift_mps: cfg.integrity.readmit_drift_mps,
            correction_ned_m: Vector3::zeros(),
        })
    }

    pub fn state(&self) -> IntegrityState {
        self.monitor.state()
    }

    /// Remember the position correction an update of this source made.
    pub fn note(&mut self, fused: &Fused) {
        if let Some(d_pos) = fused.position_correction() {
            self.correction_ned_m -= d_pos;
        }
    }

    /// Run the monitor on one epoch; true if it may be fused. The NIS is taken over
    /// `nis_rows` jointly (loose: the fix position, 3 dof; tight: all pseudoranges),
    /// the distance is |innovation| of `distance_row` (the fix position; None: the
    /// distance test abstains).
    pub fn check(
        &mut self,
        f: &mut Fuser,
        t: f64,
        nis_rows: &[Aiding],
        distance_row: Option<Aiding>,
        distance_floor_m: f64,
        clock: ReceiverClock,
    ) -> bool {
        f.flush_covariance();
        let ctx = f.context(clock);
        let stack = |list: &[Aiding]| {
            let lins: Vec<Linearized> = list.iter().filter_map(|a| a.linearize(&ctx)).collect();
            stack_rows(&lins.iter().collect::<Vec<_>>(), ctx.layout.len())
        };
        let dist_lin = distance_row.and_then(|a| stack(&[a]));
        let Some(lin) = stack(nis_rows) else {
            return true;
        };
        let nis = f.nis(&lin).unwrap_or(f64::NAN);
        let vel_std_ned_mps = f.vel_std_ned_mps();
        let step = dist_lin.as_ref().map(|l| StepInput {
            innovation_ned_m: Vector3::new(l.y[0], l.y[1], l.y[2]),
            fix_std_ned_m: Vector3::from_fn(|k, _| l.r[(k, k)].max(0.0).sqrt()),
            vel_std_ned_mps,
            gnss_correction_ned_m: self.correction_ned_m,
            ref_increment_var_ned_m2: Vector3::zeros(),
        });
        let check = EpochCheck {
            t,
            // Horizontal: the fix's vertical error (about twice the horizontal) would
            // make a 3D R false-alarm; vertical offsets are left to the chi-square test.
            distance_m: dist_lin
                .as_ref()
                .map_or(f64::NAN, |l| l.y.rows(0, 2).norm()),
            nis,
            dof: lin.y.len(),
            ref_pos_std_m: (0..3).map(|k| f.std(POS + k).powi(2)).sum::<f64>().sqrt(),
            distance_floor_m,
            step,
        };
        self.verdict(f, &check)
    }

    /// Feed one epoch to the monitor, log its transition; true if GNSS may be fused.
    pub fn verdict(&mut self, f: &mut Fuser, check: &EpochCheck) -> bool {
        self.monitor.set_direction(f.direction());
        let v = self.monitor.check(check);
        if let Some(tr) = v.transition {
            f.push_event(Event::Integrity(tr));
            // Re-admitted although it still disagrees (the reference went off with an
            // unseen slow attack): widen the position uncertainty to the disagreement
            // and the velocity's by the drift it was allowed.
            if tr.detector == Detector::Consistency {
                if let Some(step) = check.step {
                    let (y, v) = (step.innovation_ned_m, self.readmit_drift_mps);
                    f.widen(POS, y.component_mul(&y));
                    f.widen(VEL, Vector3::repeat(v * v));
                }
            }
        }
        v.use_gnss
    }
}
