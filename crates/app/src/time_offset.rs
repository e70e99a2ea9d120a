//! The GNSS-IMU time offset (docs/ALGORITHMS.md "Time offset"), in three steps before
//! the run proper:
//!
//! 1. A search (navfuse_core::time_offset_search): the GNSS course changes matched
//!    with the IMU's rotation about the vertical over the prior's initial value
//!    +- max(2 s, 3 std_s) (at most 10 s), the antenna's course lead ahead of the
//!    `[vehicle]` reference point fitted with it (known to 0.3 m with the NHC or an
//!    odometer, to 3 m otherwise). One pass over the IMU samples, no filter.
//! 2. The estimation pass: offset and rate as filter states, from the search's value
//!    when it found one (1-sigma max(2 sigma_search, 20 ms), plus what the rate prior
//!    allows over half the run), else from the configured prior.
//! 3. The choice: the pass's line when the search does not contradict it (the pass
//!    matches the turns worse by more than 25 s², 5 sigma, and lies more than 50 ms
//!    from the search) and it differs significantly from the initial value (2 sigma and
//!    half an IMU interval);
//!    the search's value when the pass contradicts it and the search differs
//!    significantly (J 9 s², 3 sigma) from the initial value; otherwise the initial
//!    value, as without estimation. The choice and why are written to events.log and
//!    summary.json.
//!
//! The run proper (pass 2) navigates with the chosen line tau(t) = tau0 + rate (t - t0)
//! held fixed, so that solution time tags (on the GNSS time scale) stay monotonic.

use crate::checks::check;
use crate::error::{Error, ResultExt};
use crate::plausibility;
use crate::summary::JobResult;
use crate::RunOptions;
use navfuse_core::config::TimeOffsetConfig;
use navfuse_core::time_offset_search::{
    course_changes, CoarseOffset, ImuBlocks, OffsetLine, TurnMatch,
};
use navfuse_core::Measurement;
use navfuse_io::config::RunConfig;
use navfuse_io::imu::open_imu;

/// The search covers at least the initial value +- this \[s\] (an offset of up to 2 s
/// is found from the default prior, 0 +- 0.5 s).
const MIN_SEARCH_HALF_RANGE_S: f64 = 2.0;

/// The estimation pass contradicts the search when its line matches the turns worse
/// by more than 25 s² (5 sigma) and its offset is this far from the search's \[s\]: a
/// filter that lost its way, not the few-sigma disagreement of two estimates.
const CONTRADICTION_S: f64 = 0.05;

/// Where the line used for the run came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeOffsetSource {
    /// The estimation pass's filter states.
    Filter,
    /// The turn-matching search (the pass contradicted it).
    Search,
    /// The configured initial value (no significant estimate).
    Initial,
}

impl TimeOffsetSource {
    pub fn name(self) -> &'static str {
        match self {
            TimeOffsetSource::Filter => "filter",
            TimeOffsetSource::Search => "search",
            TimeOffsetSource::Initial => "initial",
        }
    }
}

/// The GNSS-IMU time offset line used for the run and how it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeOffsetFit {
    /// Offset at `t0` \[s\].
    pub tau0: f64,
    /// The estimation pass's 1-sigma of the offset at its end \[s\].
    pub tau0_sd: f64,
    /// Rate [s/s].
    pub rate: f64,
    pub rate_sd: f64,
    /// The pass's first IMU time \[s\].
    pub t0: f64,
    /// Where `tau0` and `rate` come from.
    pub source: TimeOffsetSource,
    /// The search's offset at mid-run and its 1-sigma \[s\] (None: no clear minimum).
    pub search: Option<(f64, f64)>,
    /// The estimation pass's own line: offset at `t0` \[s\] and rate.
    pub filter: (f64, f64),
    /// Why this line (events.log, summary.json).
    pub note: String,
}

/// When the configuration estimates the time offset: search, run the estimation
/// pass (and, for an implausible fit, the leap-second candidates), choose, then hold
/// the chosen line fixed in `cfg` for the run proper. Returns the fit (None without
/// a time-offset state).
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
    if to.std_s.is_nan() || to.std_s <= 0.0 {
        return Ok(None);
    }
    // The search from `start`, then the estimation pass from its value.
    let search_and_pass = |start: TimeOffsetConfig| -> Result<_, Error> {
        let searched = search(cfg, measurements, &start, opts)?;
        let prior = match &searched {
            Some(s) => TimeOffsetConfig {
                initial_s: s.line.at(s.t_first),
                std_s: (2.0 * s.found.sigma_s)
                    .max(0.02)
                    .hypot(start.rate_std * 0.5 * s.span_s),
                ..start
            },
            None => start,
        };
        Ok((searched, pass(cfg, measurements, prior, opts)?))
    };
    let (searched, pass1) = search_and_pass(to)?;
    let Some(pass1) = pass1 else {
        return Ok(None);
    };
    // An implausible fit of the pass: would the offset of GPS time against UTC fit?
    if !plausibility::time_offset_fit(pass1.tau0, pass1.rate).is_empty() {
        let leap = plausibility::leap_seconds(gnss_week);
        for cand in [leap, -leap] {
            let start = TimeOffsetConfig {
                initial_s: cand,
                ..to
            };
            if let (_, Some(g)) = search_and_pass(start)? {
                let found = plausibility::leap_second_fit(pass1.tau0, g.tau0, g.rate);
                if !found.is_empty() {
                    check(job, opts.warn, found)?;
                    break;
                }
            }
        }
    }
    let fit = choose(&to, &pass1, searched.as_ref());
    cfg.nav.filter.time_offset = Some(TimeOffsetConfig {
        initial_s: fit.tau0,
        std_s: 0.0,
        random_walk: 0.0,
        initial_rate: fit.rate,
        rate_std: 0.0,
    });
    Ok(Some(fit))
}

/// The estimation pass's raw result.
struct PassFit {
    tau0: f64,
    tau0_sd: f64,
    rate: f64,
    rate_sd: f64,
    t0: f64,
    span_s: f64,
    /// Mean IMU interval of the pass \[s\].
    imu_interval_s: f64,
}

/// The search's result with what is needed to weigh other lines against it.
struct Searched {
    found: CoarseOffset,
    /// The best line (the prior's rate through the found offset at mid-run).
    line: OffsetLine,
    matcher: TurnMatch,
    t_first: f64,
    span_s: f64,
}

impl Searched {
    /// How much worse than the best line `line` matches the turns, in units of the
    /// normalised residual variance (a chi-square of 1 dof for a good fit).
    fn excess(&self, line: &OffsetLine) -> f64 {
        let best = self.matcher.cost_line(&self.line).map_or(0.0, |c| c.j);
        self.matcher
            .cost_line(line)
            .map_or(f64::INFINITY, |c| (c.j - best) / self.found.residual_var)
    }
}

/// Step 1: the turn-matching search over the run's IMU samples and GNSS inputs.
fn search(
    cfg: &RunConfig,
    measurements: &[Measurement],
    to: &TimeOffsetConfig,
    opts: &RunOptions,
) -> Result<Option<Searched>, Error> {
    let (start, end) = (
        cfg.nav.start_time,
        cfg.nav.end_time.unwrap_or(f64::INFINITY),
    );
    let mut blocks = ImuBlocks::new();
    let (mut t_first, mut t_last) = (f64::NAN, f64::NAN);
    let mut read = || -> Result<(), Error> {
        for r in open_imu(&cfg.imu)? {
            let s = opts.stop_check(r.map_err(Error::from))?;
            if s.t - s.dt < start {
                continue;
            }
            if s.t > end {
                break;
            }
            if t_first.is_nan() {
                t_first = s.t - s.dt;
            }
            t_last = s.t;
            blocks.push(&s);
        }
        Ok(())
    };
    read().context("time-offset search")?;
    if t_last.is_nan() || t_last <= t_first {
        return Ok(None);
    }
    let t_mid = 0.5 * (t_first + t_last);
    let center = OffsetLine {
        tau_ref_s: to.initial_s + to.initial_rate * (t_mid - t_first),
        rate: to.initial_rate,
        t_ref_s: t_mid,
    };
    let half_range = (3.0 * to.std_s).clamp(MIN_SEARCH_HALF_RANGE_S, 10.0);
    // The antenna's distance ahead of the vehicle reference point (where a car's
    // velocity follows its heading), body x: known to 0.3 m with the NHC or an
    // odometer (their [vehicle] lever arm), else the IMU centre +- 3 m.
    let n = &cfg.nav;
    let vehicle_known = n.odometer.enabled || n.nhc.mode != navfuse_core::config::NhcMode::Off;
    let (lead_m, lead_std_m) = match vehicle_known {
        true => (n.gnss.lever_arm_b.x - n.vehicle.lever_arm_b.x, 0.3),
        false => (n.gnss.lever_arm_b.x, 3.0),
    };
    let mut matcher = TurnMatch::new(
        blocks.finish(),
        course_changes(measurements),
        lead_m,
        lead_std_m,
    );
    Ok(matcher.search(&center, half_range).map(|found| Searched {
        found,
        line: center.moved_to(found.tau_s),
        matcher,
        t_first,
        span_s: t_last - t_first,
    }))
}

/// Step 3: which line the run uses (module documentation).
fn choose(to: &TimeOffsetConfig, p: &PassFit, searched: Option<&Searched>) -> TimeOffsetFit {
    let t_mid = p.t0 + 0.5 * p.span_s;
    let initial = OffsetLine {
        tau_ref_s: to.initial_s + to.initial_rate * (t_mid - p.t0),
        rate: to.initial_rate,
        t_ref_s: t_mid,
    };
    let filter = OffsetLine {
        tau_ref_s: p.tau0 + p.rate * (t_mid - p.t0),
        rate: p.rate,
        t_ref_s: t_mid,
    };
    // The rate only when significant; the offset then through the pass's mid-run value.
    let rate_significant = p.rate_sd > 0.0 && (p.rate - to.initial_rate).abs() > 2.0 * p.rate_sd;
    let rate = if rate_significant {
        p.rate
    } else {
        to.initial_rate
    };
    // Significant: beyond 2 sigma, and beyond half an IMU interval (the time resolution
    // of the increments; the filter's sigma can be optimistic, e.g. 0.7 ms against a
    // scatter of 2 ms in tight coupling on a MEMS IMU, RESULTS.md §18).
    let offset_significant = (filter.tau_ref_s - initial.tau_ref_s).abs()
        > (2.0 * p.tau0_sd).max(0.5 * p.imu_interval_s);
    let contradicted = searched.map(|s| (s.excess(&filter), s));
    let fmt_pass = format!(
        "estimation pass {:.4} s +- {:.4} at mid-run, rate {:.1} ppm +- {:.1}",
        filter.tau_ref_s,
        p.tau0_sd,
        p.rate * 1e6,
        p.rate_sd * 1e6
    );
    let fmt_search = searched.map_or(
        "search: no clear match of GNSS course and IMU turn rates".to_string(),
        |s| {
            format!(
                "search {:.4} s +- {:.4} ({} course changes)",
                s.found.tau_s, s.found.sigma_s, s.found.pairs
            )
        },
    );
    let line_at = |l: &OffsetLine, rate: f64| (l.tau_ref_s - rate * (t_mid - p.t0), rate);
    let (source, (tau0, rate), why) = match contradicted {
        Some((excess, s))
            if excess > 25.0 && (filter.tau_ref_s - s.found.tau_s).abs() > CONTRADICTION_S =>
        {
            // The pass disagrees with the turns (a filter that lost its way).
            if s.excess(&initial) > 9.0 {
                (
                    TimeOffsetSource::Search,
                    line_at(&s.line, to.initial_rate),
                    format!("the estimation pass contradicts the search (J {excess:.0} s² above its minimum): the search's offset is used"),
                )
            } else {
                (
                    TimeOffsetSource::Initial,
                    line_at(&initial, to.initial_rate),
                    format!("the estimation pass contradicts the search (J {excess:.0} s² above its minimum) and the search does not differ significantly from the initial value: the initial value is kept"),
                )
            }
        }
        _ if offset_significant || rate_significant => (
            TimeOffsetSource::Filter,
            line_at(&filter, rate),
            "the estimation pass's offset is used".to_string()
                + if rate_significant {
                    " with its rate"
                } else {
                    " (its rate is not significant: the initial rate is kept)"
                },
        ),
        _ => (
            TimeOffsetSource::Initial,
            line_at(&initial, to.initial_rate),
            "the estimate does not differ significantly (2 sigma, at least half an IMU interval) from the initial value: the initial value is kept".to_string(),
        ),
    };
    TimeOffsetFit {
        tau0,
        tau0_sd: p.tau0_sd,
        rate,
        rate_sd: p.rate_sd,
        t0: p.t0,
        source,
        search: searched.map(|s| (s.found.tau_s, s.found.sigma_s)),
        filter: (p.tau0, p.rate),
        note: format!("{fmt_search}; {fmt_pass}; {why}"),
    }
}

/// The time-offset estimation pass from the prior `to`: the fitted line, or None when
/// the run had no time-offset state.
fn pass(
    cfg: &RunConfig,
    measurements: &[Measurement],
    to: TimeOffsetConfig,
    opts: &RunOptions,
) -> Result<Option<PassFit>, Error> {
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
        PassFit {
            tau0: tau_end - rate * (s1.last_t - s1.first_t),
            tau0_sd: sd,
            rate,
            rate_sd,
            t0: s1.first_t,
            span_s: s1.last_t - s1.first_t,
            imu_interval_s: (s1.last_t - s1.first_t) / (s1.imu_samples.max(1) as f64),
        }
    }))
}
