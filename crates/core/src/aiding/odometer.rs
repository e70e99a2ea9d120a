//! Odometer forward speed with scale-factor error (SYSTEM.md §4b; seed 004 eq. 1-7).
//! True speed = (1 + k) * measured; k is the `OdometerScale` state (dk = k_est - k_true).
//!
//!   y = v^m_x,INS - (1 + k) s_od ~ row 1 of the vehicle_frame Jacobian - s_od dk
//!   R = std²
//!
//! With `nhc_std`, the lateral and vertical rows (v^m = \[v 0 0\]^T, seed 004's
//! three-row measurement) are appended.
//!
//! Near standstill (`calibrate` = false) the scale and mounting columns are zeroed:
//! there H_k = -s_od is the speed noise itself and would drive k (issue 15: -71 %
//! while parked with 0.1 m/s noise).

use super::{vehicle_frame::vehicle_velocity, AidingContext, Linearized};
use crate::state::Block;
use nalgebra::{DMatrix, DVector};

pub fn linearize(
    ctx: &AidingContext,
    speed_mps: f64,
    std_mps: f64,
    nhc_std: Option<[f64; 2]>,
    calibrate: bool,
) -> Linearized {
    let (v_m, h3) = vehicle_velocity(ctx);
    let rows = if nhc_std.is_some() { 3 } else { 1 };
    let k = ctx.vehicle.odometer_scale;
    let mut y = DVector::zeros(rows);
    y[0] = v_m.x - (1.0 + k) * speed_mps;
    let mut h = h3.rows(0, rows).into_owned();
    if let Some(i) = ctx.layout.index(Block::OdometerScale) {
        h[(0, i)] = if calibrate { -speed_mps } else { 0.0 };
    }
    if let (false, Some(i)) = (calibrate, ctx.layout.index(Block::Mounting)) {
        h.columns_mut(i, 2).fill(0.0);
    }
    let mut r = DMatrix::zeros(rows, rows);
    r[(0, 0)] = std_mps.powi(2);
    if let Some(s) = nhc_std {
        y[1] = v_m.y;
        y[2] = v_m.z;
        r[(1, 1)] = s[0].powi(2);
        r[(2, 2)] = s[1].powi(2);
    }
    Linearized { y, h, r }
}

// ---------------------------------------------------------------------------------
// Policy: every odometer record is fused with its speed-dependent std and gate; the
// scale and mounting are calibrated only when both the odometer and the INS move.

use super::source::{chi2_gate, AidingSource, Fuser, Handled};
use super::Aiding;
use crate::config::{NavConfig, NhcMode, OdometerOptions};
use crate::types::Measurement;

/// The odometer as an aiding source (`\[odometer\]`).
pub struct OdometerSource {
    opt: OdometerOptions,
    /// Seed 004's three-row form: the NHC rows with the odometer (when no separate
    /// NHC runs), lateral and vertical std \[m/s\].
    nhc_std: Option<[f64; 2]>,
}

impl OdometerSource {
    /// None when the odometer is not used.
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        let c = &cfg.odometer;
        c.enabled.then(|| OdometerSource {
            opt: c.clone(),
            nhc_std: (c.with_nhc && cfg.nhc.mode == NhcMode::Off).then_some(cfg.nhc.std_mps),
        })
    }
}

impl AidingSource for OdometerSource {
    fn name(&self) -> &'static str {
        "odometer"
    }

    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        let Measurement::Odometer(o) = m else {
            return Handled::No;
        };
        let c = &self.opt;
        let rows = if self.nhc_std.is_some() { 3 } else { 1 };
        let v_min = c.calibration_min_speed_mps;
        let aiding = Aiding::Odometer {
            speed_mps: o.speed_mps,
            std_mps: c.std_mps.hypot(c.std_speed_fraction * o.speed_mps),
            nhc_std: self.nhc_std,
            calibrate: o.speed_mps.abs() >= v_min && f.nav().v_n.norm() >= v_min,
        };
        f.fuse(aiding, chi2_gate(rows, c.gate_probability));
        Handled::Yes
    }
}
