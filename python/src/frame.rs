//! Columns of a table, built in Rust and handed to Python as a dict of NumPy arrays
//! (`navfuse/__init__.py` makes the DataFrame). Column names carry their units
//! (`lat_deg`, `vn_mps`), as in the CSV files navfuse writes.

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// One column's values.
pub enum Col {
    F64(Vec<f64>),
    /// Integers; a missing value makes the column float64 with NaN (as pandas reads a
    /// CSV column with empty fields).
    I64(Vec<Option<i64>>),
    /// Text; missing values are None (pandas' str dtype shows them as NaN).
    Str(Vec<Option<&'static str>>),
    Text(Vec<String>),
}

/// Named columns in order.
#[derive(Default)]
pub struct Frame {
    cols: Vec<(String, Col)>,
}

impl Frame {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn f64(&mut self, name: &str) -> usize {
        self.add(name, Col::F64(Vec::new()))
    }
    pub fn i64(&mut self, name: &str) -> usize {
        self.add(name, Col::I64(Vec::new()))
    }
    pub fn text(&mut self, name: &str) -> usize {
        self.add(name, Col::Text(Vec::new()))
    }
    fn add(&mut self, name: &str, c: Col) -> usize {
        self.cols.push((name.to_string(), c));
        self.cols.len() - 1
    }

    /// Whole columns.
    pub fn add_f64(&mut self, name: &str, v: Vec<f64>) {
        self.add(name, Col::F64(v));
    }
    pub fn add_i64(&mut self, name: &str, v: Vec<Option<i64>>) {
        self.add(name, Col::I64(v));
    }
    pub fn add_str(&mut self, name: &str, v: Vec<Option<&'static str>>) {
        self.add(name, Col::Str(v));
    }

    pub fn push_f64(&mut self, k: usize, v: f64) {
        if let Some((_, Col::F64(c))) = self.cols.get_mut(k) {
            c.push(v);
        }
    }
    pub fn push_i64(&mut self, k: usize, v: Option<i64>) {
        if let Some((_, Col::I64(c))) = self.cols.get_mut(k) {
            c.push(v);
        }
    }
    pub fn push_text(&mut self, k: usize, v: String) {
        if let Some((_, Col::Text(c))) = self.cols.get_mut(k) {
            c.push(v);
        }
    }

    /// `{name: array}` in column order (NumPy float64 / int64 arrays, lists of str).
    pub fn into_py(self, py: Python<'_>) -> PyResult<Py<PyDict>> {
        let d = PyDict::new(py);
        for (name, col) in self.cols {
            match col {
                Col::F64(v) => d.set_item(name, v.into_pyarray(py))?,
                Col::I64(v) => {
                    if v.iter().all(Option::is_some) {
                        let v: Vec<i64> = v.into_iter().flatten().collect();
                        d.set_item(name, v.into_pyarray(py))?;
                    } else {
                        let v: Vec<f64> = v
                            .into_iter()
                            .map(|x| x.map_or(f64::NAN, |x| x as f64))
                            .collect();
                        d.set_item(name, v.into_pyarray(py))?;
                    }
                }
                Col::Str(v) => d.set_item(name, PyList::new(py, v)?)?,
                Col::Text(v) => d.set_item(name, PyList::new(py, v)?)?,
            }
        }
        Ok(d.unbind())
    }
}
