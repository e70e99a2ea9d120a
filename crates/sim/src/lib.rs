//! navfuse simulator: everything the navigator reads, with exact truth.
//!
//! - [`scenario`]: the scenario file (TOML), validated.
//! - [`trajectory`]: truth from a list of segments, consistent with the navigator's
//!   WGS-84 mechanization; perfect IMU increments integrated over each interval.
//! - [`random`]: seeded random streams and Gauss-Markov processes.
//! - [`imu_model`]: IMU grades (presets and custom) applied to perfect increments.
//! - the Allan deviation that checks the IMU models is `navfuse_core::allan`.
//! - [`gnss_sim`]: constellation, raw measurements with an error budget, DGPS, fixes,
//!   dual-antenna heading, events.
//! - [`vibration`]: engine-like vibration added to the IMU (`[vibration]`).
//! - [`generate`]: one streaming pass that writes every output file.

pub mod baro_sim;
pub mod generate;
pub mod gnss_sim;
pub mod imu_model;
pub mod random;
pub mod run_config;
pub mod scenario;
pub mod trajectory;
pub mod vibration;
