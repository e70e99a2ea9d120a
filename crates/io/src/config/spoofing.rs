//! `[spoofing]`: the GNSS integrity monitor (core::integrity::IntegrityOptions).
//! The section's presence turns the monitor on (`enabled` defaults to true here).

use navfuse_core::integrity::{IntegrityOptions, IntegrityReference};
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::units::SAME;
use super::validate::{gate, non_negative, opt_or, positive, probability};
use super::values::Gate;

/// `[spoofing]`: the GNSS integrity monitor (navfuse_core::integrity).
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TSpoofing {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) enabled: Option<bool>,
    /// R [m] or false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) distance_m: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) chi2_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) window_epochs: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) window_probability: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) confirm_epochs: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) readmit_s: Option<f64>,
    /// Seconds or false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) max_refuse_s: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) readmit_drift_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gnss_corr_time_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) reference: Option<IntegrityReference>,
}

pub(super) fn convert(x: &TSpoofing) -> KResult<IntegrityOptions> {
    let d = IntegrityOptions::default();
    let count = |key: &str, v: Option<f64>, dflt: usize, min: f64| -> KResult<usize> {
        match v {
            None => Ok(dflt),
            Some(n) if n.fract() == 0.0 && n >= min && n <= 1e6 => Ok(n as usize),
            Some(n) => Err(kerr(
                key,
                format!("expected a whole number >= {min}, got {n}"),
            )),
        }
    };
    let distance_m = match x.distance_m {
        None => d.distance_m,
        Some(Gate::Off) => None,
        Some(Gate::Probability(r)) => Some(positive("spoofing.distance_m", r)?),
    };
    let window_probability = opt_or(
        "spoofing.window_probability",
        x.window_probability,
        probability,
        SAME,
        d.window_probability,
    )?;
    Ok(IntegrityOptions {
        enabled: x.enabled.unwrap_or(true),
        distance_m,
        chi2_probability: gate(
            "spoofing.chi2_probability",
            x.chi2_probability,
            d.chi2_probability,
        )?,
        window_epochs: count(
            "spoofing.window_epochs",
            x.window_epochs,
            d.window_epochs,
            0.0,
        )?,
        window_probability,
        confirm_epochs: count(
            "spoofing.confirm_epochs",
            x.confirm_epochs,
            d.confirm_epochs,
            1.0,
        )?,
        readmit_s: opt_or(
            "spoofing.readmit_s",
            x.readmit_s,
            non_negative,
            SAME,
            d.readmit_s,
        )?,
        max_refuse_s: match x.max_refuse_s {
            None => d.max_refuse_s,
            Some(Gate::Off) => None,
            Some(Gate::Probability(v)) => Some(positive("spoofing.max_refuse_s", v)?),
        },
        readmit_drift_mps: opt_or(
            "spoofing.readmit_drift_mps",
            x.readmit_drift_mps,
            non_negative,
            SAME,
            d.readmit_drift_mps,
        )?,
        gnss_corr_time_s: opt_or(
            "spoofing.gnss_corr_time_s",
            x.gnss_corr_time_s,
            non_negative,
            SAME,
            d.gnss_corr_time_s,
        )?,
        reference: x.reference.unwrap_or(d.reference),
    })
}

/// None when the monitor is off (no `[spoofing]` section).
pub(super) fn to_toml(sp: &IntegrityOptions) -> Option<TSpoofing> {
    sp.enabled.then(|| TSpoofing {
        enabled: Some(true),
        distance_m: Some(sp.distance_m.map_or(Gate::Off, Gate::Probability)),
        chi2_probability: Some(Gate::from_option(sp.chi2_probability)),
        window_epochs: Some(sp.window_epochs as f64),
        window_probability: Some(sp.window_probability),
        confirm_epochs: Some(sp.confirm_epochs as f64),
        readmit_s: Some(sp.readmit_s),
        max_refuse_s: Some(sp.max_refuse_s.map_or(Gate::Off, Gate::Probability)),
        readmit_drift_mps: Some(sp.readmit_drift_mps),
        gnss_corr_time_s: Some(sp.gnss_corr_time_s),
        reference: Some(sp.reference),
    })
}
