//! `[gnss.tight]`: tight-coupling tuning (core::config::TightOptions). Whether tight
//! coupling is on and which range rate it fuses are `gnss.coupling` and
//! `gnss.range_rate` (rinex.rs).

use std::collections::BTreeMap;

use navfuse_core::config::TightOptions;
use navfuse_core::sat::System;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::units::SAME;
use super::validate::{non_negative, opt_or, positive, system_letter};

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TTight {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) use_pseudorange: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) clock_bias_psd_sqrt: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) clock_drift_psd_sqrt: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) clock_reset_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) slip_sigma: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) slip_min_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) tdcp_max_gap_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) pseudorange_sigma_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) range_rate_sigma_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) pseudorange_sigma_floor_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) range_rate_sigma_floor_mps: Option<f64>,
    /// Factor on the pseudorange sigma by system letter (`{ R = 1.5, S = 3 }`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) sigma_scale: Option<BTreeMap<String, f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) isb_psd_sqrt: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) isb_init_sigma_m: Option<f64>,
}

/// The keys given in `x` replace those of `t`.
pub(super) fn convert(x: &TTight, t: &mut TightOptions) -> KResult<()> {
    let d = t.clone();
    let k = |name: &str| format!("gnss.tight.{name}");
    t.use_pseudorange = x.use_pseudorange.unwrap_or(d.use_pseudorange);
    t.gate_probability = match x.gate_probability {
        None => d.gate_probability,
        Some(0.0) => None,
        Some(p) if p > 0.0 && p < 1.0 => Some(p),
        Some(p) => {
            return Err(kerr(
                &k("gate_probability"),
                format!("expected a probability in (0, 1), or 0 to turn the gate off, got {p}"),
            ))
        }
    };
    t.clock_bias_psd_sqrt = opt_or(
        &k("clock_bias_psd_sqrt"),
        x.clock_bias_psd_sqrt,
        positive,
        SAME,
        d.clock_bias_psd_sqrt,
    )?;
    t.clock_drift_psd_sqrt = opt_or(
        &k("clock_drift_psd_sqrt"),
        x.clock_drift_psd_sqrt,
        positive,
        SAME,
        d.clock_drift_psd_sqrt,
    )?;
    t.clock_reset_m = opt_or(
        &k("clock_reset_m"),
        x.clock_reset_m,
        positive,
        SAME,
        d.clock_reset_m,
    )?;
    t.slip_sigma = opt_or(&k("slip_sigma"), x.slip_sigma, positive, SAME, d.slip_sigma)?;
    t.slip_min_m = opt_or(
        &k("slip_min_m"),
        x.slip_min_m,
        non_negative,
        SAME,
        d.slip_min_m,
    )?;
    t.tdcp_max_gap_s = opt_or(
        &k("tdcp_max_gap_s"),
        x.tdcp_max_gap_s,
        positive,
        SAME,
        d.tdcp_max_gap_s,
    )?;
    t.pseudorange_sigma_scale = opt_or(
        &k("pseudorange_sigma_scale"),
        x.pseudorange_sigma_scale,
        positive,
        SAME,
        d.pseudorange_sigma_scale,
    )?;
    t.range_rate_sigma_scale = opt_or(
        &k("range_rate_sigma_scale"),
        x.range_rate_sigma_scale,
        positive,
        SAME,
        d.range_rate_sigma_scale,
    )?;
    t.pseudorange_sigma_floor_m = opt_or(
        &k("pseudorange_sigma_floor_m"),
        x.pseudorange_sigma_floor_m,
        non_negative,
        SAME,
        d.pseudorange_sigma_floor_m,
    )?;
    t.range_rate_sigma_floor_mps = opt_or(
        &k("range_rate_sigma_floor_mps"),
        x.range_rate_sigma_floor_mps,
        non_negative,
        SAME,
        d.range_rate_sigma_floor_mps,
    )?;
    for (letter, &v) in x.sigma_scale.iter().flatten() {
        let key = k("sigma_scale");
        let system = system_letter(&key, letter)?;
        t.sigma_scale
            .set(system, positive(&format!("{key}.{letter}"), v)?);
    }
    t.isb_psd_sqrt = opt_or(
        &k("isb_psd_sqrt"),
        x.isb_psd_sqrt,
        positive,
        SAME,
        d.isb_psd_sqrt,
    )?;
    t.isb_init_sigma_m = opt_or(
        &k("isb_init_sigma_m"),
        x.isb_init_sigma_m,
        positive,
        SAME,
        d.isb_init_sigma_m,
    )?;
    Ok(())
}

pub(super) fn to_toml(tight: &TightOptions) -> TTight {
    TTight {
        use_pseudorange: Some(tight.use_pseudorange),
        gate_probability: Some(tight.gate_probability.unwrap_or(0.0)),
        clock_bias_psd_sqrt: Some(tight.clock_bias_psd_sqrt),
        clock_drift_psd_sqrt: Some(tight.clock_drift_psd_sqrt),
        clock_reset_m: Some(tight.clock_reset_m),
        slip_sigma: Some(tight.slip_sigma),
        slip_min_m: Some(tight.slip_min_m),
        tdcp_max_gap_s: Some(tight.tdcp_max_gap_s),
        pseudorange_sigma_scale: Some(tight.pseudorange_sigma_scale),
        range_rate_sigma_scale: Some(tight.range_rate_sigma_scale),
        pseudorange_sigma_floor_m: Some(tight.pseudorange_sigma_floor_m),
        range_rate_sigma_floor_mps: Some(tight.range_rate_sigma_floor_mps),
        sigma_scale: Some(
            System::ALL
                .iter()
                .map(|&s| (s.letter().to_string(), tight.sigma_scale.get(s)))
                .collect(),
        ),
        isb_psd_sqrt: Some(tight.isb_psd_sqrt),
        isb_init_sigma_m: Some(tight.isb_init_sigma_m),
    }
}
