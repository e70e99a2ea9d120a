//! navfuse-core: the pure navigation core. Earth model, attitude, strapdown
//! mechanization, error-state EKF and aiding measurement models. No file I/O:
//! readers and writers live in `navfuse-io`, the command line in `navfuse`.
//!
//! Map: `earth` and `attitude` (common math) -> `mechanization` (INS) ->
//! `error_model` + `filter` + `state` (EKF) -> `aiding/*` (one file per aiding
//! source) -> `engine` (the navigator and its time loop). `eval` scores solutions.

pub mod aiding;
pub mod alignment;
pub mod attitude;
pub mod chi2;
pub mod config;
pub mod earth;
pub mod engine;
pub mod error_model;
pub mod eval;
pub mod filter;
pub mod fix_error;
pub mod integrity;
pub mod mechanization;
pub mod outage;
pub mod six_state;
pub mod state;
pub mod static_detect;
pub mod time;
pub mod timeline;
pub mod types;

pub use engine::{run, Event, Fused, NavError, Navigator, RunSummary};
pub use types::{
    merge_measurements, merge_raw_epochs, GnssFix, GnssRawEpoch, HeadingObs, ImuErrors, ImuSample,
    Measurement, NavState, OdometerSample, SatMeasurement,
};
