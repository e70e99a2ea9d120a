//! Run configuration: navfuse's own TOML format ([`load_toml`]) and unchanged KF-GINS
//! YAML files ([`load_kfgins_yaml`]), both turned into a [`RunConfig`]: the input and
//! output descriptions plus a [`NavConfig`] in SI units. Users write degrees, deg/h,
//! mGal, ppm and hours; the conversion happens here. Every key is documented in
//! docs/CONFIG.md.
//!
//! Nothing here touches the data files: paths are resolved against the config file's
//! directory but not checked, so a config can be loaded (and validated) on a machine
//! without the data.

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::fmt;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use navfuse_core::config::{
    AttitudeInit, FilterOptions, FixErrorOptions, GnssFusion, GnssOptions, HeadingOptions,
    ImuNoise, InitialState, NavConfig, NhcMode, NhcOptions, OdometerOptions, RangeRate,
    TightOptions, TimeOffsetConfig, VehicleOptions, ZuptOptions, DEFAULT_COVARIANCE_PERIOD_S,
    DEFAULT_FIX_GATE_PROBABILITY, DEFAULT_GATE_TIMEOUT_S,
};
use navfuse_core::integrity::{IntegrityOptions, IntegrityReference};
use navfuse_core::outage::{OutageSchedule, Periodic, Window};
use navfuse_core::types::ImuErrors;
use serde::de::{self, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{check_finite_si, check_scale, SCALE_MAX_SI};
use crate::input::{
    AccelUnit, Coupling, CsvImuOptions, DgpsKind, DgpsSource, GapPolicy, GnssFormat, GnssSource,
    GyroUnit, HeadingSource, ImuFormat, ImuQuantity, ImuSource, OdometerFormat, OdometerSource,
    OutputSpec, RateSampling, RinexGnss, RtklibExplorerImuOptions, TimeScale, TimeUnit,
};

// ---------------------------------------------------------------------------------
// Errors

/// A configuration problem: which file, where, which key, and what was expected.
/// Displayed as `FILE:LINE: key 'K': MESSAGE` (the line and key parts are left out
/// when unknown).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigError {
    pub path: PathBuf,
    /// 1-based line in the config file.
    pub line: Option<usize>,
    /// Dotted key path, e.g. `imu_noise.arw_deg_sqrth` (TOML) or `imunoise.arw` (YAML).
    pub key: Option<String>,
    pub message: String,
}

impl ConfigError {
    fn new(path: &Path, line: Option<usize>, key: Option<String>, message: String) -> Self {
        ConfigError {
            path: path.to_path_buf(),
            line,
            key,
            message,
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        write!(f, ": ")?;
        if let Some(key) = &self.key {
            write!(f, "key '{key}': ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for ConfigError {}

/// For callers that report every bad input the same way (the key becomes the field).
impl From<ConfigError> for crate::error::InputError {
    fn from(e: ConfigError) -> Self {
        crate::error::InputError {
            path: e.path,
            line: e.line,
            field: e.key,
            message: e.message,
        }
    }
}

/// A conversion/validation failure before the line is known.
#[derive(Debug)]
struct KeyErr {
    key: String,
    msg: String,
}

type KResult<T> = Result<T, KeyErr>;

fn kerr(key: &str, msg: impl Into<String>) -> KeyErr {
    KeyErr {
        key: key.to_string(),
        msg: msg.into(),
    }
}

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
    fn resolve(&self, run_start: f64) -> Periodic {
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
    pub output: OutputSpec,
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
    /// `load_toml` of the result gives back this configuration (up to rounding in the
    /// unit conversions), minus `kfgins_output_path` and `warnings`.
    pub fn to_toml_string(&self) -> String {
        let raw = to_raw(self);
        let body =
            toml::to_string(&raw).unwrap_or_else(|e| format!("# serialization failed: {e}\n"));
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

// ---------------------------------------------------------------------------------
// Units

const D2R: f64 = PI / 180.0;

/// deg/sqrt(h) -> rad/sqrt(s)
fn arw_si(x: f64) -> f64 {
    x * D2R / 60.0
}
/// m/s/sqrt(h) -> m/s/sqrt(s)
fn vrw_si(x: f64) -> f64 {
    x / 60.0
}
/// deg/h -> rad/s
fn degph_si(x: f64) -> f64 {
    x * D2R / 3600.0
}
/// mGal -> m/s²
fn mgal_si(x: f64) -> f64 {
    x * 1e-5
}
/// ppm -> 1
fn ppm_si(x: f64) -> f64 {
    x * 1e-6
}

fn map3(v: [f64; 3], f: fn(f64) -> f64) -> [f64; 3] {
    [f(v[0]), f(v[1]), f(v[2])]
}

fn vec3(v: [f64; 3]) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

fn arr3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

// ---------------------------------------------------------------------------------
// Value shapes

/// A number applied to all three axes, or an array of exactly three numbers.
#[derive(Clone, Debug, PartialEq)]
enum Num3 {
    Scalar(f64),
    List(Vec<f64>),
}

impl Num3 {
    fn from3(v: [f64; 3]) -> Self {
        if v[0] == v[1] && v[1] == v[2] {
            Num3::Scalar(v[0])
        } else {
            Num3::List(v.to_vec())
        }
    }
}

impl<'de> Deserialize<'de> for Num3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        deserialize_num_or_list(d, "a number or an array of 3 numbers")
    }
}

/// A number or an array of numbers; `expecting` names the shape in type errors.
fn deserialize_num_or_list<'de, D: Deserializer<'de>>(
    d: D,
    expecting: &'static str,
) -> Result<Num3, D::Error> {
    struct V(&'static str);
    impl<'de> Visitor<'de> for V {
        type Value = Num3;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(self.0)
        }
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num3, E> {
            Ok(Num3::Scalar(v))
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num3, E> {
            Ok(Num3::Scalar(v as f64))
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num3, E> {
            Ok(Num3::Scalar(v as f64))
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Num3, A::Error> {
            let mut v = Vec::new();
            while let Some(x) = seq.next_element::<f64>()? {
                v.push(x);
            }
            Ok(Num3::List(v))
        }
    }
    d.deserialize_any(V(expecting))
}

impl Serialize for Num3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Num3::Scalar(x) => s.serialize_f64(*x),
            Num3::List(v) => v.serialize(s),
        }
    }
}

/// A number applied to both elements, or an array of exactly two numbers
/// (`nhc.std_mps`: lateral, vertical).
#[derive(Clone, Debug, PartialEq)]
struct Num2(Num3);

impl Num2 {
    fn from2(v: [f64; 2]) -> Self {
        if v[0] == v[1] {
            Num2(Num3::Scalar(v[0]))
        } else {
            Num2(Num3::List(v.to_vec()))
        }
    }
}

impl<'de> Deserialize<'de> for Num2 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        deserialize_num_or_list(d, "a number or an array of 2 numbers").map(Num2)
    }
}

impl Serialize for Num2 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

/// An innovation-test probability, or `false` for no test.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Gate {
    Probability(f64),
    Off,
}

impl<'de> Deserialize<'de> for Gate {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Gate;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a probability (e.g. 1e-4) or false (no innovation test)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Gate, E> {
                Ok(Gate::Probability(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Gate, E> {
                Ok(Gate::Probability(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Gate, E> {
                Ok(Gate::Probability(v as f64))
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Gate, E> {
                if v {
                    Err(E::custom(
                        "expected a probability (e.g. 1e-4) or false (no innovation test), got true",
                    ))
                } else {
                    Ok(Gate::Off)
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Gate {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Gate::Probability(p) => s.serialize_f64(*p),
            Gate::Off => s.serialize_bool(false),
        }
    }
}

impl Gate {
    fn from_option(p: Option<f64>) -> Self {
        p.map_or(Gate::Off, Gate::Probability)
    }
}

/// One table or an array of tables.
#[derive(Clone, Debug, PartialEq)]
struct OneOrMany<T>(Vec<T>);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for OneOrMany<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = OneOrMany<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a table or an array of tables")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
                T::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|t| OneOrMany(vec![t]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = seq.next_element::<T>()? {
                    v.push(x);
                }
                Ok(OneOrMany(v))
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}

impl<T: Serialize> Serialize for OneOrMany<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.len() == 1 {
            self.0[0].serialize(s)
        } else {
            let mut seq = s.serialize_seq(Some(self.0.len()))?;
            for x in &self.0 {
                seq.serialize_element(x)?;
            }
            seq.end()
        }
    }
}

// ---------------------------------------------------------------------------------
// navfuse TOML, as written (user units)

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TomlRoot {
    imu: TImu,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gnss: Option<TGnss>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    odometer: Option<TOdometer>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    heading: Option<THeading>,
    #[serde(default, skip_serializing_if = "TTime::is_empty")]
    time: TTime,
    initial: TInitial,
    imu_noise: TNoise,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vehicle: Option<TVehicle>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    nhc: Option<TNhc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    zupt: Option<TZupt>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    spoofing: Option<TSpoofing>,
    #[serde(default)]
    filter: TFilter,
    #[serde(default)]
    output: TOutput,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
enum TImuFormat {
    #[serde(rename = "kf-gins")]
    KfGins,
    #[serde(rename = "csv")]
    Csv,
    #[serde(rename = "rtklibexplorer")]
    RtklibExplorer,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TImu {
    file: String,
    format: TImuFormat,
    rate_hz: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sensor_to_body_rpy_deg: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    time_offset_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tag_file: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gap_policy: Option<TGapPolicy>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_bridge_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    csv: Option<TCsv>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
enum TGapPolicy {
    #[serde(rename = "bridge")]
    Bridge,
    #[serde(rename = "nominal")]
    Nominal,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
enum TTimeUnit {
    #[serde(rename = "s")]
    S,
    #[serde(rename = "ms")]
    Ms,
    #[serde(rename = "us")]
    Us,
    #[serde(rename = "ns")]
    Ns,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
enum TTimeScale {
    #[serde(rename = "gps_sow")]
    GpsSow,
    #[serde(rename = "gpst_unix")]
    GpstUnix,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
enum TQuantity {
    #[serde(rename = "rate")]
    Rate,
    #[serde(rename = "increment")]
    Increment,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
enum TSampling {
    #[serde(rename = "instant")]
    Instant,
    #[serde(rename = "interval_mean")]
    IntervalMean,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
enum TGyroUnit {
    #[serde(rename = "rad")]
    Rad,
    #[serde(rename = "deg")]
    Deg,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
enum TAccelUnit {
    #[serde(rename = "m")]
    M,
    #[serde(rename = "g")]
    G,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TCsv {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    skip_lines: Option<usize>,
    time_col: usize,
    gyro_cols: Vec<usize>,
    accel_cols: Vec<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    time_unit: Option<TTimeUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    time_scale: Option<TTimeScale>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    quantity: Option<TQuantity>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rate_sampling: Option<TSampling>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_unit: Option<TGyroUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    accel_unit: Option<TAccelUnit>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
enum TGnssFormat {
    #[serde(rename = "kf-gins")]
    KfGins,
    #[serde(rename = "rtklib-pos")]
    RtklibPos,
    #[serde(rename = "rinex")]
    Rinex,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum TCoupling {
    Loose,
    Tight,
}

/// `spoofing.reference` (core::integrity::IntegrityReference).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum TReference {
    Prediction,
    DeadReckoning,
}

/// `gnss.fusion` (core::config::GnssFusion).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum TFusion {
    ErrorState,
    SixState,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum TRangeRate {
    None,
    Doppler,
    Tdcp,
}

/// `[gnss.tight]`: tight-coupling tuning (core::config::TightOptions).
#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TTight {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    use_pseudorange: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_probability: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    clock_bias_psd_sqrt: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    clock_drift_psd_sqrt: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    clock_reset_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    slip_sigma: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    slip_min_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tdcp_max_gap_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pseudorange_sigma_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    range_rate_sigma_scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pseudorange_sigma_floor_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    range_rate_sigma_floor_mps: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TGnss {
    file: String,
    format: TGnssFormat,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    nav: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    coupling: Option<TCoupling>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    range_rate: Option<TRangeRate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    elevation_mask_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fde: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dgps: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dgps_corrections: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dgps_reference_obs: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dgps_reference_position_deg_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dgps_max_age_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tight: Option<TTight>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    quality: Option<Vec<u8>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    decimate_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    time_offset_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lever_arm_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    use_velocity: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    position_std_m: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    velocity_std_mps: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_timeout_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    error_corr_time_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    error_corr_fraction: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scale_window: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    robust_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    readmit_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    floor_accel_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    outages: Option<Vec<Vec<f64>>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    outage_every: Option<OneOrMany<TOutageEvery>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fusion: Option<TFusion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    six_state_every: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TOutageEvery {
    length_s: f64,
    period_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    from: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    from_start_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    until: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    until_start_s: Option<f64>,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TTime {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    start: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end: Option<f64>,
}

impl TTime {
    fn is_empty(&self) -> bool {
        self.start.is_none() && self.end.is_none()
    }
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TInitial {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    position_deg_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    velocity_mps: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    attitude_deg: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    alignment: Option<TAlignment>,
    position_std_m: Num3,
    velocity_std_mps: Num3,
    attitude_std_deg: Num3,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_bias_degph: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    accel_bias_mgal: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_scale_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    accel_scale_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_bias_std_degph: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    accel_bias_std_mgal: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_scale_std_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    accel_scale_std_ppm: Option<Num3>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
enum TAlignMode {
    #[serde(rename = "level_and_course")]
    LevelAndCourse,
    #[serde(rename = "static_gyrocompass")]
    StaticGyrocompass,
    #[serde(rename = "in_motion")]
    InMotion,
    #[serde(rename = "auto")]
    Auto,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TAlignment {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mode: Option<TAlignMode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    level_window_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyrocompass: Option<bool>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TVehicle {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mounting_rpy_deg: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lever_arm_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mounting_std_deg: Option<f64>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
enum TNhcMode {
    #[serde(rename = "off")]
    Off,
    #[serde(rename = "always")]
    Always,
    #[serde(rename = "outage")]
    Outage,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TNhc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mode: Option<TNhcMode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std_mps: Option<Num2>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    outage_after_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min_speed_mps: Option<f64>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
enum TOdoFormat {
    #[serde(rename = "speed")]
    Speed,
    #[serde(rename = "pulses")]
    Pulses,
    #[serde(rename = "navfuse")]
    Navfuse,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TOdometer {
    file: String,
    format: TOdoFormat,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    meters_per_pulse: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    speed_is_mean: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scale_ppm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scale_std_ppm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scale_random_walk_ppm_per_sqrth: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    with_nhc: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std_speed_fraction: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    calibration_min_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_probability: Option<Gate>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct THeading {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    file: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    baseline_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    course_over_ground: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    course_min_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    course_std_floor_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_probability: Option<Gate>,
}

/// `[spoofing]`: the GNSS integrity monitor (navfuse_core::integrity).
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TSpoofing {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    enabled: Option<bool>,
    /// R [m] or false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    distance_m: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    chi2_probability: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    window_epochs: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    window_probability: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    confirm_epochs: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    readmit_s: Option<f64>,
    /// Seconds or false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_refuse_s: Option<Gate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    readmit_drift_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gnss_corr_time_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reference: Option<TReference>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TZupt {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    enabled: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    window_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    accel_std_max_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_max_dps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    velocity_std_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    angular_rate_std_dps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    odometer_still_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_accel_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gate_probability: Option<Gate>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TNoise {
    arw_deg_sqrth: Num3,
    vrw_mps_sqrth: Num3,
    gyro_bias_std_degph: Num3,
    accel_bias_std_mgal: Num3,
    gyro_scale_std_ppm: Num3,
    accel_scale_std_ppm: Num3,
    corr_time_h: f64,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TFilter {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    covariance_period_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    time_offset: Option<TTimeOffset>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gap_accel_mps2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gap_rate_dps: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TTimeOffset {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    estimate: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    initial_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    random_walk: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    initial_rate_ppm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rate_std_ppm: Option<f64>,
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TOutput {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rate_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    imu_err: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    std: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    csv: Option<bool>,
}

// ---------------------------------------------------------------------------------
// Validation helpers

fn finite(key: &str, v: f64) -> KResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(kerr(key, format!("expected a finite number, got {v}")))
    }
}

/// A std, variance, rate, scale or duration: > 0, square finite and non-zero
/// (`check_scale`).
fn positive(key: &str, v: f64) -> KResult<f64> {
    positive_si(key, v, v)
}

/// `v` (file units) that is `si` in SI units, checked as [`positive`] after conversion.
fn positive_si(key: &str, v: f64, si: f64) -> KResult<f64> {
    check_scale("the value", v, si).map_err(|m| kerr(key, format!("expected a number > 0: {m}")))
}

/// The SI values of a 3-vector std (`std3`), each checked after conversion.
fn std3_si(key: &str, v: [f64; 3], to_si: fn(f64) -> f64) -> KResult<Vector3<f64>> {
    let mut out = [0.0; 3];
    for (i, (o, x)) in out.iter_mut().zip(v).enumerate() {
        *o = check_scale("a standard deviation", x, to_si(x))
            .map_err(|m| kerr(key, format!("element {i}: {m}")))?;
    }
    Ok(vec3(out))
}

fn non_negative(key: &str, v: f64) -> KResult<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(kerr(key, format!("expected a number >= 0, got {v}")))
    }
}

/// Exactly three finite numbers.
fn v3(key: &str, v: &[f64]) -> KResult<[f64; 3]> {
    if v.len() != 3 {
        return Err(kerr(
            key,
            format!("expected an array of 3 numbers, got {} element(s)", v.len()),
        ));
    }
    for (i, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(kerr(
                key,
                format!("element {i}: expected a finite number, got {x}"),
            ));
        }
    }
    Ok([v[0], v[1], v[2]])
}

fn n3(key: &str, v: &Num3) -> KResult<[f64; 3]> {
    match v {
        Num3::Scalar(x) => Ok([finite(key, *x)?; 3]),
        Num3::List(l) => v3(key, l),
    }
}

/// A std: scalar or 3-vector, every element > 0 with a finite non-zero square
/// (`check_scale`; [`std3_si`] checks again after conversion).
fn std3(key: &str, v: &Num3) -> KResult<[f64; 3]> {
    let a = n3(key, v)?;
    for (i, x) in a.iter().enumerate() {
        if let Err(m) = check_scale("a standard deviation", *x, *x) {
            let what = if matches!(v, Num3::Scalar(_)) {
                String::new()
            } else {
                format!("element {i}: ")
            };
            return Err(kerr(key, format!("{what}{m}")));
        }
    }
    Ok(a)
}

fn resolve_path(base: &Path, s: &str) -> PathBuf {
    let p = PathBuf::from(s);
    if p.is_absolute() {
        p
    } else {
        base.join(p)
    }
}

fn file_key(base: &Path, key: &str, s: &str) -> KResult<PathBuf> {
    if s.trim().is_empty() {
        return Err(kerr(key, "expected a file path, got an empty string"));
    }
    Ok(resolve_path(base, s))
}

// ---------------------------------------------------------------------------------
// Conversion: user units -> RunConfig

struct Converted {
    nav: NavConfig,
    imu: ImuSource,
    gnss: Option<GnssSource>,
    odometer: Option<OdometerSource>,
    heading: Option<HeadingSource>,
    output: OutputSpec,
    relative_outages: Vec<RelativeOutage>,
}

impl Converted {
    fn finish(self, path: &Path, kf_out: Option<PathBuf>, warnings: Vec<String>) -> RunConfig {
        RunConfig {
            nav: self.nav,
            imu: self.imu,
            gnss: self.gnss,
            odometer: self.odometer,
            heading: self.heading,
            output: self.output,
            source_path: path.to_path_buf(),
            kfgins_output_path: kf_out,
            warnings,
            relative_outages: self.relative_outages,
        }
    }
}

fn convert(raw: TomlRoot, base: &Path) -> KResult<Converted> {
    // [time]
    let start = raw
        .time
        .start
        .map(|t| finite("time.start", t))
        .transpose()?;
    let end = raw.time.end.map(|t| finite("time.end", t)).transpose()?;
    if let (Some(s), Some(e)) = (start, end) {
        if e <= s {
            return Err(kerr(
                "time.end",
                format!("expected a time after time.start = {s}, got {e}"),
            ));
        }
    }

    let imu = convert_imu(&raw.imu, base)?;
    let (gnss, gnss_opts, relative_outages, tight) = match &raw.gnss {
        Some(g) => {
            let (src, opts, rel, tight) = convert_gnss(g, base, start)?;
            (Some(src), opts, rel, tight)
        }
        None => (
            None,
            GnssOptions {
                lever_arm_b: Vector3::zeros(),
                use_velocity: true,
                position_std_override: None,
                velocity_std_override: None,
                gate_probability: None,
                gate_timeout_s: DEFAULT_GATE_TIMEOUT_S,
                outages: OutageSchedule::default(),
                fusion: GnssFusion::ErrorState,
                fix_error: FixErrorOptions::default(),
            },
            Vec::new(),
            TightOptions::default(),
        ),
    };

    // [imu_noise]
    let n = &raw.imu_noise;
    let arw = std3("imu_noise.arw_deg_sqrth", &n.arw_deg_sqrth)?;
    let vrw = std3("imu_noise.vrw_mps_sqrth", &n.vrw_mps_sqrth)?;
    let gb = std3("imu_noise.gyro_bias_std_degph", &n.gyro_bias_std_degph)?;
    let ab = std3("imu_noise.accel_bias_std_mgal", &n.accel_bias_std_mgal)?;
    let gs = std3("imu_noise.gyro_scale_std_ppm", &n.gyro_scale_std_ppm)?;
    let as_ = std3("imu_noise.accel_scale_std_ppm", &n.accel_scale_std_ppm)?;
    let corr_time_s = positive_si(
        "imu_noise.corr_time_h",
        n.corr_time_h,
        n.corr_time_h * 3600.0,
    )?;
    let imu_noise = ImuNoise {
        arw: std3_si("imu_noise.arw_deg_sqrth", arw, arw_si)?,
        vrw: std3_si("imu_noise.vrw_mps_sqrth", vrw, vrw_si)?,
        gyro_bias_std: std3_si("imu_noise.gyro_bias_std_degph", gb, degph_si)?,
        accel_bias_std: std3_si("imu_noise.accel_bias_std_mgal", ab, mgal_si)?,
        gyro_scale_std: std3_si("imu_noise.gyro_scale_std_ppm", gs, ppm_si)?,
        accel_scale_std: std3_si("imu_noise.accel_scale_std_ppm", as_, ppm_si)?,
        corr_time_s,
    };

    // [initial]
    let i = &raw.initial;
    let pos = match &i.position_deg_m {
        Some(p) => Some(v3("initial.position_deg_m", p)?),
        None => None,
    };
    if let Some(pos) = pos {
        if !(-90.0..=90.0).contains(&pos[0]) {
            return Err(kerr(
                "initial.position_deg_m",
                format!(
                    "latitude (element 0) must be in [-90, 90] deg, got {}",
                    pos[0]
                ),
            ));
        }
        if !(-180.0..=360.0).contains(&pos[1]) {
            return Err(kerr(
                "initial.position_deg_m",
                format!(
                    "longitude (element 1) must be in [-180, 360] deg, got {}",
                    pos[1]
                ),
            ));
        }
    }
    let vel = match &i.velocity_mps {
        Some(v) => v3("initial.velocity_mps", v)?,
        None => [0.0; 3],
    };
    let attitude = match (&i.attitude_deg, &i.alignment) {
        (Some(_), Some(_)) => {
            return Err(kerr(
                "initial.alignment",
                "give either initial.attitude_deg or [initial.alignment], not both",
            ))
        }
        // No attitude in the config: found from the data (static or in motion).
        (None, None) => AttitudeInit::Auto {
            level_window_s: DEFAULT_LEVEL_WINDOW_S,
            min_speed_mps: DEFAULT_ALIGN_MIN_SPEED_MPS,
            gyrocompass: false,
        },
        (None, Some(al)) => convert_alignment(al)?,
        (Some(att), None) => {
            let att = v3("initial.attitude_deg", att)?;
            if let Some(a) = att.iter().find(|a| a.abs() > 360.0) {
                return Err(kerr(
                    "initial.attitude_deg",
                    format!("expected angles within [-360, 360] deg, got {a}"),
                ));
            }
            if !(-90.0..=90.0).contains(&att[1]) {
                return Err(kerr(
                    "initial.attitude_deg",
                    format!("pitch (element 1) must be in [-90, 90] deg, got {}", att[1]),
                ));
            }
            AttitudeInit::Given(vec3(map3(att, |x| x * D2R)))
        }
    };
    // Initial IMU errors: finite, and bounded so that they convert back and forth.
    let opt3 = |key: &str, v: &Option<Num3>| -> KResult<[f64; 3]> {
        let a = match v {
            Some(v) => n3(key, v)?,
            None => [0.0; 3],
        };
        match a.iter().find(|x| x.abs() > SCALE_MAX_SI) {
            Some(x) => Err(kerr(key, format!("expected |value| <= 1e150, got {x}"))),
            None => Ok(a),
        }
    };
    let imu_errors = ImuErrors {
        gyro_bias: vec3(map3(
            opt3("initial.gyro_bias_degph", &i.gyro_bias_degph)?,
            degph_si,
        )),
        accel_bias: vec3(map3(
            opt3("initial.accel_bias_mgal", &i.accel_bias_mgal)?,
            mgal_si,
        )),
        gyro_scale: vec3(map3(
            opt3("initial.gyro_scale_ppm", &i.gyro_scale_ppm)?,
            ppm_si,
        )),
        accel_scale: vec3(map3(
            opt3("initial.accel_scale_ppm", &i.accel_scale_ppm)?,
            ppm_si,
        )),
    };
    let std_or = |key: &str, v: &Option<Num3>, default: [f64; 3]| -> KResult<[f64; 3]> {
        match v {
            Some(v) => std3(key, v),
            None => Ok(default),
        }
    };
    let std_or_si = |key: &str, v: &Option<Num3>, default: [f64; 3], to_si| {
        std3_si(key, std_or(key, v, default)?, to_si)
    };
    let imu_errors_std = ImuErrors {
        gyro_bias: std_or_si(
            "initial.gyro_bias_std_degph",
            &i.gyro_bias_std_degph,
            gb,
            degph_si,
        )?,
        accel_bias: std_or_si(
            "initial.accel_bias_std_mgal",
            &i.accel_bias_std_mgal,
            ab,
            mgal_si,
        )?,
        gyro_scale: std_or_si(
            "initial.gyro_scale_std_ppm",
            &i.gyro_scale_std_ppm,
            gs,
            ppm_si,
        )?,
        accel_scale: std_or_si(
            "initial.accel_scale_std_ppm",
            &i.accel_scale_std_ppm,
            as_,
            ppm_si,
        )?,
    };
    let initial = InitialState {
        lla: pos.map(|pos| Vector3::new(pos[0] * D2R, pos[1] * D2R, pos[2])),
        v_n: vec3(vel),
        attitude,
        imu_errors,
        pos_std: std3_si(
            "initial.position_std_m",
            std3("initial.position_std_m", &i.position_std_m)?,
            same,
        )?,
        vel_std: std3_si(
            "initial.velocity_std_mps",
            std3("initial.velocity_std_mps", &i.velocity_std_mps)?,
            same,
        )?,
        att_std: std3_si(
            "initial.attitude_std_deg",
            std3("initial.attitude_std_deg", &i.attitude_std_deg)?,
            deg_si,
        )?,
        imu_errors_std,
    };

    // [filter]
    let f = &raw.filter;
    let covariance_period_s = non_negative(
        "filter.covariance_period_s",
        f.covariance_period_s.unwrap_or(DEFAULT_COVARIANCE_PERIOD_S),
    )?;
    let time_offset = match &f.time_offset {
        None => None,
        Some(t) => {
            let initial_s = finite("filter.time_offset.initial_s", t.initial_s.unwrap_or(0.0))?;
            let std_s = positive("filter.time_offset.std_s", t.std_s.unwrap_or(0.5))?;
            let random_walk = non_negative(
                "filter.time_offset.random_walk",
                t.random_walk.unwrap_or(0.0),
            )?;
            // A clock-rate difference of a million ppm (the clocks' rates differ by a
            // factor of 2) is no time offset any more: bounded, so that writing it
            // back in ppm stays finite.
            let ppm = |key: &str, v: f64| -> KResult<f64> {
                if v.abs() <= MAX_RATE_PPM {
                    Ok(v)
                } else {
                    Err(kerr(
                        key,
                        format!("expected at most {MAX_RATE_PPM:e} ppm in magnitude, got {v:e}"),
                    ))
                }
            };
            let initial_rate = ppm(
                "filter.time_offset.initial_rate_ppm",
                finite(
                    "filter.time_offset.initial_rate_ppm",
                    t.initial_rate_ppm.unwrap_or(0.0),
                )?,
            )? * 1e-6;
            let rate_std = ppm(
                "filter.time_offset.rate_std_ppm",
                non_negative(
                    "filter.time_offset.rate_std_ppm",
                    t.rate_std_ppm.unwrap_or(0.0),
                )?,
            )? * 1e-6;
            Some(TimeOffsetConfig {
                initial_s,
                std_s: if t.estimate.unwrap_or(true) {
                    std_s
                } else {
                    0.0
                },
                random_walk,
                initial_rate,
                rate_std: if t.estimate.unwrap_or(true) {
                    rate_std
                } else {
                    0.0
                },
            })
        }
    };

    // [output]
    let o = &raw.output;
    let output = OutputSpec {
        rate_hz: o
            .rate_hz
            .map(|r| positive("output.rate_hz", r))
            .transpose()?,
        imu_err: o.imu_err.unwrap_or(true),
        std: o.std.unwrap_or(true),
        csv: o.csv.unwrap_or(false),
    };

    let vehicle = match &raw.vehicle {
        Some(v) => convert_vehicle(v)?,
        None => VehicleOptions::default(),
    };
    let nhc = match &raw.nhc {
        Some(n) => convert_nhc(n)?,
        None => NhcOptions::default(),
    };
    let (odometer_src, odometer) = match &raw.odometer {
        Some(o) => {
            let (src, opts) = convert_odometer(o, base)?;
            (Some(src), opts)
        }
        None => (None, OdometerOptions::default()),
    };
    let (heading_src, heading) = match &raw.heading {
        Some(h) => convert_heading(h, base)?,
        None => (None, HeadingOptions::default()),
    };
    let integrity = match &raw.spoofing {
        Some(x) => convert_spoofing(x)?,
        None => IntegrityOptions::default(),
    };
    let zupt = match &raw.zupt {
        Some(z) => convert_zupt(z)?,
        None => ZuptOptions::default(),
    };

    if integrity.enabled
        && integrity.reference == IntegrityReference::DeadReckoning
        && !matches!(gnss_opts.fusion, GnssFusion::SixState { .. })
    {
        return Err(kerr(
            "spoofing.reference",
            "\"dead_reckoning\" needs gnss.fusion = \"six_state\" (only that fusion keeps a dead reckoning that GNSS does not correct); use \"prediction\"".to_string(),
        ));
    }
    let nav = NavConfig {
        imu_noise,
        tight,
        integrity,
        initial,
        gnss: gnss_opts,
        filter: FilterOptions {
            covariance_period_s,
            time_offset,
            gap_accel_mps2: opt_or(
                "filter.gap_accel_mps2",
                f.gap_accel_mps2,
                non_negative,
                same,
                FilterOptions::default().gap_accel_mps2,
            )?,
            gap_rate: opt_or(
                "filter.gap_rate_dps",
                f.gap_rate_dps,
                non_negative,
                deg_si,
                FilterOptions::default().gap_rate,
            )?,
        },
        vehicle,
        nhc,
        odometer,
        heading,
        zupt,
        start_time: start.unwrap_or(f64::NEG_INFINITY),
        end_time: end,
    };
    Ok(Converted {
        nav,
        imu,
        gnss,
        odometer: odometer_src,
        heading: heading_src,
        output,
        relative_outages,
    })
}

/// Default `initial.alignment.level_window_s` [s].
const DEFAULT_LEVEL_WINDOW_S: f64 = 10.0;
/// Default `initial.alignment.min_speed_mps` [m/s].
const DEFAULT_ALIGN_MIN_SPEED_MPS: f64 = 3.0;
/// An innovation-test key of the vehicle and heading aiding: a probability in
/// [1e-15, 0.5), `false` (None, no test), or absent (`default`).
fn gate(key: &str, g: Option<Gate>, default: Option<f64>) -> KResult<Option<f64>> {
    match g {
        None => Ok(default),
        Some(Gate::Off) => Ok(None),
        Some(Gate::Probability(p)) => probability(key, p)
            .map(Some)
            .map_err(|_| {
                kerr(
                    key,
                    format!("expected a probability in [1e-15, 0.5), e.g. 1e-4, or false for no test, got {p}"),
                )
            }),
    }
}

/// An optional value checked by `check`, or the default (SI) when absent.
fn opt_or(
    key: &str,
    v: Option<f64>,
    check: fn(&str, f64) -> KResult<f64>,
    to_si: fn(f64) -> f64,
    default: f64,
) -> KResult<f64> {
    match v {
        Some(x) => {
            let si = to_si(check(key, x)?);
            check_finite_si(x, si).map_err(|m| kerr(key, m))?;
            // The same check on the SI value (a positive std must stay a usable one).
            check(key, si).map_err(|e| {
                kerr(
                    key,
                    format!("{x} is {si:e} in SI units, out of range: {}", e.msg),
                )
            })
        }
        None => Ok(default),
    }
}

fn same(x: f64) -> f64 {
    x
}

fn deg_si(x: f64) -> f64 {
    x * D2R
}

/// A std: > 0.
fn std_pos(key: &str, v: f64) -> KResult<f64> {
    check_scale("a standard deviation", v, v).map_err(|m| kerr(key, m))
}

fn convert_alignment(al: &TAlignment) -> KResult<AttitudeInit> {
    let mode = al.mode.unwrap_or(TAlignMode::LevelAndCourse);
    let mode_name = match mode {
        TAlignMode::LevelAndCourse => "level_and_course",
        TAlignMode::StaticGyrocompass => "static_gyrocompass",
        TAlignMode::InMotion => "in_motion",
        TAlignMode::Auto => "auto",
    };
    if mode == TAlignMode::InMotion && al.level_window_s.is_some() {
        return Err(kerr(
            "initial.alignment.level_window_s",
            "does not apply to mode = \"in_motion\" (no static levelling window)",
        ));
    }
    if mode == TAlignMode::StaticGyrocompass && al.min_speed_mps.is_some() {
        return Err(kerr(
            "initial.alignment.min_speed_mps",
            "does not apply to mode = \"static_gyrocompass\" (the yaw does not come from a GNSS course)",
        ));
    }
    if mode != TAlignMode::Auto && al.gyrocompass.is_some() {
        return Err(kerr(
            "initial.alignment.gyrocompass",
            format!("applies only to mode = \"auto\", not \"{mode_name}\""),
        ));
    }
    let level_window_s = al.level_window_s.unwrap_or(DEFAULT_LEVEL_WINDOW_S);
    let min_speed_mps = al.min_speed_mps.unwrap_or(DEFAULT_ALIGN_MIN_SPEED_MPS);
    if !(level_window_s > 0.0 && level_window_s.is_finite()) {
        return Err(kerr(
            "initial.alignment.level_window_s",
            format!("must be > 0 s, got {level_window_s}"),
        ));
    }
    if !(min_speed_mps > 0.0 && min_speed_mps.is_finite()) {
        return Err(kerr(
            "initial.alignment.min_speed_mps",
            format!("must be > 0 m/s, got {min_speed_mps}"),
        ));
    }
    Ok(match mode {
        TAlignMode::LevelAndCourse => AttitudeInit::LevelAndGnssCourse {
            level_window_s,
            min_speed_mps,
        },
        TAlignMode::StaticGyrocompass => AttitudeInit::StaticGyrocompass { level_window_s },
        TAlignMode::InMotion => AttitudeInit::InMotion { min_speed_mps },
        TAlignMode::Auto => AttitudeInit::Auto {
            level_window_s,
            min_speed_mps,
            gyrocompass: al.gyrocompass.unwrap_or(false),
        },
    })
}

fn convert_vehicle(v: &TVehicle) -> KResult<VehicleOptions> {
    let d = VehicleOptions::default();
    let mounting_rpy = match &v.mounting_rpy_deg {
        Some(m) => {
            let m = v3("vehicle.mounting_rpy_deg", m)?;
            if !(-90.0..=90.0).contains(&m[1]) {
                return Err(kerr(
                    "vehicle.mounting_rpy_deg",
                    format!("pitch (element 1) must be in [-90, 90] deg, got {}", m[1]),
                ));
            }
            vec3(map3(m, deg_si))
        }
        None => d.mounting_rpy,
    };
    let lever_arm_b = match &v.lever_arm_m {
        Some(l) => vec3(v3("vehicle.lever_arm_m", l)?),
        None => d.lever_arm_b,
    };
    let mounting_std = opt_or(
        "vehicle.mounting_std_deg",
        v.mounting_std_deg,
        non_negative,
        deg_si,
        d.mounting_std,
    )?;
    Ok(VehicleOptions {
        mounting_rpy,
        lever_arm_b,
        mounting_std,
    })
}

fn convert_nhc(n: &TNhc) -> KResult<NhcOptions> {
    let d = NhcOptions::default();
    let mode = match n.mode {
        None => d.mode,
        Some(TNhcMode::Off) => NhcMode::Off,
        Some(TNhcMode::Always) => NhcMode::Always,
        Some(TNhcMode::Outage) => NhcMode::DuringOutage,
    };
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
        rate_hz: opt_or("nhc.rate_hz", n.rate_hz, positive, same, d.rate_hz)?,
        outage_after_s: opt_or(
            "nhc.outage_after_s",
            n.outage_after_s,
            non_negative,
            same,
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
            same,
            d.min_speed_mps,
        )?,
    })
}

fn convert_odometer(o: &TOdometer, base: &Path) -> KResult<(OdometerSource, OdometerOptions)> {
    let d = OdometerOptions::default();
    let path = file_key(base, "odometer.file", &o.file)?;
    let format = match o.format {
        TOdoFormat::Speed => {
            if o.meters_per_pulse.is_some() {
                return Err(kerr(
                    "odometer.meters_per_pulse",
                    "applies only to odometer.format = \"pulses\" or \"navfuse\"",
                ));
            }
            OdometerFormat::Speed {
                speed_is_mean: o.speed_is_mean.unwrap_or(true),
            }
        }
        TOdoFormat::Pulses | TOdoFormat::Navfuse => {
            if o.speed_is_mean.is_some() {
                return Err(kerr(
                    "odometer.speed_is_mean",
                    "applies only to odometer.format = \"speed\" (pulse counts always give the mean speed over the interval)",
                ));
            }
            let k = o.meters_per_pulse.ok_or_else(|| {
                kerr(
                    "odometer.meters_per_pulse",
                    "missing: the distance per pulse [m] is required for pulse counts",
                )
            })?;
            let meters_per_pulse = positive("odometer.meters_per_pulse", k)?;
            if o.format == TOdoFormat::Pulses {
                OdometerFormat::Pulses { meters_per_pulse }
            } else {
                OdometerFormat::Navfuse { meters_per_pulse }
            }
        }
    };
    let ppm_finite = |key: &str, v: Option<f64>, default: f64| -> KResult<f64> {
        opt_or(key, v, finite, ppm_si, default)
    };
    let opts = OdometerOptions {
        enabled: true,
        std_mps: opt_or("odometer.std_mps", o.std_mps, std_pos, same, d.std_mps)?,
        scale_initial: ppm_finite("odometer.scale_ppm", o.scale_ppm, d.scale_initial)?,
        scale_std: opt_or(
            "odometer.scale_std_ppm",
            o.scale_std_ppm,
            non_negative,
            ppm_si,
            d.scale_std,
        )?,
        scale_random_walk: opt_or(
            "odometer.scale_random_walk_ppm_per_sqrth",
            o.scale_random_walk_ppm_per_sqrth,
            non_negative,
            ppm_sqrth_psd,
            d.scale_random_walk,
        )?,
        with_nhc: o.with_nhc.unwrap_or(d.with_nhc),
        std_speed_fraction: opt_or(
            "odometer.std_speed_fraction",
            o.std_speed_fraction,
            non_negative,
            same,
            d.std_speed_fraction,
        )?,
        calibration_min_speed_mps: opt_or(
            "odometer.calibration_min_speed_mps",
            o.calibration_min_speed_mps,
            non_negative,
            same,
            d.calibration_min_speed_mps,
        )?,
        gate_probability: gate(
            "odometer.gate_probability",
            o.gate_probability,
            d.gate_probability,
        )?,
    };
    Ok((OdometerSource { path, format }, opts))
}

/// Random walk in ppm/sqrt(h) -> PSD [1/s]: after T hours the std is q sqrt(T) ppm.
fn ppm_sqrth_psd(q: f64) -> f64 {
    (q * 1e-6).powi(2) / 3600.0
}

fn psd_ppm_sqrth(psd: f64) -> f64 {
    (psd * 3600.0).sqrt() * 1e6
}

fn convert_heading(h: &THeading, base: &Path) -> KResult<(Option<HeadingSource>, HeadingOptions)> {
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
                    check_scale("a standard deviation", s, deg_si(s))
                        .map_err(|m| kerr("heading.std_deg", m))
                })
                .transpose()?;
            (Some(HeadingSource { path }), Some(vec3(b)), std_override)
        }
        None => {
            for (key, given) in [
                ("heading.baseline_m", h.baseline_m.is_some()),
                ("heading.std_deg", h.std_deg.is_some()),
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
            same,
            d.course_min_speed_mps,
        )?,
        course_std_floor: opt_or(
            "heading.course_std_floor_deg",
            h.course_std_floor_deg,
            std_pos,
            deg_si,
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

fn convert_spoofing(x: &TSpoofing) -> KResult<IntegrityOptions> {
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
        same,
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
            same,
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
            same,
            d.readmit_drift_mps,
        )?,
        gnss_corr_time_s: opt_or(
            "spoofing.gnss_corr_time_s",
            x.gnss_corr_time_s,
            non_negative,
            same,
            d.gnss_corr_time_s,
        )?,
        reference: match x.reference {
            None | Some(TReference::Prediction) => IntegrityReference::Prediction,
            Some(TReference::DeadReckoning) => IntegrityReference::DeadReckoning,
        },
    })
}

fn probability(key: &str, p: f64) -> KResult<f64> {
    if (1e-15..0.5).contains(&p) {
        Ok(p)
    } else {
        Err(kerr(
            key,
            format!("expected a probability in [1e-15, 0.5), got {p}"),
        ))
    }
}

fn convert_zupt(z: &TZupt) -> KResult<ZuptOptions> {
    let d = ZuptOptions::default();
    Ok(ZuptOptions {
        enabled: z.enabled.unwrap_or(d.enabled),
        window_s: opt_or("zupt.window_s", z.window_s, positive, same, d.window_s)?,
        accel_std_max: opt_or(
            "zupt.accel_std_max_mps2",
            z.accel_std_max_mps2,
            positive,
            same,
            d.accel_std_max,
        )?,
        gyro_max: opt_or(
            "zupt.gyro_max_dps",
            z.gyro_max_dps,
            positive,
            deg_si,
            d.gyro_max,
        )?,
        rate_hz: opt_or("zupt.rate_hz", z.rate_hz, positive, same, d.rate_hz)?,
        velocity_std_mps: opt_or(
            "zupt.velocity_std_mps",
            z.velocity_std_mps,
            std_pos,
            same,
            d.velocity_std_mps,
        )?,
        angular_rate_std: opt_or(
            "zupt.angular_rate_std_dps",
            z.angular_rate_std_dps,
            non_negative,
            deg_si,
            d.angular_rate_std,
        )?,
        max_speed_mps: opt_or(
            "zupt.max_speed_mps",
            z.max_speed_mps,
            positive,
            same,
            d.max_speed_mps,
        )?,
        odometer_still_mps: opt_or(
            "zupt.odometer_still_mps",
            z.odometer_still_mps,
            non_negative,
            same,
            d.odometer_still_mps,
        )?,
        max_accel_mps2: opt_or(
            "zupt.max_accel_mps2",
            z.max_accel_mps2,
            positive,
            same,
            d.max_accel_mps2,
        )?,
        gate_probability: gate(
            "zupt.gate_probability",
            z.gate_probability,
            d.gate_probability,
        )?,
    })
}

fn convert_imu(m: &TImu, base: &Path) -> KResult<ImuSource> {
    let path = file_key(base, "imu.file", &m.file)?;
    let rate_hz = positive("imu.rate_hz", m.rate_hz)?;
    let sensor_to_body_rpy_deg = match &m.sensor_to_body_rpy_deg {
        Some(v) => v3("imu.sensor_to_body_rpy_deg", v)?,
        None => [0.0; 3],
    };
    let time_offset_s = finite("imu.time_offset_s", m.time_offset_s.unwrap_or(0.0))?;
    let max_bridge_s = m
        .max_bridge_s
        .map(|x| positive("imu.max_bridge_s", x))
        .transpose()?;
    let gap_policy = match m.gap_policy.unwrap_or(TGapPolicy::Bridge) {
        TGapPolicy::Bridge => GapPolicy::Bridge {
            max_s: max_bridge_s,
        },
        TGapPolicy::Nominal if max_bridge_s.is_some() => {
            return Err(kerr(
                "imu.max_bridge_s",
                "applies only to imu.gap_policy = \"bridge\"",
            ))
        }
        TGapPolicy::Nominal => GapPolicy::Nominal,
    };
    if m.format != TImuFormat::Csv && m.csv.is_some() {
        return Err(kerr(
            "imu.csv",
            "[imu.csv] applies only to imu.format = \"csv\"",
        ));
    }
    if m.format != TImuFormat::RtklibExplorer && m.tag_file.is_some() {
        return Err(kerr(
            "imu.tag_file",
            "applies only to imu.format = \"rtklibexplorer\"",
        ));
    }
    let format = match m.format {
        TImuFormat::KfGins => ImuFormat::KfGins,
        TImuFormat::Csv => {
            let c = m.csv.as_ref().ok_or_else(|| {
                kerr(
                    "imu.csv",
                    "an [imu.csv] table (time_col, gyro_cols, accel_cols, ...) is required when \
                     imu.format = \"csv\"",
                )
            })?;
            ImuFormat::Csv(convert_csv(c)?)
        }
        TImuFormat::RtklibExplorer => {
            let tag_path = match &m.tag_file {
                Some(t) => file_key(base, "imu.tag_file", t)?,
                None => {
                    let mut s = path.clone().into_os_string();
                    s.push(".tag");
                    PathBuf::from(s)
                }
            };
            ImuFormat::RtklibExplorer(RtklibExplorerImuOptions { tag_path })
        }
    };
    Ok(ImuSource {
        path,
        format,
        rate_hz,
        sensor_to_body_rpy_deg,
        time_offset_s,
        gap_policy,
    })
}

fn cols3(key: &str, v: &[usize]) -> KResult<[usize; 3]> {
    if v.len() != 3 {
        return Err(kerr(
            key,
            format!(
                "expected an array of 3 column numbers (0-based), got {} element(s)",
                v.len()
            ),
        ));
    }
    Ok([v[0], v[1], v[2]])
}

fn convert_csv(c: &TCsv) -> KResult<CsvImuOptions> {
    let gyro_cols = cols3("imu.csv.gyro_cols", &c.gyro_cols)?;
    let accel_cols = cols3("imu.csv.accel_cols", &c.accel_cols)?;
    let mut all = vec![("imu.csv.time_col", c.time_col)];
    all.extend(gyro_cols.iter().map(|&x| ("imu.csv.gyro_cols", x)));
    all.extend(accel_cols.iter().map(|&x| ("imu.csv.accel_cols", x)));
    for (k, (key, col)) in all.iter().enumerate() {
        if let Some((other, _)) = all[..k].iter().find(|(_, c2)| c2 == col) {
            return Err(kerr(
                key,
                format!("column {col} is also used by {other}: expected distinct columns"),
            ));
        }
    }
    Ok(CsvImuOptions {
        skip_lines: c.skip_lines.unwrap_or(0),
        time_col: c.time_col,
        gyro_cols,
        accel_cols,
        time_unit: match c.time_unit.unwrap_or(TTimeUnit::S) {
            TTimeUnit::S => TimeUnit::Seconds,
            TTimeUnit::Ms => TimeUnit::Milliseconds,
            TTimeUnit::Us => TimeUnit::Microseconds,
            TTimeUnit::Ns => TimeUnit::Nanoseconds,
        },
        time_scale: match c.time_scale.unwrap_or(TTimeScale::GpsSow) {
            TTimeScale::GpsSow => TimeScale::GpsSecondsOfWeek,
            TTimeScale::GpstUnix => TimeScale::GpstUnix,
        },
        quantity: match c.quantity.unwrap_or(TQuantity::Rate) {
            TQuantity::Rate => ImuQuantity::Rate,
            TQuantity::Increment => ImuQuantity::Increment,
        },
        rate_sampling: match c.rate_sampling.unwrap_or(TSampling::Instant) {
            TSampling::Instant => RateSampling::Instant,
            TSampling::IntervalMean => RateSampling::IntervalMean,
        },
        gyro_unit: match c.gyro_unit.unwrap_or(TGyroUnit::Rad) {
            TGyroUnit::Rad => GyroUnit::Rad,
            TGyroUnit::Deg => GyroUnit::Deg,
        },
        accel_unit: match c.accel_unit.unwrap_or(TAccelUnit::M) {
            TAccelUnit::M => AccelUnit::Metre,
            TAccelUnit::G => AccelUnit::G,
        },
    })
}

fn convert_gnss(
    g: &TGnss,
    base: &Path,
    start: Option<f64>,
) -> KResult<(GnssSource, GnssOptions, Vec<RelativeOutage>, TightOptions)> {
    let path = file_key(base, "gnss.file", &g.file)?;
    let rinex_only = [
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
        ("gnss.tight", g.tight.is_some()),
    ];
    if g.format != TGnssFormat::Rinex {
        if let Some((key, _)) = rinex_only.iter().find(|(_, set)| *set) {
            return Err(kerr(key, "applies only to gnss.format = \"rinex\""));
        }
    }
    let mut tight = TightOptions::default();
    let format = match g.format {
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
            let (rinex, t) = convert_rinex(g, base)?;
            tight = t;
            GnssFormat::Rinex(rinex)
        }
    };
    let decimate_s = g
        .decimate_s
        .map(|d| positive("gnss.decimate_s", d))
        .transpose()?;
    let time_offset_s = finite("gnss.time_offset_s", g.time_offset_s.unwrap_or(0.0))?;
    let src = GnssSource {
        path,
        format,
        decimate_s,
        time_offset_s,
    };

    let lever = match &g.lever_arm_m {
        Some(v) => v3("gnss.lever_arm_m", v)?,
        None => [0.0; 3],
    };
    let position_std_override = g
        .position_std_m
        .as_ref()
        .map(|v| std3("gnss.position_std_m", v).map(vec3))
        .transpose()?;
    let velocity_std_override = g
        .velocity_std_mps
        .as_ref()
        .map(|v| std3("gnss.velocity_std_mps", v).map(vec3))
        .transpose()?;
    let gate_probability = gate(
        "gnss.gate_probability",
        g.gate_probability,
        Some(DEFAULT_FIX_GATE_PROBABILITY),
    )?;
    let fd = FixErrorOptions::default();
    let fix_error = FixErrorOptions {
        corr_time_s: opt_or(
            "gnss.error_corr_time_s",
            g.error_corr_time_s,
            non_negative,
            same,
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
            Some(w) if w >= 0.0 && w <= 1e6 && w.fract() == 0.0 => w as usize,
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
        readmit_s: opt_or("gnss.readmit_s", g.readmit_s, positive, same, fd.readmit_s)?,
        floor_accel_mps2: opt_or(
            "gnss.floor_accel_mps2",
            g.floor_accel_mps2,
            non_negative,
            same,
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
        g.gate_timeout_s.unwrap_or(DEFAULT_GATE_TIMEOUT_S),
    )?;

    let mut outages = OutageSchedule::default();
    for (k, w) in g.outages.iter().flatten().enumerate() {
        let key = format!("gnss.outages[{k}]");
        if w.len() != 2 {
            return Err(kerr(
                &key,
                format!(
                    "expected a [start, end] pair of times [s], got {} element(s)",
                    w.len()
                ),
            ));
        }
        let (a, b) = (finite(&key, w[0])?, finite(&key, w[1])?);
        if b <= a {
            return Err(kerr(&key, format!("expected end > start, got [{a}, {b}]")));
        }
        outages.windows.push(Window { start: a, end: b });
    }
    let mut relative = Vec::new();
    let every = g
        .outage_every
        .as_ref()
        .map(|o| o.0.as_slice())
        .unwrap_or(&[]);
    for (k, p) in every.iter().enumerate() {
        let key = if every.len() == 1 {
            "gnss.outage_every".to_string()
        } else {
            format!("gnss.outage_every[{k}]")
        };
        let sub = |s: &str| format!("{key}.{s}");
        let length_s = positive(&sub("length_s"), p.length_s)?;
        let period_s = positive(&sub("period_s"), p.period_s)?;
        if period_s <= length_s {
            return Err(kerr(
                &sub("period_s"),
                format!("expected a period > length_s = {length_s}, got {period_s}"),
            ));
        }
        let until = p.until.map(|u| finite(&sub("until"), u)).transpose()?;
        let until_start_s = p
            .until_start_s
            .map(|u| finite(&sub("until_start_s"), u))
            .transpose()?;
        if until.is_some() && until_start_s.is_some() {
            return Err(kerr(
                &sub("until_start_s"),
                "give either until or until_start_s, not both",
            ));
        }
        match (p.from, p.from_start_s) {
            (Some(from), None) => {
                let from = finite(&sub("from"), from)?;
                if until_start_s.is_some() {
                    return Err(kerr(
                        &sub("until_start_s"),
                        "until_start_s needs from_start_s; with an absolute from use until",
                    ));
                }
                if let Some(u) = until {
                    if u <= from {
                        return Err(kerr(
                            &sub("until"),
                            format!("expected a time after from = {from}, got {u}"),
                        ));
                    }
                }
                outages.periodic.push(Periodic {
                    length: length_s,
                    period: period_s,
                    from,
                    until,
                });
            }
            (None, Some(rel)) => {
                let rel = non_negative(&sub("from_start_s"), rel)?;
                if let Some(u) = until_start_s {
                    if u <= rel {
                        return Err(kerr(
                            &sub("until_start_s"),
                            format!("expected a value > from_start_s = {rel}, got {u}"),
                        ));
                    }
                }
                let r = RelativeOutage {
                    length_s,
                    period_s,
                    from_start_s: rel,
                    until,
                    until_start_s,
                };
                match start {
                    Some(s) => outages.periodic.push(r.resolve(s)),
                    None => relative.push(r),
                }
            }
            (Some(_), Some(_)) => {
                return Err(kerr(
                    &sub("from_start_s"),
                    "give either from or from_start_s, not both",
                ))
            }
            (None, None) => return Err(kerr(
                &key,
                "expected from (absolute time [s]) or from_start_s (seconds after the run start)",
            )),
        }
    }

    let fusion = convert_fusion(g, tight.enabled)?;
    let opts = GnssOptions {
        lever_arm_b: vec3(lever),
        use_velocity: g.use_velocity.unwrap_or(true),
        position_std_override,
        velocity_std_override,
        gate_probability,
        gate_timeout_s,
        outages,
        fusion,
        fix_error,
    };
    Ok((src, opts, relative, tight))
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

/// `gnss.format = "rinex"`: navigation file, coupling, DGPS and `[gnss.tight]`.
fn convert_rinex(g: &TGnss, base: &Path) -> KResult<(RinexGnss, TightOptions)> {
    let nav = g.nav.as_deref().ok_or_else(|| {
        kerr(
            "gnss.nav",
            "gnss.format = \"rinex\" needs nav = \"RINEX navigation file\"",
        )
    })?;
    let nav_path = file_key(base, "gnss.nav", nav)?;
    let coupling = match g.coupling.unwrap_or(TCoupling::Tight) {
        TCoupling::Loose => Coupling::Loose,
        TCoupling::Tight => Coupling::Tight,
    };
    let elevation_mask_deg = g.elevation_mask_deg.unwrap_or(DEFAULT_ELEVATION_MASK_DEG);
    if !(0.0..90.0).contains(&elevation_mask_deg) {
        return Err(kerr(
            "gnss.elevation_mask_deg",
            format!("expected 0 <= mask < 90 deg, got {elevation_mask_deg}"),
        ));
    }
    let max_age_s = opt_or(
        "gnss.dgps_max_age_s",
        g.dgps_max_age_s,
        positive,
        same,
        DEFAULT_DGPS_MAX_AGE_S,
    )?;
    let dgps =
        match (
            g.dgps.unwrap_or(false),
            &g.dgps_corrections,
            &g.dgps_reference_obs,
        ) {
            (false, _, _) => None,
            (true, Some(_), Some(_)) => {
                return Err(kerr(
                    "gnss.dgps_corrections",
                    "give either dgps_corrections or dgps_reference_obs, not both",
                ))
            }
            (true, Some(f), None) => Some(DgpsKind::Corrections(file_key(
                base,
                "gnss.dgps_corrections",
                f,
            )?)),
            (true, None, Some(f)) => {
                let key = "gnss.dgps_reference_position_deg_m";
                let p = g.dgps_reference_position_deg_m.as_deref().ok_or_else(|| {
                    kerr(
                        key,
                        "dgps_reference_obs needs the station's [lat_deg, lon_deg, h_m]",
                    )
                })?;
                let p = v3(key, p)?;
                Some(DgpsKind::ReferenceStation {
                    obs_path: file_key(base, "gnss.dgps_reference_obs", f)?,
                    position_lla: [p[0] * D2R, p[1] * D2R, p[2]],
                })
            }
            (true, None, None) => return Err(kerr(
                "gnss.dgps",
                "dgps = true needs dgps_corrections = \"FILE\" or dgps_reference_obs = \"FILE\"",
            )),
        }
        .map(|kind| DgpsSource { kind, max_age_s });
    let mut t = TightOptions {
        enabled: coupling == Coupling::Tight,
        range_rate: match g.range_rate.unwrap_or(TRangeRate::Doppler) {
            TRangeRate::None => RangeRate::None,
            TRangeRate::Doppler => RangeRate::Doppler,
            TRangeRate::Tdcp => RangeRate::Tdcp,
        },
        ..TightOptions::default()
    };
    if let Some(x) = &g.tight {
        let d = t.clone();
        let k = |name: &str| format!("gnss.tight.{name}");
        t.use_pseudorange = x.use_pseudorange.unwrap_or(d.use_pseudorange);
        t.gate_probability = match x.gate_probability {
            None => d.gate_probability,
            Some(p) if p == 0.0 => None,
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
            same,
            d.clock_bias_psd_sqrt,
        )?;
        t.clock_drift_psd_sqrt = opt_or(
            &k("clock_drift_psd_sqrt"),
            x.clock_drift_psd_sqrt,
            positive,
            same,
            d.clock_drift_psd_sqrt,
        )?;
        t.clock_reset_m = opt_or(
            &k("clock_reset_m"),
            x.clock_reset_m,
            positive,
            same,
            d.clock_reset_m,
        )?;
        t.slip_sigma = opt_or(&k("slip_sigma"), x.slip_sigma, positive, same, d.slip_sigma)?;
        t.slip_min_m = opt_or(
            &k("slip_min_m"),
            x.slip_min_m,
            non_negative,
            same,
            d.slip_min_m,
        )?;
        t.tdcp_max_gap_s = opt_or(
            &k("tdcp_max_gap_s"),
            x.tdcp_max_gap_s,
            positive,
            same,
            d.tdcp_max_gap_s,
        )?;
        t.pseudorange_sigma_scale = opt_or(
            &k("pseudorange_sigma_scale"),
            x.pseudorange_sigma_scale,
            positive,
            same,
            d.pseudorange_sigma_scale,
        )?;
        t.range_rate_sigma_scale = opt_or(
            &k("range_rate_sigma_scale"),
            x.range_rate_sigma_scale,
            positive,
            same,
            d.range_rate_sigma_scale,
        )?;
        t.pseudorange_sigma_floor_m = opt_or(
            &k("pseudorange_sigma_floor_m"),
            x.pseudorange_sigma_floor_m,
            non_negative,
            same,
            d.pseudorange_sigma_floor_m,
        )?;
        t.range_rate_sigma_floor_mps = opt_or(
            &k("range_rate_sigma_floor_mps"),
            x.range_rate_sigma_floor_mps,
            non_negative,
            same,
            d.range_rate_sigma_floor_mps,
        )?;
    }
    Ok((
        RinexGnss {
            nav_path,
            coupling,
            elevation_mask_deg,
            fde: g.fde.unwrap_or(true),
            dgps,
        },
        t,
    ))
}

/// Default `gnss.elevation_mask_deg`.
pub const DEFAULT_ELEVATION_MASK_DEG: f64 = 10.0;
/// Default `gnss.dgps_max_age_s`.
pub const DEFAULT_DGPS_MAX_AGE_S: f64 = 30.0;

// ---------------------------------------------------------------------------------
// RunConfig -> TOML (user units)

impl TGnss {
    /// The RINEX-only keys, absent (for struct update syntax).
    fn no_rinex() -> TGnss {
        TGnss {
            file: String::new(),
            format: TGnssFormat::KfGins,
            nav: None,
            coupling: None,
            range_rate: None,
            elevation_mask_deg: None,
            fde: None,
            dgps: None,
            dgps_corrections: None,
            dgps_reference_obs: None,
            dgps_reference_position_deg_m: None,
            dgps_max_age_s: None,
            tight: None,
            quality: None,
            decimate_s: None,
            time_offset_s: None,
            lever_arm_m: None,
            use_velocity: None,
            position_std_m: None,
            velocity_std_mps: None,
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
        }
    }
}

fn rinex_to_toml(r: &RinexGnss, tight: &TightOptions, t: &mut TGnss) {
    t.nav = Some(path_str(&r.nav_path));
    t.coupling = Some(match r.coupling {
        Coupling::Loose => TCoupling::Loose,
        Coupling::Tight => TCoupling::Tight,
    });
    t.range_rate = Some(match tight.range_rate {
        RangeRate::None => TRangeRate::None,
        RangeRate::Doppler => TRangeRate::Doppler,
        RangeRate::Tdcp => TRangeRate::Tdcp,
    });
    t.elevation_mask_deg = Some(r.elevation_mask_deg);
    t.fde = Some(r.fde);
    t.dgps = Some(r.dgps.is_some());
    if let Some(d) = &r.dgps {
        t.dgps_max_age_s = Some(d.max_age_s);
        match &d.kind {
            DgpsKind::Corrections(p) => t.dgps_corrections = Some(path_str(p)),
            DgpsKind::ReferenceStation {
                obs_path,
                position_lla,
            } => {
                t.dgps_reference_obs = Some(path_str(obs_path));
                t.dgps_reference_position_deg_m = Some(vec![
                    position_lla[0] / D2R,
                    position_lla[1] / D2R,
                    position_lla[2],
                ]);
            }
        }
    }
    t.tight = Some(TTight {
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
    });
}

fn path_str(p: &Path) -> String {
    std::path::absolute(p)
        .unwrap_or_else(|_| p.to_path_buf())
        .to_string_lossy()
        .into_owned()
}

/// Round to 15 significant digits: hides the last-bit noise of the unit conversions
/// (0.027 deg/h -> rad/s -> 0.026999999999999996 deg/h) when writing user units.
/// Largest time-offset rate and rate std accepted [ppm].
const MAX_RATE_PPM: f64 = 1e6;

fn tidy(x: f64) -> f64 {
    format!("{x:.14e}").parse().unwrap_or(x)
}

fn to_raw(c: &RunConfig) -> TomlRoot {
    let inv = |v: &Vector3<f64>, f: fn(f64) -> f64| Num3::from3(map3(map3(arr3(v), f), tidy));
    let r2d = |x: f64| tidy(x / D2R);
    let (fmt, tag_file, csv) = match &c.imu.format {
        ImuFormat::KfGins => (TImuFormat::KfGins, None, None),
        ImuFormat::RtklibExplorer(o) => (
            TImuFormat::RtklibExplorer,
            Some(path_str(&o.tag_path)),
            None,
        ),
        ImuFormat::Csv(o) => (
            TImuFormat::Csv,
            None,
            Some(TCsv {
                skip_lines: Some(o.skip_lines),
                time_col: o.time_col,
                gyro_cols: o.gyro_cols.to_vec(),
                accel_cols: o.accel_cols.to_vec(),
                time_unit: Some(match o.time_unit {
                    TimeUnit::Seconds => TTimeUnit::S,
                    TimeUnit::Milliseconds => TTimeUnit::Ms,
                    TimeUnit::Microseconds => TTimeUnit::Us,
                    TimeUnit::Nanoseconds => TTimeUnit::Ns,
                }),
                time_scale: Some(match o.time_scale {
                    TimeScale::GpsSecondsOfWeek => TTimeScale::GpsSow,
                    TimeScale::GpstUnix => TTimeScale::GpstUnix,
                }),
                quantity: Some(match o.quantity {
                    ImuQuantity::Rate => TQuantity::Rate,
                    ImuQuantity::Increment => TQuantity::Increment,
                }),
                rate_sampling: Some(match o.rate_sampling {
                    RateSampling::Instant => TSampling::Instant,
                    RateSampling::IntervalMean => TSampling::IntervalMean,
                }),
                gyro_unit: Some(match o.gyro_unit {
                    GyroUnit::Rad => TGyroUnit::Rad,
                    GyroUnit::Deg => TGyroUnit::Deg,
                }),
                accel_unit: Some(match o.accel_unit {
                    AccelUnit::Metre => TAccelUnit::M,
                    AccelUnit::G => TAccelUnit::G,
                }),
            }),
        ),
    };
    let imu = TImu {
        file: path_str(&c.imu.path),
        format: fmt,
        rate_hz: c.imu.rate_hz,
        sensor_to_body_rpy_deg: Some(c.imu.sensor_to_body_rpy_deg.to_vec()),
        time_offset_s: Some(c.imu.time_offset_s),
        tag_file,
        gap_policy: Some(match c.imu.gap_policy {
            GapPolicy::Bridge { .. } => TGapPolicy::Bridge,
            GapPolicy::Nominal => TGapPolicy::Nominal,
        }),
        max_bridge_s: match c.imu.gap_policy {
            GapPolicy::Bridge { max_s } => max_s,
            GapPolicy::Nominal => None,
        },
        csv,
    };
    let go = &c.nav.gnss;
    let gnss = c.gnss.as_ref().map(|g| {
        let (format, quality) = match &g.format {
            GnssFormat::KfGins => (TGnssFormat::KfGins, None),
            GnssFormat::RtklibPos { quality } => (TGnssFormat::RtklibPos, Some(quality.clone())),
            GnssFormat::Rinex(_) => (TGnssFormat::Rinex, None),
        };
        let mut every: Vec<TOutageEvery> = go
            .outages
            .periodic
            .iter()
            .map(|p| TOutageEvery {
                length_s: p.length,
                period_s: p.period,
                from: Some(p.from),
                from_start_s: None,
                until: p.until,
                until_start_s: None,
            })
            .collect();
        every.extend(c.relative_outages.iter().map(|r| TOutageEvery {
            length_s: r.length_s,
            period_s: r.period_s,
            from: None,
            from_start_s: Some(r.from_start_s),
            until: r.until,
            until_start_s: r.until_start_s,
        }));
        let mut t = TGnss {
            file: path_str(&g.path),
            format,
            quality,
            decimate_s: g.decimate_s,
            time_offset_s: Some(g.time_offset_s),
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
            gate_probability: Some(Gate::from_option(go.gate_probability)),
            gate_timeout_s: Some(go.gate_timeout_s),
            error_corr_time_s: Some(go.fix_error.corr_time_s),
            error_corr_fraction: Some(go.fix_error.corr_fraction),
            scale_window: Some(go.fix_error.scale_window as f64),
            robust_probability: Some(Gate::from_option(go.fix_error.robust_probability)),
            readmit_s: Some(go.fix_error.readmit_s),
            floor_accel_mps2: Some(go.fix_error.floor_accel_mps2),
            outages: (!go.outages.windows.is_empty()).then(|| {
                go.outages
                    .windows
                    .iter()
                    .map(|w| vec![w.start, w.end])
                    .collect()
            }),
            outage_every: (!every.is_empty()).then_some(OneOrMany(every)),
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
        if let GnssFormat::Rinex(r) = &g.format {
            rinex_to_toml(r, &c.nav.tight, &mut t);
        }
        t
    });
    let i = &c.nav.initial;
    let n = &c.nav.imu_noise;
    let initial = TInitial {
        position_deg_m: i.lla.map(|p| vec![r2d(p.x), r2d(p.y), p.z]),
        velocity_mps: Some(arr3(&i.v_n).to_vec()),
        attitude_deg: match i.attitude {
            AttitudeInit::Given(rpy) => Some(map3(arr3(&rpy), r2d).to_vec()),
            _ => None,
        },
        alignment: match i.attitude {
            AttitudeInit::Given(_) => None,
            AttitudeInit::LevelAndGnssCourse {
                level_window_s,
                min_speed_mps,
            } => Some(TAlignment {
                mode: Some(TAlignMode::LevelAndCourse),
                level_window_s: Some(level_window_s),
                min_speed_mps: Some(min_speed_mps),
                gyrocompass: None,
            }),
            AttitudeInit::StaticGyrocompass { level_window_s } => Some(TAlignment {
                mode: Some(TAlignMode::StaticGyrocompass),
                level_window_s: Some(level_window_s),
                min_speed_mps: None,
                gyrocompass: None,
            }),
            AttitudeInit::InMotion { min_speed_mps } => Some(TAlignment {
                mode: Some(TAlignMode::InMotion),
                level_window_s: None,
                min_speed_mps: Some(min_speed_mps),
                gyrocompass: None,
            }),
            AttitudeInit::Auto {
                level_window_s,
                min_speed_mps,
                gyrocompass,
            } => Some(TAlignment {
                mode: Some(TAlignMode::Auto),
                level_window_s: Some(level_window_s),
                min_speed_mps: Some(min_speed_mps),
                gyrocompass: Some(gyrocompass),
            }),
        },
        position_std_m: Num3::from3(arr3(&i.pos_std)),
        velocity_std_mps: Num3::from3(arr3(&i.vel_std)),
        attitude_std_deg: inv(&i.att_std, r2d),
        gyro_bias_degph: Some(inv(&i.imu_errors.gyro_bias, |x| x * 3600.0 / D2R)),
        accel_bias_mgal: Some(inv(&i.imu_errors.accel_bias, |x| x * 1e5)),
        gyro_scale_ppm: Some(inv(&i.imu_errors.gyro_scale, |x| x * 1e6)),
        accel_scale_ppm: Some(inv(&i.imu_errors.accel_scale, |x| x * 1e6)),
        gyro_bias_std_degph: Some(inv(&i.imu_errors_std.gyro_bias, |x| x * 3600.0 / D2R)),
        accel_bias_std_mgal: Some(inv(&i.imu_errors_std.accel_bias, |x| x * 1e5)),
        gyro_scale_std_ppm: Some(inv(&i.imu_errors_std.gyro_scale, |x| x * 1e6)),
        accel_scale_std_ppm: Some(inv(&i.imu_errors_std.accel_scale, |x| x * 1e6)),
    };
    let imu_noise = TNoise {
        arw_deg_sqrth: inv(&n.arw, |x| x * 60.0 / D2R),
        vrw_mps_sqrth: inv(&n.vrw, |x| x * 60.0),
        gyro_bias_std_degph: inv(&n.gyro_bias_std, |x| x * 3600.0 / D2R),
        accel_bias_std_mgal: inv(&n.accel_bias_std, |x| x * 1e5),
        gyro_scale_std_ppm: inv(&n.gyro_scale_std, |x| x * 1e6),
        accel_scale_std_ppm: inv(&n.accel_scale_std, |x| x * 1e6),
        corr_time_h: tidy(n.corr_time_s / 3600.0),
    };
    let filter = TFilter {
        covariance_period_s: Some(c.nav.filter.covariance_period_s),
        gap_accel_mps2: Some(c.nav.filter.gap_accel_mps2),
        gap_rate_dps: Some(r2d(c.nav.filter.gap_rate)),
        time_offset: c.nav.filter.time_offset.map(|t| TTimeOffset {
            estimate: Some(t.std_s > 0.0),
            initial_s: Some(t.initial_s),
            std_s: (t.std_s > 0.0).then_some(t.std_s),
            random_walk: Some(t.random_walk),
            initial_rate_ppm: Some(tidy(t.initial_rate * 1e6)),
            rate_std_ppm: Some(tidy(t.rate_std * 1e6)),
        }),
    };
    let v = &c.nav.vehicle;
    let vehicle = TVehicle {
        mounting_rpy_deg: Some(map3(arr3(&v.mounting_rpy), r2d).to_vec()),
        lever_arm_m: Some(arr3(&v.lever_arm_b).to_vec()),
        mounting_std_deg: Some(r2d(v.mounting_std)),
    };
    let nh = &c.nav.nhc;
    let nhc = TNhc {
        mode: Some(match nh.mode {
            NhcMode::Off => TNhcMode::Off,
            NhcMode::Always => TNhcMode::Always,
            NhcMode::DuringOutage => TNhcMode::Outage,
        }),
        std_mps: Some(Num2::from2(nh.std_mps)),
        rate_hz: Some(nh.rate_hz),
        outage_after_s: Some(nh.outage_after_s),
        gate_probability: Some(Gate::from_option(nh.gate_probability)),
        min_speed_mps: Some(nh.min_speed_mps),
    };
    let od = &c.nav.odometer;
    // An odometer is configured by its file; options without one cannot be written.
    let odometer = c.odometer.as_ref().map(|src| {
        let (format, meters_per_pulse, speed_is_mean) = match src.format {
            OdometerFormat::Speed { speed_is_mean } => {
                (TOdoFormat::Speed, None, Some(speed_is_mean))
            }
            OdometerFormat::Pulses { meters_per_pulse } => {
                (TOdoFormat::Pulses, Some(meters_per_pulse), None)
            }
            OdometerFormat::Navfuse { meters_per_pulse } => {
                (TOdoFormat::Navfuse, Some(meters_per_pulse), None)
            }
        };
        TOdometer {
            file: path_str(&src.path),
            format,
            meters_per_pulse,
            speed_is_mean,
            std_mps: Some(od.std_mps),
            scale_ppm: Some(tidy(od.scale_initial * 1e6)),
            scale_std_ppm: Some(tidy(od.scale_std * 1e6)),
            scale_random_walk_ppm_per_sqrth: Some(tidy(psd_ppm_sqrth(od.scale_random_walk))),
            with_nhc: Some(od.with_nhc),
            std_speed_fraction: Some(od.std_speed_fraction),
            calibration_min_speed_mps: Some(od.calibration_min_speed_mps),
            gate_probability: Some(Gate::from_option(od.gate_probability)),
        }
    });
    let hd = &c.nav.heading;
    let dual = c.heading.as_ref().filter(|_| hd.baseline_b.is_some());
    let heading = THeading {
        file: dual.map(|h| path_str(&h.path)),
        baseline_m: dual.and(hd.baseline_b).map(|b| arr3(&b).to_vec()),
        std_deg: dual.and(hd.dual_antenna_std_override).map(r2d),
        course_over_ground: Some(hd.course_over_ground),
        course_min_speed_mps: Some(hd.course_min_speed_mps),
        course_std_floor_deg: Some(r2d(hd.course_std_floor)),
        gate_probability: Some(Gate::from_option(hd.gate_probability)),
    };
    let z = &c.nav.zupt;
    let zupt = TZupt {
        enabled: Some(z.enabled),
        window_s: Some(z.window_s),
        accel_std_max_mps2: Some(z.accel_std_max),
        gyro_max_dps: Some(r2d(z.gyro_max)),
        rate_hz: Some(z.rate_hz),
        velocity_std_mps: Some(z.velocity_std_mps),
        angular_rate_std_dps: Some(r2d(z.angular_rate_std)),
        max_speed_mps: Some(z.max_speed_mps),
        odometer_still_mps: Some(z.odometer_still_mps),
        max_accel_mps2: Some(z.max_accel_mps2),
        gate_probability: Some(Gate::from_option(z.gate_probability)),
    };
    let sp = &c.nav.integrity;
    let spoofing = sp.enabled.then(|| TSpoofing {
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
        reference: Some(match sp.reference {
            IntegrityReference::Prediction => TReference::Prediction,
            IntegrityReference::DeadReckoning => TReference::DeadReckoning,
        }),
    });
    TomlRoot {
        imu,
        gnss,
        odometer,
        heading: Some(heading),
        time: TTime {
            start: c.nav.start_time.is_finite().then_some(c.nav.start_time),
            end: c.nav.end_time,
        },
        initial,
        imu_noise,
        vehicle: Some(vehicle),
        nhc: Some(nhc),
        zupt: Some(zupt),
        spoofing,
        filter,
        output: TOutput {
            rate_hz: c.output.rate_hz,
            imu_err: Some(c.output.imu_err),
            std: Some(c.output.std),
            csv: Some(c.output.csv),
        },
    }
}

// ---------------------------------------------------------------------------------
// TOML error locations

fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

type DeTable<'i> = toml::de::DeTable<'i>;
type DeValue<'i> = toml::de::DeValue<'i>;
type Spanned<T> = toml::Spanned<T>;

/// Span of the key (or, for array elements, of the element) at a dotted path such as
/// `gnss.outage_every.length_s` or `gnss.outages[2]`; the deepest existing prefix
/// when the full path is absent.
fn toml_span_of(root: &DeTable<'_>, key: &str) -> Option<std::ops::Range<usize>> {
    let mut table = Some(root);
    let mut value: Option<&Spanned<DeValue<'_>>> = None;
    let mut best = None;
    for seg in key.split('.') {
        let (name, idx) = match seg.split_once('[') {
            Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (seg, None),
        };
        if let (None, Some(v)) = (table, value) {
            // descend into an array of tables addressed without index: take the first
            table = v
                .get_ref()
                .as_array()
                .and_then(|a| a.first())
                .and_then(|e| e.get_ref().as_table());
        }
        let t = table?;
        let Some((k, v)) = t.iter().find(|(k, _)| k.get_ref() == name) else {
            return best;
        };
        best = Some(k.span());
        let mut v = v;
        if let Some(i) = idx {
            match v.get_ref().as_array().and_then(|a| a.get(i)) {
                Some(e) => {
                    v = e;
                    best = Some(e.span());
                }
                None => return best,
            }
        }
        value = Some(v);
        table = v.get_ref().as_table();
    }
    best
}

fn toml_line_of(text: &str, key: &str) -> Option<usize> {
    let root = DeTable::parse(text).ok()?;
    toml_span_of(root.get_ref(), key).map(|s| line_of(text, s.start))
}

/// The dotted path of the entry at byte `offset`: the deepest key whose key or value
/// span contains it.
fn toml_key_at(table: &DeTable<'_>, offset: usize, prefix: &str) -> Option<String> {
    let mut fallback = None;
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if k.span().contains(&offset) {
            return Some(path);
        }
        if let Some(found) = value_key_at(v, offset, &path) {
            return Some(found);
        }
        if v.span().contains(&offset) && fallback.is_none() {
            fallback = Some(path);
        }
    }
    fallback
}

fn value_key_at(v: &Spanned<DeValue<'_>>, offset: usize, path: &str) -> Option<String> {
    match v.get_ref() {
        DeValue::Table(t) => toml_key_at(t, offset, path),
        DeValue::Array(a) => {
            for (i, e) in a.iter().enumerate() {
                let p = format!("{path}[{i}]");
                if let Some(found) = value_key_at(e, offset, &p) {
                    return Some(found);
                }
                if e.span().contains(&offset) {
                    return Some(p);
                }
            }
            None
        }
        _ => None,
    }
}

/// The dotted path of the table whose value span is exactly `span` ("" for the root).
fn toml_table_at(
    table: &DeTable<'_>,
    span: &std::ops::Range<usize>,
    prefix: &str,
) -> Option<String> {
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        if let DeValue::Table(t) = v.get_ref() {
            if let Some(p) = toml_table_at(t, span, &path) {
                return Some(p);
            }
            if v.span() == *span {
                return Some(path);
            }
        }
        if let DeValue::Array(a) = v.get_ref() {
            for (i, e) in a.iter().enumerate() {
                if let DeValue::Table(t) = e.get_ref() {
                    let p = format!("{path}[{i}]");
                    if let Some(found) = toml_table_at(t, span, &p) {
                        return Some(found);
                    }
                    if e.span() == *span {
                        return Some(p);
                    }
                }
            }
        }
    }
    None
}

/// The name between the first pair of backticks of a serde message.
fn backticked(msg: &str) -> Option<&str> {
    let rest = msg.split_once('`')?.1;
    Some(rest.split_once('`')?.0)
}

fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> ConfigError {
    let message = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return ConfigError::new(path, None, None, message);
    };
    let line = Some(line_of(text, span.start));
    let Ok(root) = DeTable::parse(text) else {
        // a syntax error: no key to name
        return ConfigError::new(path, line, None, message);
    };
    let root = root.get_ref();
    let key = if message.starts_with("missing field") {
        let field = backticked(&message).unwrap_or_default();
        match toml_table_at(root, &span, "") {
            Some(t) => Some(format!("{t}.{field}")),
            None => Some(field.to_string()),
        }
    } else {
        toml_key_at(root, span.start, "")
    };
    let top_level =
        message.starts_with("missing field") && key.as_deref().is_some_and(|k| !k.contains('.'));
    if top_level {
        // A whole section is missing: say so, and where it is described.
        let section = key.clone().unwrap_or_default();
        let message = format!(
            "missing the required section [{section}] (docs/CONFIG.md lists its keys; examples/ has a configuration per dataset)"
        );
        return ConfigError::new(path, None, key, message);
    }
    ConfigError::new(path, line, key, message)
}

// ---------------------------------------------------------------------------------
// KF-GINS YAML

/// Keys KF-GINS reads at the top level.
const KF_TOP_KEYS: &[&str] = &[
    "imupath",
    "gnsspath",
    "outputpath",
    "imudatalen",
    "imudatarate",
    "starttime",
    "endtime",
    "initpos",
    "initvel",
    "initatt",
    "initgyrbias",
    "initaccbias",
    "initgyrscale",
    "initaccscale",
    "initposstd",
    "initvelstd",
    "initattstd",
    "initbgstd",
    "initbastd",
    "initsgstd",
    "initsastd",
    "imunoise",
    "antlever",
];

const KF_NOISE_KEYS: &[&str] = &["arw", "vrw", "gbstd", "abstd", "gsstd", "asstd", "corrtime"];

/// navfuse TOML key -> KF-GINS YAML key (docs/CONFIG.md, "KF-GINS YAML mapping").
const KEY_MAP: &[(&str, &str)] = &[
    ("imu.file", "imupath"),
    ("gnss.file", "gnsspath"),
    ("imu.rate_hz", "imudatarate"),
    ("time.start", "starttime"),
    ("time.end", "endtime"),
    ("initial.position_deg_m", "initpos"),
    ("initial.velocity_mps", "initvel"),
    ("initial.attitude_deg", "initatt"),
    ("initial.gyro_bias_degph", "initgyrbias"),
    ("initial.accel_bias_mgal", "initaccbias"),
    ("initial.gyro_scale_ppm", "initgyrscale"),
    ("initial.accel_scale_ppm", "initaccscale"),
    ("initial.position_std_m", "initposstd"),
    ("initial.velocity_std_mps", "initvelstd"),
    ("initial.attitude_std_deg", "initattstd"),
    ("initial.gyro_bias_std_degph", "initbgstd"),
    ("initial.accel_bias_std_mgal", "initbastd"),
    ("initial.gyro_scale_std_ppm", "initsgstd"),
    ("initial.accel_scale_std_ppm", "initsastd"),
    ("imu_noise.arw_deg_sqrth", "imunoise.arw"),
    ("imu_noise.vrw_mps_sqrth", "imunoise.vrw"),
    ("imu_noise.gyro_bias_std_degph", "imunoise.gbstd"),
    ("imu_noise.accel_bias_std_mgal", "imunoise.abstd"),
    ("imu_noise.gyro_scale_std_ppm", "imunoise.gsstd"),
    ("imu_noise.accel_scale_std_ppm", "imunoise.asstd"),
    ("imu_noise.corr_time_h", "imunoise.corrtime"),
    ("gnss.lever_arm_m", "antlever"),
];

fn toml_to_yaml_key(k: &str) -> Option<&'static str> {
    KEY_MAP.iter().find(|(t, _)| *t == k).map(|(_, y)| *y)
}

#[derive(Debug, Deserialize)]
struct KfYaml {
    imupath: String,
    gnsspath: String,
    #[serde(default)]
    outputpath: Option<String>,
    imudatalen: i64,
    imudatarate: f64,
    starttime: f64,
    endtime: f64,
    initpos: Vec<f64>,
    initvel: Vec<f64>,
    initatt: Vec<f64>,
    initgyrbias: Vec<f64>,
    initaccbias: Vec<f64>,
    initgyrscale: Vec<f64>,
    initaccscale: Vec<f64>,
    initposstd: Vec<f64>,
    initvelstd: Vec<f64>,
    initattstd: Vec<f64>,
    #[serde(default)]
    initbgstd: Option<Vec<f64>>,
    #[serde(default)]
    initbastd: Option<Vec<f64>>,
    #[serde(default)]
    initsgstd: Option<Vec<f64>>,
    #[serde(default)]
    initsastd: Option<Vec<f64>>,
    imunoise: KfNoise,
    antlever: Vec<f64>,
}

#[derive(Debug, Deserialize)]
struct KfNoise {
    arw: Vec<f64>,
    vrw: Vec<f64>,
    gbstd: Vec<f64>,
    abstd: Vec<f64>,
    gsstd: Vec<f64>,
    asstd: Vec<f64>,
    corrtime: f64,
}

#[derive(Debug, Deserialize)]
struct KfProbe {
    #[serde(default)]
    imunoise: Option<BTreeMap<String, IgnoredAny>>,
    #[serde(flatten)]
    rest: BTreeMap<String, IgnoredAny>,
}

/// KF-GINS reads the first three elements of each vector: fewer is an error here,
/// more is accepted with a warning. The key is the navfuse TOML key (mapped back to
/// the YAML key in errors).
fn kf3(key: &str, v: Vec<f64>, warnings: &mut Vec<String>) -> KResult<Vec<f64>> {
    if v.len() < 3 {
        return Err(kerr(
            key,
            format!("expected an array of 3 numbers, got {} element(s)", v.len()),
        ));
    }
    if v.len() > 3 {
        let yk = toml_to_yaml_key(key).unwrap_or(key);
        warnings.push(format!(
            "'{yk}' has {} elements; only the first 3 are used (as KF-GINS does)",
            v.len()
        ));
    }
    Ok(v[..3].to_vec())
}

fn kfgins_to_raw(y: KfYaml, w: &mut Vec<String>) -> KResult<(TomlRoot, Option<String>)> {
    if y.imudatalen < 7 {
        return Err(kerr(
            "imudatalen",
            format!(
                "expected the number of IMU file columns, at least 7 (time, 3 angle and 3 \
                 velocity increments), got {}",
                y.imudatalen
            ),
        ));
    }
    let l = |k: &str, v: Vec<f64>, w: &mut Vec<String>| kf3(k, v, w).map(Num3::List);
    let opt = |k: &str, v: Option<Vec<f64>>, w: &mut Vec<String>| -> KResult<Option<Num3>> {
        v.map(|v| kf3(k, v, w).map(Num3::List)).transpose()
    };
    let n = y.imunoise;
    let raw = TomlRoot {
        imu: TImu {
            file: y.imupath,
            format: TImuFormat::KfGins,
            rate_hz: y.imudatarate,
            sensor_to_body_rpy_deg: None,
            time_offset_s: None,
            tag_file: None,
            gap_policy: None,
            max_bridge_s: None,
            csv: None,
        },
        gnss: Some(TGnss {
            file: y.gnsspath,
            format: TGnssFormat::KfGins,
            quality: None,
            decimate_s: None,
            time_offset_s: None,
            lever_arm_m: Some(kf3("gnss.lever_arm_m", y.antlever, w)?),
            use_velocity: Some(true),
            position_std_m: None,
            velocity_std_mps: None,
            // KF-GINS: white fixes, no gate, no down-weighting (its results).
            gate_probability: Some(Gate::Off),
            gate_timeout_s: None,
            error_corr_time_s: Some(0.0),
            error_corr_fraction: Some(0.0),
            scale_window: Some(0.0),
            robust_probability: Some(Gate::Off),
            outages: None,
            outage_every: None,
            ..TGnss::no_rinex()
        }),
        odometer: None,
        heading: None,
        time: TTime {
            start: Some(y.starttime),
            // KF-GINS: a negative endtime means the end of the IMU file
            end: (y.endtime >= 0.0 || y.endtime.is_nan()).then_some(y.endtime),
        },
        initial: TInitial {
            position_deg_m: Some(kf3("initial.position_deg_m", y.initpos, w)?),
            velocity_mps: Some(kf3("initial.velocity_mps", y.initvel, w)?),
            attitude_deg: Some(kf3("initial.attitude_deg", y.initatt, w)?),
            alignment: None,
            position_std_m: l("initial.position_std_m", y.initposstd, w)?,
            velocity_std_mps: l("initial.velocity_std_mps", y.initvelstd, w)?,
            attitude_std_deg: l("initial.attitude_std_deg", y.initattstd, w)?,
            gyro_bias_degph: Some(l("initial.gyro_bias_degph", y.initgyrbias, w)?),
            accel_bias_mgal: Some(l("initial.accel_bias_mgal", y.initaccbias, w)?),
            gyro_scale_ppm: Some(l("initial.gyro_scale_ppm", y.initgyrscale, w)?),
            accel_scale_ppm: Some(l("initial.accel_scale_ppm", y.initaccscale, w)?),
            gyro_bias_std_degph: opt("initial.gyro_bias_std_degph", y.initbgstd, w)?,
            accel_bias_std_mgal: opt("initial.accel_bias_std_mgal", y.initbastd, w)?,
            gyro_scale_std_ppm: opt("initial.gyro_scale_std_ppm", y.initsgstd, w)?,
            accel_scale_std_ppm: opt("initial.accel_scale_std_ppm", y.initsastd, w)?,
        },
        imu_noise: TNoise {
            arw_deg_sqrth: l("imu_noise.arw_deg_sqrth", n.arw, w)?,
            vrw_mps_sqrth: l("imu_noise.vrw_mps_sqrth", n.vrw, w)?,
            gyro_bias_std_degph: l("imu_noise.gyro_bias_std_degph", n.gbstd, w)?,
            accel_bias_std_mgal: l("imu_noise.accel_bias_std_mgal", n.abstd, w)?,
            gyro_scale_std_ppm: l("imu_noise.gyro_scale_std_ppm", n.gsstd, w)?,
            accel_scale_std_ppm: l("imu_noise.accel_scale_std_ppm", n.asstd, w)?,
            corr_time_h: n.corrtime,
        },
        vehicle: None,
        nhc: None,
        zupt: None,
        spoofing: None,
        filter: TFilter::default(),
        output: TOutput {
            rate_hz: None,
            imu_err: Some(true),
            std: Some(true),
            csv: Some(false),
        },
    };
    Ok((raw, y.outputpath))
}

/// 1-based line of `key` (`name` or `imunoise.name`) in a block-style YAML file.
fn yaml_line_of(text: &str, key: &str) -> Option<usize> {
    let (parent, name) = match key.split_once('.') {
        Some((p, n)) => (Some(p), n),
        None => (None, key),
    };
    let key_of = |line: &str| -> Option<(usize, String)> {
        let indent = line.len() - line.trim_start().len();
        let t = line.trim_start();
        if t.starts_with('#') {
            return None;
        }
        let (k, _) = t.split_once(':')?;
        let k = k.trim().trim_matches(|c| c == '"' || c == '\'');
        (!k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
            .then(|| (indent, k.to_string()))
    };
    let mut in_parent = parent.is_none();
    let mut parent_indent = 0;
    for (n, line) in text.lines().enumerate() {
        let Some((indent, k)) = key_of(line) else {
            continue;
        };
        match parent {
            None if indent == 0 && k == name => return Some(n + 1),
            None => {}
            Some(p) => {
                if in_parent && indent > parent_indent && k == name {
                    return Some(n + 1);
                }
                if indent <= parent_indent {
                    in_parent = k == p;
                    parent_indent = indent;
                }
            }
        }
    }
    None
}

/// The YAML key on a line, with its parent when indented under one.
fn yaml_key_on_line(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let l = *lines.get(line.checked_sub(1)?)?;
    let indent = l.len() - l.trim_start().len();
    let (k, _) = l.trim_start().split_once(':')?;
    let k = k.trim();
    if k.is_empty() || !k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return None;
    }
    if indent == 0 {
        return Some(k.to_string());
    }
    // the nearest less-indented key above is the parent
    for p in lines[..line - 1].iter().rev() {
        let pi = p.len() - p.trim_start().len();
        if pi < indent && !p.trim().is_empty() && !p.trim_start().starts_with('#') {
            let (pk, _) = p.trim_start().split_once(':')?;
            return Some(format!("{}.{k}", pk.trim()));
        }
    }
    Some(k.to_string())
}

fn yaml_error(path: &Path, text: &str, e: &serde_saphyr::Error) -> ConfigError {
    let loc = e.location().filter(|l| l.line() > 0);
    let line = loc.map(|l| l.line() as usize);
    let raw = e.without_snippet().to_string();
    // drop a trailing " at line X column Y" that duplicates our prefix
    let message = match raw.rfind(" at line ") {
        Some(i) if line.is_some() => raw[..i].to_string(),
        _ => raw.clone(),
    };
    let mut message = message.trim().to_string();
    // saphyr's parser-level messages say what failed, not what was wanted
    let hint = if message.starts_with("invalid floating point")
        || message.starts_with("invalid integer")
    {
        Some("expected a number")
    } else if message.starts_with("invalid i") || message.starts_with("invalid u") {
        Some("expected an integer")
    } else if message.starts_with("expected sequence start") {
        Some("expected a list of numbers, e.g. [1.0, 2.0, 3.0]")
    } else if message.starts_with("expected mapping start") {
        Some("expected `key: value` entries")
    } else {
        None
    };
    if let Some(i) = message.find(", set DuplicateKeyPolicy") {
        message.truncate(i);
    }
    if let Some(h) = hint {
        message = format!("{message} ({h})");
    }
    let key = if message.contains("missing field") {
        backticked(&message).map(|f| {
            if KF_NOISE_KEYS.contains(&f) && f != "imunoise" {
                format!("imunoise.{f}")
            } else {
                f.to_string()
            }
        })
    } else {
        line.and_then(|l| yaml_key_on_line(text, l))
    };
    let line = if message.contains("missing field") {
        None
    } else {
        line
    };
    ConfigError::new(path, line, key, message)
}
