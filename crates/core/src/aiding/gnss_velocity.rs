//! Loosely coupled GNSS velocity with the lever-arm rotation term. SYSTEM.md §3a.
//!
//!   v_ant = v^n + C_b^n (w_ib^b x l^b) - w_in^n x (C_b^n l^b)
//!   y = v_ant,INS - v_GNSS ~ dv + (\[C (w x l)\] x - \[w_in x\]\[C l x\]) phi
//!                            - C \[l x\] (b_g + diag(w) s_g)
//!                            + a^n dtau   (time-offset state, if present; a^n only
//!                                          while moving and accelerating)
//!   R = diag(vel_std²)

use super::{AidingContext, Linearized};
use crate::attitude::skew;
use crate::earth::{omega_en_n, omega_ie_n};
use crate::state::{Block, ATT, BG, SG, VEL};
use crate::types::GnssFix;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Antenna velocity in NED predicted from the INS \[m/s\].
pub fn antenna_velocity(ctx: &AidingContext) -> Vector3<f64> {
    let nav = ctx.nav;
    let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
    let w_in = omega_ie_n(nav.lla.x) + omega_en_n(nav.lla.x, nav.lla.z, &nav.v_n);
    nav.v_n + c_bn * ctx.w_ib_b.cross(&ctx.lever_arm_b) - w_in.cross(&(c_bn * ctx.lever_arm_b))
}

/// Antenna velocity (NED) and the Jacobian (3 x n) of its error with respect to the
/// error state.
pub fn antenna_velocity_jacobian(ctx: &AidingContext) -> (Vector3<f64>, DMatrix<f64>) {
    let nav = ctx.nav;
    let n = ctx.layout.len();
    let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
    let l = ctx.lever_arm_b;
    let w_in = omega_ie_n(nav.lla.x) + omega_en_n(nav.lla.x, nav.lla.z, &nav.v_n);
    let mut h = DMatrix::zeros(3, n);
    h.view_mut((0, VEL), (3, 3)).copy_from(&Matrix3::identity());
    let h_att = skew(&(c_bn * ctx.w_ib_b.cross(&l))) - skew(&w_in) * skew(&(c_bn * l));
    h.view_mut((0, ATT), (3, 3)).copy_from(&h_att);
    let c_lx = -(c_bn * skew(&l));
    h.view_mut((0, BG), (3, 3)).copy_from(&c_lx);
    h.view_mut((0, SG), (3, 3))
        .copy_from(&(c_lx * Matrix3::from_diagonal(&ctx.w_ib_b)));
    if let Some(i) = ctx.layout.index(Block::TimeOffset) {
        // A fix applied dtau too late sees the velocity of dtau later: + a^n dtau.
        h.view_mut((0, i), (3, 1))
            .copy_from(&time_offset_acceleration(ctx));
    }
    (antenna_velocity(ctx), h)
}

/// Below this INS speed \[m/s\] or acceleration \[m/s²\] the velocity-level
/// measurements' time-offset column is left out.
const TIME_OFFSET_MIN_SPEED_MPS: f64 = 1.0;
const TIME_OFFSET_MIN_ACCEL_MPS2: f64 = 0.3;

/// The acceleration in the time-offset column of a velocity-level measurement: the
/// INS's a^n while the vehicle moves and accelerates, else zero. At rest or cruising
/// a^n is the INS's own acceleration error (an accelerometer bias not yet estimated:
/// 0.05 m/s² for 5 mg) and the IMU's white noise: with it in H, carrier-phase rates
/// read the velocity drift as a time offset (140 ms in the first 5 s at rest, and
/// offsets run away by seconds in tight coupling; issue 30 part E).
pub fn time_offset_acceleration(ctx: &AidingContext) -> Vector3<f64> {
    let a = ctx.a_n;
    if ctx.nav.v_n.norm() >= TIME_OFFSET_MIN_SPEED_MPS && a.norm() >= TIME_OFFSET_MIN_ACCEL_MPS2 {
        a
    } else {
        Vector3::zeros()
    }
}

pub fn linearize(ctx: &AidingContext, fix: &GnssFix) -> Option<Linearized> {
    let v_meas = fix.vel_ned?;
    let std = fix.vel_std_ned?;
    let (v_ant, h) = antenna_velocity_jacobian(ctx);
    let y3 = v_ant - v_meas;
    let r = DMatrix::from_diagonal(&DVector::from_iterator(3, std.iter().map(|s| s * s)));
    Some(Linearized {
        y: DVector::from_column_slice(y3.as_slice()),
        h,
        r,
    })
}
