//! Running one configuration: [`run`] into any [`SolutionSink`], [`run_job`] into the
//! files of `navfuse run`. Whatever happens once the sink exists, it is handed the
//! run's report ([`SolutionSink::report`]), which says how the run ended (`status`:
//! completed, failed or interrupted) and why.

use crate::error::Error;
use crate::file_sink::FileSink;
use crate::navigate::navigate;
use crate::sink::SolutionSink;
use crate::stop::{Interrupted, StopFlag};
use crate::summary::JobResult;
use navfuse_io::config::RunConfig;
use std::path::Path;
use std::time::Instant;

/// How a run talks to its caller.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Draw a progress bar on stderr (when it is a terminal) and print the input notes
    /// and rejection counts at the end (`navfuse run` without `-q`).
    pub progress: bool,
    /// Print the plausibility warnings on stderr as they are found (`navfuse run`
    /// always does; they are in the [`JobResult`] either way).
    pub warn: bool,
    /// Stop the run when this flag is set (`navfuse run`: SIGINT / SIGTERM). The run
    /// then ends with [`Error::Interrupted`], its sink holding every epoch up to the
    /// one named there.
    pub stop: Option<StopFlag>,
    /// Aiding sources of your own, after the registry's (`navfuse_core::SourceFactory`;
    /// `examples/custom_source.rs`).
    pub extra_sources: Option<navfuse_core::SourceFactory>,
}

impl RunOptions {
    /// `r`, or the [`Interrupted`] error once a stop was asked for.
    pub(crate) fn stop_check<T, E: From<Interrupted>>(&self, r: Result<T, E>) -> Result<T, E> {
        match &self.stop {
            Some(s) => s.check(r),
            None => r,
        }
    }

    /// Whether a stop was asked for (see [`StopFlag::requested`]).
    pub(crate) fn stop_requested(&self) -> Option<Option<i32>> {
        self.stop.as_ref().and_then(StopFlag::requested)
    }
}

/// Run one configuration, as `navfuse run` does: read the inputs `cfg` names, check
/// them, estimate the GNSS-IMU time offset when configured (a first pass), navigate,
/// push every output epoch into `sink`, check the result, and hand the sink the
/// report. Returns the report, or why the run failed or stopped (the sink has been
/// given the report either way).
pub fn run(
    cfg: RunConfig,
    sink: &mut dyn SolutionSink,
    opts: &RunOptions,
) -> Result<JobResult, Error> {
    let t_wall = Instant::now();
    let mut job = JobResult::empty();
    let outcome = navigate(cfg, sink, opts, &mut job);
    job.wall = t_wall.elapsed();
    job.status = match &outcome {
        Ok(()) if job.unreliable().is_some() => "unreliable",
        Ok(()) => "completed",
        Err(e) if e.interrupted().is_some() => "interrupted",
        Err(_) => "failed",
    };
    if let Err(e) = &outcome {
        job.error = Some(e.to_string());
    }
    let reports = sink.report(&mut job, opts.progress);
    match (outcome, reports) {
        (Ok(()), Ok(())) => Ok(job),
        (Err(_), Err(e)) if job.status != "interrupted" => Err(Error::Other(format!(
            "{}; and then: {e}",
            job.error.as_deref().unwrap_or_default()
        ))),
        (Err(e), Err(r)) => {
            eprintln!("navfuse: error: {r}");
            Err(e)
        }
        (Err(e), Ok(())) => Err(e),
        (Ok(()), Err(e)) => Err(e),
    }
}

/// Run one configuration, writing into `out_dir` (progress and warnings printed
/// when `progress`): [`run`] into a [`FileSink`].
pub fn run_job(cfg: RunConfig, out_dir: &Path, progress: bool) -> Result<JobResult, Error> {
    run_job_opts(cfg, out_dir, progress, progress)
}

/// [`run_job`], printing the plausibility warnings when `warn`. Whatever happens once
/// the output directory exists, `events.log` and `summary.json` are written there
/// and say how the run ended (`status`: completed, unreliable, failed or interrupted)
/// and why.
pub fn run_job_opts(
    cfg: RunConfig,
    out_dir: &Path,
    progress: bool,
    warn: bool,
) -> Result<JobResult, Error> {
    let mut sink = FileSink::create(out_dir)?;
    let opts = RunOptions {
        progress,
        warn,
        stop: None,
        extra_sources: None,
    };
    run(cfg, &mut sink, &opts)
}
