//! Trajectories to score: a `.nav` file (the simulator's truth, a kept solution) or a
//! run's records in memory, as a [`Track`] of [`TrajPoint`]s.

use anyhow::Result;
use navfuse_app::SolutionRecord;
use navfuse_core::eval::TrajPoint;
use navfuse_core::NavState;
use navfuse_io::nav::read_nav;
use navfuse_io::nav_written::nav_as_written;
use navfuse_io::trajectory::points_of_rows;
use std::path::Path;

/// A trajectory with its GPS week (0 = unknown, times are seconds of week).
pub struct Track {
    pub week: u32,
    pub points: Vec<TrajPoint>,
}

impl Track {
    /// Rows of (GPS week, state); times count from the first row's week.
    pub(crate) fn of_rows(rows: impl IntoIterator<Item = (u32, NavState)>) -> Track {
        let (week, points) = points_of_rows(rows.into_iter().collect());
        Track { week, points }
    }
}

/// Read a KF-GINS `.nav` file; times count from the first row's week.
pub fn load_nav(path: &Path) -> Result<Track> {
    Ok(Track::of_rows(read_nav(path)?))
}

/// A run's solution records as [`load_nav`] would give them back from the
/// solution.nav the run writes: each value rounded to the file's 9 decimals
/// ([`nav_as_written`]). `navfuse reproduce` scores this, in memory, so that its
/// figures are the ones it gave when it scored the written file. (Scoring the
/// unrounded records moves the figures by up to 7e-5 m, as 1e-9 deg of latitude is
/// 1.1e-4 m, and changes three printed 3-decimal figures of seed000's table.)
pub fn solution_track(records: &[SolutionRecord]) -> Track {
    Track::of_rows(records.iter().map(nav_as_written))
}
