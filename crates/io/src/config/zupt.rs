//! `[zupt]`: zero-velocity and zero-angular-rate updates with static detection
//! (core::config::ZuptOptions).

use navfuse_core::config::ZuptOptions;
use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::units::{DEG, SAME};
use super::validate::{gate, non_negative, opt_or, positive, std_pos};
use super::values::Gate;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TZupt {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) enabled: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) window_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_std_max_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_max_dps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) velocity_std_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) angular_rate_std_dps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) max_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) odometer_still_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) max_accel_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<Gate>,
}

pub(super) fn convert(z: &TZupt) -> KResult<ZuptOptions> {
    let d = ZuptOptions::default();
    Ok(ZuptOptions {
        enabled: z.enabled.unwrap_or(d.enabled),
        window_s: opt_or("zupt.window_s", z.window_s, positive, SAME, d.window_s)?,
        accel_std_max: opt_or(
            "zupt.accel_std_max_mps2",
            z.accel_std_max_mps2,
            positive,
            SAME,
            d.accel_std_max,
        )?,
        gyro_max: opt_or(
            "zupt.gyro_max_dps",
            z.gyro_max_dps,
            positive,
            DEG,
            d.gyro_max,
        )?,
        rate_hz: opt_or("zupt.rate_hz", z.rate_hz, positive, SAME, d.rate_hz)?,
        velocity_std_mps: opt_or(
            "zupt.velocity_std_mps",
            z.velocity_std_mps,
            std_pos,
            SAME,
            d.velocity_std_mps,
        )?,
        angular_rate_std: opt_or(
            "zupt.angular_rate_std_dps",
            z.angular_rate_std_dps,
            non_negative,
            DEG,
            d.angular_rate_std,
        )?,
        max_speed_mps: opt_or(
            "zupt.max_speed_mps",
            z.max_speed_mps,
            positive,
            SAME,
            d.max_speed_mps,
        )?,
        odometer_still_mps: opt_or(
            "zupt.odometer_still_mps",
            z.odometer_still_mps,
            non_negative,
            SAME,
            d.odometer_still_mps,
        )?,
        max_accel_mps2: opt_or(
            "zupt.max_accel_mps2",
            z.max_accel_mps2,
            positive,
            SAME,
            d.max_accel_mps2,
        )?,
        gate_probability: gate(
            "zupt.gate_probability",
            z.gate_probability,
            d.gate_probability,
        )?,
    })
}

pub(super) fn to_toml(z: &ZuptOptions) -> TZupt {
    TZupt {
        enabled: Some(z.enabled),
        window_s: Some(z.window_s),
        accel_std_max_mps2: Some(z.accel_std_max),
        gyro_max_dps: Some(DEG.user(z.gyro_max)),
        rate_hz: Some(z.rate_hz),
        velocity_std_mps: Some(z.velocity_std_mps),
        angular_rate_std_dps: Some(DEG.user(z.angular_rate_std)),
        max_speed_mps: Some(z.max_speed_mps),
        odometer_still_mps: Some(z.odometer_still_mps),
        max_accel_mps2: Some(z.max_accel_mps2),
        gate_probability: Some(Gate::from_option(z.gate_probability)),
    }
}
