//! `[filter]`: covariance propagation interval, IMU-gap dynamics, adaptive
//! measurement noise, and the optional `[filter.time_offset]`
//! (core::config::FilterOptions).

use navfuse_core::aiding::adaptive::AdaptiveNoiseOptions;
use navfuse_core::config::FilterOptions;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::time_offset::{self, TTimeOffset};
use super::units::{DEG, SAME};
use super::validate::{non_negative, opt_or, positive};

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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) adaptive_noise: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) adaptive_window_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) adaptive_iterations: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) adaptive_sources: Option<Vec<String>>,
}

impl TFilter {
    pub(super) fn is_empty(&self) -> bool {
        self.covariance_period_s.is_none()
            && self.time_offset.is_none()
            && self.gap_accel_mps2.is_none()
            && self.gap_rate_dps.is_none()
            && self.adaptive_noise.is_none()
            && self.adaptive_window_s.is_none()
            && self.adaptive_iterations.is_none()
            && self.adaptive_sources.is_none()
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
        adaptive_noise: adaptive(f)?,
    })
}

/// `adaptive_noise` and its keys. The names of `adaptive_sources` are not checked
/// against a list: a custom source may fuse under any name.
fn adaptive(f: &TFilter) -> KResult<Option<AdaptiveNoiseOptions>> {
    if f.adaptive_noise != Some(true) {
        for (key, given) in [
            ("filter.adaptive_window_s", f.adaptive_window_s.is_some()),
            (
                "filter.adaptive_iterations",
                f.adaptive_iterations.is_some(),
            ),
            ("filter.adaptive_sources", f.adaptive_sources.is_some()),
        ] {
            if given {
                return Err(kerr(key, "applies only with adaptive_noise = true"));
            }
        }
        return Ok(None);
    }
    let d = AdaptiveNoiseOptions::default();
    let iterations = match f.adaptive_iterations {
        None => d.iterations,
        Some(n) if (1..=50).contains(&n) => n as usize,
        Some(n) => {
            return Err(kerr(
                "filter.adaptive_iterations",
                format!("expected an integer from 1 to 50, got {n}"),
            ))
        }
    };
    if let Some(list) = &f.adaptive_sources {
        if let Some(i) = list.iter().position(|s| s.trim().is_empty()) {
            return Err(kerr(
                "filter.adaptive_sources",
                format!("element {i}: expected a source name, got an empty string"),
            ));
        }
    }
    Ok(Some(AdaptiveNoiseOptions {
        window_s: match f.adaptive_window_s {
            None => d.window_s,
            Some(w) => positive("filter.adaptive_window_s", w)?,
        },
        iterations,
        sources: f.adaptive_sources.clone(),
        ..d
    }))
}

pub(super) fn to_toml(f: &FilterOptions) -> TFilter {
    TFilter {
        covariance_period_s: Some(f.covariance_period_s),
        gap_accel_mps2: Some(f.gap_accel_mps2),
        gap_rate_dps: Some(DEG.user(f.gap_rate)),
        time_offset: f.time_offset.as_ref().map(time_offset::to_toml),
        adaptive_noise: f.adaptive_noise.is_some().then_some(true),
        adaptive_window_s: f.adaptive_noise.as_ref().map(|a| a.window_s),
        adaptive_iterations: f.adaptive_noise.as_ref().map(|a| a.iterations as i64),
        adaptive_sources: f.adaptive_noise.as_ref().and_then(|a| a.sources.clone()),
    }
}
