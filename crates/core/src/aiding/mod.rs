//! Aiding sources. Each file holds one source's measurement, Jacobian and noise
//! (`linearize`); this module is the single registration point: add a variant to
//! [`Aiding`] and a line to [`Aiding::linearize`].

pub mod gnss_position;
pub mod gnss_velocity;

use crate::state::StateLayout;
use crate::types::{GnssFix, NavState};
use nalgebra::{DMatrix, DVector, Vector3};

/// What the aiding models may read about the current INS solution.
pub struct AidingContext<'a> {
    pub nav: &'a NavState,
    pub layout: &'a StateLayout,
    /// Compensated angular rate w_ib^b over the last IMU interval [rad/s].
    pub w_ib_b: Vector3<f64>,
    /// Acceleration d(v^n)/dt over the last IMU interval [m/s²].
    pub a_n: Vector3<f64>,
    /// Antenna lever arm in the body frame [m].
    pub lever_arm_b: Vector3<f64>,
}

/// A linearised measurement: innovation y = h(x_est) - z ~ H dx + v, v ~ N(0, R).
#[derive(Clone, Debug)]
pub struct Linearized {
    pub y: DVector<f64>,
    pub h: DMatrix<f64>,
    pub r: DMatrix<f64>,
}

/// Every measurement the navigator can fuse.
#[derive(Clone, Copy, Debug)]
pub enum Aiding<'a> {
    GnssPosition(&'a GnssFix),
    GnssVelocity(&'a GnssFix),
}

impl Aiding<'_> {
    /// Short name used in logs and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            Aiding::GnssPosition(_) => "gnss_position",
            Aiding::GnssVelocity(_) => "gnss_velocity",
        }
    }

    /// The measurement model; None when the measurement has nothing to offer
    /// (e.g. a fix without velocity).
    pub fn linearize(&self, ctx: &AidingContext) -> Option<Linearized> {
        match self {
            Aiding::GnssPosition(fix) => Some(gnss_position::linearize(ctx, fix)),
            Aiding::GnssVelocity(fix) => gnss_velocity::linearize(ctx, fix),
        }
    }
}
