//! `navfuse export RUN_DIR --formats ...`: the exports of a finished run, from its
//! `solution.nav` (or `smoothed.nav`) and, when present, the matching std file for
//! the `.pos` standard deviations and the CSV for the NMEA quality (integrity flag,
//! solution state).

use crate::error::Error;
use navfuse_core::SolutionState;
use navfuse_io::export::ExportFormat;
use navfuse_io::nav::{read_nav, SolutionRecord};
use navfuse_io::InputError;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// KF-GINS STD file: time -> position N E D 1-sigma \[m\] (None when absent).
fn read_pos_std(path: &Path) -> Result<Option<HashMap<i64, [f64; 3]>>, Error> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(None);
    };
    let mut m = HashMap::new();
    for (i, l) in text.lines().enumerate() {
        if l.starts_with('#') || l.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = l
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        if v.len() < 4 {
            return Err(Error::Other(format!(
                "{}:{}: expected at least 4 numeric columns (t and the position std), got {}",
                path.display(),
                i + 1,
                v.len()
            )));
        }
        m.insert((v[0] * 1e6).round() as i64, [v[1], v[2], v[3]]);
    }
    Ok(Some(m))
}

/// The per-epoch flags of `STEM.csv` (time -> integrity flag, solution state), when
/// the file is there and has those columns.
type Flags = HashMap<i64, (Option<u8>, Option<SolutionState>)>;

fn read_csv_flags(path: &Path) -> Result<Option<Flags>, Error> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(None);
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |name: &str| header.iter().position(|h| h.trim() == name);
    let (Some(t_col), integrity_col, state_col) = (col("t_s"), col("gnss_integrity"), col("state"))
    else {
        return Ok(None);
    };
    if integrity_col.is_none() && state_col.is_none() {
        return Ok(None);
    }
    let mut m = HashMap::new();
    for (i, l) in lines.enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        let bad = |what: &str| {
            Error::Other(format!(
                "{}:{}: field {what}: expected {} comma-separated fields as in the header",
                path.display(),
                i + 2,
                header.len()
            ))
        };
        let t: f64 = f
            .get(t_col)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| bad("t_s"))?;
        let integrity = integrity_col
            .and_then(|c| f.get(c))
            .and_then(|v| v.parse().ok());
        let state = state_col
            .and_then(|c| f.get(c))
            .and_then(|v| SolutionState::from_name(v.trim()));
        m.insert((t * 1e6).round() as i64, (integrity, state));
    }
    Ok(Some(m))
}

/// Write `formats` for the run in `dir` (`stem` "solution" or "smoothed") into the
/// same directory; returns the files written.
pub fn export_run(dir: &Path, stem: &str, formats: &[ExportFormat]) -> Result<Vec<PathBuf>, Error> {
    let nav_path = dir.join(format!("{stem}.nav"));
    let nav = read_nav(&nav_path)?;
    if nav.is_empty() {
        return Err(Error::Other(format!(
            "{}: no epochs to export",
            nav_path.display()
        )));
    }
    let std_name = if stem == "solution" {
        "std.txt".to_string()
    } else {
        format!("{stem}_std.txt")
    };
    let std = read_pos_std(&dir.join(std_name))?;
    let flags = read_csv_flags(&dir.join(format!("{stem}.csv")))?;
    let mut files = Vec::new();
    let mut writers = Vec::new();
    for f in formats {
        let p = dir.join(f.file_name(stem));
        writers.push(f.create(&p)?);
        files.push(p);
    }
    for (week, n) in &nav {
        let sd = std
            .as_ref()
            .and_then(|m| m.get(&((n.t * 1e6).round() as i64)).copied());
        let mut s = [0.0; 21];
        if let Some(p) = sd {
            s[..3].copy_from_slice(&p);
        }
        let (gnss_integrity, state) = flags
            .as_ref()
            .and_then(|m| m.get(&((n.t * 1e6).round() as i64)).copied())
            .unwrap_or((None, None));
        let rec = SolutionRecord {
            gps_week: *week,
            nav: *n,
            imu_errors: Default::default(),
            std: sd.map(|_| s),
            gnss_integrity,
            state,
        };
        for w in writers.iter_mut() {
            w.write_record(&rec)?;
        }
    }
    let mut err: Option<InputError> = None;
    for w in writers {
        if let Err(e) = w.finish_boxed() {
            err.get_or_insert(e);
        }
    }
    match err {
        Some(e) => Err(e.into()),
        None => Ok(files),
    }
}
