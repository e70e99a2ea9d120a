//! Time-differenced carrier phase (TDCP) as a mean range rate over the interval
//! between two epochs, one satellite. SYSTEM.md §3b; seed 000 eq. 1-7, 14.
//!
//! The integer ambiguity cancels between epochs k-1 and k of continuous tracking:
//!
//!   z      = (phi_k - phi_{k-1}) / dt                         (phi: carrier \[m\])
//!   r_prev = r_ant,k - D                                      (D: INS antenna
//!            displacement over the interval, from the mechanization, ECEF)
//!   z_INS  = (|r_sat,k - r_ant,k| - |r_sat,k-1 - r_prev|) / dt + d
//!   y = z_INS - z ~ -u_{k-1}^T C_n^e d v_ant + (u_{k-1} - u_k)^T / dt C_n^e d r_ant + dd
//!   R = (sigma_k² + sigma_{k-1}²) / dt²
//!
//! The velocity column follows from d D ~ d v dt (the error of the displacement is
//! the velocity error over the interval); using the exact INS displacement instead
//! of v_k dt keeps the acceleration over the interval out of the model. The clock
//! difference b_k - b_{k-1} is modelled as d dt. A backward run differences each epoch
//! with the later one (dt < 0, D from it): every term is a mean rate over the signed
//! interval, so the model holds unchanged.

use super::pseudorange::{antenna_ecef, row};
use super::{AidingContext, Linearized};
use crate::state::Block;
use crate::types::SatMeasurement;
use nalgebra::{DMatrix, DVector, Vector3};

/// What TDCP needs from the previous epoch of a satellite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TdcpPrevious {
    /// Time of the previous epoch \[s\].
    pub t: f64,
    pub sat_pos_ecef_m: Vector3<f64>,
    pub carrier_m: f64,
    pub carrier_std_m: f64,
}

/// The INS antenna displacement over the interval (ECEF \[m\]) and its length \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub antenna_displacement_ecef_m: Vector3<f64>,
    pub dt_s: f64,
}

pub fn linearize(
    ctx: &AidingContext,
    sat: &SatMeasurement,
    prev: &TdcpPrevious,
    interval: &Interval,
) -> Option<Linearized> {
    let phi = sat.carrier_m?;
    let dt = interval.dt_s;
    // dt < 0 in a backward run (the previous epoch is the later one): z, the
    // prediction and H are mean rates over the signed interval, the same model.
    if dt == 0.0 {
        return None;
    }
    let (r_ant, c_ne, h_pos) = antenna_ecef(ctx);
    let (_, h_vel) = super::gnss_velocity::antenna_velocity_jacobian(ctx);
    let d_k = sat.sat_pos_ecef_m - r_ant;
    let d_prev = prev.sat_pos_ecef_m - (r_ant - interval.antenna_displacement_ecef_m);
    let (u_k, u_prev) = (d_k.normalize(), d_prev.normalize());
    let predicted = (d_k.norm() - d_prev.norm()) / dt + ctx.clock.drift_mps;
    let z = (phi - prev.carrier_m) / dt;
    let n = ctx.layout.len();
    let coef_v = -(u_prev.transpose() * c_ne);
    let coef_r = ((u_prev - u_k).transpose() / dt) * c_ne;
    let h = row(&coef_v, &h_vel, ctx.layout.index(Block::ClockDrift), n)
        + row(&coef_r, &h_pos, None, n);
    let var = (sat.carrier_std_m.powi(2) + prev.carrier_std_m.powi(2)) / (dt * dt);
    Some(Linearized {
        y: DVector::from_element(1, predicted - z),
        h,
        r: DMatrix::from_element(1, 1, var),
    })
}
