//! One expectation step of the noise identification: a forward run that records for
//! the smoother and logs its applied updates, then the RTS backward pass with the
//! statistics of navfuse_core::smoother::em (the smoothed residual of every update,
//! the expected process noise per state against its Q).

use crate::error::Error;
use crate::smooth::codec;
use crate::smooth::spill::Spill;
use navfuse_core::config::NavConfig;
use navfuse_core::smoother::em::{FusedUpdate, ProcessNoiseStats, SmoothedResidual};
use navfuse_core::smoother::rts::{Gain, GainMaker};
use navfuse_core::smoother::{RtsBackward, RtsRecord};
use navfuse_core::state::{Block, StateLayout};
use navfuse_core::{ImuSample, Measurement, RunSummary, SourceFactory};
use std::path::Path;

/// Batch-means blocks per run for the standard errors.
pub(crate) const BLOCKS: f64 = 10.0;

/// What one pass gives.
pub(crate) struct PassOutput {
    /// The forward run's summary (its innovation statistics hold the likelihood).
    pub summary: RunSummary,
    pub layout: StateLayout,
    pub process: ProcessNoiseStats,
    pub residuals: Vec<SmoothedResidual>,
    /// At the first record: the smoothed error (before its updates) and variance, and
    /// the filter's initial variance per state.
    pub initial: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
}

impl PassOutput {
    /// Innovation log-likelihood of the forward run, summed over every source.
    pub fn log_likelihood(&self) -> f64 {
        self.summary
            .innovation_stats
            .values()
            .map(|s| s.log_likelihood)
            .sum()
    }
}

/// Run `nav` forward over `imu` and `measurements` (records on disk in `scratch`),
/// then backward with the EM statistics.
pub(crate) fn em_pass(
    nav: &NavConfig,
    imu: &[ImuSample],
    measurements: &[Measurement],
    extra: Option<SourceFactory>,
    scratch: &Path,
) -> Result<PassOutput, Error> {
    let io = |what: &'static str| {
        move |e: std::io::Error| Error::io(format!("noise tuning scratch file ({what})"), e)
    };
    let mut spill = Spill::create(scratch, "tune").map_err(io("records"))?;
    let mut enc = codec::Enc::default();
    let mut updates: Vec<FusedUpdate> = Vec::new();
    let mut layout: Option<StateLayout> = None;
    let mut on_record = |r: RtsRecord| -> Result<(), Error> {
        enc.clear();
        codec::put_record(&mut enc, &r);
        spill.push(&enc.0).map_err(io("records"))
    };
    let mut on_updates = |u: Vec<FusedUpdate>| -> Result<(), Error> {
        updates.extend(u);
        Ok(())
    };
    let t0 = std::time::Instant::now();
    let summary = navfuse_core::run_recording(
        nav,
        |c: &NavConfig, t0| extra.map_or_else(Vec::new, |f| f(c, t0)),
        imu.iter().map(|s| Ok::<_, Error>(*s)),
        measurements,
        None,
        |n: &navfuse_core::Navigator| {
            if layout.is_none() {
                layout = Some(n.layout().clone());
            }
            Ok(())
        },
        |_| {},
        navfuse_core::RunHooks {
            on_record: Some(&mut on_record),
            on_innovations: None,
            on_updates: Some(&mut on_updates),
        },
    )?;
    let layout = layout.ok_or_else(|| {
        Error::Other("noise tuning: the run gave no output epoch (no start found)".into())
    })?;
    let t_fwd = t0.elapsed().as_secs_f64();
    let bias = layout.index(Block::GnssBias);
    let span = (summary.last_t - summary.first_t).max(1.0);
    let mut process = ProcessNoiseStats::with_blocks(summary.first_t, span / BLOCKS);
    let mut residuals = Vec::with_capacity(updates.len());
    let mut back = RtsBackward::new();
    let total = spill.len();
    let mut rd = spill.backward().map_err(io("records"))?;
    // The gains depend on the forward records only: made on a second thread ahead of
    // the recursion (as the smoother does).
    let (tx, rx) = std::sync::mpsc::sync_channel::<Result<Gain, Error>>(64);
    let maker = std::thread::spawn(move || {
        let mut gm = GainMaker::new();
        loop {
            let g = match rd.next_entry() {
                Ok(None) => break,
                Ok(Some(bytes)) => codec::get_record(bytes)
                    .map_err(io("records"))
                    .and_then(|r| {
                        gm.gain(r)
                            .map_err(|e| Error::Other(format!("noise tuning: {e}")))
                    }),
                Err(e) => Err(io("records")(e)),
            };
            let failed = g.is_err();
            if tx.send(g).is_err() || failed {
                break;
            }
        }
    });
    // Updates carry the index of the record they were applied at, in order; the
    // records come back last first.
    let mut end = updates.len();
    let mut idx = total;
    let mut initial = None;
    for g in rx {
        let g = g?;
        idx = idx.saturating_sub(1);
        // The first record's covariance before its updates (the initial P, unless the
        // run started with an update).
        let p0: Option<Vec<f64>> = (idx == 0).then(|| {
            let mut p = g.forward_var();
            if g.updated() {
                p.fill(f64::NAN);
            }
            p.iter().copied().collect()
        });
        let mut start = end;
        while start > 0 && updates[start - 1].record >= idx {
            start -= 1;
        }
        let before = residuals.len();
        let sm = back
            .smooth_em(g, &updates[start..end], bias, &mut process, &mut residuals)
            .map_err(|e| Error::Other(format!("noise tuning: {e}")))?;
        if let Some(p0) = p0 {
            initial = Some((
                sm.s_prior.iter().copied().collect(),
                sm.var.iter().copied().collect(),
                p0,
            ));
        }
        // Reversed here and again below: time order, the record's own order kept.
        residuals[before..].reverse();
        end = start;
    }
    maker
        .join()
        .map_err(|_| Error::Other("noise tuning: the gain thread panicked".into()))?;
    residuals.reverse();
    if std::env::var_os("NAVFUSE_TUNE_DEBUG").is_some() {
        eprintln!(
            "em pass: forward {t_fwd:.3} s, backward {:.3} s, {total} records, {} updates",
            t0.elapsed().as_secs_f64() - t_fwd,
            updates.len()
        );
    }
    Ok(PassOutput {
        summary,
        layout,
        process,
        residuals,
        initial,
    })
}
