//! Data that flows between readers, the navigator and writers.
//!
//! Time `t` everywhere is GPS time in seconds of the run's reference GPS week
//! (KF-GINS files: seconds of week; data that crosses a week boundary keeps counting
//! past 604800). The week itself, when known, travels beside the data (`gps_week`).

use nalgebra::{UnitQuaternion, Vector3};

/// One IMU output interval (t - dt, t], as increments in the body frame (FRD).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// End of the interval [s].
    pub t: f64,
    /// Interval length [s].
    pub dt: f64,
    /// Angle increment over the interval [rad].
    pub dtheta: Vector3<f64>,
    /// Velocity increment (integrated specific force) over the interval [m/s].
    pub dvel: Vector3<f64>,
}

/// A GNSS receiver fix for loose coupling: antenna position, optional velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GnssFix {
    /// Time of validity [s].
    pub t: f64,
    /// Antenna position: latitude [rad], longitude [rad], ellipsoidal height [m].
    pub lla: Vector3<f64>,
    /// Position 1-sigma north, east, down [m]; each > 0.
    pub std_ned: Vector3<f64>,
    /// Antenna velocity north, east, down [m/s], if the source gives it.
    pub vel_ned: Option<Vector3<f64>>,
    /// Velocity 1-sigma north, east, down [m/s], if given.
    pub vel_std_ned: Option<Vector3<f64>>,
}

/// Navigation state of the IMU centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NavState {
    /// Time [s].
    pub t: f64,
    /// Latitude [rad], longitude [rad], ellipsoidal height [m].
    pub lla: Vector3<f64>,
    /// Velocity in NED [m/s].
    pub v_n: Vector3<f64>,
    /// Attitude C_b^n as a unit quaternion.
    pub q_bn: UnitQuaternion<f64>,
}

/// Estimated IMU errors in SI units. Compensation (KF-GINS convention):
/// `dtheta_c = (dtheta - gyro_bias * dt) / (1 + gyro_scale)`, per axis; same for accel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuErrors {
    /// Gyro bias [rad/s].
    pub gyro_bias: Vector3<f64>,
    /// Accelerometer bias [m/s²].
    pub accel_bias: Vector3<f64>,
    /// Gyro scale factor error [-] (1e-6 = 1 ppm).
    pub gyro_scale: Vector3<f64>,
    /// Accelerometer scale factor error [-].
    pub accel_scale: Vector3<f64>,
}

impl ImuErrors {
    /// Apply the error estimates to a raw sample.
    #[inline]
    pub fn compensate(&self, s: &ImuSample) -> ImuSample {
        let dtheta =
            (s.dtheta - self.gyro_bias * s.dt).component_div(&self.gyro_scale.add_scalar(1.0));
        let dvel =
            (s.dvel - self.accel_bias * s.dt).component_div(&self.accel_scale.add_scalar(1.0));
        ImuSample { dtheta, dvel, ..*s }
    }
}

/// Vehicle speed from an odometer (wheel encoder, CAN speed) at time `t`: the
/// forward speed of the vehicle reference point, before scale correction [m/s].
/// Pulse counts are converted to speed by the reader (v = K_OD dN / dt, seed 004 eq. 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometerSample {
    /// Time of validity [s]: the end of the counting interval.
    pub t: f64,
    /// Forward speed [m/s] (negative when reversing, if the sensor tells).
    pub speed_mps: f64,
    /// Length of the counting interval [s]; the speed is its mean. 0 = instantaneous.
    pub interval_s: f64,
}

/// A heading measurement: azimuth of a body-fixed direction (the dual-antenna
/// baseline) from true north, clockwise [rad], with its 1-sigma [rad].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadingObs {
    /// Time of validity [s] (GNSS time scale).
    pub t: f64,
    pub heading_rad: f64,
    pub std_rad: f64,
}

/// One time-tagged aiding input, as read from files. The navigator merges them with
/// the IMU stream in time order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measurement {
    Gnss(GnssFix),
    Odometer(OdometerSample),
    Heading(HeadingObs),
}

impl Measurement {
    /// Time of validity [s]. An odometer speed averaged over a counting interval is
    /// the speed at the interval's midpoint (exact for constant acceleration).
    pub fn t(&self) -> f64 {
        match self {
            Measurement::Gnss(f) => f.t,
            Measurement::Odometer(o) => o.t - 0.5 * o.interval_s,
            Measurement::Heading(h) => h.t,
        }
    }

    /// True for inputs time-tagged by the GNSS receiver (shifted by the GNSS-IMU time
    /// offset when it is estimated); the odometer shares the IMU clock.
    pub fn on_gnss_clock(&self) -> bool {
        !matches!(self, Measurement::Odometer(_))
    }
}

/// Merge separately read, time-sorted inputs into one time-sorted list (stable: at
/// equal times GNSS comes first, then odometer, then heading).
pub fn merge_measurements(
    gnss: &[GnssFix],
    odometer: &[OdometerSample],
    heading: &[HeadingObs],
) -> Vec<Measurement> {
    let mut all: Vec<Measurement> = Vec::with_capacity(gnss.len() + odometer.len() + heading.len());
    all.extend(gnss.iter().map(|f| Measurement::Gnss(*f)));
    all.extend(odometer.iter().map(|o| Measurement::Odometer(*o)));
    all.extend(heading.iter().map(|h| Measurement::Heading(*h)));
    all.sort_by(|a, b| a.t().total_cmp(&b.t()));
    all
}
