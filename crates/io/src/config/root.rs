//! The whole TOML file: one field per section, and the two directions over all
//! sections. A new section is its file (raw struct, `convert`, `to_toml`) plus its
//! field here and one line in each direction.

use std::path::{Path, PathBuf};

use navfuse_core::config::{GnssFusion, GnssOptions, NavConfig, TightOptions};
use navfuse_core::integrity::IntegrityReference;
use serde::{Deserialize, Serialize};

use super::baro::{self, TBaro};
use super::error::{kerr, KResult};
use super::filter::{self, TFilter};
use super::gnss::{self, TGnss};
use super::heading::{self, THeading};
use super::imu::{self, TImu};
use super::imu_noise::{self, TNoise};
use super::initial::{self, TInitial};
use super::nhc::{self, TNhc};
use super::odometer::{self, TOdometer};
use super::output::{self, TOutput};
use super::paths::PathWriter;
use super::smoother::{self, TSmoother};
use super::spoofing::{self, TSpoofing};
use super::time::{self, TTime};
use super::tuning::{self, TTuning};
use super::vehicle::{self, TVehicle};
use super::zupt::{self, TZupt};
use super::{RelativeOutage, RunConfig};
use crate::input::{
    GnssSource, HeadingSource, ImuSource, OdometerSource, OutputSpec, SmootherSpec, TuningSpec,
};

/// navfuse TOML, as written (user units).
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TomlRoot {
    pub(super) imu: TImu,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gnss: Option<TGnss>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) odometer: Option<TOdometer>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) heading: Option<THeading>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) baro: Option<TBaro>,
    #[serde(default, skip_serializing_if = "TTime::is_empty")]
    pub(super) time: TTime,
    #[serde(default)]
    pub(super) initial: TInitial,
    #[serde(default)]
    pub(super) imu_noise: TNoise,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) vehicle: Option<TVehicle>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) nhc: Option<TNhc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) zupt: Option<TZupt>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) spoofing: Option<TSpoofing>,
    #[serde(default, skip_serializing_if = "TFilter::is_empty")]
    pub(super) filter: TFilter,
    #[serde(default, skip_serializing_if = "TOutput::is_empty")]
    pub(super) output: TOutput,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) smoother: Option<TSmoother>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) tuning: Option<TTuning>,
}

/// A [`RunConfig`] but for where it came from.
#[derive(Debug, PartialEq)]
pub(super) struct Converted {
    nav: NavConfig,
    imu: ImuSource,
    gnss: Option<GnssSource>,
    odometer: Option<OdometerSource>,
    heading: Option<HeadingSource>,
    baro: Option<crate::baro::BaroSource>,
    output: OutputSpec,
    smoother: SmootherSpec,
    tuning: TuningSpec,
    relative_outages: Vec<RelativeOutage>,
    defaulted: Vec<&'static str>,
}

impl Converted {
    pub(super) fn finish(
        self,
        path: &Path,
        kf_out: Option<PathBuf>,
        warnings: Vec<String>,
    ) -> RunConfig {
        RunConfig {
            nav: self.nav,
            imu: self.imu,
            gnss: self.gnss,
            odometer: self.odometer,
            heading: self.heading,
            baro: self.baro,
            output: self.output,
            smoother: self.smoother,
            tuning: self.tuning,
            source_path: path.to_path_buf(),
            kfgins_output_path: kf_out,
            warnings,
            relative_outages: self.relative_outages,
            defaulted: self.defaulted,
        }
    }
}

/// File -> values; relative paths resolve against `base`.
pub(super) fn convert(raw: TomlRoot, base: &Path) -> KResult<Converted> {
    let (start, end) = time::convert(&raw.time)?;
    let imu = imu::convert(&raw.imu, base)?;
    let (gnss, gnss_opts, relative_outages, tight) = match &raw.gnss {
        Some(g) => {
            let (src, opts, rel, tight) = gnss::convert(g, base, start)?;
            (Some(src), opts, rel, tight)
        }
        // No GNSS: nothing to gate.
        None => (
            None,
            GnssOptions {
                gate_probability: None,
                ..GnssOptions::default()
            },
            Vec::new(),
            TightOptions::default(),
        ),
    };
    let mut defaulted = Vec::new();
    let imu_noise = imu_noise::convert(&raw.imu_noise, &mut defaulted)?;
    let initial = initial::convert(&raw.initial, &imu_noise, &mut defaulted)?;
    let filter = filter::convert(&raw.filter)?;
    let output = output::convert(&raw.output)?;
    let smoother = match &raw.smoother {
        Some(t) => smoother::convert(t)?,
        None => SmootherSpec::default(),
    };
    let tuning = match &raw.tuning {
        Some(t) => tuning::convert(t)?,
        None => TuningSpec::default(),
    };
    let d = NavConfig::new(imu_noise, initial);
    let vehicle = raw.vehicle.as_ref().map(vehicle::convert).transpose()?;
    let nhc = raw.nhc.as_ref().map(nhc::convert).transpose()?;
    let (odometer_src, odometer) = match &raw.odometer {
        Some(o) => {
            let (src, opts) = odometer::convert(o, base)?;
            (Some(src), opts)
        }
        None => (None, d.odometer.clone()),
    };
    let (heading_src, heading) = match &raw.heading {
        Some(h) => heading::convert(h, base)?,
        None => (None, d.heading.clone()),
    };
    let (baro_src, baro_opts) = match &raw.baro {
        Some(b) => {
            let (s, o) = baro::convert(b, base)?;
            (Some(s), o)
        }
        None => (None, d.baro.clone()),
    };
    let integrity = raw.spoofing.as_ref().map(spoofing::convert).transpose()?;
    let zupt = raw.zupt.as_ref().map(zupt::convert).transpose()?;
    let nav = NavConfig {
        tight,
        gnss: gnss_opts,
        filter,
        vehicle: vehicle.unwrap_or(d.vehicle.clone()),
        nhc: nhc.unwrap_or(d.nhc.clone()),
        odometer,
        heading,
        integrity: integrity.unwrap_or(d.integrity.clone()),
        zupt: zupt.unwrap_or(d.zupt.clone()),
        baro: baro_opts,
        start_time: start.unwrap_or(d.start_time),
        end_time: end.or(d.end_time),
        ..d
    };
    if nav.integrity.enabled
        && nav.integrity.reference == IntegrityReference::DeadReckoning
        && !matches!(nav.gnss.fusion, GnssFusion::SixState { .. })
    {
        return Err(kerr(
            "spoofing.reference",
            "\"dead_reckoning\" needs gnss.fusion = \"six_state\" (only that fusion keeps a dead reckoning that GNSS does not correct); use \"prediction\"".to_string(),
        ));
    }
    Ok(Converted {
        nav,
        imu,
        gnss,
        odometer: odometer_src,
        heading: heading_src,
        baro: baro_src,
        output,
        smoother,
        tuning,
        relative_outages,
        defaulted,
    })
}

/// Values -> file, every key written (defaults included).
pub(super) fn to_raw(c: &RunConfig, w: &PathWriter) -> TomlRoot {
    let n = &c.nav;
    TomlRoot {
        imu: imu::to_toml(&c.imu, w),
        gnss: c
            .gnss
            .as_ref()
            .map(|g| gnss::to_toml(g, &n.gnss, &n.tight, &c.relative_outages, w)),
        odometer: odometer::to_toml(c.odometer.as_ref(), &n.odometer, w),
        heading: Some(heading::to_toml(c.heading.as_ref(), &n.heading, w)),
        baro: baro::to_toml(c.baro.as_ref(), &n.baro, w),
        time: time::to_toml(n.start_time, n.end_time),
        initial: initial::to_toml(&n.initial),
        imu_noise: imu_noise::to_toml(&n.imu_noise),
        vehicle: Some(vehicle::to_toml(&n.vehicle)),
        nhc: Some(nhc::to_toml(&n.nhc)),
        zupt: Some(zupt::to_toml(&n.zupt)),
        spoofing: spoofing::to_toml(&n.integrity),
        filter: filter::to_toml(&n.filter),
        output: output::to_toml(&c.output),
        smoother: smoother::to_toml(&c.smoother),
        tuning: tuning::to_toml(&c.tuning),
    }
}

/// A TOML text holding only input sections (`[imu]`, `[gnss]`): what the readers of
/// a single file need (Python's `navfuse.read_imu` / `read_gnss` without a run
/// configuration).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TomlInputs {
    #[serde(default)]
    pub(super) imu: Option<TImu>,
    #[serde(default)]
    pub(super) gnss: Option<TGnss>,
}

/// [`TomlInputs`] -> the sources; relative paths resolve against `base`.
#[allow(clippy::type_complexity)]
pub(super) fn convert_inputs(
    raw: &TomlInputs,
    base: &Path,
) -> KResult<(
    Option<crate::input::ImuSource>,
    Option<(crate::input::GnssSource, GnssOptions)>,
)> {
    let imu = raw
        .imu
        .as_ref()
        .map(|m| imu::convert(m, base))
        .transpose()?;
    let gnss = match &raw.gnss {
        Some(g) => {
            let (src, opts, _, _) = gnss::convert(g, base, None)?;
            Some((src, opts))
        }
        None => None,
    };
    Ok((imu, gnss))
}
