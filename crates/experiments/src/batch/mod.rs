//! `navfuse batch MANIFEST`: many runs in one process, on a pool of threads.
//!
//! A [`Manifest`] (docs/CONFIG.md "Batch manifest") lists the cases: run
//! configurations, each optionally scored against a truth, or one simulator scenario
//! over many seeds. [`run_case`] runs one (simulate, navigate, score) and gives its
//! [`CaseRow`]; [`run_batch`] runs them all on `jobs` threads, rows in manifest order;
//! [`write_tables`] writes batch.csv, batch.json and batch_timing.csv.
//!
//! Determinism: a row depends on its case only, not on the thread, the process, the
//! number of jobs or whether the files are written: the figures are computed from the
//! run's records in memory (as solution.nav holds them, [`crate::track`]), the wall
//! times are kept apart ([`BatchResult::wall_s`], batch_timing.csv). Nothing on the
//! run path is shared between threads: each case has its own configuration, sink,
//! folder (or temporary folder, named uniquely within the process) and thread.

mod case;
mod manifest;
mod metrics;
mod tables;

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::Serialize;

pub use manifest::Manifest;
pub use metrics::{metric, METRICS};
pub use tables::write_tables;

use crate::pool::{run_indexed, Next};
use navfuse_app::StopFlag;

/// One case's result: the same for the same case whatever ran it (no wall time).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct CaseRow {
    /// Position in the manifest (0-based).
    pub index: usize,
    pub name: String,
    /// The simulator's seed (Monte Carlo cases).
    pub seed: Option<u64>,
    /// "completed", "unreliable" (ran, but its result is meaningless: summary.json
    /// says why) or "failed".
    pub status: String,
    /// Why it failed.
    pub error: Option<String>,
    /// Output epochs of the run (solution.nav rows).
    pub epochs: usize,
    /// The figures ([`METRICS`] order; those the case does not have are left out).
    pub metrics: Vec<(String, f64)>,
}

impl CaseRow {
    /// The value of figure `name`, when the case has it.
    pub fn metric(&self, name: &str) -> Option<f64> {
        metric(&self.metrics, name)
    }

    /// Whether the case failed (did not run to its end).
    pub fn failed(&self) -> bool {
        self.status != "completed" && self.status != "unreliable"
    }

    /// Whether the case ran but its result is unreliable.
    pub fn unreliable(&self) -> bool {
        self.status == "unreliable"
    }
}

/// What a batch gave: the rows in manifest order, each case's wall time \[s\] and the
/// whole batch's.
#[derive(Clone, Debug)]
pub struct BatchResult {
    pub rows: Vec<CaseRow>,
    pub wall_s: Vec<f64>,
    pub total_wall_s: f64,
    /// Stopped by its stop flag: Some(the signal, if one asked).
    pub interrupted: Option<Option<i32>>,
}

impl BatchResult {
    /// The number of failed cases.
    pub fn failed(&self) -> usize {
        self.rows.iter().filter(|r| r.failed()).count()
    }

    /// The number of cases that ran with an unreliable result.
    pub fn unreliable(&self) -> usize {
        self.rows.iter().filter(|r| r.unreliable()).count()
    }
}

/// Run case `index` of `m`: its files go to `out/<name>` (exactly what `navfuse run
/// --out out/<name>` writes; a Monte Carlo case's simulated data in
/// `out/<name>/sim`), or with `out` None nowhere (the simulated data in a temporary
/// folder, removed after). The row is the same either way. A failure is a row with
/// status "failed" and the error.
///
/// Panics when `index` is not below `m.len()`.
pub fn run_case(m: &Manifest, index: usize, out: Option<&Path>) -> CaseRow {
    let c = &m.cases[index];
    match case::run(c, case::case_dir(out, c).as_deref()) {
        Ok(o) => CaseRow {
            status: o.status.to_string(),
            epochs: o.epochs,
            metrics: o.metrics,
            ..bare_row(m, index, None)
        },
        Err(e) => bare_row(m, index, Some(format!("{e:#}"))),
    }
}

/// Run every case of `m` on `jobs` threads (each case on a fresh thread; `jobs` is
/// at least 1), the files into `out` as [`run_case`]. `progress`: one line on
/// stderr per finished case. Rows in manifest order; a failed case does not stop the
/// others. Errors only when `out` cannot be created.
pub fn run_batch(
    m: &Manifest,
    out: Option<&Path>,
    jobs: usize,
    progress: bool,
) -> Result<BatchResult> {
    run_batch_until(m, out, jobs, progress, &StopFlag::new())
}

/// [`run_batch`] that hands out no more cases once `stop` is set (`navfuse batch`:
/// SIGINT / SIGTERM): the cases under way finish, the others get the row "not run",
/// and [`BatchResult::interrupted`] says so.
pub fn run_batch_until(
    m: &Manifest,
    out: Option<&Path>,
    jobs: usize,
    progress: bool,
    stop: &StopFlag,
) -> Result<BatchResult> {
    if jobs == 0 {
        bail!("--jobs must be at least 1");
    }
    if let Some(o) = out {
        std::fs::create_dir_all(o).with_context(|| format!("{}: cannot create", o.display()))?;
    }
    let t0 = Instant::now();
    let n = m.len();
    let finished = AtomicUsize::new(0);
    let timed = run_indexed(
        n,
        jobs,
        |i| {
            let t = Instant::now();
            let row = run_case(m, i, out);
            (row, t.elapsed().as_secs_f64())
        },
        |i| (bare_row(m, i, Some("the case panicked".into())), f64::NAN),
        |_, (row, wall)| {
            let k = finished.fetch_add(1, Ordering::SeqCst) + 1;
            if progress {
                eprintln!("[{k}/{n}] {}", progress_line(row, *wall));
            }
            if stop.requested().is_some() {
                Next::Stop
            } else {
                Next::Continue
            }
        },
    );
    let interrupted = stop.requested();
    let not_run = if interrupted.is_some() {
        "not run: the batch was interrupted"
    } else {
        "not run"
    };
    let (rows, wall_s) = timed
        .into_iter()
        .enumerate()
        .map(|(i, r)| r.unwrap_or_else(|| (bare_row(m, i, Some(not_run.into())), f64::NAN)))
        .unzip();
    Ok(BatchResult {
        rows,
        wall_s,
        total_wall_s: t0.elapsed().as_secs_f64(),
        interrupted,
    })
}

/// The row of case `index` without figures: failed with `error`, or (None)
/// completed.
fn bare_row(m: &Manifest, index: usize, error: Option<String>) -> CaseRow {
    let c = &m.cases[index];
    CaseRow {
        index,
        name: c.name.clone(),
        seed: c.seed,
        status: if error.is_some() {
            "failed"
        } else {
            "completed"
        }
        .to_string(),
        error,
        epochs: 0,
        metrics: Vec::new(),
    }
}

/// `name: status, h RMS x m (wall s)`.
fn progress_line(row: &CaseRow, wall: f64) -> String {
    match (&row.error, row.metric("h_rms_m")) {
        (Some(e), _) => format!("{}: {}: {e} ({wall:.2} s)", row.name, row.status),
        (None, Some(h)) => format!("{}: {}, h RMS {h:.3} m ({wall:.2} s)", row.name, row.status),
        (None, None) => format!(
            "{}: {}, {} epochs, not scored ({wall:.2} s)",
            row.name, row.status, row.epochs
        ),
    }
}
