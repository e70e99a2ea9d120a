//! Where an experiment puts the simulated data: the `--keep` directory, or a
//! temporary directory removed when the experiment ends (however it ends).

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

pub(crate) struct WorkDir {
    dir: PathBuf,
    /// `--keep`: the directory stays, and the runs' files are written into it.
    keep: bool,
}

impl WorkDir {
    /// `keep`, or a new temporary directory named after `what` and the process.
    pub fn new(keep: Option<PathBuf>, what: &str) -> Result<WorkDir> {
        let w = match keep {
            Some(dir) => WorkDir { dir, keep: true },
            None => WorkDir {
                dir: std::env::temp_dir().join(format!("navfuse-{what}-{}", std::process::id())),
                keep: false,
            },
        };
        std::fs::create_dir_all(&w.dir)
            .with_context(|| format!("{}: cannot create", w.dir.display()))?;
        Ok(w)
    }

    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Whether this is the `--keep` directory.
    pub fn keep(&self) -> bool {
        self.keep
    }

    /// `dir`, when the runs' files are kept (`--keep`): where a run writes them.
    pub fn kept<'a>(&self, dir: &'a Path) -> Option<&'a Path> {
        self.keep.then_some(dir)
    }
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}
