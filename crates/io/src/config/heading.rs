//! `[heading]`: dual-antenna heading input and course over ground
//! (core::config::HeadingOptions, input::HeadingSource).

use std::path::Path;

use navfuse_core::config::HeadingOptions;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::paths::{file_key, PathWriter};
use super::units::{arr3, vec3, DEG, SAME};
use super::validate::{gate, opt_or, positive, std_pos, v3};
use super::values::Gate;
use crate::error::check_scale;
use crate::input::{HeadingSource, UbxHeading};

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct THeading {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) file: Option<String>,
    /// `"text"` (3 columns, the default) or `"nmea"` (HDT, THS).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) format: Option<THeadingFormat>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) date: Option<String>,
    /// `format = "ubx"`: `"fixed"` (default) or `"float"` (fixed or float).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) ubx_carrier: Option<TUbxCarrier>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) skip_lines: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) baseline_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) course_over_ground: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) course_min_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) course_std_floor_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<Gate>,
}

/// `heading.format`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum THeadingFormat {
    Text,
    Nmea,
    Ubx,
}

/// `heading.ubx_carrier`: the carrier solutions whose headings are used.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum TUbxCarrier {
    Fixed,
    Float,
}

pub(super) fn convert(
    h: &THeading,
    base: &Path,
) -> KResult<(Option<HeadingSource>, HeadingOptions)> {
    let d = HeadingOptions::default();
    let (src, baseline_b, std_override) = match &h.file {
        Some(f) => {
            let path = file_key(base, "heading.file", f)?;
            let b = h.baseline_m.as_ref().ok_or_else(|| {
                kerr(
                    "heading.baseline_m",
                    "missing: the antenna baseline [m] (primary -> secondary antenna, IMU frame F-R-D) is required with heading.file",
                )
            })?;
            let b = v3("heading.baseline_m", b)?;
            if vec3(b).norm() == 0.0 {
                return Err(kerr(
                    "heading.baseline_m",
                    "expected a non-zero baseline (its direction gives the heading axis), got [0, 0, 0]",
                ));
            }
            let std_override = h
                .std_deg
                .map(|s| {
                    check_scale("a standard deviation", s, (DEG.to_si)(s))
                        .map_err(|m| kerr("heading.std_deg", m))
                })
                .transpose()?;
            let format = h.format.unwrap_or(THeadingFormat::Text);
            if format != THeadingFormat::Ubx && h.ubx_carrier.is_some() {
                return Err(kerr(
                    "heading.ubx_carrier",
                    "applies only to heading.format = \"ubx\"",
                ));
            }
            let ubx = (format == THeadingFormat::Ubx).then(|| UbxHeading {
                float_ok: h.ubx_carrier == Some(TUbxCarrier::Float),
            });
            let nmea = match format {
                THeadingFormat::Nmea => Some(super::gnss_text::nmea(
                    "heading.date",
                    h.date.as_deref(),
                    None,
                )?),
                THeadingFormat::Text | THeadingFormat::Ubx if h.date.is_some() => {
                    return Err(kerr(
                        "heading.date",
                        "applies only to heading.format = \"nmea\"",
                    ))
                }
                THeadingFormat::Text | THeadingFormat::Ubx => None,
            };
            if format != THeadingFormat::Text && h.skip_lines.is_some() {
                return Err(kerr(
                    "heading.skip_lines",
                    "applies only to the 3-column text (heading.format = \"text\")",
                ));
            }
            (
                Some(HeadingSource {
                    path,
                    nmea,
                    ubx,
                    skip_lines: h.skip_lines,
                }),
                Some(vec3(b)),
                std_override,
            )
        }
        None => {
            for (key, given) in [
                ("heading.baseline_m", h.baseline_m.is_some()),
                ("heading.std_deg", h.std_deg.is_some()),
                ("heading.format", h.format.is_some()),
                ("heading.date", h.date.is_some()),
                ("heading.skip_lines", h.skip_lines.is_some()),
                ("heading.ubx_carrier", h.ubx_carrier.is_some()),
            ] {
                if given {
                    return Err(kerr(
                        key,
                        "applies only with heading.file (a dual-antenna heading input)",
                    ));
                }
            }
            (None, d.baseline_b, d.dual_antenna_std_override)
        }
    };
    let opts = HeadingOptions {
        baseline_b,
        dual_antenna_std_override: std_override,
        course_over_ground: h.course_over_ground.unwrap_or(d.course_over_ground),
        course_min_speed_mps: opt_or(
            "heading.course_min_speed_mps",
            h.course_min_speed_mps,
            positive,
            SAME,
            d.course_min_speed_mps,
        )?,
        course_std_floor: opt_or(
            "heading.course_std_floor_deg",
            h.course_std_floor_deg,
            std_pos,
            DEG,
            d.course_std_floor,
        )?,
        gate_probability: gate(
            "heading.gate_probability",
            h.gate_probability,
            d.gate_probability,
        )?,
    };
    Ok((src, opts))
}

pub(super) fn to_toml(
    src: Option<&HeadingSource>,
    hd: &HeadingOptions,
    w: &PathWriter,
) -> THeading {
    let dual = src.filter(|_| hd.baseline_b.is_some());
    THeading {
        file: dual.map(|h| w.path(&h.path)),
        format: dual.and_then(|h| match (&h.nmea, &h.ubx) {
            (Some(_), _) => Some(THeadingFormat::Nmea),
            (None, Some(_)) => Some(THeadingFormat::Ubx),
            (None, None) => None,
        }),
        ubx_carrier: dual.and_then(|h| h.ubx).map(|u| {
            if u.float_ok {
                TUbxCarrier::Float
            } else {
                TUbxCarrier::Fixed
            }
        }),
        date: dual
            .and_then(|h| h.nmea.as_ref())
            .and_then(super::gnss_text::nmea_date_to_toml),
        skip_lines: dual.and_then(|h| h.skip_lines),
        baseline_m: dual.and(hd.baseline_b).map(|b| arr3(&b).to_vec()),
        std_deg: dual.and(hd.dual_antenna_std_override).map(|x| DEG.user(x)),
        course_over_ground: Some(hd.course_over_ground),
        course_min_speed_mps: Some(hd.course_min_speed_mps),
        course_std_floor_deg: Some(DEG.user(hd.course_std_floor)),
        gate_probability: Some(Gate::from_option(hd.gate_probability)),
    }
}
