//! Loosely coupled GNSS position with antenna lever arm. SYSTEM.md §3a.
//!
//!   r_ant = r_imu + C_b^n l^b            (NED metres)
//!   y     = r_ant,INS - r_GNSS  ~  dr + (C_b^n l^b x) phi + v_ant dtau
//!   R     = diag(std_N², std_E², std_D²)
//!
//! dtau (optional state) is the GNSS-IMU time-offset error: a fix applied dtau too
//! late sees the antenna displaced by v_ant * dtau. With the `GnssBias` block
//! (fix_error.rs) the fix is r_ant + b + v: y gains + b_est and H an identity column.

use super::{AidingContext, Linearized};
use crate::attitude::skew;
use crate::earth::lla_diff_ned;
use crate::state::{Block, ATT, POS};
use crate::types::GnssFix;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Lever arm C_b^n l^b \[m, NED\] and the Jacobian (3 x n) of the INS antenna position
/// error (NED metres) with respect to the error state.
pub fn antenna_position_jacobian(ctx: &AidingContext) -> (Vector3<f64>, DMatrix<f64>) {
    let c_bn = ctx.nav.q_bn.to_rotation_matrix().into_inner();
    let l_n = c_bn * ctx.lever_arm_b;
    let mut h = DMatrix::zeros(3, ctx.layout.len());
    h.view_mut((0, POS), (3, 3)).copy_from(&Matrix3::identity());
    h.view_mut((0, ATT), (3, 3)).copy_from(&skew(&l_n));
    if let Some(i) = ctx.layout.index(Block::TimeOffset) {
        let v_ant = super::gnss_velocity::antenna_velocity(ctx);
        h.view_mut((0, i), (3, 1)).copy_from(&v_ant);
    }
    (l_n, h)
}

pub fn linearize(ctx: &AidingContext, fix: &GnssFix) -> Linearized {
    let (l_n, mut h) = antenna_position_jacobian(ctx);
    let mut y3 = lla_diff_ned(&ctx.nav.lla, &fix.lla) + l_n;
    if let Some(i) = ctx.layout.index(Block::GnssBias) {
        y3 += ctx.gnss_bias_ned_m;
        h.view_mut((0, i), (3, 3)).copy_from(&Matrix3::identity());
    }
    let r = DMatrix::from_diagonal(&DVector::from_iterator(
        3,
        fix.std_ned.iter().map(|s| s * s),
    ));
    Linearized {
        y: DVector::from_column_slice(y3.as_slice()),
        h,
        r,
    }
}
