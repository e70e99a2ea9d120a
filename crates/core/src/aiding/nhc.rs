//! Non-holonomic constraint: a land vehicle's reference point neither slides
//! sideways nor leaves the road, v^m_y = v^m_z = 0 (SYSTEM.md §4a; seed 002 eq. 1, 12).
//!
//!   y = \[v^m_y, v^m_z\]_INS - 0 ~ rows 2-3 of the vehicle_frame Jacobian
//!   R = diag(std_lat², std_vert²)
//!
//! When it is applied (mode, speed, static, innovation test): `NhcSource` below.

use super::{vehicle_frame::vehicle_velocity, AidingContext, Linearized};
use nalgebra::{DMatrix, DVector};

pub fn linearize(ctx: &AidingContext, std_mps: [f64; 2]) -> Linearized {
    let (v_m, h3) = vehicle_velocity(ctx);
    Linearized {
        y: DVector::from_column_slice(&[v_m.y, v_m.z]),
        h: h3.rows(1, 2).into_owned(),
        r: DMatrix::from_diagonal(&DVector::from_column_slice(&[
            std_mps[0].powi(2),
            std_mps[1].powi(2),
        ])),
    }
}

// ---------------------------------------------------------------------------------
// Policy: at `rate_hz` while moving faster than `min_speed_mps` and not static,
// always or only once GNSS has been missing for `outage_after_s` (mode).

use super::source::{chi2_gate, AidingSource, Fuser};
use super::Aiding;
use crate::config::{NavConfig, NhcMode, NhcOptions};

/// The non-holonomic constraint as an aiding source (`\[nhc\]`).
pub struct NhcSource {
    opt: NhcOptions,
    next_t: f64,
}

impl NhcSource {
    /// None when the NHC is off; `t0`: the start time (IMU time).
    pub fn from_config(cfg: &NavConfig, t0: f64) -> Option<Self> {
        (cfg.nhc.mode != NhcMode::Off).then(|| NhcSource {
            opt: cfg.nhc.clone(),
            next_t: t0,
        })
    }
}

impl AidingSource for NhcSource {
    fn name(&self) -> &'static str {
        "nhc"
    }

    fn after_imu(&mut self, f: &mut Fuser) {
        let c = &self.opt;
        let t = f.nav().t;
        // Elapsed time and cadence along the run (a backward run goes down in time).
        let dir = f.direction();
        let due = match c.mode {
            NhcMode::Off => false,
            NhcMode::Always => true,
            NhcMode::DuringOutage => {
                dir.elapsed(f.shared_ref().last_gnss_used_t, f.time_gnss()) >= c.outage_after_s
            }
        };
        if due && !f.shared_ref().is_static && dir.reached(t, self.next_t, 1e-9) {
            self.next_t = dir.advance(t, 1.0 / c.rate_hz);
            if f.nav().v_n.norm() >= c.min_speed_mps {
                let g = chi2_gate(2, c.gate_probability);
                f.fuse(Aiding::Nhc(c.std_mps), g);
            }
        }
    }
}
