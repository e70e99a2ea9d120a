//! One navigator run of an experiment, in memory: `navfuse_app::run` into a
//! [`MemorySink`]; with `--keep DIR` also into a [`FileSink`] (the files of `navfuse
//! run --out`), from the same records.

use std::path::{Path, PathBuf};

use navfuse_app::{
    run, Error, FileSink, JobResult, MemorySink, OutputLayout, RunConfig, RunOptions,
    SmoothedEpoch, SmoothedLayout, SolutionRecord, SolutionSink, StateValues,
};
use navfuse_core::InnovationRow;
use navfuse_io::smoothed::SeparationRow;

use crate::track::{solution_track, Track};

/// A finished run: its report (events, counts) and its output epochs (forward, and
/// smoothed when the smoother ran).
pub(crate) struct Navigated {
    pub job: JobResult,
    pub records: Vec<SolutionRecord>,
    pub smoothed: Vec<SolutionRecord>,
}

impl Navigated {
    /// The solution as scored: the records as solution.nav holds them.
    pub fn track(&self) -> Track {
        solution_track(&self.records)
    }
}

/// Run `cfg` (no progress, no warnings on stderr, as `run_job` in a batch), keeping
/// the records in memory; with `keep`, also write the run's files into that directory.
pub(crate) fn navigate(cfg: RunConfig, keep: Option<&Path>) -> Result<Navigated, Error> {
    let opts = RunOptions::default();
    let (job, memory) = match keep {
        None => {
            let mut memory = MemorySink::new();
            (run(cfg, &mut memory, &opts)?, memory)
        }
        Some(dir) => {
            let mut both = Both {
                memory: MemorySink::new(),
                files: FileSink::create(dir)?,
            };
            (run(cfg, &mut both, &opts)?, both.memory)
        }
    };
    Ok(Navigated {
        job,
        records: memory.records,
        smoothed: memory.smoothed.into_iter().map(|e| e.record).collect(),
    })
}

/// The records kept in memory and written to files: every call goes to the file
/// sink (so the directory holds exactly what `navfuse run --out` writes), the output
/// epochs also to memory.
struct Both {
    memory: MemorySink,
    files: FileSink,
}

impl SolutionSink for Both {
    fn configuration(&mut self, cfg: &RunConfig, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.files.configuration(cfg, files)
    }

    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.memory.begin(layout, files)?;
        self.files.begin(layout, files)
    }

    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error> {
        self.memory.epoch(record)?;
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
        self.memory.end()?;
        self.files.end()
    }

    fn begin_smoothed(
        &mut self,
        layout: &SmoothedLayout,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        self.memory.begin_smoothed(layout, files)?;
        self.files.begin_smoothed(layout, files)
    }

    fn smoothed(&mut self, epoch: &SmoothedEpoch) -> Result<(), Error> {
        self.memory.smoothed(epoch)?;
        self.files.smoothed(epoch)
    }

    fn separation(&mut self, row: &SeparationRow) -> Result<(), Error> {
        self.files.separation(row)
    }

    fn end_smoothed(&mut self) -> Result<(), Error> {
        self.memory.end_smoothed()?;
        self.files.end_smoothed()
    }

    fn scratch_dir(&self) -> Option<PathBuf> {
        self.files.scratch_dir()
    }

    fn report(&mut self, job: &mut JobResult, progress: bool) -> Result<(), Error> {
        self.memory.report(job, progress)?;
        self.files.report(job, progress)
    }
}
