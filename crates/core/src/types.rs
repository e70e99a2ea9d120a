//! Data that flows between readers, the navigator and writers.
//!
//! Time `t` everywhere is GPS time in seconds of the run's reference GPS week
//! (KF-GINS files: seconds of week; data that crosses a week boundary keeps counting
//! past 604800). The week itself, when known, travels beside the data (`gps_week`).

use nalgebra::{UnitQuaternion, Vector3};
use std::sync::Arc;

/// One IMU output interval (t - dt, t], as increments in the body frame (FRD).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// End of the interval \[s\].
    pub t: f64,
    /// Interval length \[s\].
    pub dt: f64,
    /// Angle increment over the interval \[rad\].
    pub dtheta: Vector3<f64>,
    /// Velocity increment (integrated specific force) over the interval \[m/s\].
    pub dvel: Vector3<f64>,
}

/// A GNSS receiver fix for loose coupling: antenna position, optional velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GnssFix {
    /// Time of validity \[s\].
    pub t: f64,
    /// Antenna position: latitude \[rad\], longitude \[rad\], ellipsoidal height \[m\].
    pub lla: Vector3<f64>,
    /// Position 1-sigma north, east, down \[m\]; each > 0.
    pub std_ned: Vector3<f64>,
    /// Antenna velocity north, east, down \[m/s\], if the source gives it.
    pub vel_ned: Option<Vector3<f64>>,
    /// Velocity 1-sigma north, east, down \[m/s\], if given.
    pub vel_std_ned: Option<Vector3<f64>>,
}

/// One satellite's measurements at one epoch, prepared by the GNSS layer for tight
/// coupling (SYSTEM.md §3b; seed 000 eq. 12-18). ECEF at the reception time.
/// Everything the GNSS layer can model is already removed, so that
/// `pseudorange_m = |sat_pos - antenna| + receiver clock bias \[m\] + noise`, the
/// clock bias being that of the satellite's system (GPS time plus, for the other
/// systems, the inter-system bias the tight coupling estimates, aiding/tight.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SatMeasurement {
    /// The satellite (system and number): per-satellite state (carrier differencing)
    /// is kept by it, and its system picks the inter-system bias and noise factor.
    pub sat: crate::sat::SatId,
    /// Satellite position at transmission (light time solved), rotated into the ECEF
    /// frame at reception (Sagnac) \[m\].
    pub sat_pos_ecef_m: Vector3<f64>,
    /// Its rate of change with the reception time \[m/s\].
    pub sat_vel_ecef_mps: Vector3<f64>,
    /// Elevation seen from the receiver \[rad\].
    pub elevation_rad: f64,
    /// Pseudorange with the satellite clock (relativity and TGD included) and either
    /// the broadcast ionosphere and troposphere models or the DGPS correction
    /// applied: geometric range + receiver clock bias \[m\].
    pub pseudorange_m: Option<f64>,
    /// 1-sigma of `pseudorange_m` (elevation weighted) \[m\].
    pub pseudorange_std_m: f64,
    /// Range rate from the Doppler, -lambda D, with the satellite clock drift (and the
    /// DGPS range-rate correction) removed: d|sat - antenna|/dt + receiver clock
    /// drift \[m/s\].
    pub range_rate_mps: Option<f64>,
    /// 1-sigma of `range_rate_mps` \[m/s\].
    pub range_rate_std_mps: f64,
    /// Carrier phase lambda L \[m\] with the satellite clock removed and, with DGPS, the
    /// integrated range-rate correction added (never the code-based correction, whose
    /// noise would enter the time difference). Continuous while `lost_lock` is false.
    pub carrier_m: Option<f64>,
    /// 1-sigma of one carrier phase \[m\] (elevation weighted).
    pub carrier_std_m: f64,
    /// Loss of lock or a cycle slip flagged by the receiver since the previous epoch
    /// (RINEX LLI bit 0): the carrier is not continuous with the previous epoch.
    pub lost_lock: bool,
    /// True when a DGPS correction was applied to the pseudorange.
    pub dgps: bool,
}

/// All satellites of one receiver epoch, for tight coupling.
#[derive(Clone, Debug, PartialEq)]
pub struct GnssRawEpoch {
    /// Time of validity (GPS time, seconds of the run's week) \[s\].
    pub t: f64,
    pub sats: Vec<SatMeasurement>,
    /// The epoch's single point solution, when there is one: used to find the
    /// initial position and attitude, never fused in tight coupling.
    pub fix: Option<GnssFix>,
}

/// Navigation state of the IMU centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NavState {
    /// Time \[s\].
    pub t: f64,
    /// Latitude \[rad\], longitude \[rad\], ellipsoidal height \[m\].
    pub lla: Vector3<f64>,
    /// Velocity in NED \[m/s\].
    pub v_n: Vector3<f64>,
    /// Attitude C_b^n as a unit quaternion.
    pub q_bn: UnitQuaternion<f64>,
}

/// Estimated IMU errors in SI units. Compensation (KF-GINS convention):
/// `dtheta_c = (dtheta - gyro_bias * dt) / (1 + gyro_scale)`, per axis; same for accel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuErrors {
    /// Gyro bias \[rad/s\].
    pub gyro_bias: Vector3<f64>,
    /// Accelerometer bias \[m/s²\].
    pub accel_bias: Vector3<f64>,
    /// Gyro scale factor error \[-\] (1e-6 = 1 ppm).
    pub gyro_scale: Vector3<f64>,
    /// Accelerometer scale factor error \[-\].
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
/// forward speed of the vehicle reference point, before scale correction \[m/s\].
/// Pulse counts are converted to speed by the reader (v = K_OD dN / dt, seed 004 eq. 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometerSample {
    /// Time of validity \[s\]: the end of the counting interval.
    pub t: f64,
    /// Forward speed \[m/s\] (negative when reversing, if the sensor tells).
    pub speed_mps: f64,
    /// Length of the counting interval \[s\]; the speed is its mean. 0 = instantaneous.
    pub interval_s: f64,
}

/// A heading measurement: azimuth of a body-fixed direction (the dual-antenna
/// baseline) from true north, clockwise \[rad\], with its 1-sigma \[rad\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadingObs {
    /// Time of validity \[s\] (GNSS time scale).
    pub t: f64,
    pub heading_rad: f64,
    pub std_rad: f64,
}

/// One time-tagged aiding input, as read from files. The navigator merges them with
/// the IMU stream in time order.
#[derive(Clone, Debug, PartialEq)]
pub enum Measurement {
    Gnss(GnssFix),
    /// Per-satellite measurements for tight coupling (shared: epochs are large).
    GnssRaw(Arc<GnssRawEpoch>),
    Odometer(OdometerSample),
    Heading(HeadingObs),
    /// Barometric pressure altitude (aiding/baro.rs), IMU time scale.
    Baro(crate::aiding::baro::BaroSample),
}

impl Measurement {
    /// Time of validity \[s\]. An odometer speed averaged over a counting interval is
    /// the speed at the interval's midpoint (exact for constant acceleration).
    pub fn t(&self) -> f64 {
        match self {
            Measurement::Gnss(f) => f.t,
            Measurement::GnssRaw(e) => e.t,
            Measurement::Odometer(o) => o.t - 0.5 * o.interval_s,
            Measurement::Heading(h) => h.t,
            Measurement::Baro(b) => b.t,
        }
    }

    /// True for inputs time-tagged by the GNSS receiver (shifted by the GNSS-IMU time
    /// offset when it is estimated); the odometer shares the IMU clock.
    pub fn on_gnss_clock(&self) -> bool {
        !matches!(self, Measurement::Odometer(_) | Measurement::Baro(_))
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

/// Add more inputs to a merged list, keeping it time-sorted (stable: at equal times
/// the new ones come after what was there).
pub fn merge_more(mut all: Vec<Measurement>, more: Vec<Measurement>) -> Vec<Measurement> {
    if more.is_empty() {
        return all;
    }
    all.extend(more);
    all.sort_by(|a, b| a.t().total_cmp(&b.t()));
    all
}

/// Add tight-coupling epochs to a merged list, keeping it time-sorted (stable: at
/// equal times the epochs come after what was there).
pub fn merge_raw_epochs(mut all: Vec<Measurement>, raw: Vec<GnssRawEpoch>) -> Vec<Measurement> {
    all.extend(raw.into_iter().map(|e| Measurement::GnssRaw(Arc::new(e))));
    all.sort_by(|a, b| a.t().total_cmp(&b.t()));
    all
}
