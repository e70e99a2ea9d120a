//! `[nhc]`: the non-holonomic constraint (core::config::NhcOptions).

use navfuse_core::config::{NhcMode, NhcOptions};
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::units::SAME;
use super::validate::{gate, non_negative, opt_or, positive};
use super::values::{Gate, Num2, Num3};

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TNhc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) mode: Option<NhcMode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std_mps: Option<Num2>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) outage_after_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) min_speed_mps: Option<f64>,
}

pub(super) fn convert(n: &TNhc) -> KResult<NhcOptions> {
    let d = NhcOptions::default();
    let mode: NhcMode = n.mode.unwrap_or(d.mode);
    let std_mps = match &n.std_mps {
        None => d.std_mps,
        Some(Num2(v)) => {
            let key = "nhc.std_mps";
            let a = match v {
                Num3::Scalar(x) => [*x, *x],
                Num3::List(l) if l.len() == 2 => [l[0], l[1]],
                Num3::List(l) => {
                    return Err(kerr(
                        key,
                        format!(
                            "expected a number or an array of 2 numbers [lateral, vertical], got {} element(s)",
                            l.len()
                        ),
                    ))
                }
            };
            for (i, x) in a.iter().enumerate() {
                if !(x.is_finite() && *x > 0.0) {
                    let what = if matches!(v, Num3::Scalar(_)) {
                        String::new()
                    } else {
                        format!("element {i}: ")
                    };
                    return Err(kerr(
                        key,
                        format!("{what}a standard deviation must be > 0, got {x}"),
                    ));
                }
            }
            a
        }
    };
    Ok(NhcOptions {
        mode,
        std_mps,
        rate_hz: opt_or("nhc.rate_hz", n.rate_hz, positive, SAME, d.rate_hz)?,
        outage_after_s: opt_or(
            "nhc.outage_after_s",
            n.outage_after_s,
            non_negative,
            SAME,
            d.outage_after_s,
        )?,
        gate_probability: gate(
            "nhc.gate_probability",
            n.gate_probability,
            d.gate_probability,
        )?,
        min_speed_mps: opt_or(
            "nhc.min_speed_mps",
            n.min_speed_mps,
            non_negative,
            SAME,
            d.min_speed_mps,
        )?,
    })
}

pub(super) fn to_toml(nh: &NhcOptions) -> TNhc {
    TNhc {
        mode: Some(nh.mode),
        std_mps: Some(Num2::from2(nh.std_mps)),
        rate_hz: Some(nh.rate_hz),
        outage_after_s: Some(nh.outage_after_s),
        gate_probability: Some(Gate::from_option(nh.gate_probability)),
        min_speed_mps: Some(nh.min_speed_mps),
    }
}
