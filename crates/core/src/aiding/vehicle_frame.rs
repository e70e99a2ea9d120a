//! Velocity of the vehicle reference point in the vehicle frame, shared by the
//! non-holonomic constraint and the odometer. SYSTEM.md §4b (seed 004 eq. 4-7):
//!
//!   v^m = C_b^m (C_n^b v^n + w_eb^b x l^b),   w_eb^b = w_ib^b - C_n^b w_ie^n
//!
//! Jacobian with the error conventions of state.rs (navigation and vehicle states
//! x_est - x_true, C_b^n,est = (I - phi x) C_b^n, C_b^m,est = (I - dalpha x) C_b^m with
//! dalpha = (0, p, y); IMU errors true - estimate, so w_est = w + db_g + diag(w) ds_g):
//!
//!   d v^m = C_b^m ( C_n^b dv - C_n^b \[v^n x\] phi - \[l x\] (db_g + diag(w) ds_g) )
//!           + \[v^m x\] dalpha

use super::AidingContext;
use crate::attitude::skew;
use crate::earth::omega_ie_n;
use crate::state::{Block, ATT, BG, SG, VEL};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// v^m \[m/s\] and its 3 x n Jacobian.
pub fn vehicle_velocity(ctx: &AidingContext) -> (Vector3<f64>, DMatrix<f64>) {
    let nav = ctx.nav;
    let n = ctx.layout.len();
    let c_nb = nav.q_bn.to_rotation_matrix().into_inner().transpose();
    let l = ctx.vehicle.lever_arm_b;
    let c_bm = ctx.vehicle.c_bm;
    let w_eb_b = ctx.w_ib_b - c_nb * omega_ie_n(nav.lla.x);
    let v_b = c_nb * nav.v_n + w_eb_b.cross(&l);
    let v_m = c_bm * v_b;
    let mut h = DMatrix::zeros(3, n);
    h.view_mut((0, VEL), (3, 3)).copy_from(&(c_bm * c_nb));
    h.view_mut((0, ATT), (3, 3))
        .copy_from(&(-(c_bm * c_nb * skew(&nav.v_n))));
    let c_lx = -(c_bm * skew(&l));
    h.view_mut((0, BG), (3, 3)).copy_from(&c_lx);
    h.view_mut((0, SG), (3, 3))
        .copy_from(&(c_lx * Matrix3::from_diagonal(&ctx.w_ib_b)));
    if let Some(i) = ctx.layout.index(Block::Mounting) {
        // Columns of [v^m x] for the pitch (y) and yaw (z) axes.
        let vx = skew(&v_m);
        h.view_mut((0, i), (3, 2))
            .copy_from(&vx.fixed_view::<3, 2>(0, 1));
    }
    (v_m, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aiding::tests::{context_fixture, numeric_jacobian_check};

    /// The analytic Jacobian matches finite differences of the model through the
    /// error injection of state.rs (attitude, velocity, gyro bias/scale, mounting).
    #[test]
    fn jacobian_matches_finite_differences() {
        let fx = context_fixture(true);
        numeric_jacobian_check(&fx, vehicle_velocity, 1e-6);
    }
}
