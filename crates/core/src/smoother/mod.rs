//! Post-processing: the fixed-interval smoother over a finished forward run
//! (docs/ALGORITHMS.md "Smoothing").
//!
//! - [`record`]: what the forward filter records at each covariance epoch.
//! - [`rts`]: the Rauch-Tung-Striebel backward pass over those records.
//! - [`nominal`]: the nominal values a correction acts on; the smoothed solution
//!   at an output epoch is its forward nominal with the smoothed error removed.
//! - [`combine`]: forward and backward filter solutions weighted by their
//!   covariances, and their separation.
//! - [`em`]: what noise identification learns from the backward pass (the
//!   smoothed residual of each update, the expected process noise per state).
//!
//! No I/O here: the app keeps the records on disk and feeds them back in reverse.

pub mod combine;
pub mod em;
pub mod nominal;
pub mod record;
pub mod rts;

pub use nominal::{extra_names, Nominal};
pub use record::RtsRecord;
pub use rts::{RtsBackward, SmoothError, SmoothedRecord};

use nalgebra::DVector;

/// The smoothed error at an output epoch at IMU time `t` of the segment that starts
/// at record `at` (the last record at or before `t`) and ends at `next`: the
/// forward nominal between two records is a free inertial solution, so the error
/// estimate moves from `at.s_post` to `next.s_prior` with time (linearly).
pub fn error_at(t: f64, at: &SmoothedRecord, next: Option<&SmoothedRecord>) -> DVector<f64> {
    match next {
        Some(nx) if nx.t > at.t && t > at.t => {
            let a = ((t - at.t) / (nx.t - at.t)).clamp(0.0, 1.0);
            &at.s_post * (1.0 - a) + &nx.s_prior * a
        }
        _ => at.s_post.clone(),
    }
}
