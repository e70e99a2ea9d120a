//! File paths: resolved against the config file's directory when read, written
//! absolute or relative to a directory.

use std::path::{Path, PathBuf};

use super::error::{kerr, KResult};

pub(super) fn resolve_path(base: &Path, s: &str) -> PathBuf {
    let p = PathBuf::from(s);
    if p.is_absolute() {
        p
    } else {
        base.join(p)
    }
}

pub(super) fn file_key(base: &Path, key: &str, s: &str) -> KResult<PathBuf> {
    if s.trim().is_empty() {
        return Err(kerr(key, "expected a file path, got an empty string"));
    }
    Ok(resolve_path(base, s))
}

/// How the writer spells paths.
#[derive(Clone, Debug, Default)]
pub(super) struct PathWriter {
    /// Paths under this directory are written relative to it (so that a config file
    /// written into it loads the same paths); None = every path absolute.
    pub(super) relative_to: Option<PathBuf>,
}

impl PathWriter {
    pub(super) fn path(&self, p: &Path) -> String {
        if let Some(rel) = self
            .relative_to
            .as_ref()
            .and_then(|d| p.strip_prefix(d).ok())
        {
            if !rel.as_os_str().is_empty() {
                return rel.to_string_lossy().into_owned();
            }
        }
        std::path::absolute(p)
            .unwrap_or_else(|_| p.to_path_buf())
            .to_string_lossy()
            .into_owned()
    }
}
