//! The noise parameters `navfuse tune` estimates, where their statistics come from,
//! and how a new value goes into the configuration (the maximisation step).
//!
//! Each parameter is a standard deviation (or a scale on one) whose square scales a
//! block of the filter's Q or R. The expectation step gives, per parameter, the mean
//! ratio theta of the expected squared noise to the variance the filter assumed
//! (smoother/em.rs); the maximisation step for a variance that scales a block linearly
//! is that ratio (REFERENCES \[SS82\]: Q_new = mean E\[w w^T\], R_new = mean E\[v v^T\],
//! taken here on the diagonal of each block), so the standard deviation is multiplied
//! by sqrt(theta).

use navfuse_core::config::NavConfig;
use navfuse_core::state::{Block, StateLayout, ATT, BA, BG, SA, SG, VEL};

/// The keys of `[imu_noise]` that `navfuse tune --from-data` starts from the data.
pub(crate) const NOISE_KEYS: [&str; 6] = [
    "imu_noise.arw_deg_sqrth",
    "imu_noise.vrw_mps_sqrth",
    "imu_noise.gyro_bias_std_degph",
    "imu_noise.accel_bias_std_mgal",
    "imu_noise.gyro_scale_std_ppm",
    "imu_noise.accel_scale_std_ppm",
];

/// What a parameter scales.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Target {
    /// Angle random walk of the gyro axes x, y (horizontal for a level vehicle).
    ArwHorizontal,
    /// ... of the z axis.
    ArwVertical,
    VrwHorizontal,
    VrwVertical,
    GyroBiasStd,
    AccelBiasStd,
    GyroScaleStd,
    AccelScaleStd,
    /// `[initial] gyro_bias_std_degph`, `accel_bias_std_mgal`: the turn-on biases.
    InitialGyroBiasStd,
    InitialAccelBiasStd,
    /// `[gnss] position_std_scale` (the white share of the fix error when the fixes'
    /// errors are also modelled as correlated).
    GnssPositionScale,
    /// The correlated share of the fix position error (the `GnssBias` states).
    GnssCorrelated,
    GnssVelocityScale,
    /// `[nhc] std_mps` row 0 (lateral) or 1 (vertical).
    NhcStd(usize),
    OdometerStd,
    ZuptStd,
    ZaruStd,
    PseudorangeScale,
    RangeRateScale,
    BaroStd,
}

/// Where a parameter's statistic comes from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Stat {
    /// The process noise of these states (E\[w_i²\] / Q_ii).
    Process(Vec<usize>),
    /// The initial uncertainty of these states ((s_0² + var_0) / P_0, the EM step of
    /// the initial covariance).
    Initial(Vec<usize>),
    /// The measurement noise of these rows of these update sources ((r_s² + var_s) /
    /// R).
    Residual {
        sources: &'static [&'static str],
        rows: Vec<usize>,
    },
}

/// One parameter: its key, unit, statistic and target.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ParamDef {
    pub key: &'static str,
    pub unit: &'static str,
    pub stat: Stat,
    pub target: Target,
}

/// Lowest and highest value of each parameter (user units), so that a source with
/// nothing to learn from cannot drive its noise to zero or infinity.
fn bounds(t: Target) -> (f64, f64) {
    match t {
        Target::ArwHorizontal | Target::ArwVertical => (1e-4, 200.0),
        Target::VrwHorizontal | Target::VrwVertical => (1e-4, 50.0),
        Target::GyroBiasStd => (1e-4, 1e5),
        Target::AccelBiasStd => (1e-2, 1e6),
        Target::GyroScaleStd | Target::AccelScaleStd => (1.0, 1e5),
        Target::InitialGyroBiasStd => (1e-4, 1e6),
        Target::InitialAccelBiasStd => (1e-2, 1e7),
        Target::GnssPositionScale | Target::GnssVelocityScale => (0.01, 100.0),
        Target::GnssCorrelated => (0.0, 0.95),
        Target::NhcStd(_) | Target::OdometerStd => (1e-3, 10.0),
        Target::ZuptStd => (1e-3, 1.0),
        Target::ZaruStd => (1e-3, 10.0),
        Target::PseudorangeScale | Target::RangeRateScale => (0.01, 100.0),
        Target::BaroStd => (1e-3, 100.0),
    }
}

const RAD_TO_DEG: f64 = 180.0 / std::f64::consts::PI;

impl Target {
    /// The parameter's value in the configuration's user unit (the mean of the axes it
    /// covers).
    pub fn value(self, nav: &NavConfig) -> f64 {
        let n = &nav.imu_noise;
        let mean2 = |a: f64, b: f64| 0.5 * (a + b);
        match self {
            Target::ArwHorizontal => mean2(n.arw.x, n.arw.y) * RAD_TO_DEG * 60.0,
            Target::ArwVertical => n.arw.z * RAD_TO_DEG * 60.0,
            Target::VrwHorizontal => mean2(n.vrw.x, n.vrw.y) * 60.0,
            Target::VrwVertical => n.vrw.z * 60.0,
            Target::GyroBiasStd => n.gyro_bias_std.mean() * RAD_TO_DEG * 3600.0,
            Target::AccelBiasStd => n.accel_bias_std.mean() * 1e5,
            Target::GyroScaleStd => n.gyro_scale_std.mean() * 1e6,
            Target::AccelScaleStd => n.accel_scale_std.mean() * 1e6,
            Target::InitialGyroBiasStd => {
                nav.initial.imu_errors_std.gyro_bias.mean() * RAD_TO_DEG * 3600.0
            }
            Target::InitialAccelBiasStd => nav.initial.imu_errors_std.accel_bias.mean() * 1e5,
            Target::GnssPositionScale => nav.gnss.position_std_scale,
            Target::GnssCorrelated => nav.gnss.fix_error.corr_fraction,
            Target::GnssVelocityScale => nav.gnss.velocity_std_scale,
            Target::NhcStd(k) => nav.nhc.std_mps[k],
            Target::OdometerStd => nav.odometer.std_mps,
            Target::ZuptStd => nav.zupt.velocity_std_mps,
            Target::ZaruStd => nav.zupt.angular_rate_std * RAD_TO_DEG,
            Target::PseudorangeScale => nav.tight.pseudorange_sigma_scale,
            Target::RangeRateScale => nav.tight.range_rate_sigma_scale,
            Target::BaroStd => nav.baro.std_m,
        }
    }

    /// Multiply the standard deviation(s) the parameter stands for by `f`, within the
    /// bounds; returns the factor applied.
    pub fn scale(self, nav: &mut NavConfig, f: f64) -> f64 {
        let (lo, hi) = bounds(self);
        let v = self.value(nav);
        let f = if v > 0.0 {
            (v * f).clamp(lo, hi) / v
        } else {
            1.0
        };
        let applied = |nav: &NavConfig| {
            let w = self.value(nav);
            if v > 0.0 {
                w / v
            } else {
                1.0
            }
        };
        let init = &mut nav.initial.imu_errors_std;
        let n = &mut nav.imu_noise;
        match self {
            Target::ArwHorizontal => {
                n.arw.x *= f;
                n.arw.y *= f;
            }
            Target::ArwVertical => n.arw.z *= f,
            Target::VrwHorizontal => {
                n.vrw.x *= f;
                n.vrw.y *= f;
            }
            Target::VrwVertical => n.vrw.z *= f,
            Target::GyroBiasStd => n.gyro_bias_std *= f,
            Target::AccelBiasStd => n.accel_bias_std *= f,
            Target::GyroScaleStd => n.gyro_scale_std *= f,
            Target::AccelScaleStd => n.accel_scale_std *= f,
            // A turn-on bias spreads at least as far as the in-run one: the EM step of
            // an initial variance rests on one sample (the smoothed start) and shrinks
            // towards zero when that sample is small.
            Target::InitialGyroBiasStd => {
                init.gyro_bias = (init.gyro_bias * f).sup(&n.gyro_bias_std)
            }
            Target::InitialAccelBiasStd => {
                init.accel_bias = (init.accel_bias * f).sup(&n.accel_bias_std)
            }
            Target::GnssPositionScale => nav.gnss.position_std_scale *= f,
            Target::GnssCorrelated => nav.gnss.fix_error.corr_fraction *= f,
            Target::GnssVelocityScale => nav.gnss.velocity_std_scale *= f,
            Target::NhcStd(k) => nav.nhc.std_mps[k] *= f,
            Target::OdometerStd => {
                nav.odometer.std_mps *= f;
                nav.odometer.std_speed_fraction *= f;
            }
            Target::ZuptStd => nav.zupt.velocity_std_mps *= f,
            Target::ZaruStd => nav.zupt.angular_rate_std *= f,
            Target::PseudorangeScale => nav.tight.pseudorange_sigma_scale *= f,
            Target::RangeRateScale => nav.tight.range_rate_sigma_scale *= f,
            Target::BaroStd => nav.baro.std_m *= f,
        }
        applied(nav)
    }
}

/// The parameters of this run: the IMU noise always, the correlated fix error when its
/// states are in `layout`, and the measurement noise of each source in `sources`
/// (those with updates).
pub(crate) fn params(nav: &NavConfig, layout: &StateLayout, sources: &[&str]) -> Vec<ParamDef> {
    let mut v = vec![
        ParamDef {
            key: "imu_noise.arw_deg_sqrth [x, y]",
            unit: "deg/sqrt(h)",
            stat: Stat::Process(vec![ATT, ATT + 1]),
            target: Target::ArwHorizontal,
        },
        ParamDef {
            key: "imu_noise.arw_deg_sqrth [z]",
            unit: "deg/sqrt(h)",
            stat: Stat::Process(vec![ATT + 2]),
            target: Target::ArwVertical,
        },
        ParamDef {
            key: "imu_noise.vrw_mps_sqrth [x, y]",
            unit: "m/s/sqrt(h)",
            stat: Stat::Process(vec![VEL, VEL + 1]),
            target: Target::VrwHorizontal,
        },
        ParamDef {
            key: "imu_noise.vrw_mps_sqrth [z]",
            unit: "m/s/sqrt(h)",
            stat: Stat::Process(vec![VEL + 2]),
            target: Target::VrwVertical,
        },
        ParamDef {
            key: "imu_noise.gyro_bias_std_degph",
            unit: "deg/h",
            stat: Stat::Process(vec![BG, BG + 1, BG + 2]),
            target: Target::GyroBiasStd,
        },
        ParamDef {
            key: "imu_noise.accel_bias_std_mgal",
            unit: "mGal",
            stat: Stat::Process(vec![BA, BA + 1, BA + 2]),
            target: Target::AccelBiasStd,
        },
        ParamDef {
            key: "initial.gyro_bias_std_degph",
            unit: "deg/h",
            stat: Stat::Initial(vec![BG, BG + 1, BG + 2]),
            target: Target::InitialGyroBiasStd,
        },
        ParamDef {
            key: "initial.accel_bias_std_mgal",
            unit: "mGal",
            stat: Stat::Initial(vec![BA, BA + 1, BA + 2]),
            target: Target::InitialAccelBiasStd,
        },
        ParamDef {
            key: "imu_noise.gyro_scale_std_ppm",
            unit: "ppm",
            stat: Stat::Process(vec![SG, SG + 1, SG + 2]),
            target: Target::GyroScaleStd,
        },
        ParamDef {
            key: "imu_noise.accel_scale_std_ppm",
            unit: "ppm",
            stat: Stat::Process(vec![SA, SA + 1, SA + 2]),
            target: Target::AccelScaleStd,
        },
    ];
    let has = |s: &str| sources.contains(&s);
    let mut res = |srcs: &'static [&'static str], rows: Vec<usize>, key, unit, target| {
        if srcs.iter().any(|s| has(s)) {
            v.push(ParamDef {
                key,
                unit,
                stat: Stat::Residual {
                    sources: srcs,
                    rows,
                },
                target,
            });
        }
    };
    res(
        &["gnss_position"],
        vec![0, 1, 2],
        "gnss.position_std_scale",
        "",
        Target::GnssPositionScale,
    );
    res(
        &["gnss_velocity"],
        vec![0, 1, 2],
        "gnss.velocity_std_scale",
        "",
        Target::GnssVelocityScale,
    );
    res(
        &["nhc"],
        vec![0],
        "nhc.std_mps [lateral]",
        "m/s",
        Target::NhcStd(0),
    );
    res(
        &["nhc"],
        vec![1],
        "nhc.std_mps [vertical]",
        "m/s",
        Target::NhcStd(1),
    );
    res(
        &["odometer"],
        vec![0],
        "odometer.std_mps (and std_speed_fraction)",
        "m/s",
        Target::OdometerStd,
    );
    res(
        &["zupt"],
        vec![0, 1, 2],
        "zupt.velocity_std_mps",
        "m/s",
        Target::ZuptStd,
    );
    res(
        &["zaru"],
        vec![0, 1, 2],
        "zupt.angular_rate_std_dps",
        "deg/s",
        Target::ZaruStd,
    );
    res(
        &["pseudorange"],
        vec![0],
        "gnss.tight.pseudorange_sigma_scale",
        "",
        Target::PseudorangeScale,
    );
    res(
        &["doppler", "tdcp"],
        vec![0],
        "gnss.tight.range_rate_sigma_scale",
        "",
        Target::RangeRateScale,
    );
    res(&["baro"], vec![0], "baro.std_m", "m", Target::BaroStd);
    if let Some(b) = layout.index(Block::GnssBias) {
        if has("gnss_position") && nav.gnss.fix_error.corr_fraction > 0.0 {
            v.push(ParamDef {
                key: "gnss.error_corr_fraction",
                unit: "",
                stat: Stat::Process(vec![b, b + 1, b + 2]),
                target: Target::GnssCorrelated,
            });
        }
    }
    v
}
