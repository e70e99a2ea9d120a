//! `navfuse allan`: the Allan deviation of an IMU file, read by the reader of
//! `navfuse run` (`navfuse_io::imu`, every format and option of `[imu]`), computed by
//! `navfuse_core::allan::imu`.
//!
//! The increments as the reader gives them (body frame, SI) are analysed at one
//! interval, the mean interval of the record (the first sample, whose interval is
//! the nominal one by convention, is left out). Gaps break the Allan deviation's
//! assumption of uniform sampling; they are reported as warnings.

use std::path::Path;

use navfuse_core::allan::imu::ImuAllan;
use navfuse_io::imu::{open_imu, ImuReport};
use navfuse_io::input::ImuSource;

use crate::Error;

/// The analysis with what reading found.
#[derive(Clone, Debug)]
pub struct AllanRun {
    pub allan: ImuAllan,
    /// The reader's report (samples, gaps, time span).
    pub report: ImuReport,
    /// Findings that do not stop the analysis (gaps, an interval off the nominal one).
    pub warnings: Vec<String>,
}

/// Fewest samples to analyse (a few clusters at the shortest tau).
pub const MIN_SAMPLES: usize = 20;
/// Samples read to measure the rate ([`measured_rate_hz`]).
const RATE_PROBE: usize = 1000;

/// The sample rate of `src`'s file from the median interval of its first samples
/// (`src.rate_hz` only serves the reader's first interval).
pub fn measured_rate_hz(src: &ImuSource) -> Result<f64, Error> {
    let mut t = Vec::with_capacity(RATE_PROBE);
    for s in open_imu(src)?.take(RATE_PROBE) {
        t.push(s?.t);
    }
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return Err(too_few(&src.path, t.len()));
    }
    d.sort_by(f64::total_cmp);
    Ok(1.0 / d[d.len() / 2])
}

fn too_few(path: &Path, n: usize) -> Error {
    Error::Other(format!(
        "{}: {n} IMU samples: the Allan deviation needs at least {MIN_SAMPLES}",
        path.display()
    ))
}

/// Read every sample of `src` and compute the Allan deviation of its six axes.
pub fn allan_of_imu(src: &ImuSource) -> Result<AllanRun, Error> {
    let mut reader = open_imu(src)?;
    let mut ch: [Vec<f64>; 6] = Default::default();
    let (mut t_first, mut t_last) = (None, 0.0);
    for s in reader.by_ref() {
        let s = s?;
        // The first sample's interval is the nominal one by convention: skip it.
        if t_first.is_none() {
            t_first = Some(s.t);
            continue;
        }
        for i in 0..3 {
            ch[i].push(s.dtheta[i]);
            ch[3 + i].push(s.dvel[i]);
        }
        t_last = s.t;
    }
    let report = reader.report().clone();
    let n = ch[0].len();
    if n < MIN_SAMPLES {
        return Err(too_few(&src.path, report.samples));
    }
    let dt = (t_last - t_first.unwrap_or(t_last)) / n as f64;
    let mut warnings = report.warnings.clone();
    if !report.gaps.is_empty() {
        warnings.push(format!(
            "{}: {} gap(s) longer than 1.5 sample intervals (first at t = {:.3} s): the Allan \
             deviation assumes uniform sampling",
            src.path.display(),
            report.gaps.len(),
            report.gaps[0].0
        ));
    }
    let nominal = 1.0 / src.rate_hz;
    if ((dt - nominal) / nominal).abs() > 0.01 {
        warnings.push(format!(
            "{}: the mean interval {dt:.6} s is {:+.1} % off the nominal 1 / rate_hz = {nominal:.6} \
             s; the analysis uses the mean interval",
            src.path.display(),
            100.0 * (dt - nominal) / nominal
        ));
    }
    Ok(AllanRun {
        allan: ImuAllan::from_increments(&ch, dt),
        report,
        warnings,
    })
}
