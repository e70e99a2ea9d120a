//! Odometer forward speed with scale-factor error (SYSTEM.md §4b; seed 004 eq. 1-7).
//! True speed = (1 + k) * measured; k is the `OdometerScale` state (dk = k_est - k_true).
//! The measured speed is predicted from the state (docs/ALGORITHMS.md "Odometer"):
//!
//!   s_od = v^m_x / (1 + k) + n,   n ~ N(0, std²)
//!   y = v^m_x,INS / (1 + k) - s_od ~ row 1 of the vehicle_frame Jacobian / (1 + k)
//!                                    - v^m_x / (1 + k)² dk
//!
//! Nothing of the measurement enters H, R or the calibration decision: with the older
//! form y = v^m_x - (1 + k) s_od (H_k = -s_od) the speed noise sat in H and the
//! speed-dependent std, and biased k low (errors in variables, REFERENCES \[FUL87\]), the
//! more so the more records (0.1 m/s of noise at 100 Hz: -891 ppm, -8.2 sigma).
//!
//! With `nhc_std`, the lateral and vertical rows (v^m = \[v 0 0\]^T, seed 004's
//! three-row measurement) are appended.
//!
//! Below `calibration_min_speed_mps` of predicted or INS speed the scale and mounting
//! columns are zeroed: near standstill the scale is unobservable and noise would drive
//! it (issue 15: -71 % while parked with 0.1 m/s noise).

use super::{vehicle_frame::vehicle_velocity, AidingContext, Linearized};
use crate::state::Block;
use nalgebra::{DMatrix, DVector};

/// The odometer's error model for one record (`\[odometer\]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometerNoise {
    /// Speed-independent 1-sigma \[m/s\].
    pub std_mps: f64,
    /// Speed-proportional part: 1-sigma = hypot(std_mps, fraction * predicted speed).
    pub std_speed_fraction: f64,
    /// Below this predicted (or INS) speed the scale and mounting are left alone \[m/s\].
    pub calibration_min_speed_mps: f64,
}

/// The measured speed predicted from the state, v^m_x / (1 + k) \[m/s\].
pub fn predicted_speed(ctx: &AidingContext) -> f64 {
    vehicle_velocity(ctx).0.x / (1.0 + ctx.vehicle.odometer_scale)
}

pub fn linearize(
    ctx: &AidingContext,
    speed_mps: f64,
    noise: &OdometerNoise,
    nhc_std: Option<[f64; 2]>,
) -> Linearized {
    let (v_m, h3) = vehicle_velocity(ctx);
    let rows = if nhc_std.is_some() { 3 } else { 1 };
    let inv = 1.0 / (1.0 + ctx.vehicle.odometer_scale);
    let s_pred = v_m.x * inv;
    let v_min = noise.calibration_min_speed_mps;
    let calibrate = s_pred.abs() >= v_min && ctx.nav.v_n.norm() >= v_min;
    let mut y = DVector::zeros(rows);
    y[0] = s_pred - speed_mps;
    let mut h = h3.rows(0, rows).into_owned();
    h.row_mut(0).scale_mut(inv);
    if let Some(i) = ctx.layout.index(Block::OdometerScale) {
        h[(0, i)] = if calibrate { -s_pred * inv } else { 0.0 };
    }
    if let (false, Some(i)) = (calibrate, ctx.layout.index(Block::Mounting)) {
        h.columns_mut(i, 2).fill(0.0);
    }
    let mut r = DMatrix::zeros(rows, rows);
    r[(0, 0)] = noise
        .std_mps
        .hypot(noise.std_speed_fraction * s_pred)
        .powi(2);
    if let Some(s) = nhc_std {
        y[1] = v_m.y;
        y[2] = v_m.z;
        r[(1, 1)] = s[0].powi(2);
        r[(2, 2)] = s[1].powi(2);
    }
    Linearized { y, h, r }
}

// ---------------------------------------------------------------------------------
// Policy: every odometer record is fused with its gate; the std and whether the scale
// and mounting are calibrated follow from the predicted speed (linearize).

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
        let aiding = Aiding::Odometer {
            speed_mps: o.speed_mps,
            noise: OdometerNoise {
                std_mps: c.std_mps,
                std_speed_fraction: c.std_speed_fraction,
                calibration_min_speed_mps: c.calibration_min_speed_mps,
            },
            nhc_std: self.nhc_std,
        };
        f.fuse(aiding, chi2_gate(rows, c.gate_probability));
        Handled::Yes
    }
}
