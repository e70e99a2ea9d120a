//! `[imu_noise]`: the IMU stochastic model (core::config::ImuNoise). Every key is
//! required: there is no default noise.

use navfuse_core::config::ImuNoise;
use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::units::{Unit, ARW, DEGPH, HOURS, MGAL, PPM, VRW};
use super::validate::{positive_si, std3, std3_si};
use super::values::Num3;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TNoise {
    pub(super) arw_deg_sqrth: Num3,
    pub(super) vrw_mps_sqrth: Num3,
    pub(super) gyro_bias_std_degph: Num3,
    pub(super) accel_bias_std_mgal: Num3,
    pub(super) gyro_scale_std_ppm: Num3,
    pub(super) accel_scale_std_ppm: Num3,
    pub(super) corr_time_h: f64,
}

pub(super) fn convert(n: &TNoise) -> KResult<ImuNoise> {
    let std = |key: &str, v: &Num3, unit: Unit| std3_si(key, std3(key, v)?, unit);
    let arw = std("imu_noise.arw_deg_sqrth", &n.arw_deg_sqrth, ARW)?;
    let vrw = std("imu_noise.vrw_mps_sqrth", &n.vrw_mps_sqrth, VRW)?;
    let gyro_bias_std = std(
        "imu_noise.gyro_bias_std_degph",
        &n.gyro_bias_std_degph,
        DEGPH,
    )?;
    let accel_bias_std = std(
        "imu_noise.accel_bias_std_mgal",
        &n.accel_bias_std_mgal,
        MGAL,
    )?;
    let gyro_scale_std = std("imu_noise.gyro_scale_std_ppm", &n.gyro_scale_std_ppm, PPM)?;
    let accel_scale_std = std("imu_noise.accel_scale_std_ppm", &n.accel_scale_std_ppm, PPM)?;
    let corr_time_s = positive_si(
        "imu_noise.corr_time_h",
        n.corr_time_h,
        (HOURS.to_si)(n.corr_time_h),
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
        arw_deg_sqrth: ARW.user3(&n.arw),
        vrw_mps_sqrth: VRW.user3(&n.vrw),
        gyro_bias_std_degph: DEGPH.user3(&n.gyro_bias_std),
        accel_bias_std_mgal: MGAL.user3(&n.accel_bias_std),
        gyro_scale_std_ppm: PPM.user3(&n.gyro_scale_std),
        accel_scale_std_ppm: PPM.user3(&n.accel_scale_std),
        corr_time_h: HOURS.user(n.corr_time_s),
    }
}
