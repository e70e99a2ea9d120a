//! Run configuration: navfuse's own TOML format ([`load_toml`]) and unchanged KF-GINS
//! YAML files ([`load_kfgins_yaml`]), both turned into a [`RunConfig`]: the input and
//! output descriptions plus a [`NavConfig`] in SI units. Users write degrees, deg/h,
//! mGal, ppm and hours; the conversion happens here. Every key is documented in
//! docs/CONFIG.md.
//!
//! Nothing here touches the data files: paths are resolved against the config file's
//! directory but not checked, so a config can be loaded (and validated) on a machine
//! without the data.
//!
//! One file per TOML section (`imu.rs`, `gnss.rs`, `zupt.rs`, ...), each holding the
//! section as written (its raw serde struct), its conversion to values and its
//! writing back; `root.rs` lists the sections. Shared pieces: `values.rs` (value
//! shapes), `units.rs`, `validate.rs`, `paths.rs`, `error.rs`, `locate.rs` (TOML
//! error locations), `kfgins.rs` (the KF-GINS YAML translation) and `write.rs`
//! (writing: every key, or only those that differ from what loading fills in).

mod alignment;
mod baro;
mod error;
mod filter;
mod gnss;
mod gnss_text;
mod heading;
mod imu;
mod imu_csv;
mod imu_files;
mod imu_noise;
mod initial;
mod kfgins;
mod locate;
mod nhc;
mod odometer;
mod outages;
mod output;
mod paths;
mod rinex;
mod root;
mod smoother;
mod spoofing;
mod tight;
mod time;
mod time_offset;
mod tuning;
mod ubx;
pub mod units;
mod validate;
mod values;
mod vehicle;
mod write;
mod zupt;

use std::path::{Path, PathBuf};

use navfuse_core::config::NavConfig;
use navfuse_core::outage::Periodic;

pub use crate::input::TuningSpec;
pub use error::ConfigError;
pub use rinex::{DEFAULT_DGPS_MAX_AGE_S, DEFAULT_ELEVATION_MASK_DEG};
pub use write::TomlStyle;

use crate::input::{GnssSource, HeadingSource, ImuSource, OdometerSource, OutputSpec};
use error::KeyErr;
use kfgins::{kfgins_to_raw, toml_to_yaml_key, yaml_error, yaml_line_of, KfProbe, KfYaml};
use kfgins::{KF_NOISE_KEYS, KF_TOP_KEYS};
/// The line of a key and the error of a TOML parse, for other TOML files read the
/// same way (`navfuse batch`'s manifest).
pub use locate::{toml_error, toml_line_of};
use paths::resolve_path;
use root::{convert, convert_inputs, TomlInputs, TomlRoot};

// ---------------------------------------------------------------------------------
// The result

/// Periodic outages given relative to the run start (`gnss.outage_every.from_start_s`)
/// while `[time] start` is not set: resolved by [`RunConfig::resolve_relative_outages`]
/// once the first IMU epoch is known.
#[derive(Clone, Debug, PartialEq)]
pub struct RelativeOutage {
    /// Outage length (s).
    pub length_s: f64,
    /// Period (s).
    pub period_s: f64,
    /// First outage start, seconds after the run start.
    pub from_start_s: f64,
    /// No outage starts at or after this absolute time (s).
    pub until: Option<f64>,
    /// No outage starts at or after run start + this (s).
    pub until_start_s: Option<f64>,
}

impl RelativeOutage {
    pub(super) fn resolve(&self, run_start: f64) -> Periodic {
        Periodic {
            length: self.length_s,
            period: self.period_s,
            from: run_start + self.from_start_s,
            until: self.until.or(self.until_start_s.map(|u| run_start + u)),
        }
    }
}

/// Everything a run needs: what to read, how to navigate, what to write.
#[derive(Clone, Debug, PartialEq)]
pub struct RunConfig {
    /// Navigator settings in SI units. `start_time` is `f64::NEG_INFINITY` when the
    /// config gives no start (= the first IMU epoch).
    pub nav: NavConfig,
    pub imu: ImuSource,
    /// None = pure inertial run (no `[gnss]` section).
    pub gnss: Option<GnssSource>,
    /// Odometer input (`[odometer]`); None = no odometer. Times on the IMU time scale.
    pub odometer: Option<OdometerSource>,
    /// Dual-antenna heading input (`heading.file`); None = none. Times on the GNSS
    /// time scale.
    pub heading: Option<HeadingSource>,
    /// Barometer input (`[baro]`); None = none. Times on the IMU time scale.
    pub baro: Option<crate::baro::BaroSource>,
    pub output: OutputSpec,
    /// Post-processing after the forward run (`[smoother]`).
    pub smoother: crate::input::SmootherSpec,
    /// Noise identification before the run (`[tuning]`).
    pub tuning: crate::input::TuningSpec,
    /// The config file this came from.
    pub source_path: PathBuf,
    /// KF-GINS `outputpath` (resolved against the YAML's directory); the CLI's `--out`
    /// takes precedence. Always None for TOML.
    pub kfgins_output_path: Option<PathBuf>,
    /// Things accepted but worth telling the user (unknown KF-GINS keys, extra vector
    /// elements). Always empty for TOML, where these are errors.
    pub warnings: Vec<String>,
    /// Periodic outages still relative to the run start; empty once resolved.
    pub relative_outages: Vec<RelativeOutage>,
    /// The noise and initial-uncertainty keys the file did not give, which took their
    /// defaults (`imu_noise::DEFAULT_NOISE`, `initial::DEFAULT_INITIAL_STD`): `navfuse
    /// run` warns about them, `navfuse tune` starts them from the data.
    pub defaulted: Vec<&'static str>,
}

impl RunConfig {
    /// Turn the outages given relative to the run start into absolute ones, now that
    /// the run start (the first IMU epoch used) is known. Calling it again is a no-op.
    pub fn resolve_relative_outages(&mut self, run_start: f64) {
        for r in self.relative_outages.drain(..) {
            self.nav.gnss.outages.periodic.push(r.resolve(run_start));
        }
    }

    /// This configuration in navfuse's TOML format, every key written out (defaults
    /// included), values in the units of the file format. Paths are written absolute.
    /// `load_toml` of the result gives back this configuration (exactly, unless a
    /// value has no exact decimal in the file's unit), minus `kfgins_output_path` and
    /// `warnings`. [`RunConfig::to_toml_with`] writes relative paths or leaves out
    /// defaults.
    pub fn to_toml_string(&self) -> String {
        let body = self.to_toml_with(&TomlStyle::default());
        let mut out = format!(
            "# navfuse run configuration (docs/CONFIG.md), written from {}\n",
            self.source_path.display()
        );
        if let Some(p) = &self.kfgins_output_path {
            out.push_str(&format!("# KF-GINS outputpath was {}\n", p.display()));
        }
        out.push('\n');
        out.push_str(&body);
        out
    }
}

// ---------------------------------------------------------------------------------
// Entry points

/// Load a config file, choosing the format by extension: `.toml` (navfuse) or
/// `.yaml` / `.yml` (KF-GINS).
pub fn load(path: &Path) -> Result<RunConfig, ConfigError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => load_toml(path),
        Some("yaml") | Some("yml") => load_kfgins_yaml(path),
        _ => Err(ConfigError::new(
            path,
            None,
            None,
            "unknown config file type: expected a .toml (navfuse) or .yaml/.yml (KF-GINS) file"
                .into(),
        )),
    }
}

fn read_text(path: &Path) -> Result<String, ConfigError> {
    std::fs::read_to_string(path).map_err(|e| {
        let msg = e.to_string();
        let msg = msg.find(" (os error ").map_or(msg.as_str(), |i| &msg[..i]);
        ConfigError::new(path, None, None, format!("cannot read config file: {msg}"))
    })
}

fn base_dir(path: &Path) -> PathBuf {
    path.parent().map(Path::to_path_buf).unwrap_or_default()
}

/// Load navfuse's own TOML format (docs/CONFIG.md). Unknown keys, wrong types, wrong
/// vector lengths and out-of-range values are errors naming the key and line.
pub fn load_toml(path: &Path) -> Result<RunConfig, ConfigError> {
    let text = read_text(path)?;
    parse_toml_str(&text, path)
}

/// [`load_toml`] on text already in memory; `path` names it in errors and relative
/// paths resolve against its directory.
pub fn parse_toml_str(text: &str, path: &Path) -> Result<RunConfig, ConfigError> {
    let raw: TomlRoot = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    let conv = convert(raw, &base_dir(path)).map_err(|e| {
        let line = toml_line_of(text, &e.key);
        ConfigError::new(path, line, Some(e.key), e.msg)
    })?;
    Ok(conv.finish(path, None, Vec::new()))
}

/// The `[imu]` and `[gnss]` sections of a TOML text alone, without the rest of a run
/// configuration (a reader of one file: Python's `navfuse.read_imu("f.txt",
/// format = ...)`), the GNSS one with its options (systems, signals). Keys as in
/// [`load_toml`]; other sections are errors. `path` names
/// the text in errors and relative paths resolve against its directory.
#[allow(clippy::type_complexity)]
pub fn parse_input_sections(
    text: &str,
    path: &Path,
) -> Result<
    (
        Option<ImuSource>,
        Option<(GnssSource, navfuse_core::config::GnssOptions)>,
    ),
    ConfigError,
> {
    let raw: TomlInputs = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    convert_inputs(&raw, &base_dir(path)).map_err(|e| {
        let line = toml_line_of(text, &e.key);
        ConfigError::new(path, line, Some(e.key), e.msg)
    })
}

/// Load an unchanged KF-GINS YAML configuration (KF-GINS README section 4 keys).
/// Unknown keys are accepted, as KF-GINS does, and listed in `warnings`.
pub fn load_kfgins_yaml(path: &Path) -> Result<RunConfig, ConfigError> {
    let text = read_text(path)?;
    parse_kfgins_yaml_str(&text, path)
}

/// [`load_kfgins_yaml`] on text already in memory.
pub fn parse_kfgins_yaml_str(text: &str, path: &Path) -> Result<RunConfig, ConfigError> {
    let opts = serde_saphyr::options! { with_snippet: false };
    let y: KfYaml =
        serde_saphyr::from_str_with_options(text, opts).map_err(|e| yaml_error(path, text, &e))?;
    let mut warnings = Vec::new();
    // Unknown keys: a second, lenient pass over the key names only.
    let probe_opts = serde_saphyr::options! { with_snippet: false };
    if let Ok(p) = serde_saphyr::from_str_with_options::<KfProbe>(text, probe_opts) {
        for k in p.rest.keys() {
            if !KF_TOP_KEYS.contains(&k.as_str()) {
                warnings.push(format!(
                    "unknown KF-GINS key '{k}' ignored (as KF-GINS does)"
                ));
            }
        }
        for k in p.imunoise.unwrap_or_default().keys() {
            if !KF_NOISE_KEYS.contains(&k.as_str()) {
                warnings.push(format!(
                    "unknown KF-GINS key 'imunoise.{k}' ignored (as KF-GINS does)"
                ));
            }
        }
    }
    let err = |e: KeyErr| {
        let key = toml_to_yaml_key(&e.key)
            .map(str::to_string)
            .unwrap_or(e.key);
        let line = yaml_line_of(text, &key);
        ConfigError::new(path, line, Some(key), e.msg)
    };
    let (raw, out_path) = kfgins_to_raw(y, &mut warnings).map_err(err)?;
    let conv = convert(raw, &base_dir(path)).map_err(err)?;
    let kf_out = out_path.map(|p| resolve_path(&base_dir(path), &p));
    Ok(conv.finish(path, kf_out, warnings))
}
