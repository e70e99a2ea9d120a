//! navfuse's errors as Python exceptions (classes in `navfuse/_errors.py`): a bad
//! input or configuration is `navfuse.InputError` (also a `ValueError`) with `file`,
//! `line` and `field`; a run that failed is `navfuse.RunError` with `result`, what
//! was computed before it failed.

use navfuse_app::Error;
use navfuse_io::config::ConfigError;
use navfuse_io::InputError;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Where an input error points.
struct Located {
    file: String,
    line: Option<usize>,
    field: Option<String>,
}

fn located(e: &Error) -> Option<Located> {
    match e {
        Error::Input(i) => Some(of_input(i)),
        Error::Config(c) => Some(of_config(c)),
        Error::Context { inner, .. } => located(inner),
        _ => None,
    }
}

fn of_input(i: &InputError) -> Located {
    Located {
        file: i.path.display().to_string(),
        line: i.line,
        field: i.field.clone(),
    }
}

fn of_config(c: &ConfigError) -> Located {
    Located {
        file: c.path.display().to_string(),
        line: c.line,
        field: c.key.clone(),
    }
}

/// An instance of `navfuse._errors.<class>` raised with `message` and keywords.
pub fn raise(py: Python<'_>, class: &str, message: String, kw: &Bound<'_, PyDict>) -> PyErr {
    let made = py
        .import("navfuse._errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call((message.clone(),), Some(kw)));
    match made {
        Ok(v) => PyErr::from_value(v),
        Err(e) => PyRuntimeError::new_err(format!("{message} (and navfuse._errors: {e})")),
    }
}

fn raise_located(
    py: Python<'_>,
    message: String,
    l: Option<Located>,
    partial: Option<Py<PyDict>>,
) -> PyErr {
    let kw = PyDict::new(py);
    let class = match l {
        Some(l) => {
            let _ = kw.set_item("file", l.file);
            let _ = kw.set_item("line", l.line);
            let _ = kw.set_item("field", l.field);
            "InputError"
        }
        None => "RunError",
    };
    if partial.is_some() {
        let _ = kw.set_item("partial", partial);
    }
    raise(py, class, message, &kw)
}

/// A run's error (`partial`: the run's collected output, when it had started).
pub fn to_py_err(py: Python<'_>, e: &Error, partial: Option<Py<PyDict>>) -> PyErr {
    raise_located(py, e.to_string(), located(e), partial)
}

/// Any error of the lower layers (anyhow chains from the simulator and batch).
pub fn to_py_err_any(py: Python<'_>, e: &anyhow::Error) -> PyErr {
    let mut l = None;
    for c in e.chain() {
        if let Some(i) = c.downcast_ref::<InputError>() {
            l = Some(of_input(i));
        } else if let Some(c) = c.downcast_ref::<ConfigError>() {
            l = Some(of_config(c));
        } else if let Some(a) = c.downcast_ref::<Error>() {
            l = located(a);
        }
        if l.is_some() {
            break;
        }
    }
    raise_located(py, format!("{e:#}"), l, None)
}

/// A bad value of an option (`outages=`, `smooth_mode=`, `formats=`): InputError
/// with the option as its field.
pub fn option_error(py: Python<'_>, option: &str, message: String) -> PyErr {
    let kw = PyDict::new(py);
    let _ = kw.set_item("field", option);
    raise(py, "InputError", format!("{option}: {message}"), &kw)
}

/// A run stopped by its stop flag (not Ctrl-C): navfuse.Interrupted.
pub fn interrupted(py: Python<'_>, message: String, partial: Option<Py<PyDict>>) -> PyErr {
    let kw = PyDict::new(py);
    let _ = kw.set_item("partial", partial);
    raise(py, "Interrupted", message, &kw)
}

/// A panic in the extension (a bug): RunError saying so.
pub fn panicked(py: Python<'_>) -> PyErr {
    raise(
        py,
        "RunError",
        "navfuse: the run panicked (a bug: please report it with the configuration)".into(),
        &PyDict::new(py),
    )
}
