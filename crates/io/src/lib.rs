//! navfuse-io: file formats and configuration. Every reader reports bad input as an
//! [`InputError`] naming the file, line and field; none panics.

pub mod allan;
pub mod baro;
pub mod config;
pub mod dgps;
pub mod error;
pub mod export;
pub mod fmt;
pub mod gnss;
pub mod gnss_csv;
pub mod heading;
pub mod imu;
pub mod innovations;
pub mod input;
pub mod nav;
pub mod nav_written;
pub mod nmea;
pub mod odometer;
pub mod rinex_clk;
pub mod rinex_nav;
mod rinex_nav_gnss;
pub mod rinex_obs;
pub mod smoothed;
pub mod sp3;
pub mod table;
pub mod time;
pub mod timetag;
pub mod trajectory;
pub mod ubx;
pub mod ulog;

pub use error::InputError;
