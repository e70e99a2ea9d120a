//! [`SolutionSink`]: where the pipeline puts what it computes, in the spirit of
//! ripgrep's `Sink`. The pipeline pushes every output epoch into the sink as it is
//! computed, then hands it the finished run's report (events, findings, how it ended).
//! [`FileSink`](crate::FileSink) writes the files of `navfuse run`; [`MemorySink`]
//! keeps the records in a `Vec`.

use crate::error::Error;
use crate::summary::JobResult;
use navfuse_core::{Event, InnovationRow};
use navfuse_io::config::RunConfig;
use navfuse_io::nav::SolutionRecord;
use navfuse_io::smoothed::SeparationRow;
use std::path::PathBuf;

/// What the records of a run carry and which solution tables a file sink writes
/// (from `[output]` and `[spoofing]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OutputLayout {
    /// `[output] imu_err`: the KF-GINS IMU_ERR table.
    pub imu_err: bool,
    /// `[output] std`: records carry the 21 standard deviations (KF-GINS STD table).
    pub std: bool,
    /// `[output] csv`: the CSV table.
    pub csv: bool,
    /// The integrity monitor runs: records carry its flag; the CSV table (with the
    /// flag column) and integrity.csv are written.
    pub integrity: bool,
    /// `[output] formats`: the exports a file sink writes beside the solution
    /// (`solution.kml`, `solution.pos`, ...).
    pub exports: navfuse_io::export::ExportSet,
}

/// What the smoothed output holds (when `[smoother]` is on).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SmoothedLayout {
    /// As the forward output's.
    pub base: OutputLayout,
    /// `"rts"` or `"combined"`.
    pub mode: &'static str,
    /// The filter states beyond the 21 INS ones (`smoothed_states.csv` columns).
    pub state_names: Vec<String>,
}

/// One smoothed output epoch: the record (smoothed solution, IMU errors and 1-sigma)
/// and the extra states with their 1-sigma, in [`SmoothedLayout::state_names`] order.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothedEpoch {
    pub record: SolutionRecord,
    pub states: Vec<f64>,
    pub states_std: Vec<f64>,
}

/// The filter states beyond the 21 INS ones at one forward output epoch (the
/// columns of `states.csv`).
#[derive(Clone, Copy, Debug)]
pub struct StateValues<'a> {
    /// State names with units (`navfuse_core::smoother::extra_names`).
    pub names: &'a [String],
    pub gps_week: u32,
    /// GPS seconds of week.
    pub t: f64,
    pub values: &'a [f64],
    pub std: &'a [f64],
}

/// Receives a run's output. Calls, in order: [`begin`](Self::begin) once the inputs
/// are read and checked (not at all when the run is refused before), then
/// [`epoch`](Self::epoch) per output epoch (each followed by [`states`](Self::states)
/// when the filter has extra states; [`innovations`](Self::innovations) in between),
/// [`end`](Self::end) after the last one
/// (also when the run stopped early); when smoothing, after a completed forward run,
/// [`begin_smoothed`](Self::begin_smoothed), [`smoothed`](Self::smoothed) per
/// output epoch with [`separation`](Self::separation) rows in between, and
/// [`end_smoothed`](Self::end_smoothed); and [`report`](Self::report) once the run
/// has ended, however it ended (also after a failure before `begin`).
pub trait SolutionSink {
    /// The configuration the run uses (relative outages resolved), before
    /// [`begin`](Self::begin); push the path of a file it is written to onto `files`.
    fn configuration(&mut self, cfg: &RunConfig, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        let _ = (cfg, files);
        Ok(())
    }

    /// With `[tuning]`: the noise model estimated before the run (the run then uses
    /// `tuned.config`); push the paths of the files it is written to onto `files`.
    fn tuning(
        &mut self,
        tuned: &crate::tune::Tuned,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        let _ = (tuned, files);
        Ok(())
    }

    /// Get ready for records laid out as `layout`; push the paths of the files this
    /// sink will write onto `files` (they appear in the summary).
    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error>;

    /// One output epoch. An error stops the run (the records so far are kept).
    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error>;

    /// The extra filter states at the output epoch just handed to
    /// [`epoch`](Self::epoch) (only when the filter has states beyond the INS ones,
    /// and at most at 10 Hz: the first output epoch of each 0.1 s of GNSS time).
    fn states(&mut self, states: &StateValues) -> Result<(), Error> {
        let _ = states;
        Ok(())
    }

    /// Updates the aiding sources tried since the previous call, in time order.
    fn innovations(&mut self, rows: &[InnovationRow]) -> Result<(), Error> {
        let _ = rows;
        Ok(())
    }

    /// Where the output is kept, for messages: "its output is kept in LOCATION".
    fn location(&self) -> String {
        "memory".to_string()
    }

    /// After the last epoch: everything handed on. Called only after `begin`.
    fn end(&mut self) -> Result<(), Error> {
        Ok(())
    }

    /// Get ready for the smoothed solution; push the paths of the files it goes to.
    fn begin_smoothed(
        &mut self,
        layout: &SmoothedLayout,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        let _ = (layout, files);
        Ok(())
    }

    /// One smoothed output epoch, in time order.
    fn smoothed(&mut self, epoch: &SmoothedEpoch) -> Result<(), Error> {
        let _ = epoch;
        Ok(())
    }

    /// One row of the separation report.
    fn separation(&mut self, row: &SeparationRow) -> Result<(), Error> {
        let _ = row;
        Ok(())
    }

    /// After the last smoothed epoch (also when smoothing failed half-way).
    fn end_smoothed(&mut self) -> Result<(), Error> {
        Ok(())
    }

    /// A scratch directory for the smoother's disk-backed store (None: the system's
    /// temporary directory).
    fn scratch_dir(&self) -> Option<PathBuf> {
        None
    }

    /// The finished run (status, error, findings, notes, `summary.events`); a sink
    /// that writes reports lists them in `job.files`. `progress`: the user watches
    /// stderr (`navfuse run` without `-q`).
    fn report(&mut self, job: &mut JobResult, progress: bool) -> Result<(), Error> {
        let _ = (job, progress);
        Ok(())
    }
}

/// Keeps a run's output in memory: the records as computed and the run's events.
#[derive(Clone, Debug, Default)]
pub struct MemorySink {
    /// The layout `begin` was given.
    pub layout: OutputLayout,
    /// Every output epoch, in order.
    pub records: Vec<SolutionRecord>,
    /// The run's events (as in events.log), set when the run has ended.
    pub events: Vec<Event>,
    /// The smoothed output layout, when smoothing ran.
    pub smoothed_layout: Option<SmoothedLayout>,
    /// Every smoothed epoch, in order.
    pub smoothed: Vec<SmoothedEpoch>,
    /// The separation report.
    pub separation: Vec<SeparationRow>,
}

impl MemorySink {
    pub fn new() -> Self {
        Self::default()
    }
}

impl SolutionSink for MemorySink {
    fn begin(&mut self, layout: &OutputLayout, _files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.layout = *layout;
        Ok(())
    }

    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error> {
        self.records.push(*record);
        Ok(())
    }

    fn begin_smoothed(
        &mut self,
        layout: &SmoothedLayout,
        _files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        self.smoothed_layout = Some(layout.clone());
        Ok(())
    }

    fn smoothed(&mut self, epoch: &SmoothedEpoch) -> Result<(), Error> {
        self.smoothed.push(epoch.clone());
        Ok(())
    }

    fn separation(&mut self, row: &SeparationRow) -> Result<(), Error> {
        self.separation.push(*row);
        Ok(())
    }

    fn report(&mut self, job: &mut JobResult, _progress: bool) -> Result<(), Error> {
        self.events = job.summary.events.clone();
        Ok(())
    }
}
