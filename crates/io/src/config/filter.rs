//! `[filter]`: covariance propagation interval, IMU-gap dynamics, and the optional
//! `[filter.time_offset]` (core::config::FilterOptions).

use navfuse_core::config::FilterOptions;
use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::time_offset::{self, TTimeOffset};
use super::units::{DEG, SAME};
use super::validate::{non_negative, opt_or};

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TFilter {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) covariance_period_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_offset: Option<TTimeOffset>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gap_accel_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gap_rate_dps: Option<f64>,
}

impl TFilter {
    pub(super) fn is_empty(&self) -> bool {
        self.covariance_period_s.is_none()
            && self.time_offset.is_none()
            && self.gap_accel_mps2.is_none()
            && self.gap_rate_dps.is_none()
    }
}

pub(super) fn convert(f: &TFilter) -> KResult<FilterOptions> {
    let d = FilterOptions::default();
    Ok(FilterOptions {
        covariance_period_s: non_negative(
            "filter.covariance_period_s",
            f.covariance_period_s.unwrap_or(d.covariance_period_s),
        )?,
        time_offset: match &f.time_offset {
            None => d.time_offset,
            Some(t) => Some(time_offset::convert(t)?),
        },
        gap_accel_mps2: opt_or(
            "filter.gap_accel_mps2",
            f.gap_accel_mps2,
            non_negative,
            SAME,
            d.gap_accel_mps2,
        )?,
        gap_rate: opt_or(
            "filter.gap_rate_dps",
            f.gap_rate_dps,
            non_negative,
            DEG,
            d.gap_rate,
        )?,
    })
}

pub(super) fn to_toml(f: &FilterOptions) -> TFilter {
    TFilter {
        covariance_period_s: Some(f.covariance_period_s),
        gap_accel_mps2: Some(f.gap_accel_mps2),
        gap_rate_dps: Some(DEG.user(f.gap_rate)),
        time_offset: f.time_offset.as_ref().map(time_offset::to_toml),
    }
}
