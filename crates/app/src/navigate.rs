//! The run proper: read, check, estimate the time offset, navigate into the sink,
//! check the result. The engine (time loop) is `navfuse_core::run`; this file wires
//! the inputs and the sink to it.

use crate::checks::{self, check, AfterRun};
use crate::error::{Error, ResultExt};
use crate::inputs::{self, split_week};
use crate::plausibility::{self, Span};
use crate::sink::{OutputLayout, SolutionSink, StateValues};
use crate::smooth::ForwardLog;
use crate::stop::Interrupted;
use crate::summary::JobResult;
use crate::{time_offset, RunOptions};
use indicatif::{ProgressBar, ProgressStyle};
use navfuse_core::smoother::extra_names;
use navfuse_core::state::N_INS;
use navfuse_core::{Navigator, RunSummary};
use navfuse_io::config::RunConfig;
use navfuse_io::nav::SolutionRecord;

/// The most rows per second of states.csv \[Hz\].
const STATES_RATE_HZ: f64 = 10.0;

/// A run's inputs, read and checked, with the time offset estimated: what the
/// navigation (and the noise tuning) starts from.
pub(crate) struct Prepared {
    pub cfg: RunConfig,
    /// The IMU reader after its first sample, and that sample.
    pub reader: navfuse_io::imu::ImuReader,
    pub first: navfuse_core::ImuSample,
    pub imu_week: Option<u32>,
    /// The week output times count from.
    pub week: u32,
    /// The merged, time-sorted measurements.
    pub measurements: Vec<navfuse_core::Measurement>,
    /// GNSS epoch times (fixes, or raw epochs with tight coupling).
    pub gnss_times: Vec<f64>,
    pub gnss_span: Option<Span>,
    pub run_start: f64,
}

/// Read the inputs, check them, merge the measurements and, with
/// `estimate_time_offset`, estimate the time offset (held fixed in the configuration
/// afterwards); fills `job`.
pub(crate) fn prepare(
    mut cfg: RunConfig,
    opts: &RunOptions,
    job: &mut JobResult,
    estimate_time_offset: bool,
) -> Result<Prepared, Error> {
    let warn = opts.warn;
    let inputs::Inputs {
        mut reader,
        imu_week,
        gnss_week,
        week,
        fixes,
        raw,
        gnss_skipped,
        odometer,
        heading,
        other,
    } = inputs::read(&cfg, job, warn)?;
    // GNSS epoch times (fixes, or raw epochs with tight coupling).
    let gnss_times: Vec<f64> = fixes
        .iter()
        .map(|f| f.t)
        .chain(raw.iter().map(|e| e.t))
        .collect();
    let last_gnss_t = gnss_times.last().copied();
    let gnss_span = match (&cfg.gnss, gnss_times.first(), gnss_times.last()) {
        (Some(g), Some(&first), Some(&last)) => Some(Span {
            file: g.path.display().to_string(),
            first,
            last,
            week: gnss_week,
        }),
        _ => None,
    };
    // GNSS epochs offered to the navigator: fixes, or raw epochs (tight coupling).
    let gnss_epochs = fixes.len() + raw.len();
    job.gnss_fixes = gnss_epochs;
    job.odometer_samples = odometer.len();
    job.heading_records = heading.len();
    // Configuration and input checks before the run.
    let found = checks::before_run(&cfg, gnss_epochs, gnss_skipped, last_gnss_t);
    check(job, warn, found)?;
    let first_fix = fixes.first().map(|f| f.lla);
    let measurements = navfuse_core::merge_more(
        navfuse_core::merge_raw_epochs(
            navfuse_core::merge_measurements(&fixes, &odometer, &heading),
            raw,
        ),
        other,
    );

    let first = match reader.next() {
        Some(Ok(s)) => s,
        Some(Err(e)) => return Err(e.into()),
        None => {
            return Err(Error::Other(format!(
                "{}: no IMU samples: the file is empty or holds only headers/comments (check [imu] file and [imu.csv] skip_lines)",
                cfg.imu.path.display()
            )))
        }
    };
    let imu_span = Span {
        file: cfg.imu.path.display().to_string(),
        first: first.t,
        last: f64::INFINITY,
        week: imu_week,
    };
    if let Some(g) = &gnss_span {
        check(job, warn, plausibility::time_overlap(&imu_span, g))?;
    }
    let found = checks::imu_window(&cfg, first_fix);
    check(job, warn, found)?;
    let run_start = if cfg.nav.start_time.is_finite() {
        cfg.nav.start_time.max(first.t)
    } else {
        first.t
    };
    cfg.resolve_relative_outages(run_start);

    if estimate_time_offset {
        let fit = time_offset::estimate(&mut cfg, &measurements, gnss_week, opts, job)?;
        job.time_offset = fit;
    }
    Ok(Prepared {
        cfg,
        reader,
        first,
        imu_week,
        week,
        measurements,
        gnss_times,
        gnss_span,
        run_start,
    })
}

/// Read, check, navigate, push the solution into `sink`; fills `job` as it goes.
pub(crate) fn navigate(
    cfg: RunConfig,
    sink: &mut dyn SolutionSink,
    opts: &RunOptions,
    job: &mut JobResult,
) -> Result<(), Error> {
    let warn = opts.warn;
    // [tuning]: the noise model from the data first; the run is the tuned one's.
    let cfg = if cfg.tuning.enabled {
        let tuned = crate::tune::tune_config(&cfg, opts).map_err(|e| match e {
            Error::Interrupted(_) => e,
            e => Error::Other(format!("[tuning]: {e}")),
        })?;
        sink.tuning(&tuned, &mut job.files)?;
        tuned.config
    } else {
        cfg
    };
    if cfg.smoother.enabled
        && matches!(
            cfg.nav.gnss.fusion,
            navfuse_core::config::GnssFusion::SixState { .. }
        )
    {
        return Err(Error::Other(format!(
            "{}: [smoother] (or --smooth) works on the error-state filter; gnss.fusion = \"six_state\" cannot be smoothed: use the default fusion or turn smoothing off",
            cfg.source_path.display()
        )));
    }
    let Prepared {
        cfg,
        mut reader,
        first,
        imu_week,
        week,
        measurements,
        gnss_times,
        gnss_span,
        run_start,
    } = prepare(cfg, opts, job, true)?;
    let last_gnss_t = gnss_times.last().copied();
    let first_t = first.t;
    let imu_file = cfg.imu.path.display().to_string();
    let imu_span = |last: f64| Span {
        file: imu_file.clone(),
        first: first_t,
        last,
        week: imu_week,
    };

    let monitor_on = cfg.nav.integrity.enabled;
    let layout = OutputLayout {
        imu_err: cfg.output.imu_err,
        std: cfg.output.std,
        csv: cfg.output.csv,
        integrity: monitor_on,
        exports: navfuse_io::export::ExportSet::of(&cfg.output.formats),
    };
    job.integrity_table = monitor_on;
    sink.configuration(&cfg, &mut job.files)?;
    sink.begin(&layout, &mut job.files)?;
    // The smoother's scratch files: beside the output (a temporary directory may be
    // in memory).
    let log = match cfg.smoother.enabled {
        true => {
            let dir = sink.scratch_dir().unwrap_or_else(std::env::temp_dir);
            Some(ForwardLog::create(&dir, &cfg.smoother, week)?)
        }
        false => None,
    };
    let log = std::cell::RefCell::new(log);

    let t_end = cfg.nav.end_time.or(last_gnss_t).unwrap_or(run_start);
    let bar = (opts.progress && t_end > run_start).then(|| {
        let b = ProgressBar::new(((t_end - run_start) * 10.0) as u64);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    });

    // A stop request ends the run at the next output epoch (the records so far are
    // all in the sink), or before the first one at the next IMU sample.
    let want_std = cfg.output.std;
    let started = std::cell::Cell::new(false);
    let mut stopped: Option<RunSummary> = None;
    let mut last_out_t = None;
    let mut on_record = |r: navfuse_core::smoother::RtsRecord| match log.borrow_mut().as_mut() {
        Some(l) => l.record(r),
        None => Ok(()),
    };
    // The sink takes the innovations between output epochs; RefCell: the output
    // closure hands it the epochs.
    let sink = std::cell::RefCell::new(sink);
    let mut on_innovations =
        |rows: &[navfuse_core::InnovationRow]| sink.borrow_mut().innovations(rows);
    let mut state_names: Option<Vec<String>> = None;
    // states.csv: the first output epoch of each 0.1 s (slowly varying estimates; at
    // the IMU rate the file would cost a fifth of the run).
    let mut states_bucket: Option<i64> = None;
    let result = navfuse_core::run_recording(
        &cfg.nav,
        |c: &navfuse_core::config::NavConfig, t0| {
            opts.extra_sources.map_or_else(Vec::new, |f| f(c, t0))
        },
        std::iter::once(Ok(first)).chain(reader.by_ref().map(|r| {
            let r = r.map_err(Error::from);
            let r = if started.get() { r } else { opts.stop_check(r) };
            if let (Ok(s), Some(l)) = (&r, log.borrow_mut().as_mut()) {
                l.imu(s)?;
            }
            r
        })),
        &measurements,
        cfg.output.rate_hz.map(|r| 1.0 / r),
        |n: &Navigator| {
            started.set(true);
            if let Some(signal) = opts.stop_requested() {
                stopped = Some(n.summary().clone());
                return Err(Interrupted {
                    signal,
                    t: last_out_t,
                }
                .into());
            }
            let nav = *n.nav();
            let (wk, t) = split_week(week, n.time_gnss());
            let rec = SolutionRecord {
                gps_week: wk,
                nav: navfuse_core::NavState { t, ..nav },
                imu_errors: *n.imu_errors(),
                std: if want_std { Some(n.std21()) } else { None },
                gnss_integrity: monitor_on.then(|| n.integrity_state().flag()),
                state: Some(n.solution_state()),
            };
            last_out_t = Some(n.time_gnss());
            if let Some(l) = log.borrow_mut().as_mut() {
                l.epoch(n, rec.gnss_integrity, rec.state)?;
            }
            let mut sink = sink.borrow_mut();
            let mut written = sink.epoch(&rec);
            let layout = n.layout();
            let bucket = ((n.time_gnss() + 1e-6) * STATES_RATE_HZ).floor() as i64;
            if written.is_ok() && layout.len() > N_INS && states_bucket != Some(bucket) {
                states_bucket = Some(bucket);
                let names = state_names.get_or_insert_with(|| extra_names(layout));
                let p = n.covariance();
                let std: Vec<f64> = (N_INS..layout.len())
                    .map(|i| p[(i, i)].max(0.0).sqrt())
                    .collect();
                written = sink.states(&StateValues {
                    names,
                    gps_week: wk,
                    t,
                    values: &n.nominal().extra_values(layout),
                    std: &std,
                });
            }
            if let Err(e) = written {
                stopped = Some(n.summary().clone());
                return Err(e);
            }
            Ok(())
        },
        |t| {
            if let Some(b) = &bar {
                b.set_position(((t - run_start) * 10.0).max(0.0) as u64);
                b.set_message(format!("t = {t:.1}"));
            }
        },
        navfuse_core::RunHooks {
            on_record: match cfg.smoother.enabled {
                true => Some(&mut on_record),
                false => None,
            },
            on_innovations: Some(&mut on_innovations),
            on_updates: None,
        },
    );
    let sink = sink.into_inner();
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let ended = sink.end();
    let report = reader.report().clone();
    if !report.to_string().is_empty() {
        job.notes.push(report.to_string());
    }
    if let Some(s) = stopped {
        job.summary = s;
        job.summary.outputs -= 1;
    }
    job.last_output_t = last_out_t;
    ended?;
    job.summary = result.map_err(|e| match e {
        Error::Interrupted(i) => Error::Interrupted(i),
        e => e.context(format!(
            "run stopped; the output up to the failure is in {}",
            sink.location()
        )),
    })?;
    // After the run: results the program can tell are meaningless, and suspicious fits.
    let imu_last = report.last_t.unwrap_or(first_t);
    let after = AfterRun {
        imu: imu_span(imu_last),
        gnss: gnss_span.as_ref(),
        gnss_times: &gnss_times,
    };
    let found = checks::after_run(&cfg, job, &after);
    check(job, warn, found).with_context(|| {
        format!(
            "the run's result is meaningless (its output is kept in {})",
            sink.location()
        )
    })?;
    if let Some(l) = log.into_inner() {
        // A stop asked for at the end of the forward run: no smoothing (the forward
        // output is complete).
        if let Some(signal) = opts.stop_requested() {
            return Err(Interrupted {
                signal,
                t: job.last_output_t,
            }
            .into());
        }
        let inputs = crate::smooth::BackwardInputs {
            nav: &cfg.nav,
            measurements: &measurements,
            extra_sources: opts.extra_sources,
        };
        let rep = l.smooth(&layout, sink, opts.progress, job, &inputs)?;
        let found = checks::after_smoothing(&cfg, &rep);
        job.smoother = Some(rep);
        check(job, warn, found)?;
    }
    if opts.progress {
        for n in &job.notes {
            eprintln!("navfuse: note: {n}");
        }
        let rej = job
            .summary
            .events
            .iter()
            .filter(|e| matches!(e, navfuse_core::Event::Rejected { .. }))
            .count();
        if rej > 0 {
            eprintln!(
                "navfuse: {rej} measurements rejected by the innovation gate (see events.log)"
            );
        }
    }
    Ok(())
}
