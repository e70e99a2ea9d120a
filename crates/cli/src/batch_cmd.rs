//! `navfuse batch MANIFEST`: many runs in one process (`navfuse_experiments::batch`),
//! a folder per case and one table; exit status 1 when a case failed (the tables are
//! written first).

use std::path::Path;

use anyhow::{bail, Context, Result};
use navfuse_experiments::batch::{run_batch, write_tables, Manifest};

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
    let r = run_batch(&m, (!tables_only).then_some(out), jobs, !quiet)?;
    write_tables(out, &r)?;
    let n = r.rows.len();
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
    Ok(())
}
