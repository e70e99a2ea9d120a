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
//! The error of the displacement is the velocity error integrated over the interval,
//! and the velocity error changes over it with its own dynamics (SYSTEM.md §2, the
//! velocity rows F_v of F): d v(t) = d v_k - (t_k - t) F_v dx, so
//!
//!   d D = d v_k dt - dt²/2 F_v dx,   F_v dx ~ (f^n x) phi + C_b^n d b_a + C_b^n diag(f^b) d s_a
//!
//! (the tilt and accelerometer terms; the Coriolis and gravity-gradient ones are
//! below 1e-4 of them), with f^n = gravity's share (0, 0, -g): tilt, not yaw. Without
//! the second term the carriers, a mean rate over the interval, would be read as the
//! velocity at its end: a tilt error of 0.1 deg is then 8 mm/s of velocity bias at
//! 1 Hz (an error-free simulated drive: 7.6 cm horizontal RMS, 3.1 cm with the term).
//! The vehicle's own accelerations are left out: with them (the last sample's, or
//! the interval's mean) the carriers also pull the yaw, and the handheld walk
//! `examples/walk_0827_tight.toml` went from 8.2 m to 338 m (14.7 m) RMS, its UBX and
//! RINEX runs 5.6 m apart. Using the exact INS displacement instead of
//! v_k dt keeps the acceleration over the interval out of the model. The clock
//! difference b_k - b_{k-1} is modelled as d dt. A backward run differences each epoch
//! with the later one (dt < 0, D from it): every term is a mean rate over the signed
//! interval, so the model holds unchanged.

use super::pseudorange::{antenna_ecef, row};
use super::{AidingContext, Linearized};
use crate::attitude::skew;
use crate::earth::gravity_normal;
use crate::state::{Block, ATT, BA, SA};
use crate::types::SatMeasurement;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

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
    let (_, mut h_vel) = super::gnss_velocity::antenna_velocity_jacobian(ctx);
    // The mean velocity error over the interval: less dt/2 F_v dx (module doc), with
    // gravity's share of the specific force.
    let nav = ctx.nav;
    let f_n = Vector3::new(0.0, 0.0, -gravity_normal(nav.lla.x, nav.lla.z));
    let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
    let f_b = c_bn.transpose() * f_n;
    let half = 0.5 * dt;
    for (col, m) in [
        (ATT, skew(&f_n)),
        (BA, c_bn),
        (SA, c_bn * Matrix3::from_diagonal(&f_b)),
    ] {
        for i in 0..3 {
            for j in 0..3 {
                h_vel[(i, col + j)] -= half * m[(i, j)];
            }
        }
    }
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
