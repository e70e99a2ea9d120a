//! Where an experiment puts the simulated data: the `--keep` directory, or a
//! temporary directory removed when the experiment ends (however it ends).

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

pub(crate) struct WorkDir {
    dir: PathBuf,
    /// `--keep`: the directory stays, and the runs' files are written into it.
    keep: bool,
}

impl WorkDir {
    /// `keep`, or a new temporary directory named after `what`, the process and a
    /// number counted in the process (so that threads of one process running at once
    /// each get their own).
    pub fn new(keep: Option<PathBuf>, what: &str) -> Result<WorkDir> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let w = match keep {
            Some(dir) => WorkDir { dir, keep: true },
            None => {
                let n = NEXT.fetch_add(1, Ordering::Relaxed);
                let name = format!("navfuse-{what}-{}-{n}", std::process::id());
                WorkDir {
                    dir: std::env::temp_dir().join(name),
                    keep: false,
                }
            }
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
