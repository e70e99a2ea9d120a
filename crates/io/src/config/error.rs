//! The configuration error: which file, where, which key, and what was expected; and
//! the key-level error the section conversions return before the line is known.

use std::fmt;
use std::path::{Path, PathBuf};

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
    pub(super) fn new(
        path: &Path,
        line: Option<usize>,
        key: Option<String>,
        message: String,
    ) -> Self {
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
pub(super) struct KeyErr {
    pub(super) key: String,
    pub(super) msg: String,
}

pub(super) type KResult<T> = Result<T, KeyErr>;

pub(super) fn kerr(key: &str, msg: impl Into<String>) -> KeyErr {
    KeyErr {
        key: key.to_string(),
        msg: msg.into(),
    }
}
