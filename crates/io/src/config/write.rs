//! Writing a [`RunConfig`] as TOML: every key, or only the keys that loading would
//! not fill in by itself; paths absolute or relative to a directory.

use std::path::{Path, PathBuf};

use super::paths::PathWriter;
use super::root::{convert, to_raw, TomlRoot};
use super::RunConfig;

/// How [`RunConfig::to_toml_with`] writes.
#[derive(Clone, Debug, Default)]
pub struct TomlStyle {
    /// Paths under this directory are written relative to it, for a config file
    /// written into it; None = every path absolute.
    pub relative_to: Option<PathBuf>,
    /// Leave out every key (and section) whose absence loads the same configuration:
    /// the defaults, and values that follow from other keys.
    pub omit_defaults: bool,
    /// With `omit_defaults`: dotted keys (`gnss.coupling`) written all the same, for
    /// the reader.
    pub keep: Vec<String>,
}

impl RunConfig {
    /// This configuration in navfuse's TOML format, without a header comment. The
    /// numbers are in the file's units, each the value that loads back exactly where
    /// one exists (units.rs `Unit::user`).
    pub fn to_toml_with(&self, style: &TomlStyle) -> String {
        let w = PathWriter {
            relative_to: style.relative_to.clone(),
        };
        let raw = to_raw(self, &w);
        let raw = if style.omit_defaults {
            let base = style.relative_to.clone().unwrap_or_default();
            minimal(raw, &base, &style.keep)
        } else {
            raw
        };
        toml::to_string(&raw).unwrap_or_else(|e| format!("# serialization failed: {e}\n"))
    }
}

/// `raw` without the keys whose removal loads the same values, bit for bit (paths
/// resolved against `base`): each section, then each key of what stays, tried in turn.
fn minimal(raw: TomlRoot, base: &Path, keep: &[String]) -> TomlRoot {
    let Ok(mut table) = toml::Table::try_from(&raw) else {
        return raw;
    };
    // Compared as printed: bit for bit (-0.0 is not 0.0 here), which == is not.
    let load = |t: &toml::Table| {
        let r: TomlRoot = toml::Value::Table(t.clone()).try_into().ok()?;
        convert(r, base).ok().map(|c| format!("{c:?}"))
    };
    let Some(target) = load(&table) else {
        return raw;
    };
    let mut paths = Vec::new();
    key_paths(&table, &mut Vec::new(), &mut paths);
    for path in paths {
        let dotted = path.join(".");
        if keep
            .iter()
            .any(|k| *k == dotted || k.starts_with(&format!("{dotted}.")))
        {
            continue;
        }
        let mut trial = table.clone();
        if remove(&mut trial, &path) && load(&trial).as_ref() == Some(&target) {
            table = trial;
        }
    }
    toml::Value::Table(table).try_into().unwrap_or(raw)
}

/// Every key path, each table before its keys.
fn key_paths(t: &toml::Table, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    for (k, v) in t {
        prefix.push(k.clone());
        out.push(prefix.clone());
        if let toml::Value::Table(sub) = v {
            key_paths(sub, prefix, out);
        }
        prefix.pop();
    }
}

/// Remove the key at `path`; false when it is not there (its table went before).
fn remove(t: &mut toml::Table, path: &[String]) -> bool {
    match path {
        [] => false,
        [k] => t.remove(k).is_some(),
        [k, rest @ ..] => match t.get_mut(k) {
            Some(toml::Value::Table(sub)) => remove(sub, rest),
            _ => false,
        },
    }
}

impl RunConfig {
    /// This configuration as a user who gives only files, frames, lever arms, rates
    /// and the initial pose writes it: every noise key at its default (`[imu_noise]`
    /// as `imu_noise::DEFAULT_NOISE`, listed in `defaulted`, and the initial IMU error
    /// stds following it; the GNSS fix stds as the file gives them with the default
    /// error model; the odometer, NHC and ZUPT noise and the mounting and
    /// odometer-scale uncertainty at their defaults). The initial position, velocity
    /// and attitude and their stds stay (they say what the user knows of the start,
    /// not how the sensors err). The start of noise identification (`navfuse tune`)
    /// and of its benchmark.
    pub fn without_noise_model(&self) -> RunConfig {
        use navfuse_core::config::{
            FixErrorOptions, GnssOptions, NhcOptions, OdometerOptions, VehicleOptions, ZuptOptions,
        };
        let mut c = self.clone();
        let mut defaulted = Vec::new();
        let noise = super::imu_noise::convert(&Default::default(), &mut defaulted)
            .expect("the default noise model converts");
        let n = &mut c.nav;
        n.initial.imu_errors_std = noise.error_stds();
        n.imu_noise = noise;
        let g = GnssOptions::default();
        n.gnss.position_std_override = None;
        n.gnss.velocity_std_override = None;
        n.gnss.position_std_scale = g.position_std_scale;
        n.gnss.velocity_std_scale = g.velocity_std_scale;
        let fe = FixErrorOptions::default();
        n.gnss.fix_error.corr_time_s = fe.corr_time_s;
        n.gnss.fix_error.corr_fraction = fe.corr_fraction;
        let (o, h, z, v) = (
            OdometerOptions::default(),
            NhcOptions::default(),
            ZuptOptions::default(),
            VehicleOptions::default(),
        );
        n.odometer.std_mps = o.std_mps;
        n.odometer.std_speed_fraction = o.std_speed_fraction;
        n.odometer.scale_std = o.scale_std;
        n.nhc.std_mps = h.std_mps;
        n.zupt.velocity_std_mps = z.velocity_std_mps;
        n.zupt.angular_rate_std = z.angular_rate_std;
        n.vehicle.mounting_std = v.mounting_std;
        c.defaulted = defaulted;
        c
    }
}
