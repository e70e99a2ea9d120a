//! `[imu_noise]`: the IMU stochastic model (core::config::ImuNoise). The section and
//! each key are optional: what is not given takes the value of a generic consumer
//! MEMS IMU ([`DEFAULT_NOISE`]), is listed in `RunConfig::defaulted`, and `navfuse run`
//! warns about it (`navfuse tune` estimates the model from the data).

use navfuse_core::config::ImuNoise;
use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::units::{Unit, ARW, DEGPH, HOURS, MGAL, PPM, VRW};
use super::validate::{positive_si, std3, std3_si};
use super::values::Num3;

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TNoise {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) arw_deg_sqrth: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) vrw_mps_sqrth: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_bias_std_degph: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_bias_std_mgal: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_scale_std_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_scale_std_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) corr_time_h: Option<f64>,
}

/// The defaults of a generic consumer MEMS IMU (user units: deg/sqrt(h), m/s/sqrt(h),
/// deg/h, mGal, ppm, ppm, h), for what `[imu_noise]` does not give. An IMU of this
/// class under a vehicle's vibration is often noisier; `navfuse tune` estimates the
/// model from the data.
pub const DEFAULT_NOISE: [(&str, f64); 7] = [
    ("imu_noise.arw_deg_sqrth", 0.5),
    ("imu_noise.vrw_mps_sqrth", 0.2),
    ("imu_noise.gyro_bias_std_degph", 20.0),
    ("imu_noise.accel_bias_std_mgal", 500.0),
    ("imu_noise.gyro_scale_std_ppm", 1000.0),
    ("imu_noise.accel_scale_std_ppm", 1000.0),
    ("imu_noise.corr_time_h", 1.0),
];

/// The model; the keys that took their default are pushed to `defaulted`.
pub(super) fn convert(n: &TNoise, defaulted: &mut Vec<&'static str>) -> KResult<ImuNoise> {
    let mut std = |k: usize, v: &Option<Num3>, unit: Unit| {
        let key = DEFAULT_NOISE[k].0;
        match v {
            Some(v) => std3_si(key, std3(key, v)?, unit),
            None => {
                defaulted.push(key);
                std3_si(key, [DEFAULT_NOISE[k].1; 3], unit)
            }
        }
    };
    let arw = std(0, &n.arw_deg_sqrth, ARW)?;
    let vrw = std(1, &n.vrw_mps_sqrth, VRW)?;
    let gyro_bias_std = std(2, &n.gyro_bias_std_degph, DEGPH)?;
    let accel_bias_std = std(3, &n.accel_bias_std_mgal, MGAL)?;
    let gyro_scale_std = std(4, &n.gyro_scale_std_ppm, PPM)?;
    let accel_scale_std = std(5, &n.accel_scale_std_ppm, PPM)?;
    let corr_time_h = match n.corr_time_h {
        Some(c) => c,
        None => {
            defaulted.push(DEFAULT_NOISE[6].0);
            DEFAULT_NOISE[6].1
        }
    };
    let corr_time_s = positive_si(
        "imu_noise.corr_time_h",
        corr_time_h,
        (HOURS.to_si)(corr_time_h),
    )?;
    Ok(ImuNoise {
        arw,
        vrw,
        gyro_bias_std,
        accel_bias_std,
        gyro_scale_std,
        accel_scale_std,
        corr_time_s,
    })
}

pub(super) fn to_toml(n: &ImuNoise) -> TNoise {
    TNoise {
        arw_deg_sqrth: Some(ARW.user3(&n.arw)),
        vrw_mps_sqrth: Some(VRW.user3(&n.vrw)),
        gyro_bias_std_degph: Some(DEGPH.user3(&n.gyro_bias_std)),
        accel_bias_std_mgal: Some(MGAL.user3(&n.accel_bias_std)),
        gyro_scale_std_ppm: Some(PPM.user3(&n.gyro_scale_std)),
        accel_scale_std_ppm: Some(PPM.user3(&n.accel_scale_std)),
        corr_time_h: Some(HOURS.user(n.corr_time_s)),
    }
}
