//! `navfuse report`: one self-contained HTML page (inline SVG, inline style and
//! script, nothing fetched) for a finished run, and the same figures as standalone
//! SVG files. Plots are drawn with plotters' SVG backend (chart.rs) from a run
//! directory thinned as it is read (run_dir.rs) and decimated per chart
//! (decimate.rs); figures.rs says what is drawn, html.rs lays the page out.
//!
//! Layering: reads navfuse-io formats and scores with navfuse-core's `eval`; the
//! truth comes in as trajectory points (the CLI reads its format).

pub mod allan;
pub mod chart;
pub mod decimate;
pub mod figures;
pub mod html;
pub mod run_dir;

use navfuse_core::eval::TrajPoint;
use std::path::{Path, PathBuf};

/// What went wrong, with the file (and line) it concerns.
#[derive(Clone, Debug, PartialEq)]
pub struct Error(pub String);

impl Error {
    pub fn new(m: impl Into<String>) -> Self {
        Error(m.into())
    }
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

/// A reference trajectory to score against.
#[derive(Clone, Debug)]
pub struct Truth {
    /// Its file, for the page.
    pub path: PathBuf,
    /// Sorted by time (GPS seconds of week, as the solution).
    pub points: Vec<TrajPoint>,
    /// Body-frame point to move the solution to before comparing (the antenna, for
    /// an antenna track) \[m\].
    pub lever_arm_b: Option<nalgebra::Vector3<f64>>,
}

/// At most this many reference epochs are scored (every k-th beyond).
pub const SCORED_EPOCHS: usize = 50_000;

/// One figure: its file name (for `--svg DIR`), section, caption and SVG text.
#[derive(Clone, Debug)]
pub struct Figure {
    pub name: String,
    pub section: &'static str,
    pub caption: String,
    pub svg: String,
}

/// A table for the page: caption, header and rows (already formatted).
#[derive(Clone, Debug, Default)]
pub struct Table {
    pub section: &'static str,
    pub caption: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// The report of one run.
#[derive(Clone, Debug)]
pub struct Report {
    pub title: String,
    pub figures: Vec<Figure>,
    pub tables: Vec<Table>,
    /// Things the page should say first (no truth, thinned, missing files).
    pub notes: Vec<String>,
    pub config: Option<String>,
    pub events: Vec<String>,
    pub summary: Option<serde_json::Value>,
}

impl Report {
    /// The page.
    pub fn html(&self) -> String {
        html::page(self)
    }

    /// Write every figure as `DIR/NAME.svg`; returns the files.
    pub fn write_svgs(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        std::fs::create_dir_all(dir)
            .map_err(|e| Error::new(format!("cannot create {}: {e}", dir.display())))?;
        let mut files = Vec::new();
        for f in &self.figures {
            let p = dir.join(format!("{}.svg", f.name));
            std::fs::write(&p, &f.svg)
                .map_err(|e| Error::new(format!("cannot write {}: {e}", p.display())))?;
            files.push(p);
        }
        Ok(files)
    }
}

/// Read the run in `dir`, score it against `truth` when given, and draw it.
pub fn build(dir: &Path, truth: Option<&Truth>) -> Result<Report, Error> {
    let score_t: Vec<f64> = match truth {
        Some(t) => {
            let k = t.points.len().div_ceil(SCORED_EPOCHS).max(1);
            t.points.iter().step_by(k).map(|p| p.t).collect()
        }
        None => Vec::new(),
    };
    let run = run_dir::read_run(dir, &score_t)?;
    figures::draw(&run, truth)
}
