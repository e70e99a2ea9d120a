//! `[output]`: what to write and how often (input::OutputSpec).

use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::validate::positive;
use crate::export::ExportFormat;
use crate::input::OutputSpec;

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TOutput {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) imu_err: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) csv: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) formats: Option<Vec<ExportFormat>>,
}

impl TOutput {
    pub(super) fn is_empty(&self) -> bool {
        self.rate_hz.is_none()
            && self.imu_err.is_none()
            && self.std.is_none()
            && self.csv.is_none()
            && self.formats.is_none()
    }
}

pub(super) fn convert(o: &TOutput) -> KResult<OutputSpec> {
    let d = OutputSpec::default();
    Ok(OutputSpec {
        rate_hz: o
            .rate_hz
            .map(|r| positive("output.rate_hz", r))
            .transpose()?
            .or(d.rate_hz),
        imu_err: o.imu_err.unwrap_or(d.imu_err),
        std: o.std.unwrap_or(d.std),
        csv: o.csv.unwrap_or(d.csv),
        formats: o.formats.clone().unwrap_or(d.formats),
    })
}

pub(super) fn to_toml(o: &OutputSpec) -> TOutput {
    TOutput {
        rate_hz: o.rate_hz,
        imu_err: Some(o.imu_err),
        std: Some(o.std),
        csv: Some(o.csv),
        formats: (!o.formats.is_empty()).then(|| o.formats.clone()),
    }
}
