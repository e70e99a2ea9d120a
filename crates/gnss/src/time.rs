//! GPS time: the workspace's one GPS time type lives in `navfuse_core::time`
//! (core is the lowest layer, so the readers in navfuse-io use the same type);
//! re-exported here so `navfuse_gnss::time::GpsTime` keeps working.

pub use navfuse_core::time::*;
