//! Tightly coupled pseudorange, one satellite. SYSTEM.md §3b; seed 000 eq. 15-22.
//!
//!   r_ant   = r_imu + C_n^e C_b^n l^b                      (ECEF)
//!   rho_INS = |r_sat - r_ant| + b                          (b: receiver clock \[m\])
//!   y = rho_INS - rho_GNSS ~ -u^T C_n^e d r_ant + db,  u = (r_sat - r_ant) / |.|
//!   R = sigma² (elevation weighted by the GNSS layer)
//!
//! d r_ant (NED) comes from gnss_position::antenna_position_jacobian (position,
//! attitude through the lever arm, time offset).

use super::{AidingContext, Linearized};
use crate::earth::{c_ne, lla_to_ecef};
use crate::state::Block;
use crate::types::SatMeasurement;
use nalgebra::{DMatrix, DVector, Matrix3, RowVector3, Vector3};

/// Antenna position (ECEF \[m\]), C_n^e, and the NED Jacobian of its error.
pub fn antenna_ecef(ctx: &AidingContext) -> (Vector3<f64>, Matrix3<f64>, DMatrix<f64>) {
    let (l_n, h_pos) = super::gnss_position::antenna_position_jacobian(ctx);
    let c = c_ne(ctx.nav.lla.x, ctx.nav.lla.y);
    (lla_to_ecef(&ctx.nav.lla) + c * l_n, c, h_pos)
}

/// One row `coef_ned^T H_pos` (+ 1 in the clock column `clock`), as a 1 x n matrix.
pub(crate) fn row(
    coef_ned: &RowVector3<f64>,
    h3: &DMatrix<f64>,
    clock: Option<usize>,
    n: usize,
) -> DMatrix<f64> {
    let mut h = DMatrix::zeros(1, n);
    for j in 0..n {
        h[(0, j)] = coef_ned[0] * h3[(0, j)] + coef_ned[1] * h3[(1, j)] + coef_ned[2] * h3[(2, j)];
    }
    if let Some(i) = clock {
        h[(0, i)] += 1.0;
    }
    h
}

pub fn linearize(ctx: &AidingContext, sat: &SatMeasurement) -> Option<Linearized> {
    let rho = sat.pseudorange_m?;
    let (r_ant, c_ne, h_pos) = antenna_ecef(ctx);
    let d = sat.sat_pos_ecef_m - r_ant;
    let range = d.norm();
    let u = d / range;
    let predicted = range + ctx.clock.bias_m;
    let coef = -(u.transpose() * c_ne);
    let h = row(
        &coef,
        &h_pos,
        ctx.layout.index(Block::ClockBias),
        ctx.layout.len(),
    );
    Some(Linearized {
        y: DVector::from_element(1, predicted - rho),
        h,
        r: DMatrix::from_element(1, 1, sat.pseudorange_std_m.powi(2)),
    })
}
