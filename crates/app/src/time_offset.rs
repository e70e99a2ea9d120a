//! The GNSS-IMU time offset: pass 1 estimates offset and rate as filter states; pass 2
//! (the run proper) navigates with the resulting line tau(t) = tau0 + rate (t - t0)
//! held fixed, so that solution time tags (on the GNSS time scale) stay monotonic.

use crate::checks::check;
use crate::error::{Error, ResultExt};
use crate::plausibility;
use crate::summary::JobResult;
use crate::RunOptions;
use navfuse_core::config::TimeOffsetConfig;
use navfuse_core::Measurement;
use navfuse_io::config::RunConfig;
use navfuse_io::imu::open_imu;

/// The GNSS-IMU time offset line found by the estimation pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeOffsetFit {
    /// Offset at `t0` \[s\].
    pub tau0: f64,
    /// Its 1-sigma at the end of the pass \[s\].
    pub tau0_sd: f64,
    /// Rate [s/s].
    pub rate: f64,
    pub rate_sd: f64,
    /// The pass's first IMU time \[s\].
    pub t0: f64,
}

/// When the configuration estimates the time offset: run the estimation pass (and,
/// for an implausible fit, the leap-second candidates), then hold the fitted line
/// fixed in `cfg` for the run proper. Returns the fit (None without a time-offset
/// state).
pub(crate) fn estimate(
    cfg: &mut RunConfig,
    measurements: &[Measurement],
    gnss_week: Option<u32>,
    opts: &RunOptions,
    job: &mut JobResult,
) -> Result<Option<TimeOffsetFit>, Error> {
    let Some(to) = cfg.nav.filter.time_offset else {
        return Ok(None);
    };
    if !(to.std_s > 0.0) {
        return Ok(None);
    }
    let fit = pass(cfg, measurements, to, opts)?;
    if let Some(f) = fit {
        // An implausible fit: would the offset of GPS time against UTC fit?
        if !plausibility::time_offset_fit(f.tau0, f.rate).is_empty() {
            let leap = plausibility::leap_seconds(gnss_week);
            for cand in [leap, -leap] {
                let start = TimeOffsetConfig {
                    initial_s: cand,
                    ..to
                };
                if let Some(g) = pass(cfg, measurements, start, opts)? {
                    let found = plausibility::leap_second_fit(f.tau0, g.tau0, g.rate);
                    if !found.is_empty() {
                        check(job, opts.warn, found)?;
                        break;
                    }
                }
            }
        }
        cfg.nav.filter.time_offset = Some(TimeOffsetConfig {
            initial_s: f.tau0,
            std_s: 0.0,
            random_walk: 0.0,
            initial_rate: f.rate,
            rate_std: 0.0,
        });
    }
    Ok(fit)
}

/// The time-offset estimation pass from the prior `to`: the fitted line, or None when
/// the run had no time-offset state.
fn pass(
    cfg: &RunConfig,
    measurements: &[Measurement],
    to: TimeOffsetConfig,
    opts: &RunOptions,
) -> Result<Option<TimeOffsetFit>, Error> {
    let mut nav = cfg.nav.clone();
    nav.filter.time_offset = Some(to);
    let reader = open_imu(&cfg.imu)?;
    let s1 = navfuse_core::run_with_sources(
        &nav,
        |c: &navfuse_core::config::NavConfig, t0| {
            opts.extra_sources.map_or_else(Vec::new, |f| f(c, t0))
        },
        reader.map(|r| opts.stop_check(r.map_err(Error::from))),
        measurements,
        Some(f64::INFINITY),
        |_| Ok(()),
        |_| {},
    )
    .context("time-offset estimation pass")?;
    Ok(s1.time_offset.map(|(tau_end, sd)| {
        let (rate, rate_sd) = s1.time_offset_rate.unwrap_or((to.initial_rate, 0.0));
        TimeOffsetFit {
            tau0: tau_end - rate * (s1.last_t - s1.first_t),
            tau0_sd: sd,
            rate,
            rate_sd,
            t0: s1.first_t,
        }
    }))
}
