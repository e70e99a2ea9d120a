//! Tightly coupled pseudorange, one satellite. SYSTEM.md §3b; seed 000 eq. 15-22.
//!
//!   r_ant   = r_imu + C_n^e C_b^n l^b                      (ECEF)
//!   rho_INS = |r_sat - r_ant| + b + ISB_sys                (b: receiver clock \[m\])
//!   y = rho_INS - rho_GNSS ~ -u^T C_n^e d r_ant + db + dISB_sys,  u = (r_sat - r_ant) / |.|
//!   R = sigma² (elevation weighted by the GNSS layer, times the system's factor)
//!
//! b is the receiver clock on GPS time; ISB_sys = c (dt_sys - dt_GPS) as the receiver
//! sees it (system time offset plus the receiver's inter-system hardware delay), one
//! state per system other than GPS, zero for GPS and for QZSS and SBAS, which are
//! on GPS time (RTKLIB `pntpos` shares the GPS clock with them the same way).
//!
//! d r_ant (NED) comes from gnss_position::antenna_position_jacobian (position,
//! attitude through the lever arm, time offset).

use super::{AidingContext, Linearized};
use crate::earth::{c_ne, lla_to_ecef};
use crate::sat::System;
use crate::state::Block;
use crate::types::SatMeasurement;
use nalgebra::{DMatrix, DVector, Matrix3, RowVector3, Vector3};

/// The inter-system bias state of `system` (`Block::Source` of the tight source,
/// named for states.csv); None for the systems on GPS time.
pub fn isb_block(system: System) -> Option<Block> {
    let name = match system {
        System::Gps | System::Qzss | System::Sbas => return None,
        System::Glonass => "isb_glonass_m",
        System::Galileo => "isb_galileo_m",
        System::BeiDou => "isb_beidou_m",
        System::Navic => "isb_navic_m",
    };
    Some(Block::Source { name, len: 1 })
}

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
    let system = sat.sat.system;
    let predicted = range + ctx.clock.bias_for(system);
    let coef = -(u.transpose() * c_ne);
    let mut h = row(
        &coef,
        &h_pos,
        ctx.layout.index(Block::ClockBias),
        ctx.layout.len(),
    );
    if let Some(i) = isb_block(system).and_then(|b| ctx.layout.index(b)) {
        h[(0, i)] += 1.0;
    }
    Some(Linearized {
        y: DVector::from_element(1, predicted - rho),
        h,
        r: DMatrix::from_element(1, 1, sat.pseudorange_std_m.powi(2)),
    })
}
