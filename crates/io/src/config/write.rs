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
