//! Non-holonomic constraint: a land vehicle's reference point neither slides
//! sideways nor leaves the road, v^m_y = v^m_z = 0 (SYSTEM.md §4a; seed 002 eq. 1, 12).
//!
//!   y = [v^m_y, v^m_z]_INS - 0 ~ rows 2-3 of the vehicle_frame Jacobian
//!   R = diag(std_lat², std_vert²)
//!
//! When it is applied (mode, speed, static, innovation test) is the engine's choice.

use super::{vehicle_frame::vehicle_velocity, AidingContext, Linearized};
use nalgebra::{DMatrix, DVector};

pub fn linearize(ctx: &AidingContext, std_mps: [f64; 2]) -> Linearized {
    let (v_m, h3) = vehicle_velocity(ctx);
    Linearized {
        y: DVector::from_column_slice(&[v_m.y, v_m.z]),
        h: h3.rows(1, 2).into_owned(),
        r: DMatrix::from_diagonal(&DVector::from_column_slice(&[
            std_mps[0].powi(2),
            std_mps[1].powi(2),
        ])),
    }
}
