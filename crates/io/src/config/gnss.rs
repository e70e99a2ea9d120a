//! `[gnss]`: the GNSS input (input::GnssSource) and how its fixes are used
//! (core::config::GnssOptions). The RINEX-only keys are converted in rinex.rs, the
//! outage keys in outages.rs.

use std::path::Path;

use navfuse_core::config::{FixErrorOptions, GnssFusion, GnssOptions, RangeRate, TightOptions};
use navfuse_core::sat::System;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::gnss_text::{self, TGnssCsv};
use super::outages::{self, TOutageEvery};
use super::paths::{file_key, PathWriter};
use super::rinex;
use super::tight::TTight;
use super::units::{arr3, vec3, SAME};
use super::validate::{finite, gate, non_negative, opt_or, positive, std3, system_letter, v3};
use super::values::{Gate, Num3, OneOrMany, Strings};
use super::RelativeOutage;
use crate::input::{Coupling, GnssFormat, GnssSource};

/// Largest `[gnss] time_snap_s` \[s\]: a fix moved further than this is not a
/// rounding of time tags.
const MAX_TIME_SNAP_S: f64 = 0.05;

/// `gnss.format`. A raw type: `GnssFormat`'s variants carry `gnss.quality` and the
/// RINEX keys.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub(super) enum TGnssFormat {
    #[serde(rename = "kf-gins")]
    KfGins,
    #[serde(rename = "rtklib-pos")]
    RtklibPos,
    #[serde(rename = "rinex")]
    Rinex,
    #[serde(rename = "ulog")]
    Ulog,
    #[serde(rename = "nmea")]
    Nmea,
    #[serde(rename = "csv")]
    Csv,
    #[serde(rename = "ubx")]
    Ubx,
}

/// `gnss.fusion`. A raw type: `GnssFusion::SixState` carries `gnss.six_state_every`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum TFusion {
    ErrorState,
    SixState,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TGnss {
    pub(super) file: String,
    pub(super) format: TGnssFormat,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) ubx_source: Option<super::ubx::TUbxSource>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) nav: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) coupling: Option<Coupling>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) range_rate: Option<RangeRate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) elevation_mask_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) fde: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) signals: Option<std::collections::BTreeMap<String, Strings>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) dual_frequency: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) orbits: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) sp3: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) clk: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) cn0_sigma_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) cn0_reference_dbhz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) dgps: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) dgps_corrections: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) dgps_reference_obs: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) dgps_reference_position_deg_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) dgps_max_age_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) systems: Option<Strings>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) tight: Option<TTight>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) quality: Option<Vec<u8>>,
    /// `gnss.format = "ulog"`: the GPS topic instance (multi_id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) ulog_instance: Option<u8>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) skip_lines: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) decimate_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_offset_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_snap_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) lever_arm_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) use_velocity: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) position_std_m: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) velocity_std_mps: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) position_std_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) velocity_std_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_timeout_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) error_corr_time_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) error_corr_fraction: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) scale_window: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) robust_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) readmit_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) floor_accel_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) outages: Option<Vec<Vec<f64>>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) outage_every: Option<OneOrMany<TOutageEvery>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) fusion: Option<TFusion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) six_state_every: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) date: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) csv: Option<TGnssCsv>,
}

impl TGnss {
    /// The RINEX-only keys, absent (for struct update syntax).
    pub(super) fn no_rinex() -> TGnss {
        TGnss {
            file: String::new(),
            format: TGnssFormat::KfGins,
            ubx_source: None,
            nav: None,
            coupling: None,
            range_rate: None,
            elevation_mask_deg: None,
            fde: None,
            signals: None,
            dual_frequency: None,
            orbits: None,
            sp3: None,
            clk: None,
            cn0_sigma_m: None,
            cn0_reference_dbhz: None,
            dgps: None,
            dgps_corrections: None,
            dgps_reference_obs: None,
            dgps_reference_position_deg_m: None,
            dgps_max_age_s: None,
            systems: None,
            tight: None,
            quality: None,
            ulog_instance: None,
            skip_lines: None,
            decimate_s: None,
            time_offset_s: None,
            time_snap_s: None,
            lever_arm_m: None,
            use_velocity: None,
            position_std_m: None,
            velocity_std_mps: None,
            position_std_scale: None,
            velocity_std_scale: None,
            gate_probability: None,
            gate_timeout_s: None,
            error_corr_time_s: None,
            error_corr_fraction: None,
            scale_window: None,
            robust_probability: None,
            readmit_s: None,
            floor_accel_mps2: None,
            outages: None,
            outage_every: None,
            fusion: None,
            six_state_every: None,
            date: None,
            csv: None,
        }
    }
}

pub(super) fn convert(
    g: &TGnss,
    base: &Path,
    start: Option<f64>,
) -> KResult<(GnssSource, GnssOptions, Vec<RelativeOutage>, TightOptions)> {
    let path = file_key(base, "gnss.file", &g.file)?;
    if g.ubx_source.is_some() && g.format != TGnssFormat::Ubx {
        return Err(kerr(
            "gnss.ubx_source",
            "applies only to gnss.format = \"ubx\"",
        ));
    }
    if !matches!(g.format, TGnssFormat::Rinex | TGnssFormat::Ubx) {
        if let Some(key) = rinex_key_set(g) {
            return Err(kerr(key, "applies only to gnss.format = \"rinex\""));
        }
    }
    if g.format != TGnssFormat::Ulog && g.ulog_instance.is_some() {
        return Err(kerr(
            "gnss.ulog_instance",
            "applies only to gnss.format = \"ulog\"",
        ));
    }
    for (key, set, fmt) in [
        ("gnss.date", g.date.is_some(), TGnssFormat::Nmea),
        ("gnss.csv", g.csv.is_some(), TGnssFormat::Csv),
    ] {
        if set && g.format != fmt {
            let name = if fmt == TGnssFormat::Nmea {
                "nmea"
            } else {
                "csv"
            };
            return Err(kerr(
                key,
                format!("applies only to gnss.format = \"{name}\""),
            ));
        }
    }
    if g.quality.is_some() && g.format != TGnssFormat::RtklibPos && g.format != TGnssFormat::KfGins
    {
        return Err(kerr(
            "gnss.quality",
            "applies only to gnss.format = \"rtklib-pos\"",
        ));
    }
    let mut position_std_override = g
        .position_std_m
        .as_ref()
        .map(|v| std3("gnss.position_std_m", v))
        .transpose()?;
    let mut velocity_std_override = g
        .velocity_std_mps
        .as_ref()
        .map(|v| std3("gnss.velocity_std_mps", v))
        .transpose()?;
    let mut tight = TightOptions::default();
    let format = match g.format {
        TGnssFormat::Ulog => GnssFormat::Ulog {
            multi_id: g.ulog_instance.unwrap_or(0),
        },
        // The NMEA and CSV readers take the stds as their fallback (module doc of
        // gnss_text.rs), so they are not overrides there.
        TGnssFormat::Nmea => GnssFormat::Nmea(gnss_text::nmea(
            "gnss.date",
            g.date.as_deref(),
            position_std_override.take(),
        )?),
        TGnssFormat::Csv => {
            let c = g.csv.as_ref().ok_or_else(|| {
                kerr(
                    "gnss.csv",
                    "missing: gnss.format = \"csv\" needs a [gnss.csv] table declaring the columns",
                )
            })?;
            GnssFormat::Csv(gnss_text::csv(
                c,
                position_std_override.take(),
                velocity_std_override.take(),
            )?)
        }
        TGnssFormat::KfGins => {
            if g.quality.is_some() {
                return Err(kerr(
                    "gnss.quality",
                    "applies only to gnss.format = \"rtklib-pos\"",
                ));
            }
            GnssFormat::KfGins
        }
        TGnssFormat::RtklibPos => {
            let quality = g.quality.clone().unwrap_or_else(|| vec![1]);
            if quality.is_empty() {
                return Err(kerr(
                    "gnss.quality",
                    "expected a non-empty array of RTKLIB Q flags (1 = fix, 2 = float, ...)",
                ));
            }
            if let Some(q) = quality.iter().find(|q| !(1..=6).contains(*q)) {
                return Err(kerr(
                    "gnss.quality",
                    format!("expected RTKLIB Q flags in 1..=6, got {q}"),
                ));
            }
            GnssFormat::RtklibPos { quality }
        }
        TGnssFormat::Rinex => {
            let (rinex, t) = rinex::convert(g, base)?;
            tight = t;
            GnssFormat::Rinex(rinex)
        }
        TGnssFormat::Ubx => {
            let (u, t) = super::ubx::convert(g, base)?;
            tight = t;
            GnssFormat::Ubx(u)
        }
    };
    let decimate_s = g
        .decimate_s
        .map(|d| positive("gnss.decimate_s", d))
        .transpose()?;
    let time_offset_s = finite("gnss.time_offset_s", g.time_offset_s.unwrap_or(0.0))?;
    if g.skip_lines.is_some()
        && !matches!(format, GnssFormat::KfGins | GnssFormat::RtklibPos { .. })
    {
        return Err(kerr(
            "gnss.skip_lines",
            "applies only to gnss.format = \"kf-gins\" or \"rtklib-pos\" (csv: gnss.csv.skip_lines; NMEA and binary formats need none)",
        ));
    }
    let src = GnssSource {
        path,
        format,
        decimate_s,
        time_offset_s,
        skip_lines: g.skip_lines,
    };

    let d = GnssOptions::default();
    let lever_arm_b = match &g.lever_arm_m {
        Some(v) => vec3(v3("gnss.lever_arm_m", v)?),
        None => d.lever_arm_b,
    };
    let position_std_override = position_std_override.map(vec3);
    let velocity_std_override = velocity_std_override.map(vec3);
    let gate_probability = gate(
        "gnss.gate_probability",
        g.gate_probability,
        d.gate_probability,
    )?;
    let fd = d.fix_error;
    let fix_error = FixErrorOptions {
        corr_time_s: opt_or(
            "gnss.error_corr_time_s",
            g.error_corr_time_s,
            non_negative,
            SAME,
            fd.corr_time_s,
        )?,
        corr_fraction: match g.error_corr_fraction {
            None => fd.corr_fraction,
            Some(r) if (0.0..1.0).contains(&r) => r,
            Some(r) => {
                return Err(kerr(
                    "gnss.error_corr_fraction",
                    format!("expected a share of the fix variance in [0, 1), e.g. 0.5, got {r}"),
                ))
            }
        },
        scale_window: match g.scale_window {
            None => fd.scale_window,
            Some(w) if (0.0..=1e6).contains(&w) && w.fract() == 0.0 => w as usize,
            Some(w) => {
                return Err(kerr(
                    "gnss.scale_window",
                    format!("expected a whole number of fixes in [0, 1000000] (0 = off), got {w}"),
                ))
            }
        },
        robust_probability: gate(
            "gnss.robust_probability",
            g.robust_probability,
            fd.robust_probability,
        )?,
        readmit_s: opt_or("gnss.readmit_s", g.readmit_s, positive, SAME, fd.readmit_s)?,
        floor_accel_mps2: opt_or(
            "gnss.floor_accel_mps2",
            g.floor_accel_mps2,
            non_negative,
            SAME,
            fd.floor_accel_mps2,
        )?,
    };
    if let (Some(r), Some(gp)) = (fix_error.robust_probability, gate_probability) {
        if r <= gp {
            return Err(kerr(
                "gnss.robust_probability",
                format!("must be larger than gnss.gate_probability ({gp}): down-weighting starts before the gate rejects; got {r}"),
            ));
        }
    }

    let gate_timeout_s = positive(
        "gnss.gate_timeout_s",
        g.gate_timeout_s.unwrap_or(d.gate_timeout_s),
    )?;

    let (outages, relative) = outages::convert(g.outages.as_ref(), g.outage_every.as_ref(), start)?;

    let time_snap_s = match g.time_snap_s {
        None => d.time_snap_s,
        Some(s) if (0.0..=MAX_TIME_SNAP_S).contains(&s) => s,
        Some(s) => {
            return Err(kerr(
                "gnss.time_snap_s",
                format!("expected a tolerance in [0, {MAX_TIME_SNAP_S}] s (0 = each fix at its own time; KF-GINS uses 0.001), got {s}"),
            ))
        }
    };

    let fusion = convert_fusion(g, tight.enabled)?;
    let opts = GnssOptions {
        time_snap_s,
        lever_arm_b,
        use_velocity: g.use_velocity.unwrap_or(d.use_velocity),
        position_std_override,
        velocity_std_override,
        position_std_scale: positive(
            "gnss.position_std_scale",
            g.position_std_scale.unwrap_or(d.position_std_scale),
        )?,
        velocity_std_scale: positive(
            "gnss.velocity_std_scale",
            g.velocity_std_scale.unwrap_or(d.velocity_std_scale),
        )?,
        gate_probability,
        gate_timeout_s,
        outages,
        fusion,
        fix_error,
        systems: match &g.systems {
            Some(letters) => convert_systems(&letters.0)?,
            None => d.systems,
        },
    };
    Ok((src, opts, relative, tight))
}

/// The first RINEX-only key `g` sets (the keys of raw observations).
pub(super) fn rinex_key_set(g: &TGnss) -> Option<&'static str> {
    [
        ("gnss.nav", g.nav.is_some()),
        ("gnss.coupling", g.coupling.is_some()),
        ("gnss.range_rate", g.range_rate.is_some()),
        ("gnss.elevation_mask_deg", g.elevation_mask_deg.is_some()),
        ("gnss.fde", g.fde.is_some()),
        ("gnss.dgps", g.dgps.is_some()),
        ("gnss.dgps_corrections", g.dgps_corrections.is_some()),
        ("gnss.dgps_reference_obs", g.dgps_reference_obs.is_some()),
        (
            "gnss.dgps_reference_position_deg_m",
            g.dgps_reference_position_deg_m.is_some(),
        ),
        ("gnss.dgps_max_age_s", g.dgps_max_age_s.is_some()),
        ("gnss.systems", g.systems.is_some()),
        ("gnss.tight", g.tight.is_some()),
    ]
    .into_iter()
    .find(|(_, set)| *set)
    .map(|(key, _)| key)
}

/// `gnss.systems`: RINEX letters or system names (either case; a string may list
/// several, separated by commas or spaces), each once, at least one.
fn convert_systems(items: &[String]) -> KResult<Vec<System>> {
    let key = "gnss.systems";
    let letters: Vec<&str> = items
        .iter()
        .flat_map(|s| s.split([',', ' ']))
        .filter(|t| !t.is_empty())
        .collect();
    if letters.is_empty() {
        return Err(kerr(
            key,
            "expected at least one system, e.g. [\"G\", \"E\"]",
        ));
    }
    let mut out = Vec::with_capacity(letters.len());
    for l in letters {
        let s = system_letter(key, l)?;
        if out.contains(&s) {
            return Err(kerr(key, format!("{} (\"{l}\") is listed twice", s.name())));
        }
        out.push(s);
    }
    Ok(out)
}

/// `gnss.fusion` and `gnss.six_state_every` (SYSTEM.md §5; seed 004 §3): the
/// six-state cascade takes fixes, so not with tight coupling.
fn convert_fusion(g: &TGnss, tight: bool) -> KResult<GnssFusion> {
    match g.fusion.unwrap_or(TFusion::ErrorState) {
        TFusion::ErrorState => {
            if g.six_state_every.is_some() {
                return Err(kerr(
                    "gnss.six_state_every",
                    "applies only to gnss.fusion = \"six_state\"",
                ));
            }
            Ok(GnssFusion::ErrorState)
        }
        TFusion::SixState => {
            if tight {
                return Err(kerr(
                    "gnss.fusion",
                    "\"six_state\" fuses GNSS fixes (loose coupling) only, and gnss.coupling is \"tight\" (the default for rinex): set gnss.coupling = \"loose\", or gnss.fusion = \"error_state\"",
                ));
            }
            let n = g.six_state_every.unwrap_or(1.0);
            let whole = n.fract() == 0.0 && (1.0..=1e6).contains(&n);
            match std::num::NonZeroU32::new(if whole { n as u32 } else { 0 }) {
                Some(every) => Ok(GnssFusion::SixState { every }),
                None => Err(kerr(
                    "gnss.six_state_every",
                    format!("expected a whole number of GNSS epochs >= 1 (1 = every fix), got {n}"),
                )),
            }
        }
    }
}

/// None for a pure inertial run.
pub(super) fn to_toml(
    g: &GnssSource,
    go: &GnssOptions,
    tight: &TightOptions,
    relative: &[RelativeOutage],
    w: &PathWriter,
) -> TGnss {
    let (format, quality) = match &g.format {
        GnssFormat::KfGins => (TGnssFormat::KfGins, None),
        GnssFormat::RtklibPos { quality } => (TGnssFormat::RtklibPos, Some(quality.clone())),
        GnssFormat::Rinex(_) => (TGnssFormat::Rinex, None),
        GnssFormat::Ulog { .. } => (TGnssFormat::Ulog, None),
        GnssFormat::Nmea(_) => (TGnssFormat::Nmea, None),
        GnssFormat::Csv(_) => (TGnssFormat::Csv, None),
        GnssFormat::Ubx(_) => (TGnssFormat::Ubx, None),
    };
    let (outages, outage_every) = outages::to_toml(&go.outages, relative);
    let mut t = TGnss {
        file: w.path(&g.path),
        format,
        quality,
        ulog_instance: match g.format {
            GnssFormat::Ulog { multi_id } => Some(multi_id),
            _ => None,
        },
        skip_lines: g.skip_lines,
        decimate_s: g.decimate_s,
        time_offset_s: Some(g.time_offset_s),
        time_snap_s: (go.time_snap_s != 0.0).then_some(go.time_snap_s),
        lever_arm_m: Some(arr3(&go.lever_arm_b).to_vec()),
        use_velocity: Some(go.use_velocity),
        position_std_m: go
            .position_std_override
            .as_ref()
            .map(|v| Num3::from3(arr3(v))),
        velocity_std_mps: go
            .velocity_std_override
            .as_ref()
            .map(|v| Num3::from3(arr3(v))),
        position_std_scale: Some(go.position_std_scale),
        velocity_std_scale: Some(go.velocity_std_scale),
        gate_probability: Some(Gate::from_option(go.gate_probability)),
        gate_timeout_s: Some(go.gate_timeout_s),
        error_corr_time_s: Some(go.fix_error.corr_time_s),
        error_corr_fraction: Some(go.fix_error.corr_fraction),
        scale_window: Some(go.fix_error.scale_window as f64),
        robust_probability: Some(Gate::from_option(go.fix_error.robust_probability)),
        readmit_s: Some(go.fix_error.readmit_s),
        floor_accel_mps2: Some(go.fix_error.floor_accel_mps2),
        outages,
        outage_every,
        fusion: Some(match go.fusion {
            GnssFusion::ErrorState => TFusion::ErrorState,
            GnssFusion::SixState { .. } => TFusion::SixState,
        }),
        six_state_every: match go.fusion {
            GnssFusion::ErrorState => None,
            GnssFusion::SixState { every } => Some(f64::from(every.get())),
        },
        ..TGnss::no_rinex()
    };
    match &g.format {
        GnssFormat::Nmea(o) => {
            t.date = gnss_text::nmea_date_to_toml(o);
            t.position_std_m = o.position_std_m.map(Num3::from3);
        }
        GnssFormat::Csv(o) => {
            t.csv = Some(gnss_text::csv_to_toml(o));
            t.position_std_m = o.position_std_m.map(Num3::from3);
            t.velocity_std_mps = o.velocity_std_mps.map(Num3::from3);
        }
        _ => {}
    }
    if let GnssFormat::Rinex(r) = &g.format {
        rinex::to_toml(r, tight, &mut t, w);
        t.systems = Some(Strings(
            go.systems.iter().map(|s| s.letter().to_string()).collect(),
        ));
    }
    if let GnssFormat::Ubx(u) = &g.format {
        super::ubx::to_toml(u, tight, &mut t, w);
        if matches!(u, crate::input::UbxGnss::Raw(_)) {
            t.systems = Some(Strings(
                go.systems.iter().map(|s| s.letter().to_string()).collect(),
            ));
        }
    }
    t
}
