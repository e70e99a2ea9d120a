//! `navfuse.batch*`: `navfuse batch` from Python, and one case at a time for the
//! schedulers (Dask, Ray, Slurm): the same `navfuse_experiments::batch::run_case`, so a
//! row is the same whoever computes it.

use crate::detached;
use crate::errors::to_py_err_any;
use navfuse_app::StopFlag;
use navfuse_experiments::batch::{
    run_batch_until, run_case, write_tables, CaseRow, Manifest, METRICS,
};
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule};
use std::path::PathBuf;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(batch_cases, m)?)?;
    m.add_function(wrap_pyfunction!(batch_case, m)?)?;
    m.add_function(wrap_pyfunction!(batch, m)?)?;
    Ok(())
}

fn load(py: Python<'_>, manifest: &PathBuf) -> PyResult<Manifest> {
    Manifest::load(manifest).map_err(|e| to_py_err_any(py, &e))
}

/// A row as batch.csv has it: index, name, seed, status, epochs, every figure of
/// METRICS (NaN where the case has none), error.
fn row_to_py(py: Python<'_>, r: &CaseRow) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    d.set_item("index", r.index)?;
    d.set_item("name", &r.name)?;
    d.set_item("seed", r.seed)?;
    d.set_item("status", &r.status)?;
    d.set_item("epochs", r.epochs)?;
    for (m, _) in METRICS {
        d.set_item(m, r.metric(m).unwrap_or(f64::NAN))?;
    }
    d.set_item("error", r.error.as_deref())?;
    Ok(d.unbind())
}

/// The case names of a manifest, in order.
#[pyfunction]
fn batch_cases(py: Python<'_>, manifest: PathBuf) -> PyResult<Vec<String>> {
    Ok(load(py, &manifest)?.case_names())
}

/// One case (`out`: the batch folder; its run goes to out/<name>).
#[pyfunction]
#[pyo3(signature = (manifest, index, out=None))]
fn batch_case(
    py: Python<'_>,
    manifest: PathBuf,
    index: usize,
    out: Option<PathBuf>,
) -> PyResult<Py<PyDict>> {
    let m = load(py, &manifest)?;
    if index >= m.len() {
        return Err(PyIndexError::new_err(format!(
            "{}: case {index} asked for, the manifest has {} (0 .. {})",
            manifest.display(),
            m.len(),
            m.len().saturating_sub(1)
        )));
    }
    // On a fresh thread, as navfuse batch runs each case (see crate::detached).
    let stop = StopFlag::new();
    let (row, signal) = detached(py, &stop, || run_case(&m, index, out.as_deref()))?;
    if let Some(sig) = signal {
        return Err(sig);
    }
    row_to_py(py, &row)
}

/// Every case on `jobs` threads (0: the CPUs this process may use); with `out`, the case folders and the tables
/// (batch.csv, batch.json, batch_timing.csv). Returns (rows, wall_s, total_wall_s).
#[pyfunction]
#[pyo3(signature = (manifest, out=None, jobs=0, progress=false))]
fn batch(
    py: Python<'_>,
    manifest: PathBuf,
    out: Option<PathBuf>,
    jobs: usize,
    progress: bool,
) -> PyResult<(Vec<Py<PyDict>>, Vec<f64>, f64)> {
    let m = load(py, &manifest)?;
    // 0: as many as the CLI's default (the CPUs this process may use).
    let jobs = match jobs {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    let stop = StopFlag::new();
    let (r, signal) = detached(py, &stop, || -> anyhow::Result<_> {
        let r = run_batch_until(&m, out.as_deref(), jobs, progress, &stop)?;
        if let Some(o) = &out {
            write_tables(o, &r)?;
        }
        Ok(r)
    })?;
    let r = r.map_err(|e| to_py_err_any(py, &e))?;
    let rows: Vec<Py<PyDict>> = r
        .rows
        .iter()
        .map(|x| row_to_py(py, x))
        .collect::<PyResult<_>>()?;
    if let Some(sig) = signal {
        // Ctrl-C: no more cases were started; KeyboardInterrupt with the rows (the
        // others "not run"), once the tables are written.
        sig.value(py)
            .setattr("result", (rows, r.wall_s, r.total_wall_s))?;
        return Err(sig);
    }
    Ok((rows, r.wall_s, r.total_wall_s))
}
