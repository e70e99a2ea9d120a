//! Zero-velocity (ZUPT) and zero-angular-rate (ZARU) updates while the vehicle is
//! static; the static detector is in the engine.
//!
//!   ZUPT: y = v^n_INS - 0 ~ dv,                       R = std² I
//!   ZARU: y = w_ib^b,mean - C_n^b w_ie^n ~ db_g + diag(w) ds_g,   R = std² I
//!         (compensated rate w = w_true + db_g + diag(w) ds_g with the IMU error states
//!         true - estimate; static: w_true = w_ie^b)

use super::{AidingContext, Linearized};
use crate::earth::omega_ie_n;
use crate::state::{BG, SG, VEL};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

pub fn linearize_zupt(ctx: &AidingContext, std_mps: f64) -> Linearized {
    let mut h = DMatrix::zeros(3, ctx.layout.len());
    h.view_mut((0, VEL), (3, 3)).copy_from(&Matrix3::identity());
    Linearized {
        y: DVector::from_column_slice(ctx.nav.v_n.as_slice()),
        h,
        r: DMatrix::from_diagonal_element(3, 3, std_mps.powi(2)),
    }
}

/// `w_ib_b_mean`: compensated angular rate averaged over the static window [rad/s].
pub fn linearize_zaru(ctx: &AidingContext, w_ib_b_mean: &Vector3<f64>, std: f64) -> Linearized {
    let c_nb = ctx.nav.q_bn.to_rotation_matrix().into_inner().transpose();
    let y = w_ib_b_mean - c_nb * omega_ie_n(ctx.nav.lla.x);
    let mut h = DMatrix::zeros(3, ctx.layout.len());
    h.view_mut((0, BG), (3, 3)).copy_from(&Matrix3::identity());
    h.view_mut((0, SG), (3, 3))
        .copy_from(&Matrix3::from_diagonal(w_ib_b_mean));
    Linearized {
        y: DVector::from_column_slice(y.as_slice()),
        h,
        r: DMatrix::from_diagonal_element(3, 3, std.powi(2)),
    }
}
