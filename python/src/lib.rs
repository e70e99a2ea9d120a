//! `navfuse._navfuse`: the Rust side of the Python package. Every function takes
//! plain values (paths, TOML text, arrays) and returns dicts of columns; the Python
//! side (`navfuse/__init__.py`) makes the DataFrames and the result objects. Runs
//! release the GIL; errors become `navfuse.InputError` (with `file`, `line`, `field`)
//! or `navfuse.NavfuseError`.

mod batch;
mod collect;
mod errors;
mod frame;
mod readers;

use collect::{CollectSink, Collected};
use errors::{to_py_err, to_py_err_any};
use frame::Frame;
use navfuse_app::{FileSink, RunOptions, RunOverrides, StopFlag};
use navfuse_io::config::{self, RunConfig};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Read a configuration: `kind` "path" (a .toml or KF-GINS .yaml file), "toml" or
/// "yaml" (text; relative paths against `base_dir`, which names it in errors).
fn load_config(kind: &str, value: &str, base_dir: &Path) -> Result<RunConfig, navfuse_app::Error> {
    let named = |ext: &str| base_dir.join(format!("<config {ext}>"));
    Ok(match kind {
        "path" => config::load(Path::new(value))?,
        "yaml-path" => config::load_kfgins_yaml(Path::new(value))?,
        "toml" => config::parse_toml_str(value, &named("text"))?,
        "yaml" => config::parse_kfgins_yaml_str(value, &named("yaml"))?,
        k => {
            return Err(navfuse_app::Error::Other(format!(
                "unknown config kind '{k}'"
            )))
        }
    })
}

/// Run `f` without the GIL on a fresh thread of its own (as navfuse batch runs each
/// case: faer's AVX kernels leave a thread's upper vector state dirty, which slows
/// later SSE code in it; navfuse_experiments pool.rs), checking Python's signals every
/// 50 ms: Ctrl-C sets `stop` (the run ends cleanly, its output kept) and is raised
/// once the run has ended.
fn detached<T: Send>(
    py: Python<'_>,
    stop: &StopFlag,
    f: impl FnOnce() -> T + Send,
) -> PyResult<(T, Option<PyErr>)> {
    std::thread::scope(|s| {
        let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
        let h = s.spawn(move || {
            let v = f();
            let _ = done_tx.send(());
            v
        });
        let mut signal: Option<PyErr> = None;
        let mut rx = done_rx;
        loop {
            // The receiver moves into the GIL-free closure and back (it is not Sync).
            let (back, waited) = py.detach(move || {
                let w = rx.recv_timeout(Duration::from_millis(50));
                (rx, w)
            });
            rx = back;
            if !matches!(waited, Err(std::sync::mpsc::RecvTimeoutError::Timeout)) {
                break; // done, or the thread ended without sending (a panic)
            }
            if signal.is_none() {
                if let Err(e) = py.check_signals() {
                    stop.atomic().store(2, std::sync::atomic::Ordering::SeqCst);
                    signal = Some(e);
                }
            }
        }
        match h.join() {
            Ok(v) => Ok((v, signal)),
            Err(_) => Err(errors::panicked(py)),
        }
    })
}

/// Everything a run returns to Python.
fn collected_to_py(py: Python<'_>, c: Collected) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    let frame =
        |f: Option<Frame>| -> PyResult<Option<Py<PyDict>>> { f.map(|f| f.into_py(py)).transpose() };
    d.set_item("solution", frame(c.solution.map(|s| s.frame()))?)?;
    d.set_item("imu_errors", frame(c.imu_errors.map(|s| s.frame()))?)?;
    d.set_item("states", frame(c.states.map(|s| s.frame))?)?;
    d.set_item("smoothed", frame(c.smoothed.map(|s| s.frame()))?)?;
    d.set_item(
        "smoothed_states",
        frame(c.smoothed_states.map(|s| s.frame))?,
    )?;
    d.set_item("innovations", c.innovations.frame().into_py(py)?)?;
    d.set_item("summary_json", c.summary_json)?;
    d.set_item("events_log", c.events_log)?;
    Ok(d.unbind())
}

/// `navfuse.run`: see navfuse/__init__.py.
#[pyfunction]
#[pyo3(signature = (kind, value, base_dir, out=None, outages=None, smooth=false, smooth_mode=None, formats=None))]
#[allow(clippy::too_many_arguments)]
fn run(
    py: Python<'_>,
    kind: &str,
    value: &str,
    base_dir: PathBuf,
    out: Option<PathBuf>,
    outages: Option<String>,
    smooth: bool,
    smooth_mode: Option<String>,
    formats: Option<String>,
) -> PyResult<(Py<PyDict>, Vec<String>)> {
    // The options first: a bad value is the caller's InputError, naming the option.
    if let Some(m) = smooth_mode
        .as_deref()
        .filter(|m| !matches!(*m, "rts" | "combined"))
    {
        return Err(errors::option_error(
            py,
            "smooth_mode",
            format!("expected \"rts\" or \"combined\", found \"{m}\""),
        ));
    }
    if let Some(o) = &outages {
        navfuse_core::outage::OutageSchedule::parse(o)
            .map_err(|e| errors::option_error(py, "outages", e.to_string()))?;
    }
    if let Some(f) = &formats {
        navfuse_io::export::ExportFormat::parse_list(f)
            .map_err(|e| errors::option_error(py, "formats", e.to_string()))?;
    }
    let stop = StopFlag::new();
    let stop_run = stop.clone();
    let work =
        move || -> Result<(Collected, Vec<String>), (navfuse_app::Error, Option<Collected>)> {
            let mut cfg = load_config(kind, value, &base_dir).map_err(|e| (e, None))?;
            let warnings = cfg.warnings.clone();
            RunOverrides {
                outages,
                smooth,
                smooth_mode,
                formats,
                ..Default::default()
            }
            .apply(&mut cfg)
            .map_err(|e| (e, None))?;
            let files = match &out {
                Some(dir) => Some(FileSink::create(dir).map_err(|e| (e, None))?),
                None => None,
            };
            let mut sink = CollectSink::new(files);
            let opts = RunOptions {
                stop: Some(stop_run),
                ..Default::default()
            };
            match navfuse_app::run(cfg, &mut sink, &opts) {
                Ok(_) => Ok((sink.out, warnings)),
                Err(e) => Err((e, Some(sink.out))),
            }
        };
    let (r, signal) = detached(py, &stop, work)?;
    // Ctrl-C: KeyboardInterrupt once the run has stopped, carrying what was computed
    // (also when the run had got past its last stop check and completed).
    let with_result = |sig: PyErr, partial: Option<Py<PyDict>>| -> PyResult<PyErr> {
        sig.value(py).setattr("result", partial)?;
        Ok(sig)
    };
    match r {
        Ok((c, warnings)) => {
            let d = collected_to_py(py, c)?;
            match signal {
                Some(sig) => Err(with_result(sig, Some(d))?),
                None => Ok((d, warnings)),
            }
        }
        Err((e, partial)) => {
            let partial = partial.map(|c| collected_to_py(py, c)).transpose()?;
            match signal {
                Some(sig) if e.interrupted().is_some() => Err(with_result(sig, partial)?),
                _ if e.interrupted().is_some() => {
                    Err(errors::interrupted(py, e.to_string(), partial))
                }
                _ => Err(to_py_err(py, &e, partial)),
            }
        }
    }
}

/// `navfuse.simulate`: generate into `out`; returns sim_summary.json's text.
#[pyfunction]
#[pyo3(signature = (kind, value, base_dir, out, seed=None))]
fn simulate(
    py: Python<'_>,
    kind: &str,
    value: &str,
    base_dir: PathBuf,
    out: PathBuf,
    seed: Option<u64>,
) -> PyResult<String> {
    use navfuse_sim::scenario::Scenario;
    let stop = StopFlag::new();
    let work = || -> anyhow::Result<String> {
        let mut sc = match kind {
            "path" => Scenario::load(Path::new(value))?,
            _ => Scenario::from_text(&base_dir.join("<scenario text>"), value.to_string())?,
        };
        if let Some(s) = seed {
            sc.file.seed = s;
        }
        let summary = navfuse_sim::generate::generate(&sc, &out)?;
        let json = serde_json::to_string_pretty(&summary)? + "\n";
        std::fs::write(out.join("sim_summary.json"), &json)?;
        Ok(json)
    };
    let (r, signal) = detached(py, &stop, work)?;
    if let Some(sig) = signal {
        return Err(sig);
    }
    r.map_err(|e| to_py_err_any(py, &e))
}

/// The Python module.
#[pymodule]
fn _navfuse(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    readers::register(m)?;
    batch::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
