//! `[smoother]`: post-processing after the forward run (input::SmootherSpec).

use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::validate::{non_negative, positive};
use crate::input::{SmootherMode, SmootherSpec};

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TSmoother {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) enabled: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) mode: Option<SmootherMode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) separation_sigma: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) separation_period_s: Option<f64>,
}

pub(super) fn convert(t: &TSmoother) -> KResult<SmootherSpec> {
    let d = SmootherSpec::default();
    Ok(SmootherSpec {
        // A [smoother] section with a mode and no `enabled` means: smooth.
        enabled: t.enabled.unwrap_or(t.mode.is_some()),
        mode: t.mode.unwrap_or(d.mode),
        separation_sigma: match t.separation_sigma {
            Some(k) => positive("smoother.separation_sigma", k)?,
            None => d.separation_sigma,
        },
        separation_period_s: match t.separation_period_s {
            Some(p) => non_negative("smoother.separation_period_s", p)?,
            None => d.separation_period_s,
        },
    })
}

pub(super) fn to_toml(s: &SmootherSpec) -> Option<TSmoother> {
    (*s != SmootherSpec::default()).then_some(TSmoother {
        enabled: Some(s.enabled),
        mode: Some(s.mode),
        separation_sigma: Some(s.separation_sigma),
        separation_period_s: Some(s.separation_period_s),
    })
}
