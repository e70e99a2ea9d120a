//! One navigator run of an experiment, in memory: `navfuse_app::run` into a
//! [`TrackSink`] (the solution as solution.nav holds it); with `--keep DIR` also into
//! a [`FileSink`] (the files of `navfuse run --out`), from the same records.

use std::path::{Path, PathBuf};

use navfuse_app::{
    run, Error, FileSink, JobResult, OutputLayout, RunConfig, RunOptions, SmoothedEpoch,
    SmoothedLayout, SolutionRecord, SolutionSink, StateValues,
};
use navfuse_core::{InnovationRow, NavState};
use navfuse_io::nav_written::nav_as_written;
use navfuse_io::smoothed::SeparationRow;

use crate::track::Track;

/// A finished run: its report (events, counts) and its output epochs (forward, and
/// smoothed when the smoother ran) as solution.nav (smoothed.nav) holds them.
pub(crate) struct Navigated {
    pub job: JobResult,
    pub rows: Vec<(u32, NavState)>,
    pub smoothed: Vec<(u32, NavState)>,
}

impl Navigated {
    /// The solution as scored: the records as solution.nav holds them.
    pub fn track(&self) -> Track {
        Track::of_rows(self.rows.iter().copied())
    }

    /// The smoothed solution as smoothed.nav holds it (empty without smoothing).
    pub fn smoothed_track(&self) -> Track {
        Track::of_rows(self.smoothed.iter().copied())
    }
}

/// Run `cfg` (no progress, no warnings on stderr, as `run_job` in a batch), keeping
/// the solution in memory; with `keep`, also write the run's files into that
/// directory.
pub(crate) fn navigate(cfg: RunConfig, keep: Option<&Path>) -> Result<Navigated, Error> {
    let opts = RunOptions::default();
    let (job, track) = match keep {
        None => {
            let mut track = TrackSink::default();
            (run(cfg, &mut track, &opts)?, track)
        }
        Some(dir) => {
            let mut both = Both {
                track: TrackSink::default(),
                files: FileSink::create(dir)?,
            };
            (run(cfg, &mut both, &opts)?, both.track)
        }
    };
    Ok(Navigated {
        job,
        rows: track.rows,
        smoothed: track.smoothed,
    })
}

/// Keeps the solution (and the smoothed one) as the `.nav` files hold it: (GPS week,
/// state) rounded as written, what [`crate::track::solution_track`] makes of the
/// records, kept epoch by epoch (a quarter of a record's size: a 200 Hz hour is 70
/// MB, not 280).
#[derive(Default)]
struct TrackSink {
    rows: Vec<(u32, NavState)>,
    smoothed: Vec<(u32, NavState)>,
}

impl SolutionSink for TrackSink {
    fn begin(&mut self, _layout: &OutputLayout, _files: &mut Vec<PathBuf>) -> Result<(), Error> {
        Ok(())
    }

    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error> {
        self.rows.push(nav_as_written(record));
        Ok(())
    }

    fn smoothed(&mut self, epoch: &SmoothedEpoch) -> Result<(), Error> {
        self.smoothed.push(nav_as_written(&epoch.record));
        Ok(())
    }
}

/// The records kept in memory and written to files: every call goes to the file
/// sink (so the directory holds exactly what `navfuse run --out` writes), the output
/// epochs also to memory.
struct Both {
    track: TrackSink,
    files: FileSink,
}

impl SolutionSink for Both {
    fn configuration(&mut self, cfg: &RunConfig, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.files.configuration(cfg, files)
    }

    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.files.begin(layout, files)
    }

    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error> {
        self.track.epoch(record)?;
        self.files.epoch(record)
    }

    fn states(&mut self, states: &StateValues) -> Result<(), Error> {
        self.files.states(states)
    }

    fn innovations(&mut self, rows: &[InnovationRow]) -> Result<(), Error> {
        self.files.innovations(rows)
    }

    fn location(&self) -> String {
        self.files.location()
    }

    fn end(&mut self) -> Result<(), Error> {
        self.files.end()
    }

    fn begin_smoothed(
        &mut self,
        layout: &SmoothedLayout,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        self.files.begin_smoothed(layout, files)
    }

    fn smoothed(&mut self, epoch: &SmoothedEpoch) -> Result<(), Error> {
        self.track.smoothed(epoch)?;
        self.files.smoothed(epoch)
    }

    fn separation(&mut self, row: &SeparationRow) -> Result<(), Error> {
        self.files.separation(row)
    }

    fn end_smoothed(&mut self) -> Result<(), Error> {
        self.files.end_smoothed()
    }

    fn scratch_dir(&self) -> Option<PathBuf> {
        self.files.scratch_dir()
    }

    fn report(&mut self, job: &mut JobResult, progress: bool) -> Result<(), Error> {
        self.files.report(job, progress)
    }
}
