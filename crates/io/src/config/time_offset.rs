//! `[filter.time_offset]`: the GNSS-IMU time offset and its rate as filter states
//! (core::config::TimeOffsetConfig).

use navfuse_core::config::TimeOffsetConfig;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::units::PPM;
use super::validate::{finite, non_negative, positive};

/// Largest time-offset rate and rate std accepted [ppm].
const MAX_RATE_PPM: f64 = 1e6;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TTimeOffset {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) estimate: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) initial_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) random_walk: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) initial_rate_ppm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) rate_std_ppm: Option<f64>,
}

pub(super) fn convert(t: &TTimeOffset) -> KResult<TimeOffsetConfig> {
    let d = TimeOffsetConfig::default();
    let initial_s = finite(
        "filter.time_offset.initial_s",
        t.initial_s.unwrap_or(d.initial_s),
    )?;
    let std_s = positive("filter.time_offset.std_s", t.std_s.unwrap_or(d.std_s))?;
    let random_walk = non_negative(
        "filter.time_offset.random_walk",
        t.random_walk.unwrap_or(d.random_walk),
    )?;
    // A clock-rate difference of a million ppm (the clocks' rates differ by a
    // factor of 2) is no time offset any more: bounded, so that writing it
    // back in ppm stays finite.
    let ppm = |key: &str, v: f64| -> KResult<f64> {
        if v.abs() <= MAX_RATE_PPM {
            Ok(v)
        } else {
            Err(kerr(
                key,
                format!("expected at most {MAX_RATE_PPM:e} ppm in magnitude, got {v:e}"),
            ))
        }
    };
    let initial_rate = match t.initial_rate_ppm {
        Some(x) => (PPM.to_si)(ppm(
            "filter.time_offset.initial_rate_ppm",
            finite("filter.time_offset.initial_rate_ppm", x)?,
        )?),
        None => d.initial_rate,
    };
    let rate_std = match t.rate_std_ppm {
        Some(x) => (PPM.to_si)(ppm(
            "filter.time_offset.rate_std_ppm",
            non_negative("filter.time_offset.rate_std_ppm", x)?,
        )?),
        None => d.rate_std,
    };
    let estimate = t.estimate.unwrap_or(true);
    Ok(TimeOffsetConfig {
        initial_s,
        std_s: if estimate { std_s } else { 0.0 },
        random_walk,
        initial_rate,
        rate_std: if estimate { rate_std } else { 0.0 },
    })
}

pub(super) fn to_toml(t: &TimeOffsetConfig) -> TTimeOffset {
    TTimeOffset {
        estimate: Some(t.std_s > 0.0),
        initial_s: Some(t.initial_s),
        std_s: (t.std_s > 0.0).then_some(t.std_s),
        random_walk: Some(t.random_walk),
        initial_rate_ppm: Some(PPM.user(t.initial_rate)),
        rate_std_ppm: Some(PPM.user(t.rate_std)),
    }
}
