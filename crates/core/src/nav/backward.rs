//! The backward run: the navigator from the end of the data to its start, with
//! time-reversed strapdown mechanization and time-reversed aiding, independent of
//! the forward run (post-processing: a smoother combines the two;
//! docs/ALGORITHMS.md "Backward filter (time-reversed)").
//!
//! - Mechanization: each compensated interval (t - dt, t] is integrated from t down to
//!   t - dt by the same `Mechanizer` with the increments negated and a negative step
//!   (timeline::ReverseRest hands the pieces out in that form).
//! - Covariance: Phi = I + F dt with the signed dt for the kinematic couplings,
//!   Qd = Qc |dt|, the Gauss-Markov states decaying with |dt| (error_model.rs).
//! - Time line: the mirror of the forward one (timeline::ReverseInbox): a measurement
//!   is applied when the navigator comes down to its time, the interval cut there.
//! - Aiding: every elapsed time and cadence goes along the run
//!   (`timeline::TimeDirection`, `Fuser::direction`).

use super::navigator::{NavError, Navigator};
use super::timeline::{effective_time, ReverseInbox, SNAP_S};
use crate::aiding::registry;
use crate::aiding::source::AidingSource;
use crate::config::{GnssFusion, NavConfig};
use crate::events::{Event, RunSummary};
use crate::types::{ImuSample, Measurement};
use nalgebra::Vector3;

/// The initial state of a backward run, at its first (latest) epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackwardStart {
    /// IMU time \[s\].
    pub t: f64,
    /// Latitude \[rad\], longitude \[rad\], ellipsoidal height \[m\] of the IMU centre.
    pub lla: Vector3<f64>,
    /// NED velocity \[m/s\].
    pub v_n: Vector3<f64>,
    /// Roll, pitch, yaw \[rad\].
    pub rpy: Vector3<f64>,
}

/// Run the navigator backward in time from `start` over `imu_reversed` (decreasing
/// t; each sample still the interval (t - dt, t], dt > 0) and the time-sorted
/// (increasing) `measurements` the forward run uses.
///
/// The run starts at `start` without alignment, with the covariance and the IMU
/// error estimates of `cfg.initial` (not the forward run's: the two runs share only
/// the initial pose). The first sample is the interval ending at `start.t` (a sample
/// that straddles it is cut there; samples after it, or after `cfg.end_time`, are
/// skipped); integrating it takes the state to t - dt, and so on; the run stops
/// before a sample reaching below `cfg.start_time`. A measurement is applied when the
/// navigator reaches its time (the interval cut there); at equal times they come in
/// the reverse of the merged order; inputs at or after `start.t` are not used; GNSS
/// outages are withheld as forward.
///
/// `on_output` is called at every IMU epoch reached (`output_period_s = None`) or at
/// the first epoch at or before each multiple of the period (GNSS time scale), in
/// decreasing time; `on_progress` every 8192 samples. `GnssFusion::SixState` is not
/// supported backward.
#[allow(clippy::too_many_arguments)]
pub fn run_backward<E: From<NavError>>(
    cfg: &NavConfig,
    extra_sources: impl FnOnce(&NavConfig, f64) -> Vec<Box<dyn AidingSource>>,
    start: BackwardStart,
    imu_reversed: impl Iterator<Item = Result<ImuSample, E>>,
    measurements: &[Measurement],
    output_period_s: Option<f64>,
    mut on_output: impl FnMut(&Navigator) -> Result<(), E>,
    mut on_progress: impl FnMut(f64),
) -> Result<RunSummary, E> {
    if matches!(cfg.gnss.fusion, GnssFusion::SixState { .. }) {
        return Err(NavError(
            "gnss fusion \"six_state\" is not supported by the backward run (its dead reckoning and six-state cascade run forward only); use the error-state fusion".into(),
        )
        .into());
    }
    let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
    if !start.t.is_finite() || !finite(&start.lla) || !finite(&start.v_n) || !finite(&start.rpy) {
        return Err(NavError(format!(
            "backward run: the start state at t = {:.3} is not finite",
            start.t
        ))
        .into());
    }
    let mut sources = registry::sources(cfg, start.t);
    sources.extend(extra_sources(cfg, start.t));
    let mut n = Navigator::with_sources(cfg, start.t, start.lla, start.rpy, start.v_n, sources);
    n.reverse_time();
    n.push_event(Event::Aligned {
        t: start.t,
        method: "given (backward start)",
        reason: String::new(),
        skipped_s: 0.0,
        rpy_deg: [
            start.rpy.x.to_degrees(),
            start.rpy.y.to_degrees(),
            start.rpy.z.to_degrees(),
        ],
    });
    // Inputs at or after the initial epoch are not used (the mirror of forward).
    let mut inbox =
        ReverseInbox::new(measurements, &cfg.gnss.outages).with_gnss_snap(cfg.gnss.time_snap_s);
    let offset0 = n.time_offset();
    let after = inbox.skip_while(|m| effective_time(m, offset0) >= start.t);
    n.summary_mut().gnss_before_start += after
        .iter()
        .filter(|m| matches!(m, Measurement::Gnss(_) | Measurement::GnssRaw(_)))
        .count();
    let end = cfg.end_time.unwrap_or(f64::INFINITY);
    let mut t_prev = start.t - n.time_offset();
    let period = output_period_s.filter(|p| *p > 0.0);
    for item in imu_reversed {
        let mut s = item?;
        if s.t - s.dt < cfg.start_time {
            break;
        }
        if s.t > end || s.t - s.dt >= start.t - SNAP_S {
            continue;
        }
        if s.t > start.t + SNAP_S {
            // Straddles the start: only the part below it.
            let lambda = (start.t - (s.t - s.dt)) / s.dt;
            s = ImuSample {
                t: start.t,
                dt: s.dt * lambda,
                dtheta: s.dtheta * lambda,
                dvel: s.dvel * lambda,
            };
        }
        n.step_backward(&s, &mut inbox)?;
        // Cadence on the time scale the records carry (GNSS time), going down: the
        // first epoch at or before each multiple of the period.
        let t_out = n.time_gnss();
        let due = match period {
            None => true,
            Some(p) => ((t_out - 1e-6) / p).ceil() < ((t_prev - 1e-6) / p).ceil(),
        };
        if due {
            n.summary_mut().outputs += 1;
            on_output(&n)?;
        }
        if n.summary().imu_samples.is_multiple_of(8192) {
            on_progress(s.t);
        }
        t_prev = t_out;
    }
    Ok(n.finish())
}
