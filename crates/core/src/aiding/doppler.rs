//! Tightly coupled Doppler range rate, one satellite. SYSTEM.md §3b; seed 000
//! eq. 16-18, 23-28.
//!
//!   rr_INS = u . (v_sat - v_ant) + d                       (ECEF; d: clock drift \[m/s\])
//!   y = rr_INS - rr_GNSS ~ -u^T C_n^e d v_ant - dv^T (I - u u^T) / |r| C_n^e d r_ant + dd
//!   R = sigma²
//!
//! The second term (the line of sight turning with a position error) is small
//! (~1e-4 (m/s)/m) but exact and cheap.

use super::pseudorange::{antenna_ecef, row};
use super::{AidingContext, Linearized};
use crate::state::Block;
use crate::types::SatMeasurement;
use nalgebra::{DMatrix, DVector, Matrix3};

pub fn linearize(ctx: &AidingContext, sat: &SatMeasurement) -> Option<Linearized> {
    let rr = sat.range_rate_mps?;
    let (r_ant, c_ne, h_pos) = antenna_ecef(ctx);
    let (v_ant_n, h_vel) = super::gnss_velocity::antenna_velocity_jacobian(ctx);
    let d = sat.sat_pos_ecef_m - r_ant;
    let range = d.norm();
    let u = d / range;
    let dv = sat.sat_vel_ecef_mps - c_ne * v_ant_n;
    let predicted = u.dot(&dv) + ctx.clock.drift_mps;
    let n = ctx.layout.len();
    let coef_v = -(u.transpose() * c_ne);
    let coef_r = -(dv.transpose() * (Matrix3::identity() - u * u.transpose()) / range) * c_ne;
    let h = row(&coef_v, &h_vel, ctx.layout.index(Block::ClockDrift), n)
        + row(&coef_r, &h_pos, None, n);
    Some(Linearized {
        y: DVector::from_element(1, predicted - rr),
        h,
        r: DMatrix::from_element(1, 1, sat.range_rate_std_mps.powi(2)),
    })
}
