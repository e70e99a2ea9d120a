//! Plausibility checks of the run pipeline (`navfuse run`): inputs and results that
//! parse but cannot be what the user meant (units, axes, time scales, weeks, empty
//! files). Each check is a small function of plain values returning its findings, so
//! that it can be tested alone. A [`Severity::Error`] means the result would be
//! meaningless: the run is refused (before it) or reported as failed (after it, with
//! its output kept); a [`Severity::Unreliable`] finding, after the run, means the
//! program can tell its result is meaningless although it ran: every file is written,
//! `summary.json` says `"status": "unreliable"` with the reasons and `navfuse run`
//! exits with status 3; a [`Severity::Warning`] names the likely mistake and the
//! configuration key to change.

use nalgebra::Vector3;
use navfuse_core::earth::OMEGA_IE;
use navfuse_core::ImuSample;
use std::fmt;

/// Standard gravity [m/s²] (the unit `g`).
const G0: f64 = 9.806_65;
/// GPS - UTC has been a whole number of seconds between these (1996: 11 s ... 2017: 18 s;
/// with a margin either side).
const LEAP_SECONDS: std::ops::RangeInclusive<i64> = 10..=19;
/// Lever arms longer than this \[m\] are probably given in cm or mm.
pub const MAX_LEVER_ARM_M: f64 = 5.0;
/// A time-offset prior this wide \[s\] lets the first pass lock onto a wrong epoch.
pub const MAX_TIME_OFFSET_STD_S: f64 = 30.0;
/// Fitted offsets beyond these are reported.
pub const MAX_TIME_OFFSET_S: f64 = 2.0;
pub const MAX_TIME_OFFSET_RATE_PPM: f64 = 1000.0;
/// Below this fraction of usable GNSS epochs used, the reasons are reported.
pub const MIN_GNSS_USED_FRACTION: f64 = 0.5;
/// Land-vehicle roll / pitch beyond this \[deg\] at alignment is reported.
pub const MAX_LAND_TILT_DEG: f64 = 45.0;
/// Seconds of IMU data at the start of the file looked at by [`imu_window`].
pub const DEFAULT_IMU_WINDOW_S: f64 = 10.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Warning,
    /// The run's result is kept but cannot be trusted (status "unreliable").
    Unreliable,
    Error,
}

/// One finding of a check.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub severity: Severity,
    pub message: String,
}

impl Finding {
    pub fn warning(message: impl Into<String>) -> Self {
        Finding {
            severity: Severity::Warning,
            message: message.into(),
        }
    }
    pub fn error(message: impl Into<String>) -> Self {
        Finding {
            severity: Severity::Error,
            message: message.into(),
        }
    }
    pub fn unreliable(message: impl Into<String>) -> Self {
        Finding {
            severity: Severity::Unreliable,
            message: message.into(),
        }
    }
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
    pub fn is_unreliable(&self) -> bool {
        self.severity == Severity::Unreliable
    }
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.severity {
            Severity::Warning => write!(f, "warning: {}", self.message),
            Severity::Unreliable => write!(f, "unreliable: {}", self.message),
            Severity::Error => write!(f, "error: {}", self.message),
        }
    }
}

/// A time span [first, last] of some input, with its file and GPS week when known.
#[derive(Clone, Debug, PartialEq)]
pub struct Span {
    pub file: String,
    pub first: f64,
    pub last: f64,
    pub week: Option<u32>,
}

/// The GNSS epochs and the IMU data must overlap. `imu.last` may be +inf before the
/// IMU file has been read to its end (then only GNSS wholly before the IMU is found).
/// Times are on the IMU's week reference (GNSS already shifted by the week difference).
pub fn time_overlap(imu: &Span, gnss: &Span) -> Vec<Finding> {
    if gnss.last >= imu.first && gnss.first <= imu.last {
        return Vec::new();
    }
    let imu_end = if imu.last.is_finite() {
        format!("{:.3}", imu.last)
    } else {
        "...".to_string()
    };
    let mut msg = format!(
        "the GNSS epochs ({}, t {:.3} .. {:.3}) do not overlap the IMU data ({}, t {:.3} .. {imu_end}): the run would be free inertial",
        gnss.file, gnss.first, gnss.last, imu.file, imu.first
    );
    // Distance between the spans, to name the likely cause.
    let gap = if gnss.first > imu.last {
        gnss.first - imu.last
    } else {
        gnss.last - imu.first
    };
    match (imu.week, gnss.week) {
        (Some(wi), Some(wg)) if wi != wg => msg.push_str(&format!(
            "; week mismatch: the IMU data are in GPS week {wi}, the GNSS in week {wg} \
             (fix the time tags, or shift one input with [imu] time_offset_s / [gnss] time_offset_s)"
        )),
        _ if (gap.abs() / WEEK_S).round() >= 1.0 && (gap.abs() % WEEK_S) < 3600.0 * 24.0 => {
            msg.push_str(
                "; the gap is about a whole number of weeks: one input in another GPS week? \
                 (shift it with [imu] time_offset_s / [gnss] time_offset_s)",
            )
        }
        _ => msg.push_str(
            "; are both on the same time scale (GPS seconds of week)? check [imu.csv] time_scale, \
             [imu] time_offset_s and [gnss] time_offset_s",
        ),
    }
    vec![Finding::error(msg)]
}

use navfuse_core::time::SECONDS_PER_WEEK as WEEK_S;

/// A GNSS input was configured but gave no epoch.
pub fn gnss_not_empty(file: &str, epochs: usize, skipped: usize) -> Vec<Finding> {
    if epochs > 0 {
        return Vec::new();
    }
    let why = if skipped > 0 {
        format!(
            "all {skipped} epochs were dropped by [gnss] quality / decimate_s: relax those keys"
        )
    } else {
        "the file holds no epoch: is it the right file? (remove [gnss] for a free-inertial run)"
            .to_string()
    };
    vec![Finding::error(format!("{file}: no GNSS epochs; {why}"))]
}

/// `[time] start` must lie before the end of the data (`data_last`, from `what`).
pub fn start_before_end(start: f64, data_last: f64, what: &str) -> Vec<Finding> {
    if !start.is_finite() || start <= data_last {
        return Vec::new();
    }
    vec![Finding::error(format!(
        "[time] start = {start:.3} is after the end of the data ({what} ends at t = {data_last:.3}): nothing to navigate; set [time] start within the data"
    ))]
}

/// GNSS epoch counts after a run (RunSummary) and the epochs inside the IMU span.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GnssUse {
    pub in_span: usize,
    pub used: usize,
    pub rejected: usize,
    pub in_outages: usize,
    pub before_start: usize,
}

/// Fewer than half of the GNSS epochs that could be used (inside the IMU data and not
/// in a configured outage) were used: the reasons, with counts.
pub fn gnss_usage(u: &GnssUse) -> Vec<Finding> {
    let usable = u.in_span.saturating_sub(u.in_outages);
    if usable == 0 || u.used as f64 >= MIN_GNSS_USED_FRACTION * usable as f64 {
        return Vec::new();
    }
    let other = usable.saturating_sub(u.used + u.rejected + u.before_start);
    let mut why = Vec::new();
    if u.rejected > 0 {
        why.push(format!(
            "{} rejected by the innovation gate (see events.log; [gnss] gate_probability, the [imu_noise] stds, or a time offset: [filter] time_offset)",
            u.rejected
        ));
    }
    if u.before_start > 0 {
        why.push(format!(
            "{} before the start or used for the alignment ([time] start, [initial.alignment])",
            u.before_start
        ));
    }
    if other > 0 {
        why.push(format!(
            "{other} after the run stopped or otherwise not fused ([time] end)"
        ));
    }
    let message = format!(
        "GNSS: only {} of the {usable} epochs within the IMU data and outside outages were used ({}): the solution is mostly free inertial",
        u.used,
        why.join("; ")
    );
    // Almost every usable epoch refused by the filter's own test: the INS and the
    // GNSS disagree throughout, so the output is neither (a wrong unit, axis or time
    // scale is the usual cause; the warnings before name it).
    let refused = usable.saturating_sub(u.before_start);
    if usable >= MIN_EPOCHS_FOR_VERDICT
        && (u.used as f64) < MAX_GNSS_USED_FRACTION_UNRELIABLE * usable as f64
        && 2 * u.rejected >= refused
    {
        vec![Finding::unreliable(message)]
    } else {
        vec![Finding::warning(message)]
    }
}

/// Below this fraction of usable GNSS epochs used, with most of the rest rejected by
/// the filter's test, the run is unreliable.
pub const MAX_GNSS_USED_FRACTION_UNRELIABLE: f64 = 0.05;
/// Fewer GNSS epochs or updates than this give no verdict on the whole run.
pub const MIN_EPOCHS_FOR_VERDICT: usize = 10;
/// A source whose updates have an extreme NIS (per row above
/// `navfuse_core::events::EXTREME_NIS_PER_ROW`) more often than this makes the run
/// unreliable.
pub const MAX_EXTREME_NIS_SHARE: f64 = 0.5;
/// Mean NIS per row of a source outside these bounds is reported (1 for a
/// consistent filter; the bounds leave room for a few outliers and a short run).
pub const NIS_PER_ROW_WARN: (f64, f64) = (0.3, 3.0);
/// Fewer updates than this give no verdict on a source's noise.
pub const MIN_UPDATES_FOR_NOISE_VERDICT: usize = 30;
/// Lag-1 autocorrelation of a source's normalised innovations above this (and
/// significant) is reported as errors correlated in time.
pub const MAX_INNOVATION_AUTOCORRELATION: f64 = 0.3;

/// The configuration key that sets a source's measurement noise, for the messages.
pub fn noise_key(source: &str) -> &'static str {
    match source {
        "gnss_position" => "[gnss] position_std_scale (or position_std_m)",
        "gnss_velocity" => "[gnss] velocity_std_scale (or velocity_std_mps)",
        "nhc" => "[nhc] std_mps",
        "odometer" => "[odometer] std_mps",
        "zupt" => "[zupt] velocity_std_mps",
        "zaru" => "[zupt] angular_rate_std_dps",
        "dual_antenna_heading" => "[heading] std_deg",
        "course_over_ground" => "[heading] course_std_floor_deg",
        "pseudorange" => "[gnss.tight] pseudorange_sigma_scale",
        "doppler" | "tdcp" => "[gnss.tight] range_rate_sigma_scale",
        "baro" => "[baro] std_m",
        _ => "the source's noise setting",
    }
}

/// One source's innovations after the run: how many were tried, the mean NIS per row
/// of those applied, and their statistics (`navfuse_core::InnovationStats`).
#[derive(Clone, Copy, Debug)]
pub struct SourceInnovations<'a> {
    pub source: &'a str,
    pub nis_per_row: Option<f64>,
    pub applied: usize,
    pub stats: &'a navfuse_core::InnovationStats,
    /// The model already has the source's errors time-correlated (Gauss-Markov
    /// states), so correlated innovations mean a wrong correlation time.
    pub correlated_model: bool,
}

/// A source's innovations against its noise setting: extreme most of the time
/// (unreliable), a mean NIS per row far from 1 (a noise setting off by the square root
/// of it), or clearly correlated from one update to the next (errors correlated in
/// time where the model has them white).
pub fn innovation_consistency(s: &SourceInnovations) -> Vec<Finding> {
    let mut out = Vec::new();
    let key = noise_key(s.source);
    let st = s.stats;
    if st.tried >= MIN_EPOCHS_FOR_VERDICT && st.extreme_share() > MAX_EXTREME_NIS_SHARE {
        out.push(Finding::unreliable(format!(
            "{}: {} of its {} updates ({:.0} %) had a normalised innovation squared above {:.0} per row: the data and the filter disagree by more than 10 sigma for most of the run (units, axes, lever arm or time scale of an input? the warnings before name the likely one; else {key} and [imu_noise] far too small)",
            s.source,
            st.extreme,
            st.tried,
            100.0 * st.extreme_share(),
            navfuse_core::events::EXTREME_NIS_PER_ROW
        )));
        return out;
    }
    if s.applied >= MIN_UPDATES_FOR_NOISE_VERDICT {
        if let Some(nis) = s.nis_per_row {
            let (lo, hi) = NIS_PER_ROW_WARN;
            if s.source == "gnss_position" && nis > MAX_FIX_NIS_PER_ROW {
                // Far beyond a noise setting: the likely mistakes by name.
                out.extend(fix_agreement(nis));
            } else if nis > hi {
                out.push(Finding::warning(format!(
                    "{}: mean NIS per row {nis:.1} (1 for a consistent filter): its errors are about {:.1} times what the filter expects, so the filter is overconfident; raise {key} or the [imu_noise] values, or let `navfuse tune` estimate them",
                    s.source,
                    nis.sqrt()
                )));
            } else if nis < lo {
                out.push(Finding::warning(format!(
                    "{}: mean NIS per row {nis:.2} (1 for a consistent filter): its errors are about {:.1} times smaller than the filter expects, so it is underconfident and weighs this source too little; lower {key} (or the [imu_noise] values), or let `navfuse tune` estimate them",
                    s.source,
                    1.0 / nis.sqrt()
                )));
            }
        }
    }
    let rows = if s.source == "gnss_position" || s.source == "gnss_velocity" {
        3
    } else {
        1
    };
    let rho: Vec<f64> = (0..rows).filter_map(|k| st.autocorrelation(k)).collect();
    let pairs = st.pairs.iter().copied().max().unwrap_or(0);
    if !rho.is_empty() && pairs >= MIN_UPDATES_FOR_NOISE_VERDICT {
        let mean = rho.iter().sum::<f64>() / rho.len() as f64;
        // Significant: beyond 3 standard errors of a white sequence (1/sqrt(n)).
        let significant = mean > (3.0 / (pairs as f64).sqrt()).max(MAX_INNOVATION_AUTOCORRELATION);
        if significant {
            let dt = st.mean_pair_dt().unwrap_or(f64::NAN);
            let what = if s.source == "gnss_velocity" {
                "the fix velocities' errors are correlated in time (a receiver's own velocity filter) where the model has them white (the fix-error model covers positions only)"
            } else if s.correlated_model {
                "the fix errors are correlated longer than the fix-error model allows ([gnss] error_corr_time_s, error_corr_fraction)"
            } else {
                "the errors are correlated in time where the model has them white"
            };
            let fix = match s.source {
                "gnss_velocity" => {
                    "set [gnss] use_velocity = false, or raise [gnss] velocity_std_scale so that they weigh less"
                }
                "gnss_position" if !s.correlated_model => {
                    "model them as Gauss-Markov ([gnss] error_corr_time_s)"
                }
                "gnss_position" => "lengthen [gnss] error_corr_time_s",
                _ => "raise {key} so that the correlated errors weigh less",
            };
            out.push(Finding::warning(format!(
                "{}: its innovations are correlated from one update to the next (lag-1 autocorrelation {mean:.2} at {dt:.2} s over {pairs} pairs; about 0 when the noise model fits the data): {what}, or the [imu_noise] values are off; {}, or let `navfuse tune` estimate the noise model",
                s.source,
                fix.replace("{key}", key)
            )));
        }
    }
    out
}

/// The IMU data end well before the GNSS data (and the configured end): the run
/// covers only part of what it was given (a truncated file, a logger that stopped).
pub fn imu_ends_early(
    imu_last: f64,
    gnss_first: f64,
    gnss_last: f64,
    end_time: Option<f64>,
) -> Vec<Finding> {
    let wanted_end = end_time.map_or(gnss_last, |e| e.min(gnss_last));
    let missing = wanted_end - imu_last;
    let span = (gnss_last - gnss_first).max(0.0);
    let allowed = MIN_IMU_SHORTFALL_S.max(MIN_IMU_SHORTFALL_FRACTION * span);
    if missing.is_nan() || missing <= allowed {
        return Vec::new();
    }
    vec![Finding::unreliable(format!(
        "the IMU data end at t = {imu_last:.3}, {missing:.1} s ({:.0} % of the GNSS span) before the GNSS data (t = {wanted_end:.3}): the IMU file was cut short (a truncated copy, a logger that stopped, a file still being written?); the solution covers only the IMU's part (set [time] end to accept that)",
        100.0 * missing / span.max(1e-9)
    ))]
}

/// The IMU may end this long \[s\] (and this fraction of the GNSS span) before the
/// GNSS before the run is unreliable.
pub const MIN_IMU_SHORTFALL_S: f64 = 30.0;
pub const MIN_IMU_SHORTFALL_FRACTION: f64 = 0.1;

/// The fitted GNSS-IMU time offset \[s\] and rate \[s/s\].
pub fn time_offset_fit(tau_s: f64, rate: f64) -> Vec<Finding> {
    let mut out = Vec::new();
    if !tau_s.is_finite() || !rate.is_finite() {
        out.push(Finding::error(format!(
            "the GNSS-IMU time offset estimate is not finite (offset {tau_s}, rate {rate}): check [filter] time_offset"
        )));
        return out;
    }
    if tau_s.abs() > MAX_TIME_OFFSET_S {
        let n = tau_s.round() as i64;
        let hint = if (tau_s - n as f64).abs() <= 0.5 && LEAP_SECONDS.contains(&n.abs()) {
            format!(
                " ({n} s: UTC vs GPST? GPS time is ahead of UTC by the leap seconds, 18 s since 2017; tag both inputs in GPS time or set [gnss] time_offset_s = {})",
                n
            )
        } else {
            " (a logging latency, or inputs on different time scales? set [gnss] time_offset_s or [imu] time_offset_s to it)".to_string()
        };
        out.push(Finding::warning(format!(
            "the fitted GNSS-IMU time offset is {tau_s:.3} s, more than {MAX_TIME_OFFSET_S} s{hint}"
        )));
    }
    let ppm = rate * 1e6;
    if ppm.abs() > MAX_TIME_OFFSET_RATE_PPM {
        out.push(Finding::warning(format!(
            "the fitted GNSS-IMU time offset rate is {ppm:.0} ppm, more than {MAX_TIME_OFFSET_RATE_PPM:.0} ppm: a wrong [imu] rate_hz or [imu.csv] time_unit? (or set [filter] time_offset rate_std_ppm smaller)"
        )));
    }
    out
}

pub use navfuse_core::time::leap_seconds;

/// The fit from a zero prior was implausible (`tau0_s`); a second fit started from
/// plus or minus the leap seconds found `tau_s` with rate `rate` [s/s]: when that one
/// is plausible and a whole number of leap seconds, the GNSS tags are likely UTC.
pub fn leap_second_fit(tau0_s: f64, tau_s: f64, rate: f64) -> Vec<Finding> {
    let n = tau_s.round();
    let plausible_rate = (rate * 1e6).abs() <= MAX_TIME_OFFSET_RATE_PPM;
    if !plausible_rate || (tau_s - n).abs() > 0.5 || !LEAP_SECONDS.contains(&(n.abs() as i64)) {
        return Vec::new();
    }
    vec![Finding::warning(format!(
        "the GNSS-IMU time offset fitted from the prior is {tau0_s:.3} s, but started from {n:.0} s it fits {tau_s:.3} s at {:.0} ppm: {n:.0} s: UTC vs GPST? the GNSS (or IMU) time tags look like UTC labelled as GPS time; tag both in GPS time, or set [gnss] time_offset_s = {n:.0} (and keep [filter] time_offset for the rest)",
        rate * 1e6
    ))]
}

/// The time-offset prior std \[s\] of the configuration.
pub fn time_offset_prior(std_s: f64) -> Vec<Finding> {
    if std_s < MAX_TIME_OFFSET_STD_S {
        return Vec::new();
    }
    vec![Finding::warning(format!(
        "[filter] time_offset std_s = {std_s} s: a prior this wide lets the estimation lock onto a wrong epoch (offsets of -14 to -52 s have been seen); find the offset roughly, set [filter] time_offset initial_s (or [gnss] time_offset_s) to it and keep std_s under {MAX_TIME_OFFSET_STD_S} s"
    ))]
}

/// Mean NIS per row of the fused fix positions above which the fixes and the INS
/// disagree by far more than either's uncertainty (a tuned MEMS car reaches 8-10).
const MAX_FIX_NIS_PER_ROW: f64 = 50.0;

/// The fixes fused, but far outside what the filter expected of them: the solution is
/// a tug of war between the GNSS and a wrongly configured INS.
pub fn fix_agreement(nis_per_row: f64) -> Vec<Finding> {
    if nis_per_row.is_nan() || nis_per_row <= MAX_FIX_NIS_PER_ROW {
        return Vec::new();
    }
    vec![Finding::warning(format!(
        "the GNSS fixes disagreed with the INS by {:.0} times their expected spread (mean normalised innovation squared per row {nis_per_row:.0}, see summary.json nis_per_row): a lever arm in the wrong unit or sign ([gnss] lever_arm_m, metres, body F R D), a time offset ([gnss] time_offset_s), IMU units or axes ([imu.csv]), or far too small [imu_noise] values?",
        nis_per_row.sqrt()
    ))]
}

/// The GNSS integrity monitor judges GNSS against the dead reckoning: an INS alone
/// drifts too fast to tell a slow spoofer from its own drift, and then takes the real
/// signal for the spoofer.
pub fn spoofing_reference(monitor: bool, odometer: bool, nhc: bool) -> Vec<Finding> {
    if !monitor || odometer || nhc {
        return Vec::new();
    }
    vec![Finding::warning(
        "[spoofing] runs with neither an odometer nor the NHC: its reference is the free INS, which drifts too fast to tell a slow spoofer from its own drift (a 0.01 m/s^2 attack goes unseen, and the real GNSS can then be refused); add [odometer] or [nhc] mode = \"always\"",
    )]
}

/// A lever arm (`key`, metres) longer than [`MAX_LEVER_ARM_M`].
pub fn lever_arm(key: &str, arm_m: &Vector3<f64>) -> Vec<Finding> {
    let n = arm_m.norm();
    if n <= MAX_LEVER_ARM_M {
        return Vec::new();
    }
    vec![Finding::warning(format!(
        "{key} = [{}, {}, {}] is {n:.1} m long: given in cm or mm? the key is in metres (e.g. [{}, {}, {}] if it was cm)",
        arm_m.x,
        arm_m.y,
        arm_m.z,
        arm_m.x / 100.0,
        arm_m.y / 100.0,
        arm_m.z / 100.0
    ))]
}

/// Mean specific force [m/s²] and angular rate [rad/s] (body frame, as read) over
/// the IMU window at the start of the file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuWindow {
    pub duration_s: f64,
    pub mean_f: Vector3<f64>,
    pub mean_w: Vector3<f64>,
}

/// Means over the samples (None without a positive total interval).
pub fn imu_window(samples: &[ImuSample]) -> Option<ImuWindow> {
    let dt: f64 = samples.iter().map(|s| s.dt).sum();
    if dt.is_nan() || dt <= 0.0 {
        return None;
    }
    let dv: Vector3<f64> = samples.iter().map(|s| s.dvel).sum();
    let da: Vector3<f64> = samples.iter().map(|s| s.dtheta).sum();
    Some(ImuWindow {
        duration_s: dt,
        mean_f: dv / dt,
        mean_w: da / dt,
    })
}

/// How the IMU file declares its units, to name the key to change.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuUnits {
    /// m/s² per accelerometer unit as declared (1 or 9.80665).
    pub accel_scale: f64,
    /// rad/s per gyro unit as declared (1 or pi/180).
    pub gyro_scale: f64,
    /// Where the units are set: `[imu.csv]` keys, or None when the format fixes them.
    pub csv: bool,
}

/// Specific force against local gravity and angular rate against Earth rate plus the
/// gyro-bias bound over the window at the start of the file (`static_start`: the
/// configured alignment expects the vehicle at rest there). `gyro_bias_bound` [rad/s]
/// is what the configuration allows the bias to be (3 sigma plus the initial estimate).
pub fn imu_magnitudes(
    w: &ImuWindow,
    units: &ImuUnits,
    gravity: f64,
    gyro_bias_bound: f64,
    static_start: bool,
) -> Vec<Finding> {
    let f = w.mean_f.norm();
    let rate = w.mean_w.norm();
    let head = format!(
        "over the first {:.1} s of the IMU file the mean specific force is {f:.3} m/s² (local gravity {gravity:.3}) and the mean angular rate {:.4} rad/s ({:.1} deg/h)",
        w.duration_s,
        rate,
        rate.to_degrees() * 3600.0
    );
    let key = |k: &str, v: &str| {
        if units.csv {
            format!("set [imu.csv] {k}{v}")
        } else {
            "the format fixes the units: check [imu] format (docs/FORMATS.md)".to_string()
        }
    };
    let near = |x: f64, target: f64, tol: f64| (x - target).abs() <= tol * target;
    let f_ok = near(f, gravity, 0.2);
    // Reading the gyro columns in the accelerometer's declared unit.
    let gyro_as_accel = rate / units.gyro_scale * units.accel_scale;
    if !f_ok && near(gyro_as_accel, gravity, 0.25) {
        return vec![Finding::warning(format!(
            "{head}: the gyro columns read about 1 g and the accelerometer does not: accelerometer and gyro columns swapped? {}",
            key("accel_cols / gyro_cols", "")
        ))];
    }
    let mut out = Vec::new();
    if !f_ok {
        let msg = if near(f, gravity / G0, 0.25) {
            format!(
                "{head}: 1/9.81 of gravity: accelerometer in g declared as m/s²? {}",
                key("accel_unit", " = \"g\"")
            )
        } else if near(f, gravity * G0, 0.25) {
            format!(
                "{head}: 9.81 times gravity: accelerometer in m/s² declared as g? {}",
                key("accel_unit", " = \"m\"")
            )
        } else {
            format!(
                "{head}: not gravity: a wrong accelerometer unit or columns ({}), or the vehicle not at rest at the start?",
                key("accel_unit / accel_cols", "")
            )
        };
        out.push(Finding::warning(msg));
    }
    let limit = OMEGA_IE + gyro_bias_bound;
    if static_start && rate > limit {
        // The same numbers read as deg/s.
        let as_deg = rate.to_radians();
        let msg = if units.gyro_scale == 1.0 && as_deg <= limit * 2.0 {
            format!(
                "{head}, far above Earth rate plus the gyro bias bound ({:.1} deg/h): gyro in deg/s declared as rad/s? {}",
                limit.to_degrees() * 3600.0,
                key("gyro_unit", " = \"deg\"")
            )
        } else {
            format!(
                "{head}, above Earth rate plus the gyro bias bound ({:.1} deg/h): the vehicle not at rest at the start, a wrong gyro unit ({}), or a gyro bias larger than [initial] gyro_bias_std_degph allows?",
                limit.to_degrees() * 3600.0,
                key("gyro_unit", "")
            )
        };
        out.push(Finding::warning(msg));
    }
    out
}

/// Largest |roll| and |pitch| at the start of a run of any vehicle before a warning
/// (a body frame upside down or on end) [deg].
const MAX_ANY_ROLL_DEG: f64 = 100.0;
const MAX_ANY_PITCH_DEG: f64 = 75.0;

/// Roll and pitch of the aligned attitude \[deg\]. A land vehicle (NHC or odometer) sits
/// within a few degrees of level; a tilt beyond [`MAX_LAND_TILT_DEG`] means the sensor
/// axes were not turned into the body frame; any vehicle upside down or on end at the
/// start likewise.
pub fn aligned_tilt(rpy_deg: [f64; 3], land_vehicle: bool) -> Vec<Finding> {
    let (roll, pitch) = (rpy_deg[0], rpy_deg[1]);
    let tilted = roll.abs() > MAX_LAND_TILT_DEG || pitch.abs() > MAX_LAND_TILT_DEG;
    // Any vehicle: upside down (or on its nose) at the start is a frame mistake.
    let inverted = roll.abs() > MAX_ANY_ROLL_DEG || pitch.abs() > MAX_ANY_PITCH_DEG;
    let hint = "sensor-to-body rotation forgotten? set [imu] sensor_to_body_rpy_deg (e.g. [180, 0, 0] for a sensor z axis pointing up)";
    if land_vehicle && tilted {
        return vec![Finding::warning(format!(
            "the initial attitude has roll {roll:.1} deg, pitch {pitch:.1} deg: a land vehicle (NHC / odometer configured) is close to level; {hint}"
        ))];
    }
    if inverted {
        return vec![Finding::warning(format!(
            "the initial attitude has roll {roll:.1} deg, pitch {pitch:.1} deg: the body frame starts upside down or on end; {hint}"
        ))];
    }
    Vec::new()
}

/// The alignment could not find the yaw from the data (`method` of the events line).
pub fn aligned_yaw_unknown(method: &str) -> Vec<Finding> {
    let what = if method.contains("yaw unknown") {
        "the yaw starts at 0 deg"
    } else if method.contains("yaw uncertain") {
        "the yaw starts from the course of a single GNSS epoch, maybe its velocity noise"
    } else {
        return Vec::new();
    };
    vec![Finding::warning(format!(
        "the data did not give the initial yaw (no GNSS course clear of the velocity noise, no horizontal acceleration the velocity matching could use, gyros too coarse to gyrocompass): {what} (events.log, aligned line); give [initial] attitude_deg"
    ))]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(first: f64, last: f64, week: Option<u32>) -> Span {
        Span {
            file: "f".into(),
            first,
            last,
            week,
        }
    }

    #[test]
    fn overlap_and_week_mismatch() {
        assert!(time_overlap(&span(0.0, 100.0, None), &span(50.0, 200.0, None)).is_empty());
        let e = time_overlap(&span(0.0, 100.0, None), &span(300.0, 400.0, None));
        assert!(e[0].is_error() && e[0].message.contains("do not overlap"));
        assert!(e[0].message.contains("time_offset_s"));
        let e = time_overlap(
            &span(0.0, 100.0, Some(2374)),
            &span(WEEK_S, WEEK_S + 100.0, Some(2375)),
        );
        assert!(e[0].message.contains("week mismatch"), "{}", e[0]);
        assert!(e[0].message.contains("2374") && e[0].message.contains("2375"));
        // Before the IMU's end is known, only GNSS wholly before it is an error.
        assert!(time_overlap(&span(50.0, f64::INFINITY, None), &span(60.0, 70.0, None)).is_empty());
        assert_eq!(
            time_overlap(&span(50.0, f64::INFINITY, None), &span(0.0, 10.0, None)).len(),
            1
        );
    }

    #[test]
    fn empty_gnss_and_late_start() {
        assert!(gnss_not_empty("g", 3, 0).is_empty());
        assert!(gnss_not_empty("g", 0, 0)[0]
            .message
            .contains("no GNSS epochs"));
        assert!(gnss_not_empty("g", 0, 7)[0].message.contains("quality"));
        assert!(start_before_end(5.0, 10.0, "x").is_empty());
        assert!(start_before_end(f64::NEG_INFINITY, 10.0, "x").is_empty());
        let e = start_before_end(20.0, 10.0, "the IMU file");
        assert!(
            e[0].is_error() && e[0].message.contains("20.000") && e[0].message.contains("10.000")
        );
    }

    #[test]
    fn gnss_usage_reasons() {
        let ok = GnssUse {
            in_span: 100,
            used: 60,
            ..Default::default()
        };
        assert!(gnss_usage(&ok).is_empty());
        // Outages are deliberate: not counted against the fraction.
        let outages = GnssUse {
            in_span: 100,
            used: 30,
            in_outages: 50,
            ..Default::default()
        };
        assert!(gnss_usage(&outages).is_empty());
        let bad = GnssUse {
            in_span: 100,
            used: 10,
            rejected: 80,
            before_start: 5,
            in_outages: 0,
        };
        let w = gnss_usage(&bad);
        assert_eq!(w.len(), 1);
        let m = &w[0].message;
        assert!(m.contains("10 of the 100") && m.contains("80 rejected") && m.contains("5 before"));
        assert!(m.contains("5 after"), "{m}");
    }

    #[test]
    fn time_offsets() {
        assert!(time_offset_fit(0.2, 300e-6).is_empty());
        let w = time_offset_fit(18.03, 0.0);
        assert!(w[0].message.contains("18 s: UTC vs GPST?"), "{}", w[0]);
        let w = time_offset_fit(-17.8, 0.0);
        assert!(w[0].message.contains("-18 s: UTC vs GPST?"), "{}", w[0]);
        let w = time_offset_fit(3.0, 0.0);
        assert!(!w[0].message.contains("UTC") && w[0].message.contains("3.000"));
        let w = time_offset_fit(0.0, 2000e-6);
        assert!(w[0].message.contains("2000 ppm"));
        assert!(time_offset_fit(f64::NAN, 0.0)[0].is_error());
        assert_eq!(leap_seconds(Some(2374)), 18.0);
        assert_eq!(leap_seconds(Some(1600)), 15.0);
        assert_eq!(leap_seconds(None), 18.0);
        let w = leap_second_fit(-3.6, 17.98, 290e-6);
        assert!(w[0].message.contains("18 s: UTC vs GPST?"), "{}", w[0]);
        assert!(leap_second_fit(-3.6, 17.98, 0.1).is_empty());
        assert!(leap_second_fit(-3.6, 3.0, 0.0).is_empty());
        assert!(time_offset_prior(0.5).is_empty());
        assert!(time_offset_prior(30.0)[0].message.contains("wrong epoch"));
    }

    #[test]
    fn lever_arms() {
        assert!(lever_arm("[gnss] lever_arm_m", &Vector3::new(0.0, -0.05, -1.2)).is_empty());
        let w = lever_arm("[gnss] lever_arm_m", &Vector3::new(0.0, -5.0, -120.0));
        assert!(w[0].message.contains("cm or mm") && w[0].message.contains("[gnss] lever_arm_m"));
    }

    fn window(f: [f64; 3], w: [f64; 3]) -> ImuWindow {
        ImuWindow {
            duration_s: 10.0,
            mean_f: Vector3::from(f),
            mean_w: Vector3::from(w),
        }
    }

    const CSV_SI: ImuUnits = ImuUnits {
        accel_scale: 1.0,
        gyro_scale: 1.0,
        csv: true,
    };
    const BIAS: f64 = 1e-3; // about 200 deg/h

    #[test]
    fn imu_units_and_axes() {
        let g = 9.80;
        // Right: gravity and a small rate.
        assert!(imu_magnitudes(
            &window([0.1, 0.0, -9.8], [1e-4, 0.0, 0.0]),
            &CSV_SI,
            g,
            BIAS,
            true
        )
        .is_empty());
        // Accelerometer in g declared m/s².
        let w = imu_magnitudes(
            &window([0.0, 0.0, -1.0], [1e-4, 0.0, 0.0]),
            &CSV_SI,
            g,
            BIAS,
            true,
        );
        assert!(
            w[0].message
                .contains("accelerometer in g declared as m/s²? set [imu.csv] accel_unit"),
            "{}",
            w[0]
        );
        // Columns swapped: |f| ~ 0, |w| ~ 9.8.
        let w = imu_magnitudes(
            &window([1e-4, 0.0, 0.0], [0.0, 0.0, -9.8]),
            &CSV_SI,
            g,
            BIAS,
            true,
        );
        assert_eq!(w.len(), 1);
        assert!(w[0].message.contains("columns swapped"), "{}", w[0]);
        // Swapped in g and deg/s: the gyro columns read 1 (g) as deg/s.
        let gdeg = ImuUnits {
            accel_scale: G0,
            gyro_scale: 1f64.to_radians(),
            csv: true,
        };
        let w = imu_magnitudes(
            &window([0.2 * G0, 0.0, 0.0], [0.0, 0.0, 1f64.to_radians()]),
            &gdeg,
            g,
            BIAS,
            true,
        );
        assert!(w[0].message.contains("columns swapped"), "{}", w[0]);
        // Gyro deg/s declared rad/s: 0.2 deg/s bias read as 0.2 rad/s.
        let w = imu_magnitudes(
            &window([0.0, 0.0, -9.8], [0.2, 0.0, 0.0]),
            &CSV_SI,
            g,
            0.2f64.to_radians() * 3.0,
            true,
        );
        assert!(
            w[0].message
                .contains("gyro in deg/s declared as rad/s? set [imu.csv] gyro_unit"),
            "{}",
            w[0]
        );
        // Not static: no gyro finding.
        assert!(imu_magnitudes(
            &window([0.0, 0.0, -9.8], [0.2, 0.0, 0.0]),
            &CSV_SI,
            g,
            BIAS,
            false
        )
        .is_empty());
        // A format with fixed units names the format instead.
        let fixed = ImuUnits {
            csv: false,
            ..CSV_SI
        };
        let w = imu_magnitudes(&window([0.0, 0.0, -1.0], [0.0; 3]), &fixed, g, BIAS, true);
        assert!(w[0].message.contains("[imu] format"));
    }

    #[test]
    fn window_means() {
        let s = |t: f64| ImuSample {
            t,
            dt: 0.01,
            dtheta: Vector3::new(0.0, 0.0, 1e-3),
            dvel: Vector3::new(0.0, 0.0, -0.098),
        };
        let w = imu_window(&[s(0.01), s(0.02)]).unwrap();
        assert!((w.mean_f.z + 9.8).abs() < 1e-9 && (w.mean_w.z - 0.1).abs() < 1e-12);
        assert!(imu_window(&[]).is_none());
    }

    #[test]
    fn tilt() {
        assert!(aligned_tilt([2.0, -1.0, 90.0], true).is_empty());
        assert_eq!(aligned_tilt([179.0, 0.0, 90.0], false).len(), 1);
        assert!(aligned_tilt([60.0, 0.0, 90.0], false).is_empty());
        let w = aligned_tilt([179.0, 0.5, 90.0], true);
        assert!(w[0]
            .message
            .contains("sensor-to-body rotation forgotten? set [imu] sensor_to_body_rpy_deg"));
    }

    #[test]
    fn spoofing_without_a_reference_warns() {
        assert_eq!(spoofing_reference(true, false, false).len(), 1);
        assert!(spoofing_reference(true, true, false).is_empty());
        assert!(spoofing_reference(true, false, true).is_empty());
        assert!(spoofing_reference(false, false, false).is_empty());
    }

    #[test]
    fn upside_down_start_warns_for_any_vehicle() {
        assert_eq!(aligned_tilt([-178.0, 2.0, 30.0], false).len(), 1);
        assert!(aligned_tilt([20.0, -10.0, 30.0], false).is_empty());
        assert_eq!(aligned_tilt([50.0, 0.0, 0.0], true).len(), 1);
    }

    #[test]
    fn fixes_far_off_the_ins_warn() {
        assert!(fix_agreement(9.5).is_empty());
        assert!(fix_agreement(f64::NAN).is_empty());
        assert!(fix_agreement(163.0)[0].message.contains("lever arm"));
    }
}
