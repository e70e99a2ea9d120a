//! `\[baro\]`: barometric altitude aiding (core aiding::baro::BaroOptions,
//! baro::BaroSource).

use std::path::Path;

use navfuse_core::aiding::baro::{BaroOptions, ISA_P0_PA};
use serde::{Deserialize, Serialize};

use super::error::KResult;
use super::paths::{file_key, PathWriter};
use super::units::{arr3, vec3, SAME, VRW};
use super::validate::{finite, gate, non_negative, opt_or, positive, std_pos, v3};
use super::values::Gate;
use crate::baro::{BaroFormat, BaroQuantity, BaroSource};

/// `baro.format`: text records (default) or a PX4 ULog.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum TBaroFormat {
    Text,
    Ulog,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TBaro {
    pub(super) file: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) format: Option<TBaroFormat>,
    /// `baro.format = "ulog"`: the topic instance (multi_id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) ulog_instance: Option<u8>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) skip_lines: Option<usize>,
    /// What the value column holds (default: pressure in Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) quantity: Option<BaroQuantity>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) reference_pressure_pa: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) delay_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std_m: Option<f64>,
    /// Random walk of the bias \[m/sqrt(h)\] (the conversion of `VRW`: / 60).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) bias_drift_m_per_sqrth: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) lever_arm_m: Option<Vec<f64>>,
}

pub(super) fn convert(b: &TBaro, base: &Path) -> KResult<(BaroSource, BaroOptions)> {
    let d = BaroOptions::default();
    let format = match b.format.unwrap_or(TBaroFormat::Text) {
        TBaroFormat::Ulog => BaroFormat::Ulog {
            multi_id: b.ulog_instance.unwrap_or(0),
        },
        TBaroFormat::Text if b.ulog_instance.is_some() => {
            return Err(super::error::kerr(
                "baro.ulog_instance",
                "applies only to baro.format = \"ulog\"",
            ))
        }
        TBaroFormat::Text => BaroFormat::Text,
    };
    if b.skip_lines.is_some() && format != BaroFormat::Text {
        return Err(super::error::kerr(
            "baro.skip_lines",
            "applies only to text files (baro.format = \"text\")",
        ));
    }
    let src = BaroSource {
        format,
        path: file_key(base, "baro.file", &b.file)?,
        quantity: b.quantity.unwrap_or(BaroQuantity::PressurePa),
        reference_pressure_pa: opt_or(
            "baro.reference_pressure_pa",
            b.reference_pressure_pa,
            positive,
            SAME,
            ISA_P0_PA,
        )?,
        delay_s: opt_or("baro.delay_s", b.delay_s, finite, SAME, 0.0)?,
        skip_lines: b.skip_lines,
    };
    let lever_arm_b = match &b.lever_arm_m {
        Some(l) => vec3(v3("baro.lever_arm_m", l)?),
        None => d.lever_arm_b,
    };
    let opts = BaroOptions {
        enabled: true,
        std_m: opt_or("baro.std_m", b.std_m, std_pos, SAME, d.std_m)?,
        bias_random_walk: opt_or(
            "baro.bias_drift_m_per_sqrth",
            b.bias_drift_m_per_sqrth,
            non_negative,
            VRW,
            d.bias_random_walk,
        )?,
        gate_probability: gate(
            "baro.gate_probability",
            b.gate_probability,
            d.gate_probability,
        )?,
        lever_arm_b,
    };
    Ok((src, opts))
}

pub(super) fn to_toml(src: Option<&BaroSource>, o: &BaroOptions, w: &PathWriter) -> Option<TBaro> {
    let src = src.filter(|_| o.enabled)?;
    Some(TBaro {
        file: w.path(&src.path),
        format: match src.format {
            BaroFormat::Text => None,
            BaroFormat::Ulog { .. } => Some(TBaroFormat::Ulog),
        },
        ulog_instance: match src.format {
            BaroFormat::Ulog { multi_id } => Some(multi_id),
            BaroFormat::Text => None,
        },
        skip_lines: src.skip_lines,
        quantity: Some(src.quantity),
        reference_pressure_pa: Some(src.reference_pressure_pa),
        delay_s: Some(src.delay_s),
        std_m: Some(o.std_m),
        bias_drift_m_per_sqrth: Some(VRW.user(o.bias_random_walk)),
        gate_probability: Some(Gate::from_option(o.gate_probability)),
        lever_arm_m: Some(arr3(&o.lever_arm_b).to_vec()),
    })
}
