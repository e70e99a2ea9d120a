//! Trajectories to score: a `.nav` file (the simulator's truth, a kept solution) as
//! a [`Track`] of [`TrajPoint`]s.

use anyhow::Result;
use navfuse_core::attitude::euler_from_q_bn;
use navfuse_core::eval::TrajPoint;
use navfuse_io::nav::read_nav;
use std::path::Path;

/// Seconds in a GPS week.
pub const WEEK_S: f64 = 604_800.0;

/// A trajectory with its GPS week (0 = unknown, times are seconds of week).
pub struct Track {
    pub week: u32,
    pub points: Vec<TrajPoint>,
}

/// Read a KF-GINS `.nav` file; times count from the first row's week.
pub fn load_nav(path: &Path) -> Result<Track> {
    let rows = read_nav(path)?;
    let week = rows.first().map_or(0, |r| r.0);
    let points = rows
        .iter()
        .map(|(w, s)| TrajPoint {
            t: s.t + (*w as f64 - week as f64) * WEEK_S,
            lla: s.lla,
            v_n: Some(s.v_n),
            rpy: Some(euler_from_q_bn(&s.q_bn)),
        })
        .collect();
    Ok(Track { week, points })
}
