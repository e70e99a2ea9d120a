//! What reading an IMU file found: the report and its warnings.

use super::MAX_DT_S;
use crate::input::GapPolicy;
use std::fmt;
use std::path::PathBuf;

/// What happened while reading an IMU file. Complete once the reader is exhausted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImuReport {
    /// The file.
    pub path: PathBuf,
    /// Lines read (all lines, including headers and blank lines).
    pub lines: usize,
    /// Samples returned.
    pub samples: usize,
    /// Header lines (`skip_lines`), blank lines and `#` / `%` comment lines.
    pub skipped_lines: usize,
    /// Truncated first / last lines skipped (rtklibexplorer logs).
    pub truncated_lines: usize,
    /// Samples dropped because their time tag equals the previous one.
    pub duplicates: usize,
    /// The first few (at most [`MAX_DUPLICATE_TIMES`](super::MAX_DUPLICATE_TIMES)) duplicate time tags \[s\].
    pub duplicate_times: Vec<f64>,
    /// Intervals (t_{k-1}, t_k) longer than 1.5 / rate_hz \[s\].
    pub gaps: Vec<(f64, f64)>,
    /// Nominal sample interval 1 / rate_hz \[s\].
    pub nominal_dt: f64,
    /// Time tag of the first sample read (after the offset) \[s\].
    pub first_t: Option<f64>,
    /// Time tag of the last sample read \[s\].
    pub last_t: Option<f64>,
    /// What was done with intervals longer than [`MAX_DT_S`].
    pub gap_policy: GapPolicy,
    /// Findings that did not stop the read: a damaged last line dropped, gaps bridged.
    pub warnings: Vec<String>,
    /// What the source was read from, when more than the file (UBX: message kind and
    /// time mapping).
    pub source_note: Option<String>,
}

impl fmt::Display for ImuReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} lines, {} samples",
            self.path.display(),
            self.lines,
            self.samples
        )?;
        if let (Some(a), Some(b)) = (self.first_t, self.last_t) {
            write!(f, " from t = {a:.3} to {b:.3} s ({:.3} s)", b - a)?;
        }
        if self.skipped_lines > 0 {
            write!(
                f,
                "; {} header/blank/comment lines skipped",
                self.skipped_lines
            )?;
        }
        if self.truncated_lines > 0 {
            write!(
                f,
                "; {} truncated first/last lines skipped",
                self.truncated_lines
            )?;
        }
        if self.duplicates > 0 {
            write!(
                f,
                "; {} samples with a repeated time tag dropped (first at",
                self.duplicates
            )?;
            for (k, t) in self.duplicate_times.iter().enumerate() {
                write!(f, "{}{t:.3}", if k == 0 { " " } else { ", " })?;
            }
            if self.duplicates > self.duplicate_times.len() {
                f.write_str(", ...")?;
            }
            f.write_str(" s)")?;
        } else {
            f.write_str("; no duplicate time tags")?;
        }
        if self.gaps.is_empty() {
            write!(
                f,
                "; no gaps longer than {:.1} ms",
                1500.0 * self.nominal_dt
            )?;
        } else {
            let longest = self.gaps.iter().copied().fold((0.0, 0.0), |acc, g| {
                if g.1 - g.0 > acc.1 - acc.0 {
                    g
                } else {
                    acc
                }
            });
            let over = self.gaps.iter().filter(|g| g.1 - g.0 > MAX_DT_S).count();
            write!(
                f,
                "; {} gaps longer than {:.1} ms (nominal {:.1} ms), longest {:.3} s from \
                 t = {:.3}",
                self.gaps.len(),
                1500.0 * self.nominal_dt,
                1000.0 * self.nominal_dt,
                longest.1 - longest.0,
                longest.0
            )?;
            if over > 0 {
                match self.gap_policy {
                    GapPolicy::Nominal => {
                        write!(f, "; {over} longer than {MAX_DT_S} s use dt = 1/rate")?
                    }
                    GapPolicy::Bridge { .. } => write!(
                        f,
                        "; {over} longer than {MAX_DT_S} s bridged with dt = the real interval"
                    )?,
                }
            }
        }
        f.write_str(".")?;
        if let Some(n) = &self.source_note {
            write!(f, " {n}.")?;
        }
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        Ok(())
    }
}

/// How many bridged gaps a warning lists.
const MAX_LISTED_GAPS: usize = 5;

impl ImuReport {
    /// The warning listing the gaps bridged (longer than [`MAX_DT_S`]), if any.
    pub(super) fn bridged_gaps_warning(&self) -> Option<String> {
        let long: Vec<&(f64, f64)> = self.gaps.iter().filter(|g| g.1 - g.0 > MAX_DT_S).collect();
        if long.is_empty() || self.gap_policy == GapPolicy::Nominal {
            return None;
        }
        let mut w = format!(
            "{}: {} gaps longer than {MAX_DT_S} s bridged by dead reckoning over their real \
             length (imu.gap_policy = \"bridge\"):",
            self.path.display(),
            long.len()
        );
        for (k, g) in long.iter().take(MAX_LISTED_GAPS).enumerate() {
            let sep = if k == 0 { " " } else { ", " };
            w.push_str(&format!("{sep}{:.3} s from t = {:.3}", g.1 - g.0, g.0));
        }
        if long.len() > MAX_LISTED_GAPS {
            w.push_str(", ...");
        }
        Some(w)
    }
}
