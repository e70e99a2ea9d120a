//! Navigator configuration in SI units. File formats (TOML, KF-GINS YAML) are read
//! by `navfuse-io::config`, which converts user units into these structs.

use crate::outage::OutageSchedule;
use crate::sat::System;
use crate::types::ImuErrors;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// IMU stochastic model (SI units). SYSTEM.md §2: biases and scale factors are
/// first-order Gauss-Markov processes with correlation time `corr_time_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuNoise {
    /// Angle random walk \[rad/sqrt(s)\].
    pub arw: Vector3<f64>,
    /// Velocity random walk \[m/s/sqrt(s)\].
    pub vrw: Vector3<f64>,
    /// Gyro bias Gauss-Markov std \[rad/s\].
    pub gyro_bias_std: Vector3<f64>,
    /// Accelerometer bias Gauss-Markov std \[m/s²\].
    pub accel_bias_std: Vector3<f64>,
    /// Gyro scale-factor Gauss-Markov std \[-\].
    pub gyro_scale_std: Vector3<f64>,
    /// Accelerometer scale-factor Gauss-Markov std \[-\].
    pub accel_scale_std: Vector3<f64>,
    /// Correlation time of all twelve Gauss-Markov states \[s\].
    pub corr_time_s: f64,
}

impl ImuNoise {
    /// The noise model's bias and scale-factor stds as initial IMU error stds (what
    /// KF-GINS assumes when a configuration gives none).
    pub fn error_stds(&self) -> ImuErrors {
        ImuErrors {
            gyro_bias: self.gyro_bias_std,
            accel_bias: self.accel_bias_std,
            gyro_scale: self.gyro_scale_std,
            accel_scale: self.accel_scale_std,
        }
    }
}

/// How the initial attitude is found (SYSTEM.md §1 "Initial alignment"; alignment.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AttitudeInit {
    /// Roll, pitch, yaw \[rad\] given by the user.
    Given(Vector3<f64>),
    /// Roll and pitch from the mean specific force over the first `level_window_s`
    /// (the vehicle must be static then), yaw from the first GNSS course over ground at
    /// or above `min_speed_mps`. The filter refines both.
    LevelAndGnssCourse {
        level_window_s: f64,
        min_speed_mps: f64,
    },
    /// Static coarse alignment over the first `level_window_s`: roll and pitch from the
    /// specific force, yaw by gyrocompassing. Yaw error is about
    /// bias / (15.04 deg/h cos(lat)): 0.1 deg/h gives 0.4 deg at 21 N.
    StaticGyrocompass { level_window_s: f64 },
    /// In-motion alignment for low-cost IMUs: the run starts at the first GNSS epoch
    /// whose horizontal speed is at least `min_speed_mps`; yaw from the course (minus
    /// the IMU mounting), roll and pitch from the specific force corrected by the GNSS
    /// acceleration, velocity from GNSS. The filter refines them (fine alignment).
    InMotion { min_speed_mps: f64 },
    /// Levelling and gyrocompassing / course when the first window is static, otherwise
    /// in-motion alignment. `gyrocompass` picks the static yaw source.
    Auto {
        level_window_s: f64,
        min_speed_mps: f64,
        gyrocompass: bool,
    },
}

/// Default levelling window of the alignments that level \[s\].
pub const DEFAULT_LEVEL_WINDOW_S: f64 = 10.0;
/// Default speed from which a GNSS course gives the yaw \[m/s\].
pub const DEFAULT_ALIGN_MIN_SPEED_MPS: f64 = 3.0;

impl Default for AttitudeInit {
    /// Found from the data: static levelling and GNSS course when the start is
    /// static, in-motion alignment otherwise (no attitude in the configuration).
    fn default() -> Self {
        AttitudeInit::Auto {
            level_window_s: DEFAULT_LEVEL_WINDOW_S,
            min_speed_mps: DEFAULT_ALIGN_MIN_SPEED_MPS,
            gyrocompass: false,
        }
    }
}

/// Initial state and its uncertainty.
#[derive(Clone, Debug, PartialEq)]
pub struct InitialState {
    /// Latitude \[rad\], longitude \[rad\], height \[m\] of the IMU centre; None = the first
    /// GNSS fix at or after the start, moved from the antenna to the IMU centre.
    pub lla: Option<Vector3<f64>>,
    /// NED velocity \[m/s\].
    pub v_n: Vector3<f64>,
    pub attitude: AttitudeInit,
    /// Initial IMU error estimates.
    pub imu_errors: ImuErrors,
    /// 1-sigma of position NED \[m\], velocity NED \[m/s\], attitude roll/pitch/yaw \[rad\].
    pub pos_std: Vector3<f64>,
    pub vel_std: Vector3<f64>,
    pub att_std: Vector3<f64>,
    /// 1-sigma of the initial IMU errors (SI); KF-GINS defaults them to the noise stds.
    pub imu_errors_std: ImuErrors,
}

impl InitialState {
    /// The given position, velocity and attitude stds, everything else at its default:
    /// position from the first GNSS fix, at rest, attitude found from the data
    /// ([`AttitudeInit::default`]), zero IMU errors with the noise model's stds
    /// ([`ImuNoise::error_stds`]). There is no `Default`: the stds have none.
    pub fn new(
        pos_std: Vector3<f64>,
        vel_std: Vector3<f64>,
        att_std: Vector3<f64>,
        imu_noise: &ImuNoise,
    ) -> Self {
        InitialState {
            lla: None,
            v_n: Vector3::zeros(),
            attitude: AttitudeInit::default(),
            imu_errors: ImuErrors::default(),
            pos_std,
            vel_std,
            att_std,
            imu_errors_std: imu_noise.error_stds(),
        }
    }
}

/// GNSS-to-IMU time offset tau(t) = tau0 + rate * (t - t0): a GNSS epoch tagged t is
/// applied at IMU time t + tau. Estimated as filter states when the stds are > 0
/// (the rate state absorbs a clock-rate difference between the IMU time tags and GPS
/// time, e.g. a logger clock that runs a few hundred ppm off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeOffsetConfig {
    /// Offset at the start of the run \[s\].
    pub initial_s: f64,
    /// Initial 1-sigma of the offset \[s\]; 0 = known, not estimated.
    pub std_s: f64,
    /// Random-walk PSD of the offset \[s²/s\] (0 = constant).
    pub random_walk: f64,
    /// Offset rate \[s/s\] at the start.
    pub initial_rate: f64,
    /// Initial 1-sigma of the rate \[s/s\]; 0 = no rate state (rate stays `initial_rate`).
    pub rate_std: f64,
}

impl Default for TimeOffsetConfig {
    /// Estimated, starting from 0 with a 0.5 s std, constant, no rate state (the
    /// defaults of `\[filter.time_offset\]`).
    fn default() -> Self {
        TimeOffsetConfig {
            initial_s: 0.0,
            std_s: 0.5,
            random_walk: 0.0,
            initial_rate: 0.0,
            rate_std: 0.0,
        }
    }
}

/// How GNSS fixes are used.
#[derive(Clone, Debug, PartialEq)]
pub struct GnssOptions {
    /// Antenna phase centre in the body frame, from the IMU centre (F, R, D) \[m\].
    pub lever_arm_b: Vector3<f64>,
    /// A GNSS-clock input within this of an IMU epoch is applied at that epoch
    /// (KF-GINS: 1 ms; nav/timeline.rs); 0 = at its own time, the IMU interval split
    /// there \[s\].
    pub time_snap_s: f64,
    /// Use the fix's velocity, when present.
    pub use_velocity: bool,
    /// Replace per-epoch position std with this (N, E, D) \[m\].
    pub position_std_override: Option<Vector3<f64>>,
    /// Replace per-epoch velocity std with this (N, E, D) \[m/s\].
    pub velocity_std_override: Option<Vector3<f64>>,
    /// Factor on every fix's position std (the reported one or the override): the
    /// receiver's own figures are often optimistic or pessimistic by a constant
    /// factor (`navfuse tune` estimates it).
    pub position_std_scale: f64,
    /// Factor on every fix's velocity std.
    pub velocity_std_scale: f64,
    /// Innovation gate: chi-square tail probability at which a fix is rejected
    /// (e.g. 1e-4); None = no gating (KF-GINS behaviour).
    pub gate_probability: Option<f64>,
    /// Six-state fusion: after this long \[s\] of consecutive gate rejections the next
    /// fix is accepted anyway (logged). Tight coupling: no pseudorange used for this
    /// long is a return from a gap (uncertainty widened, carriers restarted).
    /// Loosely coupled fixes use `fix_error.readmit_s` instead.
    pub gate_timeout_s: f64,
    /// Withheld epochs.
    pub outages: OutageSchedule,
    /// How loosely coupled fixes are fused (error-state filter or six-state cascade).
    pub fusion: GnssFusion,
    /// Error model of the fixes and the handling of disagreeing ones (fix_error.rs).
    pub fix_error: FixErrorOptions,
    /// The satellite systems used (`\[gnss\] systems`, GPS only by default): tight
    /// coupling ignores the measurements of the others and estimates an inter-system
    /// bias for each of these but GPS (and QZSS and SBAS, on GPS time). The raw-data
    /// reader and SPP read the same list.
    pub systems: Vec<System>,
}

impl Default for GnssOptions {
    /// The `\[gnss\]` defaults: no lever arm, velocity used, the fixes' own stds, the
    /// default gate and timeout, no outages, error-state fusion, correlated fixes.
    fn default() -> Self {
        GnssOptions {
            lever_arm_b: Vector3::zeros(),
            time_snap_s: 0.0,
            use_velocity: true,
            position_std_override: None,
            velocity_std_override: None,
            position_std_scale: 1.0,
            velocity_std_scale: 1.0,
            gate_probability: Some(DEFAULT_FIX_GATE_PROBABILITY),
            gate_timeout_s: DEFAULT_GATE_TIMEOUT_S,
            outages: OutageSchedule::default(),
            fusion: GnssFusion::ErrorState,
            fix_error: FixErrorOptions::default(),
            systems: vec![System::Gps],
        }
    }
}

/// The loosely coupled fixes' error model and outlier handling (fix_error.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixErrorOptions {
    /// Correlation time of the fixes' position errors \[s\] (Gauss-Markov states);
    /// 0 = white errors.
    pub corr_time_s: f64,
    /// Share of each fix's position variance that is time-correlated, in [0, 1).
    pub corr_fraction: f64,
    /// Fixes in the robust innovation-scale window (fix_error.rs
    /// `InnovationScale`); 0 = the tests use the filter's own covariance.
    pub scale_window: usize,
    /// Tail probability beyond which a fix is down-weighted (IGG-III, up to the
    /// gate); None = full weight up to the gate.
    pub robust_probability: Option<f64>,
    /// After a gate-rejection streak whose fixes agree with each other for this long
    /// \[s\], the filter re-admits them (its position and velocity uncertainty widened
    /// to the disagreement); a shorter burst stays rejected.
    pub readmit_s: f64,
    /// A fix beyond the gate is rejected only when its innovation also exceeds
    /// 3 sqrt(scale) std + a dt²/2 (dt since the last trusted fix, at least 1 s;
    /// velocity: 3 sqrt(scale) std + a dt): the drift an INS with this acceleration
    /// error can plausibly have \[m/s²\]. Inside that bound it is taken with a reduced
    /// weight (a MEMS INS in a hard manoeuvre is often further off than its
    /// covariance says).
    pub floor_accel_mps2: f64,
}

impl Default for FixErrorOptions {
    fn default() -> Self {
        FixErrorOptions {
            corr_time_s: 60.0,
            corr_fraction: 0.5,
            scale_window: 60,
            robust_probability: Some(1e-3),
            readmit_s: 30.0,
            floor_accel_mps2: 1.0,
        }
    }
}

impl FixErrorOptions {
    /// White fixes, no adaptation, no down-weighting (KF-GINS).
    pub fn white() -> Self {
        FixErrorOptions {
            corr_time_s: 0.0,
            corr_fraction: 0.0,
            scale_window: 0,
            robust_probability: None,
            ..Self::default()
        }
    }

    /// The Gauss-Markov states are in use.
    pub fn correlated(&self) -> bool {
        self.corr_time_s > 0.0 && self.corr_fraction > 0.0
    }
}

/// How loosely coupled GNSS fixes are fused.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GnssFusion {
    /// Each fix aids the error-state filter (SYSTEM.md §3a).
    #[default]
    ErrorState,
    /// SYSTEM.md §5; seed 004 §3: the error-state filter dead-reckons without GNSS
    /// (IMU + odometer + NHC + ZUPT as configured; the start may still take its
    /// position from the first fix), and every `every`-th fix updates a 6-state KF
    /// X = \[r^n, v^n\], H = I_6, driven by the dead-reckoning increments
    /// (six_state.rs). The solution's position and velocity are that filter's, the
    /// attitude the dead reckoning's. Loose coupling only.
    SixState { every: std::num::NonZeroU32 },
}

/// Which range rate tight coupling fuses with the pseudoranges (SYSTEM.md §3b).
/// In the TOML `gnss.range_rate`: "none", "doppler", "tdcp".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RangeRate {
    /// Pseudoranges only.
    None,
    /// -lambda x Doppler (seed 000's "traditional" tight coupling).
    Doppler,
    /// Time-differenced carrier phase between consecutive epochs (seed 000 eq. 14).
    Tdcp,
}

/// One number per satellite system, in [`System::ALL`] order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerSystem(pub [f64; System::ALL.len()]);

impl PerSystem {
    pub fn get(&self, s: System) -> f64 {
        self.0[s.index()]
    }

    pub fn set(&mut self, s: System, v: f64) {
        self.0[s.index()] = v;
    }

    /// 1 for every system.
    pub const ONES: PerSystem = PerSystem([1.0; System::ALL.len()]);
}

/// Tightly coupled GNSS: receiver clock states, per-satellite gates, cycle slips.
#[derive(Clone, Debug, PartialEq)]
pub struct TightOptions {
    /// Add the receiver clock states and fuse per-satellite measurements.
    pub enabled: bool,
    pub range_rate: RangeRate,
    /// Fuse the pseudoranges (off: range rates only).
    pub use_pseudorange: bool,
    /// Per-satellite innovation gate, chi-square tail probability (1 dof); None = off.
    pub gate_probability: Option<f64>,
    /// Receiver clock bias random walk \[m/sqrt(s)\] and drift random walk
    /// \[m/s/sqrt(s)\] (clock model x_b' = x_d + w_b, x_d' = w_d).
    pub clock_bias_psd_sqrt: f64,
    pub clock_drift_psd_sqrt: f64,
    /// Initial 1-sigma of the clock drift \[m/s\] (the bias starts from the median
    /// pseudorange residual with the position uncertainty as its sigma).
    pub clock_drift_std0_mps: f64,
    /// A common pseudorange residual larger than this \[m\] is a receiver clock jump:
    /// the bias state is reset instead of fused.
    pub clock_reset_m: f64,
    /// Cycle-slip test: a TDCP innovation beyond this many sigma, or beyond
    /// `slip_min_m` metres over the interval, marks a slip (the satellite's TDCP
    /// restarts at this epoch).
    pub slip_sigma: f64,
    pub slip_min_m: f64,
    /// Longest gap between epochs over which the carrier is differenced \[s\].
    pub tdcp_max_gap_s: f64,
    /// Scale applied to all pseudorange sigmas from the GNSS layer (e.g. to cover
    /// errors correlated in time, which the filter treats as white).
    pub pseudorange_sigma_scale: f64,
    /// Scale applied to range-rate (Doppler and TDCP) sigmas.
    pub range_rate_sigma_scale: f64,
    /// Lower bounds of the pseudorange sigma \[m\] and of the range-rate sigma (Doppler
    /// and TDCP) \[m/s\], after scaling: for error sources the GNSS layer does not
    /// model (e.g. Selective Availability, 100 m and 1 m/s in seed 000 Table 1).
    pub pseudorange_sigma_floor_m: f64,
    pub range_rate_sigma_floor_mps: f64,
    /// Factor per system on the pseudorange sigma (after `pseudorange_sigma_scale`,
    /// before the floor); 1 by default: the GNSS layer's sigmas already carry each
    /// system's error factor (RTKLIB's EFACT_*, `navfuse_gnss::spp::system_error_factor`).
    pub sigma_scale: PerSystem,
    /// Random walk of each inter-system bias state \[m/sqrt(s)\].
    pub isb_psd_sqrt: f64,
    /// 1-sigma of an inter-system bias when it is set from a system's pseudorange
    /// residuals \[m\].
    pub isb_init_sigma_m: f64,
}

impl Default for TightOptions {
    fn default() -> Self {
        TightOptions {
            enabled: false,
            range_rate: RangeRate::Doppler,
            use_pseudorange: true,
            gate_probability: Some(1e-4),
            clock_bias_psd_sqrt: 0.1,
            clock_drift_psd_sqrt: 0.05,
            clock_drift_std0_mps: 100.0,
            clock_reset_m: 1000.0,
            slip_sigma: 6.0,
            slip_min_m: 0.1,
            tdcp_max_gap_s: 5.0,
            pseudorange_sigma_scale: 1.0,
            range_rate_sigma_scale: 1.0,
            pseudorange_sigma_floor_m: 0.0,
            range_rate_sigma_floor_mps: 0.0,
            sigma_scale: PerSystem::ONES,
            isb_psd_sqrt: 0.01,
            isb_init_sigma_m: 30.0,
        }
    }
}

/// Default `GnssOptions::gate_timeout_s` \[s\].
pub const DEFAULT_GATE_TIMEOUT_S: f64 = 5.0;

/// Default innovation gate of loosely coupled fixes (3 dof tail probability).
pub const DEFAULT_FIX_GATE_PROBABILITY: f64 = 1e-4;

/// Default covariance propagation interval \[s\]. Propagating every 0.2 s instead of
/// every IMU sample changes the KF-GINS stand-in results by < 0.001 mm and 4e-5 deg
/// (docs/ALGORITHMS.md) and makes the filter ~20x cheaper.
pub const DEFAULT_COVARIANCE_PERIOD_S: f64 = 0.2;

/// Filter options.
#[derive(Clone, Debug, PartialEq)]
pub struct FilterOptions {
    /// Covariance propagation interval \[s\]; the transition matrix is built from the
    /// mean specific force and rate over the interval. 0 = every IMU sample.
    pub covariance_period_s: f64,
    /// Estimate a GNSS-IMU time offset.
    pub time_offset: Option<TimeOffsetConfig>,
    /// Over an IMU gap (an interval longer than 0.1 s and 5 nominal intervals,
    /// bridged by the reader) the INS knows nothing of the motion: the velocity and
    /// attitude variances grow by (a dt)² and (w dt)², the position's by
    /// (a dt²/2)², with these plausible vehicle dynamics \[m/s², rad/s\].
    pub gap_accel_mps2: f64,
    pub gap_rate: f64,
    /// Adaptive measurement noise (aiding/adaptive.rs); None = off (the default).
    pub adaptive_noise: Option<crate::aiding::adaptive::AdaptiveNoiseOptions>,
}

impl Default for FilterOptions {
    fn default() -> Self {
        FilterOptions {
            covariance_period_s: DEFAULT_COVARIANCE_PERIOD_S,
            time_offset: None,
            gap_accel_mps2: 2.0,
            gap_rate: 10f64.to_radians(),
            adaptive_noise: None,
        }
    }
}

/// How the IMU sits in the vehicle (SYSTEM.md §4b): the vehicle frame m has x forward
/// along the velocity of the reference point (rear-axle centre or odometer wheel),
/// where the non-holonomic constraint holds.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleOptions {
    /// IMU frame relative to the vehicle frame: roll, pitch, yaw \[rad\] (ZYX), so
    /// C_b^m = c_bn_from_euler(mounting_rpy).
    pub mounting_rpy: Vector3<f64>,
    /// Lever arm from the IMU centre to the vehicle reference point, IMU frame \[m\].
    pub lever_arm_b: Vector3<f64>,
    /// Initial 1-sigma of the mounting pitch and yaw errors \[rad\]; 0 = the mounting is
    /// known and not estimated. Estimated only when NHC or the odometer is used.
    pub mounting_std: f64,
}

impl Default for VehicleOptions {
    fn default() -> Self {
        VehicleOptions {
            mounting_rpy: Vector3::zeros(),
            lever_arm_b: Vector3::zeros(),
            mounting_std: 0.0,
        }
    }
}

/// When the non-holonomic constraint is applied. In the TOML `nhc.mode`: "off",
/// "always", "outage".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NhcMode {
    Off,
    /// At every constraint epoch while moving.
    Always,
    /// Only while no GNSS measurement has been used for `NhcOptions::outage_after_s`
    /// (seed 002's advice: the constraint matters when GNSS is degraded or lost).
    #[serde(rename = "outage")]
    DuringOutage,
}

/// Non-holonomic constraint: zero lateral and vertical velocity of the vehicle
/// reference point in the vehicle frame (SYSTEM.md §4a; seed 002 eq. 1, 12).
#[derive(Clone, Debug, PartialEq)]
pub struct NhcOptions {
    pub mode: NhcMode,
    /// 1-sigma of the lateral and vertical pseudo-measurement \[m/s\] (seed 002: 0.1).
    pub std_mps: [f64; 2],
    /// Constraint rate \[Hz\].
    pub rate_hz: f64,
    /// In `DuringOutage` mode: GNSS silence \[s\] after which the constraint starts.
    pub outage_after_s: f64,
    /// Innovation test: chi-square (2 dof) tail probability at which the constraint is
    /// judged violated (skid, ramp) and skipped; None = always applied.
    pub gate_probability: Option<f64>,
    /// Below this speed \[m/s\] the constraint is not applied (it holds trivially and
    /// the zero-velocity update takes over); also skipped while static.
    pub min_speed_mps: f64,
}

impl Default for NhcOptions {
    fn default() -> Self {
        NhcOptions {
            mode: NhcMode::Off,
            std_mps: [0.1, 0.1],
            rate_hz: 10.0,
            outage_after_s: 1.5,
            gate_probability: Some(1e-4),
            min_speed_mps: 0.5,
        }
    }
}

/// Odometer: forward speed of the vehicle reference point, with scale-factor error
/// and mounting states (SYSTEM.md §4b; seed 004 eq. 1-7, the 18-state filter).
#[derive(Clone, Debug, PartialEq)]
pub struct OdometerOptions {
    /// Use the odometer input.
    pub enabled: bool,
    /// 1-sigma of the speed \[m/s\] (includes pulse quantisation over the interval).
    pub std_mps: f64,
    /// Initial scale-factor estimate k: true speed = (1 + k) * measured.
    pub scale_initial: f64,
    /// Initial 1-sigma of k \[-\]; 0 = not estimated.
    pub scale_std: f64,
    /// Random-walk PSD of k \[1/s\] (tyre wear, load; 0 = constant).
    pub scale_random_walk: f64,
    /// Also apply zero lateral/vertical velocity with each odometer speed (seed 004's
    /// 3-row measurement v^m = \[v 0 0\]) when the NHC is otherwise off.
    pub with_nhc: bool,
    /// Speed-proportional part of the speed noise \[-\]: the 1-sigma is
    /// sqrt(std_mps² + (std_speed_fraction v)²) (wheel slip, tyre deformation).
    pub std_speed_fraction: f64,
    /// Below this speed (measured or INS) the odometer update does not touch the scale
    /// and mounting states: near standstill their columns are noise (v H_k) \[m/s\].
    pub calibration_min_speed_mps: f64,
    /// Innovation test probability (1 dof); None = no gate.
    pub gate_probability: Option<f64>,
}

impl Default for OdometerOptions {
    fn default() -> Self {
        OdometerOptions {
            enabled: false,
            std_mps: 0.05,
            std_speed_fraction: 0.0,
            calibration_min_speed_mps: 1.0,
            scale_initial: 0.0,
            scale_std: 0.01,
            scale_random_walk: 0.0,
            with_nhc: false,
            gate_probability: Some(1e-4),
        }
    }
}

/// Heading from GNSS (SYSTEM.md §3c; seed 001 eq. 10-11).
#[derive(Clone, Debug, PartialEq)]
pub struct HeadingOptions {
    /// Dual-antenna heading input: the baseline from the primary to the secondary
    /// antenna in the IMU frame (direction only matters) \[m\]; None = not used.
    pub baseline_b: Option<Vector3<f64>>,
    /// Replace the input's per-epoch heading std \[rad\].
    pub dual_antenna_std_override: Option<f64>,
    /// Course over ground as the heading of the vehicle's forward axis, from each fix's
    /// velocity (or from consecutive fixes without velocity).
    pub course_over_ground: bool,
    /// Course is used only at or above this horizontal speed \[m/s\].
    pub course_min_speed_mps: f64,
    /// Course noise floor \[rad\] (sideslip, antenna lever arm in turns); the velocity
    /// noise adds sigma_v / speed on top (seed 001: noise grows as speed falls).
    pub course_std_floor: f64,
    /// Innovation test probability (1 dof); None = no gate.
    pub gate_probability: Option<f64>,
}

impl Default for HeadingOptions {
    fn default() -> Self {
        HeadingOptions {
            baseline_b: None,
            dual_antenna_std_override: None,
            course_over_ground: false,
            course_min_speed_mps: 5.0,
            course_std_floor: 1.0_f64.to_radians(),
            gate_probability: Some(1e-4),
        }
    }
}

/// Zero-velocity and zero-angular-rate updates with automatic static detection.
#[derive(Clone, Debug, PartialEq)]
pub struct ZuptOptions {
    pub enabled: bool,
    /// Detection window \[s\]: the vehicle is static when, over the window, the standard
    /// deviation of the specific-force vector is below `accel_std_max`, the standard
    /// deviation of the angular rate is below `gyro_max` (deviations, not means, so a
    /// gyro turn-on bias does not matter), and (when an odometer is used) its speed is
    /// zero (static_detect.rs).
    pub window_s: f64,
    /// \[m/s²\].
    pub accel_std_max: f64,
    /// Angular-rate standard deviation threshold \[rad/s\].
    pub gyro_max: f64,
    /// Update rate while static \[Hz\].
    pub rate_hz: f64,
    /// 1-sigma of the zero-velocity pseudo-measurement \[m/s\].
    pub velocity_std_mps: f64,
    /// 1-sigma of the zero-angular-rate pseudo-measurement on the window mean \[rad/s\];
    /// 0 = no ZARU.
    pub angular_rate_std: f64,
    /// A standstill is only declared while the INS speed and the speed of the latest
    /// GNSS fix (within 2 s) are below this \[m/s\]: constant-velocity straight driving
    /// looks static to an IMU without vibration (e.g. in simulation).
    pub max_speed_mps: f64,
    /// The odometer vetoes a standstill while the mean of its speeds over the window
    /// exceeds this \[m/s\] (a noisy odometer reads non-zero when parked).
    pub odometer_still_mps: f64,
    /// No standstill while the INS's own mean acceleration over the window (its
    /// mechanization, without filter corrections) exceeds this \[m/s²\]: smooth
    /// braking without vibration looks static to the IMU detector.
    pub max_accel_mps2: f64,
    /// Innovation test probability of ZUPT and ZARU (3 dof); None = no gate. A
    /// rejected ZUPT ends the standstill.
    pub gate_probability: Option<f64>,
}

impl Default for ZuptOptions {
    fn default() -> Self {
        ZuptOptions {
            enabled: false,
            window_s: 1.0,
            accel_std_max: 0.05,
            gyro_max: 0.5_f64.to_radians(),
            rate_hz: 5.0,
            velocity_std_mps: 0.01,
            angular_rate_std: 0.01_f64.to_radians(),
            max_speed_mps: 1.0,
            odometer_still_mps: 0.2,
            max_accel_mps2: 0.5,
            gate_probability: Some(1e-4),
        }
    }
}

/// Everything the navigator needs besides the data.
#[derive(Clone, Debug, PartialEq)]
pub struct NavConfig {
    pub imu_noise: ImuNoise,
    /// Tight coupling (used when the GNSS input is per-satellite measurements).
    pub tight: TightOptions,
    /// GNSS integrity monitor against spoofing (off by default).
    pub integrity: crate::integrity::IntegrityOptions,
    pub initial: InitialState,
    pub gnss: GnssOptions,
    pub filter: FilterOptions,
    pub vehicle: VehicleOptions,
    pub nhc: NhcOptions,
    pub odometer: OdometerOptions,
    pub heading: HeadingOptions,
    pub zupt: ZuptOptions,
    /// Barometric altitude aiding (aiding/baro.rs).
    pub baro: crate::aiding::baro::BaroOptions,
    /// Start time \[s\]; IMU data before it are skipped.
    pub start_time: f64,
    /// End time \[s\]; None = to the end of the data.
    pub end_time: Option<f64>,
}

impl NavConfig {
    /// The given IMU noise model and initial state, every other option at its default
    /// (the defaults of the run configuration, docs/CONFIG.md): loosely coupled GNSS
    /// with the default gate, no vehicle aiding, no integrity monitor, from the first
    /// to the last IMU epoch. There is no `Default`: the noise model and the initial
    /// stds have none.
    pub fn new(imu_noise: ImuNoise, initial: InitialState) -> Self {
        NavConfig {
            imu_noise,
            tight: TightOptions::default(),
            integrity: crate::integrity::IntegrityOptions::default(),
            initial,
            gnss: GnssOptions::default(),
            filter: FilterOptions::default(),
            vehicle: VehicleOptions::default(),
            nhc: NhcOptions::default(),
            odometer: OdometerOptions::default(),
            heading: HeadingOptions::default(),
            zupt: ZuptOptions::default(),
            baro: Default::default(),
            start_time: f64::NEG_INFINITY,
            end_time: None,
        }
    }
}
