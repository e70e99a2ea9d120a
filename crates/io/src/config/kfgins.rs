//! KF-GINS YAML: its keys, their translation into navfuse's TOML sections (so one
//! conversion serves both formats), and YAML error locations.

use std::collections::BTreeMap;
use std::path::Path;

use serde::de::IgnoredAny;
use serde::Deserialize;

use super::error::{kerr, ConfigError, KResult};
use super::filter::TFilter;
use super::gnss::{TGnss, TGnssFormat};
use super::imu::{TImu, TImuFormat};
use super::imu_noise::TNoise;
use super::initial::TInitial;
use super::locate::backticked;
use super::output::TOutput;
use super::root::TomlRoot;
use super::time::TTime;
use super::values::{Gate, Num3};

/// Keys KF-GINS reads at the top level.
pub(super) const KF_TOP_KEYS: &[&str] = &[
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

pub(super) const KF_NOISE_KEYS: &[&str] =
    &["arw", "vrw", "gbstd", "abstd", "gsstd", "asstd", "corrtime"];

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

pub(super) fn toml_to_yaml_key(k: &str) -> Option<&'static str> {
    KEY_MAP.iter().find(|(t, _)| *t == k).map(|(_, y)| *y)
}

#[derive(Debug, Deserialize)]
pub(super) struct KfYaml {
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
pub(super) struct KfProbe {
    #[serde(default)]
    pub(super) imunoise: Option<BTreeMap<String, IgnoredAny>>,
    #[serde(flatten)]
    pub(super) rest: BTreeMap<String, IgnoredAny>,
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

pub(super) fn kfgins_to_raw(y: KfYaml, w: &mut Vec<String>) -> KResult<(TomlRoot, Option<String>)> {
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
            ulog_instance: None,
            files: None,
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
        baro: None,
        smoother: None,
        tuning: None,
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
            position_std_m: Some(l("initial.position_std_m", y.initposstd, w)?),
            velocity_std_mps: Some(l("initial.velocity_std_mps", y.initvelstd, w)?),
            attitude_std_deg: Some(l("initial.attitude_std_deg", y.initattstd, w)?),
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
            arw_deg_sqrth: Some(l("imu_noise.arw_deg_sqrth", n.arw, w)?),
            vrw_mps_sqrth: Some(l("imu_noise.vrw_mps_sqrth", n.vrw, w)?),
            gyro_bias_std_degph: Some(l("imu_noise.gyro_bias_std_degph", n.gbstd, w)?),
            accel_bias_std_mgal: Some(l("imu_noise.accel_bias_std_mgal", n.abstd, w)?),
            gyro_scale_std_ppm: Some(l("imu_noise.gyro_scale_std_ppm", n.gsstd, w)?),
            accel_scale_std_ppm: Some(l("imu_noise.accel_scale_std_ppm", n.asstd, w)?),
            corr_time_h: Some(n.corrtime),
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
            formats: None,
        },
    };
    Ok((raw, y.outputpath))
}

/// 1-based line of `key` (`name` or `imunoise.name`) in a block-style YAML file.
pub(super) fn yaml_line_of(text: &str, key: &str) -> Option<usize> {
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

pub(super) fn yaml_error(path: &Path, text: &str, e: &serde_saphyr::Error) -> ConfigError {
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
