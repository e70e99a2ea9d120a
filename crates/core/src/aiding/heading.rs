//! Heading from GNSS (SYSTEM.md §3c; seed 001 eq. 10-11): the azimuth of a body-fixed
//! direction d, either the dual-antenna baseline (given in the IMU frame) or the
//! vehicle's forward axis d_b = C_m^b e_x (course over ground while driving).
//!
//!   d^n = C_b^n d_b,  psi = atan2(d^n_E, d^n_N)
//!   y = wrap(psi_INS - psi_meas) ~ g \[d^n x\] phi  (- g C_b^n C_m^b \[e_x x\] dalpha)
//!   g = dpsi/dd^n = (-d_E, d_N, 0) / (d_N² + d_E²),  R = std²

use super::{AidingContext, Linearized};
use crate::attitude::{skew, wrap_pi};
use crate::state::{Block, ATT};
use crate::types::HeadingObs;
use nalgebra::{DMatrix, DVector, RowVector3, Vector3};

/// Which body-fixed direction the heading belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HeadingAxis {
    /// A direction in the IMU frame (dual-antenna baseline).
    Body(Vector3<f64>),
    /// The vehicle's forward axis (uses the mounting estimate).
    VehicleForward,
}

/// None when the direction is (nearly) vertical, so that it has no azimuth.
pub fn linearize(ctx: &AidingContext, obs: &HeadingObs, axis: HeadingAxis) -> Option<Linearized> {
    let c_bn = ctx.nav.q_bn.to_rotation_matrix().into_inner();
    let c_mb = ctx.vehicle.c_bm.transpose();
    let d_b = match axis {
        HeadingAxis::Body(b) => b,
        HeadingAxis::VehicleForward => c_mb.column(0).into_owned(),
    };
    let d_n = c_bn * d_b;
    let hor2 = d_n.x * d_n.x + d_n.y * d_n.y;
    if hor2 < 1e-6 * d_n.norm_squared() {
        return None;
    }
    let g = RowVector3::new(-d_n.y / hor2, d_n.x / hor2, 0.0);
    let psi = d_n.y.atan2(d_n.x);
    let n = ctx.layout.len();
    let mut h = DMatrix::zeros(1, n);
    h.view_mut((0, ATT), (1, 3)).copy_from(&(g * skew(&d_n)));
    if let (HeadingAxis::VehicleForward, Some(i)) = (axis, ctx.layout.index(Block::Mounting)) {
        let h_a = -(g * c_bn * c_mb * skew(&Vector3::x()));
        h[(0, i)] = h_a[1];
        h[(0, i + 1)] = h_a[2];
    }
    Some(Linearized {
        y: DVector::from_element(1, wrap_pi(psi - obs.heading_rad)),
        h,
        r: DMatrix::from_element(1, 1, obs.std_rad.powi(2)),
    })
}

// ---------------------------------------------------------------------------------
// Policy: a dual-antenna heading record is fused with its std (or the configured
// one) and the gate; the course over ground is the loose GNSS source's (gnss_loose.rs).

use super::source::{chi2_gate, AidingSource, Fuser, Handled};
use super::Aiding;
use crate::config::{HeadingOptions, NavConfig};
use crate::types::Measurement;

/// Dual-antenna heading as an aiding source (`\[heading\]` with a baseline).
pub struct DualAntennaHeading {
    opt: HeadingOptions,
    baseline_b: Vector3<f64>,
}

impl DualAntennaHeading {
    /// None without a baseline (no dual-antenna heading is fused).
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        let c = &cfg.heading;
        c.baseline_b.map(|b| DualAntennaHeading {
            opt: c.clone(),
            baseline_b: b,
        })
    }
}

impl AidingSource for DualAntennaHeading {
    fn name(&self) -> &'static str {
        "dual_antenna_heading"
    }

    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        let Measurement::Heading(h) = m else {
            return Handled::No;
        };
        let mut obs = *h;
        if let Some(s) = self.opt.dual_antenna_std_override {
            obs.std_rad = s;
        }
        let g = chi2_gate(1, self.opt.gate_probability);
        f.fuse(Aiding::Heading(&obs, HeadingAxis::Body(self.baseline_b)), g);
        Handled::Yes
    }
}
