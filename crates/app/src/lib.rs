//! navfuse-app: the complete `navfuse run` pipeline as a library. Read the inputs a
//! [`RunConfig`] names (IMU, GNSS fixes or RINEX observations, odometer, heading), put
//! them on one GPS week, check them ([`plausibility`]), estimate the GNSS-IMU time
//! offset in a first pass when configured, navigate (`navfuse_core::run`), and push
//! every output epoch into a [`SolutionSink`]: a [`FileSink`] writes the files of
//! `navfuse run --out DIR` (byte for byte), a [`MemorySink`] keeps the records.
//!
//! ```no_run
//! use navfuse_app::{config, run, MemorySink, RunOptions};
//! let cfg = config::load("examples/drive_0708.toml".as_ref())?;
//! let mut sink = MemorySink::new();
//! let job = run(cfg, &mut sink, &RunOptions::default())?;
//! println!("{} epochs; {}", sink.records.len(), job.summary_line());
//! # Ok::<(), navfuse_app::Error>(())
//! ```
//!
//! Map: [`job`](run) (status, reports) -> `navigate` (the run proper) -> `inputs`
//! (reading, week alignment), [`gnss_input`] (RINEX), `time_offset` (the first pass),
//! `checks` + [`plausibility`]; [`sink`](SolutionSink) and [`FileSink`] (the writer
//! thread, events.log, integrity.csv, summary.json); [`JobResult`] (summary.json).

pub mod allan;
mod checks;
mod error;
mod export;
mod file_sink;
pub mod gnss_input;
mod inputs;
mod job;
mod navigate;
mod overrides;
pub mod plausibility;
pub mod score;
mod sink;
mod smooth;
pub mod spp;
mod stop;
mod summary;
mod time_offset;
pub mod tune;
pub mod ubx_input;

pub use error::Error;
pub use export::export_run;
pub use file_sink::{events_log_text, FileSink};
pub use job::{run, run_job, run_job_opts, RunOptions};
pub use navfuse_io::config::{self, RunConfig};
pub use navfuse_io::nav::SolutionRecord;
pub use overrides::RunOverrides;
pub use sink::{
    MemorySink, OutputLayout, SmoothedEpoch, SmoothedLayout, SolutionSink, StateValues,
};
pub use smooth::SmootherReport;
pub use stop::{Interrupted, StopFlag};
pub use summary::{JobResult, Unreliable, EXIT_UNRELIABLE};
pub use time_offset::{TimeOffsetFit, TimeOffsetSource};

/// What a program that runs navfuse usually needs, in one `use`:
/// `use navfuse_app::prelude::*;`.
pub mod prelude {
    pub use crate::{run, Error, FileSink, JobResult, MemorySink, RunOptions, SolutionSink};
    pub use navfuse_core::prelude::*;
    pub use navfuse_io::config::{load as load_config, RunConfig};
    pub use navfuse_io::nav::SolutionRecord;
}
