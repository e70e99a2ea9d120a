//! navfuse-core: the pure navigation core. Earth model, attitude, strapdown
//! mechanization, error-state EKF and aiding measurement models. No file I/O:
//! readers and writers live in `navfuse-io`, the command line in `navfuse`.

pub mod attitude;
pub mod config;
pub mod earth;
pub mod outage;
pub mod types;

pub use types::{GnssFix, ImuErrors, ImuSample, NavState};
