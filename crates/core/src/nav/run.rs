//! The driver: an IMU stream and a time-sorted list of measurements through the
//! navigator, with the solution handed out at the output cadence.

use super::navigator::{NavError, Navigator};
use super::start::find_start;
use super::timeline::{effective_time, Inbox};
use crate::aiding::registry;
use crate::aiding::source::AidingSource;
use crate::config::{GnssFusion, NavConfig};
use crate::events::{Event, InnovationRow, RunSummary};
use crate::smoother::em::FusedUpdate;
use crate::smoother::RtsRecord;
use crate::types::{ImuSample, Measurement};

/// Run the navigator over an IMU stream and a time-sorted list of measurements
/// (types::merge_measurements).
///
/// `on_output` is called at every IMU epoch (`output_period_s = None`) or at the
/// first epoch at or after each multiple of the period; `on_progress` every 8192
/// samples with the current time. The first IMU sample at or after
/// `cfg.start_time` fixes the initial epoch (its own interval is not integrated).
/// With static alignment, the samples of the levelling window are buffered, the
/// initial attitude is computed, and the window is then navigated like any other
/// data; with in-motion alignment the run starts at the aligning GNSS epoch.
pub fn run<E: From<NavError>>(
    cfg: &NavConfig,
    imu: impl Iterator<Item = Result<ImuSample, E>>,
    measurements: &[Measurement],
    output_period_s: Option<f64>,
    on_output: impl FnMut(&Navigator) -> Result<(), E>,
    on_progress: impl FnMut(f64),
) -> Result<RunSummary, E> {
    let none = |_: &NavConfig, _: f64| Vec::new();
    run_with_sources(
        cfg,
        none,
        imu,
        measurements,
        output_period_s,
        on_output,
        on_progress,
    )
}

/// Your own aiding sources for [`run_with_sources`], made from the configuration and
/// the start time (IMU time scale); they follow the registry's.
pub type SourceFactory = fn(&NavConfig, f64) -> Vec<Box<dyn AidingSource>>;

/// [`run`] with aiding sources of your own after the registry's (a custom source:
/// `crates/app/examples/custom_source.rs`).
pub fn run_with_sources<E: From<NavError>>(
    cfg: &NavConfig,
    extra_sources: impl FnOnce(&NavConfig, f64) -> Vec<Box<dyn AidingSource>>,
    imu: impl Iterator<Item = Result<ImuSample, E>>,
    measurements: &[Measurement],
    output_period_s: Option<f64>,
    on_output: impl FnMut(&Navigator) -> Result<(), E>,
    on_progress: impl FnMut(f64),
) -> Result<RunSummary, E> {
    drive(
        cfg,
        extra_sources,
        imu,
        measurements,
        output_period_s,
        on_output,
        on_progress,
        RunHooks::default(),
    )
}

/// What [`run_recording`] hands out besides the output epochs.
pub struct RunHooks<'a, E> {
    /// Record for the RTS smoother (crate::smoother): every record is handed out as
    /// it closes, the last one after the last IMU sample; output epochs know their
    /// record by [`Navigator::smoother_record_index`].
    pub on_record: Option<&'a mut dyn FnMut(RtsRecord) -> Result<(), E>>,
    /// Every update tried ([`InnovationRow`]), after each IMU step.
    #[allow(clippy::type_complexity)]
    pub on_innovations: Option<&'a mut dyn FnMut(&[InnovationRow]) -> Result<(), E>>,
    /// With `on_record`: every update applied, as noise identification needs it
    /// ([`FusedUpdate`]), after each IMU step.
    pub on_updates: Option<&'a mut dyn FnMut(Vec<FusedUpdate>) -> Result<(), E>>,
}

impl<E> Default for RunHooks<'_, E> {
    fn default() -> Self {
        RunHooks {
            on_record: None,
            on_innovations: None,
            on_updates: None,
        }
    }
}

/// [`run_with_sources`] with [`RunHooks`]: smoother records and the innovations.
#[allow(clippy::too_many_arguments)]
pub fn run_recording<E: From<NavError>>(
    cfg: &NavConfig,
    extra_sources: impl FnOnce(&NavConfig, f64) -> Vec<Box<dyn AidingSource>>,
    imu: impl Iterator<Item = Result<ImuSample, E>>,
    measurements: &[Measurement],
    output_period_s: Option<f64>,
    on_output: impl FnMut(&Navigator) -> Result<(), E>,
    on_progress: impl FnMut(f64),
    hooks: RunHooks<'_, E>,
) -> Result<RunSummary, E> {
    if hooks.on_record.is_some() && matches!(cfg.gnss.fusion, GnssFusion::SixState { .. }) {
        return Err(NavError(
            "smoothing works on the error-state filter; gnss fusion \"six_state\" cannot be smoothed (use the default fusion)".into(),
        )
        .into());
    }
    drive(
        cfg,
        extra_sources,
        imu,
        measurements,
        output_period_s,
        on_output,
        on_progress,
        hooks,
    )
}

#[allow(clippy::too_many_arguments)]
fn drive<E: From<NavError>>(
    cfg: &NavConfig,
    extra_sources: impl FnOnce(&NavConfig, f64) -> Vec<Box<dyn AidingSource>>,
    imu: impl Iterator<Item = Result<ImuSample, E>>,
    measurements: &[Measurement],
    output_period_s: Option<f64>,
    mut on_output: impl FnMut(&Navigator) -> Result<(), E>,
    mut on_progress: impl FnMut(f64),
    hooks: RunHooks<'_, E>,
) -> Result<RunSummary, E> {
    let RunHooks {
        mut on_record,
        mut on_innovations,
        mut on_updates,
    } = hooks;
    if matches!(cfg.gnss.fusion, GnssFusion::SixState { .. }) && cfg.tight.enabled {
        return Err(NavError(
            "gnss fusion \"six_state\" fuses GNSS fixes (loose coupling) only; it cannot be used with tight coupling".into(),
        )
        .into());
    }
    let end = cfg.end_time.unwrap_or(f64::INFINITY);
    let mut imu = imu.filter(|r| r.as_ref().map_or(true, |s| s.t >= cfg.start_time));
    let first = match imu.next() {
        Some(r) => r?,
        None => return Ok(RunSummary::default()),
    };
    let t_first_read = first.t;
    let Some(start) = find_start(cfg, first, &mut imu, measurements)? else {
        return Ok(RunSummary::default());
    };
    // What the alignment learnt about the data: its attitude uncertainty, the IMU
    // biases, the vibration of a static start (ZUPT thresholds).
    let adapted;
    let cfg = if start.att_std.is_some() || start.zupt_thresholds.is_some() || start.bias.is_some()
    {
        let mut c = cfg.clone();
        if let Some((g, a)) = start.bias {
            c.initial.imu_errors.gyro_bias += g;
            c.initial.imu_errors.accel_bias += a;
        }
        if let Some(a) = start.att_std {
            c.initial.att_std = a;
        }
        if let Some((a, g)) = start.zupt_thresholds {
            c.zupt.accel_std_max = a;
            c.zupt.gyro_max = g;
        }
        adapted = c;
        &adapted
    } else {
        cfg
    };
    let mut sources = registry::sources(cfg, start.t0);
    sources.extend(extra_sources(cfg, start.t0));
    let mut n = Navigator::with_sources(cfg, start.t0, start.lla, start.rpy, start.v_n, sources);
    if on_record.is_some() {
        n.record_for_smoothing();
        if on_updates.is_some() {
            n.log_updates();
        }
    }
    if on_innovations.is_some() {
        n.log_innovations();
    }
    if matches!(cfg.gnss.fusion, GnssFusion::SixState { .. }) && !n.has_six_state() {
        return Err(NavError(format!(
            "six-state fusion: the initial position, velocity or their standard deviations are not finite (start at t = {:.3})",
            start.t0
        ))
        .into());
    }
    n.push_event(Event::Aligned {
        t: start.t0,
        method: start.method,
        reason: start.reason.clone(),
        skipped_s: start.t0 - t_first_read,
        rpy_deg: [
            start.rpy.x.to_degrees(),
            start.rpy.y.to_degrees(),
            start.rpy.z.to_degrees(),
        ],
    });
    // Inputs up to the initial epoch are not used.
    let mut inbox =
        Inbox::new(measurements, &cfg.gnss.outages).with_gnss_snap(cfg.gnss.time_snap_s);
    let offset0 = n.time_offset();
    let before = inbox.skip_while(|m| {
        effective_time(m, offset0) <= start.t0 || (m.on_gnss_clock() && m.t() <= start.used_until)
    });
    n.summary_mut().gnss_before_start += before
        .iter()
        .filter(|m| matches!(m, Measurement::Gnss(_) | Measurement::GnssRaw(_)))
        .count();
    let mut t_prev = start.t0 - n.time_offset();
    let period = output_period_s.filter(|p| *p > 0.0);
    for item in start.replay.into_iter().map(Ok).chain(imu) {
        let s = item?;
        if s.t > end {
            break;
        }
        n.step(&s, &mut inbox)?;
        if let Some(f) = on_record.as_mut() {
            for r in n.take_smoother_records() {
                f(r)?;
            }
        }
        if let Some(f) = on_innovations.as_mut() {
            let rows = n.take_innovations();
            if !rows.is_empty() {
                f(&rows)?;
            }
        }
        if let Some(f) = on_updates.as_mut() {
            let ups = n.take_updates();
            if !ups.is_empty() {
                f(ups)?;
            }
        }
        // Cadence on the time scale the records carry (GNSS time).
        let t_out = n.time_gnss();
        let due = match period {
            None => true,
            Some(p) => ((t_out + 1e-6) / p).floor() > ((t_prev + 1e-6) / p).floor(),
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
    let summary = n.finish();
    if let Some(f) = on_record.as_mut() {
        for r in n.take_smoother_records() {
            f(r)?;
        }
    }
    Ok(summary)
}
