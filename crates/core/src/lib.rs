//! navfuse-core: the pure navigation core. Earth model, attitude, strapdown
//! mechanization, error-state EKF, aiding sources and the navigator. No file I/O:
//! readers and writers live in `navfuse-io`, the run pipeline in `navfuse-app`.
//!
//! Map: `earth` and `attitude` (common math) -> `mechanization` (INS) ->
//! `error_model` + `filter` + `state` (EKF) -> `aiding/*` (one file per aiding
//! source: model, policy, state; `aiding::registry` lists them) -> `nav` (the INS
//! filter, one IMU step, the measurement inbox, the start, the driver). `events`
//! holds what a run reports; `eval` scores solutions.

pub mod aiding;
pub(crate) mod alignment;
pub mod allan;
pub mod attitude;
pub mod chi2;
pub mod config;
pub mod earth;
pub(crate) mod error_model;
pub mod eval;
pub mod events;
pub(crate) mod filter;
pub(crate) mod fix_error;
pub mod integrity;
pub(crate) mod mechanization;
pub mod nav;
pub mod outage;
pub mod sat;
pub(crate) mod six_state;
pub mod smoother;
pub mod state;
pub(crate) mod static_detect;
pub mod time;
pub mod time_offset_search;
pub mod types;

pub use aiding::source::{AidingSource, Fuser, Handled};
pub use events::{
    AidStatus, Event, InnovationRow, InnovationStats, RunSummary, SolutionState, UpdateKind,
};
pub use nav::backward::{run_backward, BackwardStart};
pub use nav::ins_filter::{BlockProcess, BlockSpec, Fused};
pub use nav::navigator::{NavError, Navigator};
pub use nav::run::{run, run_recording, run_with_sources, RunHooks, SourceFactory};
pub use nav::timeline;
pub use nav::timeline::TimeDirection;
pub use sat::{SatId, System};
pub use types::{
    merge_measurements, merge_more, merge_raw_epochs, GnssFix, GnssRawEpoch, HeadingObs, ImuErrors,
    ImuSample, Measurement, NavState, OdometerSample, SatMeasurement,
};

/// The core's common items in one `use`: `use navfuse_core::prelude::*;`.
pub mod prelude {
    pub use crate::aiding::source::{AidingSource, Fuser, Handled, Shared};
    pub use crate::aiding::{Aiding, Linearized};
    pub use crate::config::NavConfig;
    pub use crate::events::{AidStatus, Event, RunSummary};
    pub use crate::nav::backward::{run_backward, BackwardStart};
    pub use crate::nav::ins_filter::{BlockProcess, BlockSpec, Fused};
    pub use crate::nav::navigator::{NavError, Navigator};
    pub use crate::nav::run::{run, run_with_sources, SourceFactory};
    pub use crate::nav::timeline::TimeDirection;
    pub use crate::state::{Block, StateLayout};
    pub use crate::types::{GnssFix, ImuErrors, ImuSample, Measurement, NavState};
}
