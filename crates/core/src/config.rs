//! Navigator configuration in SI units. File formats (TOML, KF-GINS YAML) are read
//! by `navfuse-io::config`, which converts user units into these structs.

use crate::outage::OutageSchedule;
use crate::types::ImuErrors;
use nalgebra::Vector3;

/// IMU stochastic model (SI units). SYSTEM.md §2: biases and scale factors are
/// first-order Gauss-Markov processes with correlation time `corr_time_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuNoise {
    /// Angle random walk [rad/sqrt(s)].
    pub arw: Vector3<f64>,
    /// Velocity random walk [m/s/sqrt(s)].
    pub vrw: Vector3<f64>,
    /// Gyro bias Gauss-Markov std [rad/s].
    pub gyro_bias_std: Vector3<f64>,
    /// Accelerometer bias Gauss-Markov std [m/s²].
    pub accel_bias_std: Vector3<f64>,
    /// Gyro scale-factor Gauss-Markov std [-].
    pub gyro_scale_std: Vector3<f64>,
    /// Accelerometer scale-factor Gauss-Markov std [-].
    pub accel_scale_std: Vector3<f64>,
    /// Correlation time of all twelve Gauss-Markov states [s].
    pub corr_time_s: f64,
}

/// How the initial attitude is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AttitudeInit {
    /// Roll, pitch, yaw [rad] given by the user.
    Given(Vector3<f64>),
    /// Roll and pitch from the mean specific force over the first `level_window_s`
    /// (the vehicle must be static then), yaw from the first GNSS course over ground at
    /// or above `min_speed_mps` (`alignment.rs`). The filter refines both.
    LevelAndGnssCourse {
        level_window_s: f64,
        min_speed_mps: f64,
    },
}

/// Initial state and its uncertainty.
#[derive(Clone, Debug, PartialEq)]
pub struct InitialState {
    /// Latitude [rad], longitude [rad], height [m] of the IMU centre; None = the first
    /// GNSS fix at or after the start, moved from the antenna to the IMU centre.
    pub lla: Option<Vector3<f64>>,
    /// NED velocity [m/s].
    pub v_n: Vector3<f64>,
    pub attitude: AttitudeInit,
    /// Initial IMU error estimates.
    pub imu_errors: ImuErrors,
    /// 1-sigma of position NED [m], velocity NED [m/s], attitude roll/pitch/yaw [rad].
    pub pos_std: Vector3<f64>,
    pub vel_std: Vector3<f64>,
    pub att_std: Vector3<f64>,
    /// 1-sigma of the initial IMU errors (SI); KF-GINS defaults them to the noise stds.
    pub imu_errors_std: ImuErrors,
}

/// GNSS-to-IMU time offset tau(t) = tau0 + rate * (t - t0): a GNSS epoch tagged t is
/// applied at IMU time t + tau. Estimated as filter states when the stds are > 0
/// (the rate state absorbs a clock-rate difference between the IMU time tags and GPS
/// time, e.g. a logger clock that runs a few hundred ppm off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeOffsetConfig {
    /// Offset at the start of the run [s].
    pub initial_s: f64,
    /// Initial 1-sigma of the offset [s]; 0 = known, not estimated.
    pub std_s: f64,
    /// Random-walk PSD of the offset [s²/s] (0 = constant).
    pub random_walk: f64,
    /// Offset rate [s/s] at the start.
    pub initial_rate: f64,
    /// Initial 1-sigma of the rate [s/s]; 0 = no rate state (rate stays `initial_rate`).
    pub rate_std: f64,
}

/// How GNSS fixes are used.
#[derive(Clone, Debug, PartialEq)]
pub struct GnssOptions {
    /// Antenna phase centre in the body frame, from the IMU centre (F, R, D) [m].
    pub lever_arm_b: Vector3<f64>,
    /// Use the fix's velocity, when present.
    pub use_velocity: bool,
    /// Replace per-epoch position std with this (N, E, D) [m].
    pub position_std_override: Option<Vector3<f64>>,
    /// Replace per-epoch velocity std with this (N, E, D) [m/s].
    pub velocity_std_override: Option<Vector3<f64>>,
    /// Innovation gate: chi-square tail probability at which a fix is rejected
    /// (e.g. 1e-4); None = no gating (KF-GINS behaviour).
    pub gate_probability: Option<f64>,
    /// After this long [s] of consecutive gate rejections, the next fix is accepted
    /// anyway (the filter has drifted, or a step in the GNSS is real); logged.
    pub gate_timeout_s: f64,
    /// Withheld epochs.
    pub outages: OutageSchedule,
}

/// Default `GnssOptions::gate_timeout_s` [s].
pub const DEFAULT_GATE_TIMEOUT_S: f64 = 5.0;

/// Default covariance propagation interval [s]. Propagating every 0.2 s instead of
/// every IMU sample changes the KF-GINS stand-in results by < 0.001 mm and 4e-5 deg
/// (docs/ALGORITHMS.md) and makes the filter ~20x cheaper.
pub const DEFAULT_COVARIANCE_PERIOD_S: f64 = 0.2;

/// Filter options.
#[derive(Clone, Debug, PartialEq)]
pub struct FilterOptions {
    /// Covariance propagation interval [s]; the transition matrix is built from the
    /// mean specific force and rate over the interval. 0 = every IMU sample.
    pub covariance_period_s: f64,
    /// Estimate a GNSS-IMU time offset.
    pub time_offset: Option<TimeOffsetConfig>,
}

impl Default for FilterOptions {
    fn default() -> Self {
        FilterOptions {
            covariance_period_s: DEFAULT_COVARIANCE_PERIOD_S,
            time_offset: None,
        }
    }
}

/// Everything the navigator needs besides the data.
#[derive(Clone, Debug, PartialEq)]
pub struct NavConfig {
    pub imu_noise: ImuNoise,
    pub initial: InitialState,
    pub gnss: GnssOptions,
    pub filter: FilterOptions,
    /// Start time [s]; IMU data before it are skipped.
    pub start_time: f64,
    /// End time [s]; None = to the end of the data.
    pub end_time: Option<f64>,
}
