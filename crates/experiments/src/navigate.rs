//! One navigator run of an experiment, in memory: `navfuse_app::run` into a
//! [`MemorySink`]; with `--keep DIR` also into a [`FileSink`] (the files of `navfuse
//! run --out`), from the same records.

use std::path::{Path, PathBuf};

use navfuse_app::{
    run, Error, FileSink, JobResult, MemorySink, OutputLayout, RunConfig, RunOptions,
    SolutionRecord, SolutionSink,
};

use crate::track::{solution_track, Track};

/// A finished run: its report (events, counts) and its output epochs.
pub(crate) struct Navigated {
    pub job: JobResult,
    pub records: Vec<SolutionRecord>,
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
    })
}

/// The records kept in memory and written to files.
struct Both {
    memory: MemorySink,
    files: FileSink,
}

impl SolutionSink for Both {
    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.memory.begin(layout, files)?;
        self.files.begin(layout, files)
    }

    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error> {
        self.memory.epoch(record)?;
        self.files.epoch(record)
    }

    fn location(&self) -> String {
        self.files.location()
    }

    fn end(&mut self) -> Result<(), Error> {
        self.memory.end()?;
        self.files.end()
    }

    fn report(&mut self, job: &mut JobResult, progress: bool) -> Result<(), Error> {
        self.memory.report(job, progress)?;
        self.files.report(job, progress)
    }
}
