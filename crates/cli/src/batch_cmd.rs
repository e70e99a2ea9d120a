//! `navfuse batch MANIFEST`: many runs in one process (`navfuse_experiments::batch`),
//! a folder per case and one table; exit status 1 when a case failed (the tables are
//! written first).

use std::path::Path;

use anyhow::{bail, Context, Result};
use navfuse_app::StopFlag;
use navfuse_experiments::batch::{run_batch_until, write_tables, Manifest};

/// `--out` when not given.
pub const DEFAULT_OUT: &str = "out/batch";

pub fn main(
    manifest: &Path,
    out: &Path,
    jobs: Option<usize>,
    tables_only: bool,
    quiet: bool,
) -> Result<()> {
    let m = Manifest::load(manifest)?;
    let jobs = match jobs {
        Some(j) => j,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    if jobs == 0 {
        bail!("--jobs must be at least 1");
    }
    // Before the runs: a folder that cannot be made is found out at once.
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    // SIGINT / SIGTERM: no more cases are started, those under way finish, and the
    // tables are written with the others "not run" (exit status 128 + signal).
    let stop = StopFlag::new();
    crate::run_cmd::install_signal_handlers(&stop)
        .context("cannot install the SIGINT/SIGTERM handlers")?;
    let r = run_batch_until(&m, (!tables_only).then_some(out), jobs, !quiet, &stop)?;
    write_tables(out, &r)?;
    let n = r.rows.len();
    if let Some(signal) = r.interrupted {
        let done = r
            .rows
            .iter()
            .filter(|x| x.error.as_deref().is_none_or(|e| !e.starts_with("not run")))
            .count();
        return Err(anyhow::Error::new(navfuse_app::Error::Interrupted(
            navfuse_app::Interrupted { signal, t: None },
        ))
        .context(format!(
            "navfuse batch stopped: {done} of {n} cases ran; the tables in {} hold them, the others \"not run\"",
            out.display()
        )));
    }
    let failed = r.failed();
    eprintln!(
        "navfuse batch: {n} cases in {:.2} s ({:.2} cases/s, {jobs} jobs); {failed} failed; tables in {}",
        r.total_wall_s,
        n as f64 / r.total_wall_s,
        out.join("batch.csv").display()
    );
    if failed > 0 {
        bail!(
            "{failed} of {n} cases failed (their errors are in {})",
            out.join("batch.csv").display()
        );
    }
    let unreliable = r.unreliable();
    if unreliable > 0 {
        // Exit status 3, as `navfuse run` with an unreliable result.
        return Err(anyhow::Error::new(navfuse_app::Unreliable {
            reasons: vec![format!(
                "{unreliable} of {n} cases ran with an unreliable result (status \"unreliable\" in {}; each case's summary.json says why)",
                out.join("batch.csv").display()
            )],
        }));
    }
    Ok(())
}
