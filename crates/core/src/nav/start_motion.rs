//! The in-motion part of the start: GNSS velocities on the IMU time scale, and the
//! search for a window of GNSS epochs whose velocity matching
//! (alignment::velocity_match) determines the attitude, waiting while the data cannot:
//! too few epochs, a GNSS gap, too slow for a course and too little horizontal
//! acceleration for the yaw, or an inconsistent fit (docs/ALGORITHMS.md "In-motion
//! alignment").

use crate::alignment::velocity_match::{
    fit, yaw_information_bound, CourseHold, Fit, FitSetup, VelEpoch,
};
use crate::attitude::c_bn_from_euler;
use crate::config::NavConfig;
use crate::earth::lla_diff_ned;
use crate::nav::start::STILL_SPEED_MPS;
use crate::types::{GnssFix, ImuSample};
use nalgebra::{Rotation3, Vector3};
use std::collections::VecDeque;

/// Spans of the windows tried from each start epoch \[s\] (the first that determines
/// the attitude is taken).
pub(crate) const WINDOW_SPANS_S: [f64; 2] = [10.0, 20.0];
/// Fewest GNSS epochs in a window.
pub(crate) const MIN_EPOCHS: usize = 5;
/// Longest gap between two GNSS epochs of a window \[s\].
pub(crate) const MAX_GAP_S: f64 = 3.0;
/// When a window cannot align, the next starts this much later \[s\].
pub(crate) const SLIDE_S: f64 = 2.0;
/// Roll and pitch must be determined to this 1-sigma \[rad\].
pub(crate) const TILT_STD_MAX: f64 = std::f64::consts::PI / 180.0;
/// The fit's yaw is taken before the course when its 1-sigma is at most this \[rad\]
/// (the IMU's own yaw: no mounting or sideslip in it).
pub(crate) const YAW_FIT_SHARP: f64 = std::f64::consts::PI / 180.0;
/// The yaw is determined when its 1-sigma is at most this \[rad\] (with the course
/// when the course agrees with the IMU, otherwise from the fit alone).
pub(crate) const YAW_FIT_STD_MAX: f64 = 2.0 * std::f64::consts::PI / 180.0;
/// 1-sigma of a vehicle's yaw against its course (sideslip, mounting) \[rad\].
pub(crate) const COURSE_STD: f64 = 2.0 * std::f64::consts::PI / 180.0;
/// The course is refused when the held fit's yaw differs from the free fit's by more
/// than 2 sigma of the latter plus this \[rad\] (a body whose heading is not its
/// course, or a mounting yaw not configured: the fit is the IMU's own yaw).
pub(crate) const COURSE_MARGIN: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// Assumed distance of the antenna from the point of a vehicle that does not slip
/// (the rear axle) when weighting the course in turns \[m\].
pub(crate) const TURN_LEVER_M: f64 = 2.0;
/// A fit whose residuals are more than this many times the GNSS velocity noise, or
/// that keeps fewer than [`MIN_INLIER_SHARE`] of its epochs, is inconsistent.
pub(crate) const SCALE_MAX: f64 = 3.0;
pub(crate) const MIN_INLIER_SHARE: f64 = 0.7;
/// Default GNSS velocity 1-sigma when the receiver gives none \[m/s\].
pub(crate) const DEFAULT_VEL_STD_MPS: f64 = 0.1;

/// GNSS epochs with a velocity, on the IMU time scale, and the fix each came from.
pub(crate) struct Epochs {
    pub(crate) vel: Vec<VelEpoch>,
    pub(crate) fix: Vec<GnssFix>,
}

/// Velocities of the fixes at or after `t_from` (IMU time; fix times + `offset_s`):
/// the receiver's, or the central difference of the neighbouring positions (each at
/// most 2 s away) with the variance of the positions.
pub(crate) fn vel_epochs(fixes: &[GnssFix], offset_s: f64, t_from: f64) -> Epochs {
    let mut out = Epochs {
        vel: Vec::new(),
        fix: Vec::new(),
    };
    for (k, f) in fixes.iter().enumerate() {
        let t = f.t + offset_s;
        if t < t_from - 1e-9 {
            continue;
        }
        let (v_n, var_n) = match f.vel_ned {
            Some(v) => (
                v,
                f.vel_std_ned
                    .map_or(Vector3::repeat(DEFAULT_VEL_STD_MPS.powi(2)), |s| {
                        s.map(|x| x * x)
                    }),
            ),
            None => {
                let (Some(a), Some(b)) = (
                    k.checked_sub(1).and_then(|i| fixes.get(i)),
                    fixes.get(k + 1),
                ) else {
                    continue;
                };
                let dt = b.t - a.t;
                if !(dt > 0.0 && f.t - a.t <= 2.0 && b.t - f.t <= 2.0) {
                    continue;
                }
                (
                    lla_diff_ned(&b.lla, &a.lla) / dt,
                    (a.std_ned.map(|x| x * x) + b.std_ned.map(|x| x * x)) / (dt * dt),
                )
            }
        };
        if v_n.iter().chain(var_n.iter()).all(|x| x.is_finite()) {
            out.vel.push(VelEpoch { t, v_n, var_n });
            out.fix.push(*f);
        }
    }
    out
}

/// A window that determined the attitude.
pub(crate) struct Aligned {
    pub(crate) fit: Fit,
    /// The yaw came from the course (else from the fit).
    pub(crate) yaw_from_course: bool,
    /// First and last epoch of the window (indices into [`Epochs`]).
    pub(crate) i: usize,
    pub(crate) j: usize,
}

/// The free fit of one window (no course), or why it cannot align; Ok also says
/// whether the window reaches the speed of a course.
fn try_free(
    cfg: &NavConfig,
    site: Vector3<f64>,
    samples: &[ImuSample],
    ep: &[VelEpoch],
    min_speed_mps: f64,
) -> Result<(Fit, bool), String> {
    let span = ep[ep.len() - 1].t - ep[0].t;
    if ep.len() < MIN_EPOCHS {
        return Err(format!("only {} GNSS epochs in {span:.1} s", ep.len()));
    }
    if let Some(g) = ep
        .windows(2)
        .map(|p| p[1].t - p[0].t)
        .find(|g| *g > MAX_GAP_S)
    {
        return Err(format!("a GNSS gap of {g:.1} s"));
    }
    let speed_max = ep.iter().map(|e| e.v_n.xy().norm()).fold(0.0, f64::max);
    let course_ok = speed_max >= min_speed_mps;
    if !course_ok && yaw_information_bound(ep) < YAW_FIT_STD_MAX.powi(-2) {
        return Err(format!(
            "too slow for a course (at most {speed_max:.1} m/s < {min_speed_mps} m/s) and too little horizontal acceleration to find the yaw"
        ));
    }
    let free = fit(&setup(cfg, site, samples, ep, None))
        .ok_or("the velocity-matching fit failed (degenerate)")?;
    if !consistent(&free) {
        return Err(format!(
            "inconsistent fit: residuals {:.1}x the GNSS velocity noise, {} of {} epochs agree",
            free.scale, free.inliers, free.epochs
        ));
    }
    if free.tilt_std() > TILT_STD_MAX {
        return Err(format!(
            "roll and pitch not determined (1-sigma {:.2} deg)",
            free.tilt_std().to_degrees()
        ));
    }
    Ok((free, course_ok))
}

fn setup<'a>(
    cfg: &NavConfig,
    site: Vector3<f64>,
    samples: &'a [ImuSample],
    ep: &'a [VelEpoch],
    course: Option<CourseHold>,
) -> FitSetup<'a> {
    FitSetup {
        samples,
        epochs: ep,
        lla: site,
        lever_arm_b: cfg.gnss.lever_arm_b,
        vrw: cfg.imu_noise.vrw.max(),
        gyro_bias_std: cfg.initial.imu_errors_std.gyro_bias,
        accel_bias_std: cfg.initial.imu_errors_std.accel_bias,
        gyro_scale_std: cfg.initial.imu_errors_std.gyro_scale,
        course,
    }
}

fn consistent(f: &Fit) -> bool {
    f.scale <= SCALE_MAX && f.inliers as f64 >= MIN_INLIER_SHARE * f.epochs as f64
}

/// The window with the vehicle yaw held to its course, checked against the free fit:
/// a course that disagrees with the IMU (a body whose heading is not its course, or a
/// wrong mounting) is refused.
fn try_course(
    cfg: &NavConfig,
    site: Vector3<f64>,
    samples: &[ImuSample],
    ep: &[VelEpoch],
    min_speed_mps: f64,
    free: &Fit,
) -> Result<Fit, String> {
    let hold = CourseHold {
        c_bm: c_bn_from_euler(&cfg.vehicle.mounting_rpy),
        min_speed_mps,
        std_rad: COURSE_STD,
        turn_lever_m: TURN_LEVER_M,
    };
    let held = fit(&setup(cfg, site, samples, ep, Some(hold)))
        .ok_or("the course-held fit failed (degenerate)")?;
    let dyaw = Rotation3::from_matrix(&(held.c_bn * free.c_bn.transpose()))
        .scaled_axis()
        .z
        .abs();
    if !consistent(&held) || dyaw > 2.0 * free.yaw_std() + COURSE_MARGIN {
        return Err(format!(
            "the course disagrees with the IMU by {:.1} deg (heading not the course?; residuals {:.1}x)",
            dyaw.to_degrees(),
            held.scale
        ));
    }
    if held.yaw_std() > YAW_FIT_STD_MAX {
        return Err(format!(
            "yaw not determined: 1-sigma {:.1} deg with the course (slow, turning)",
            held.yaw_std().to_degrees()
        ));
    }
    Ok(held)
}

/// How a search ended.
pub(crate) enum SearchEnd {
    Found(Box<Aligned>),
    /// The IMU data ended first.
    EndOfData,
    /// The buffer reached `max_buffer_s` (static look-ahead).
    Limit,
}

/// What a search went through: (window start, why it could not align), consecutive
/// repeats of the same reason merged.
#[derive(Default)]
pub(crate) struct Waits(pub(crate) Vec<(f64, f64, String)>);

impl Waits {
    fn push(&mut self, t: f64, why: String) {
        match self.0.last_mut() {
            Some((_, t1, w)) if *w == why => *t1 = t,
            _ => self.0.push((t, t, why)),
        }
    }

    /// "waited 12 s: too slow ... (100.0-112.0 s); ..." (the last three reasons).
    pub(crate) fn summary(&self) -> Option<String> {
        let (first, last) = (self.0.first()?, self.0.last()?);
        let parts: Vec<String> = self
            .0
            .iter()
            .rev()
            .take(3)
            .rev()
            .map(|(a, b, w)| format!("{w} ({a:.1}-{b:.1} s)"))
            .collect();
        Some(format!(
            "windows from {:.1} to {:.1} s could not align: {}",
            first.0,
            last.1,
            parts.join("; ")
        ))
    }
}

/// Read the IMU into `buf` until it covers `t`; false when the stream ended first.
pub(crate) fn fill_until<E>(
    buf: &mut VecDeque<ImuSample>,
    imu: &mut impl Iterator<Item = Result<ImuSample, E>>,
    t: f64,
) -> Result<bool, E> {
    while buf.back().is_none_or(|s| s.t < t) {
        match imu.next() {
            Some(r) => buf.push_back(r?),
            None => return Ok(false),
        }
    }
    Ok(true)
}

/// Search windows of `ep` starting at epoch `i0` and later for one that determines
/// the attitude, reading the IMU into `buf` as far as needed. `keep_all`: never drop
/// samples from `buf` (they are navigated after the start); otherwise samples more
/// than 1 s before the window start are dropped. `max_buffer_s`: give up (`Limit`)
/// once `buf` spans more than this. `extra_rate`: subtracted from the compensated
/// rates (a static start's mean rate).
#[allow(clippy::too_many_arguments)]
pub(crate) fn search<E>(
    cfg: &NavConfig,
    buf: &mut VecDeque<ImuSample>,
    imu: &mut impl Iterator<Item = Result<ImuSample, E>>,
    ep: &Epochs,
    i0: usize,
    min_speed_mps: f64,
    keep_all: bool,
    max_buffer_s: Option<f64>,
    extra_rate: Vector3<f64>,
    waits: &mut Waits,
) -> Result<SearchEnd, E> {
    let v = &ep.vel;
    // Gravity and Earth rate at the configured position or the first fix.
    let site = cfg
        .initial
        .lla
        .or(ep.fix.first().map(|f| f.lla))
        .unwrap_or_default();
    let mut i = i0;
    let mut ended = false;
    // Horizontally still (speed within 3 sigma of STILL_SPEED_MPS).
    let still = |e: &VelEpoch| {
        e.v_n.xy().norm() - 3.0 * (0.5 * (e.var_n.x + e.var_n.y)).sqrt() <= STILL_SPEED_MPS
    };
    while i + 1 < v.len() && !ended {
        // A window starts where the motion does (the last still epoch before it): over
        // a standstill the yaw drifts with the unknown gyro bias and nothing shows it.
        if still(&v[i]) && still(&v[i + 1]) {
            let k = (i + 1..v.len()).find(|&k| !still(&v[k]));
            let t_i = v[i].t;
            match k {
                Some(k) => {
                    waits.push(t_i, "still (GNSS speed about 0)".into());
                    i = k - 1;
                }
                None => {
                    waits.push(t_i, "still until the end of the GNSS data".into());
                    break;
                }
            }
        }
        let t_i = v[i].t;
        if !keep_all {
            while buf.len() > 1 && buf[1].t <= t_i - 1.0 {
                buf.pop_front();
            }
        }
        let mut last_j = i;
        let mut why = String::new();
        for span in WINDOW_SPANS_S {
            let mut j = i;
            while j + 1 < v.len() && v[j + 1].t <= t_i + span + 1e-9 {
                j += 1;
            }
            // Past the look-ahead: stop before reading (and holding) the IMU that far.
            if let (Some(lim), Some(a)) = (max_buffer_s, buf.front()) {
                if v[j].t - a.t > lim {
                    return Ok(SearchEnd::Limit);
                }
            }
            if !fill_until(buf, imu, v[j].t + 0.03)? {
                ended = true;
                let t_last = buf.back().map_or(f64::NEG_INFINITY, |s| s.t);
                while j > i && v[j].t > t_last - 0.03 {
                    j -= 1;
                }
            }
            if let (Some(lim), Some(a), Some(b)) = (max_buffer_s, buf.front(), buf.back()) {
                if b.t - a.t > lim {
                    return Ok(SearchEnd::Limit);
                }
            }
            if j == last_j {
                if ended {
                    break;
                }
                continue;
            }
            last_j = j;
            let (lo, hi) = (v[i].t - 0.05, v[j].t + 0.05);
            let from = buf.partition_point(|s| s.t < lo);
            let samples: Vec<ImuSample> = buf
                .range(from..)
                .take_while(|s| s.t - s.dt <= hi)
                .map(|s| {
                    let mut c = cfg.initial.imu_errors.compensate(s);
                    c.dtheta -= extra_rate * c.dt;
                    c
                })
                .collect();
            // The fit's own yaw when it is sharp; else a vehicle's course that agrees
            // with it (the course and the fit together); else the fit's yaw when it
            // is determined at all.
            match try_free(cfg, site, &samples, &v[i..=j], min_speed_mps) {
                Ok((free, course_ok)) => {
                    let found = |fit: Fit, yaw_from_course: bool| {
                        Ok(SearchEnd::Found(Box::new(Aligned {
                            fit,
                            yaw_from_course,
                            i,
                            j,
                        })))
                    };
                    if free.yaw_std() <= YAW_FIT_SHARP {
                        return found(free, false);
                    }
                    if course_ok {
                        match try_course(cfg, site, &samples, &v[i..=j], min_speed_mps, &free) {
                            Ok(held) => return found(held, true),
                            Err(e) => why = e,
                        }
                    }
                    if free.yaw_std() <= YAW_FIT_STD_MAX {
                        return found(free, false);
                    }
                    if !course_ok {
                        why = format!(
                            "yaw not determined: 1-sigma {:.1} deg from the horizontal acceleration, too slow for a course",
                            free.yaw_std().to_degrees()
                        );
                    }
                }
                Err(e) => why = e,
            }
            if ended {
                break;
            }
        }
        if !why.is_empty() {
            waits.push(t_i, why);
        }
        let t_next = t_i + SLIDE_S;
        i += 1;
        while i + 1 < v.len() && v[i].t < t_next - 1e-9 {
            i += 1;
        }
    }
    Ok(SearchEnd::EndOfData)
}
