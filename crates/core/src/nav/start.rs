//! Where and how the navigation starts: the initial position (given, or the first
//! fix moved to the IMU centre), the initial attitude (given, static levelling with
//! gyrocompassing or the first GNSS course, or in-motion alignment from GNSS) and the
//! IMU samples read while aligning (REFERENCES \[SYS\] §1 "Initial alignment";
//! docs/ALGORITHMS.md "Alignment").
//!
//! `mode = "auto"` judges the first levelling window static from the data's own
//! vibration and the GNSS speed (static_detect::imu_stillness); static: levelling, then
//! the yaw from the first motion (velocity matching, or its course); moving: in-motion
//! alignment by velocity matching over a window of GNSS epochs (start_motion.rs). Every
//! IMU sample it reads is navigated after the start or lies before a start whose
//! events line says why.

use super::start_motion::{search, vel_epochs, Aligned, Epochs, SearchEnd, Waits};
use crate::alignment;
use crate::attitude::{c_bn_from_euler, euler_from_c_bn, quat_from_rotvec};
use crate::config::{AttitudeInit, NavConfig};
use crate::earth::{lla_add_ned, lla_diff_ned, omega_ie_n, OMEGA_IE};
use crate::nav::navigator::NavError;
use crate::static_detect::{imu_stillness, sub_windows, ImuStillness, SubWindow};
use crate::types::{GnssFix, ImuSample, Measurement};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use std::collections::VecDeque;

/// Where a static start takes its yaw from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum YawFrom {
    /// The Earth rate seen by the gyros.
    Gyrocompass,
    /// The first GNSS course at a horizontal speed of at least `min_speed_mps`.
    FirstCourse { min_speed_mps: f64 },
}

/// Where and how the navigation starts.
pub(crate) struct Start {
    pub(crate) t0: f64,
    pub(crate) lla: Vector3<f64>,
    pub(crate) rpy: Vector3<f64>,
    pub(crate) v_n: Vector3<f64>,
    /// IMU samples read during alignment that are navigated after the start.
    pub(crate) replay: Vec<ImuSample>,
    /// Measurements at or before this GNSS time are not used (the fix that gave the
    /// initial position, fixes before the start).
    pub(crate) used_until: f64,
    pub(crate) method: &'static str,
    /// Why this alignment ran and what it saw (events.log, summary.json).
    pub(crate) reason: String,
    /// Initial attitude 1-sigma \[rad\] when the alignment knows it worse than the
    /// configuration says (never narrower).
    pub(crate) att_std: Option<Vector3<f64>>,
    /// `[zupt]` thresholds (accel std \[m/s²\], rate std \[rad/s\]) raised to the
    /// vibration of a static start.
    pub(crate) zupt_thresholds: Option<(f64, f64)>,
    /// Gyro \[rad/s\] and accelerometer \[m/s²\] biases the alignment found, added to
    /// the configured initial estimates.
    pub(crate) bias: Option<(Vector3<f64>, Vector3<f64>)>,
}

/// A GNSS speed at most this \[m/s\] (beyond 3 sigma of its noise) is still.
pub(crate) const STILL_SPEED_MPS: f64 = 0.3;
/// A static start looks this far ahead \[s\] for the motion that gives the yaw
/// (the IMU data meanwhile is held to be navigated); then the first course.
pub(crate) const YAW_LOOKAHEAD_S: f64 = 600.0;
/// Initial yaw 1-sigma when the data cannot give the yaw \[rad\]: as wide as the
/// linearised filter tolerates (wider, it turns the yaw on noise: on the PX4 SITL log
/// 180 deg gave 11.6 deg RMS of wandering against 0.8 deg with 30).
pub(crate) const YAW_UNKNOWN_STD: f64 = 30.0 * std::f64::consts::PI / 180.0;
/// `[zupt]` thresholds after a static start: this many times the median
/// sub-window vibration of the levelling window (when above the configured ones).
pub(crate) const ZUPT_VIBRATION_FACTOR: f64 = 2.0;

/// GNSS fixes as a plain list, for the alignment routines.
fn fixes_of(meas: &[Measurement]) -> Vec<GnssFix> {
    meas.iter()
        .filter_map(|m| match m {
            Measurement::Gnss(f) => Some(*f),
            Measurement::GnssRaw(e) => e.fix,
            _ => None,
        })
        .collect()
}

/// Initial position from the config, or from the first fix at or after `t0`
/// (moved from the antenna to the IMU centre with the attitude `c_bn`).
fn initial_position(
    cfg: &NavConfig,
    t0: f64,
    fixes: &[GnssFix],
    c_bn: &Matrix3<f64>,
) -> Result<(Vector3<f64>, Option<f64>), NavError> {
    if let Some(lla) = cfg.initial.lla {
        return Ok((lla, None));
    }
    let fix = fixes.iter().find(|f| f.t >= t0 - 0.5).ok_or_else(|| {
        NavError(format!(
            "no initial position given and no GNSS fix at or after t = {t0:.3}"
        ))
    })?;
    Ok((
        lla_add_ned(&fix.lla, &(-(c_bn * cfg.gnss.lever_arm_b))),
        Some(fix.t),
    ))
}

/// Roll and pitch by levelling on the window (its last sample left out) and its mean
/// compensated rate.
fn level(cfg: &NavConfig, window: &[ImuSample]) -> Result<(f64, f64, Vector3<f64>), NavError> {
    let used = &window[..window.len().saturating_sub(1)];
    let compensated: Vec<ImuSample> = used
        .iter()
        .map(|s| cfg.initial.imu_errors.compensate(s))
        .collect();
    let (f_b, w_b) = alignment::mean_motion(&compensated)
        .ok_or_else(|| NavError("alignment: no IMU samples in the levelling window".into()))?;
    let (roll, pitch) = alignment::level(&f_b);
    Ok((roll, pitch, w_b))
}

/// IMU yaw of a vehicle moving on `course` with the configured mounting.
fn yaw_of_course(cfg: &NavConfig, course: f64) -> f64 {
    let c_mn = c_bn_from_euler(&Vector3::new(0.0, 0.0, course));
    euler_from_c_bn(&(c_mn * c_bn_from_euler(&cfg.vehicle.mounting_rpy))).z
}

/// A static start at `t0` with its attitude; `window` is navigated after it.
fn static_with(
    cfg: &NavConfig,
    t0: f64,
    window: Vec<ImuSample>,
    fixes: &[GnssFix],
    rpy: Vector3<f64>,
    method: &'static str,
) -> Result<Start, NavError> {
    let (lla, fix_t) = initial_position(cfg, t0, fixes, &c_bn_from_euler(&rpy))?;
    Ok(Start {
        t0,
        lla,
        rpy,
        v_n: cfg.initial.v_n,
        replay: window,
        used_until: fix_t.unwrap_or(f64::NEG_INFINITY),
        method,
        reason: String::new(),
        att_std: None,
        zupt_thresholds: None,
        bias: None,
    })
}

/// Static start over the buffered `window`: levelling, yaw by gyrocompassing or from
/// the first GNSS course. SYSTEM.md §1 "Initial alignment".
fn static_start(
    cfg: &NavConfig,
    t0: f64,
    window: Vec<ImuSample>,
    fixes: &[GnssFix],
    yaw_from: YawFrom,
) -> Result<Start, NavError> {
    let (roll, pitch, w_b) = level(cfg, &window)?;
    let (yaw, method) = match yaw_from {
        YawFrom::Gyrocompass => (
            alignment::gyrocompass_yaw(&w_b, roll, pitch),
            "static levelling + gyrocompassing",
        ),
        YawFrom::FirstCourse { min_speed_mps } => {
            let (_, course) = alignment::first_course(fixes, t0, min_speed_mps).ok_or_else(|| {
            NavError(format!(
                "alignment: no GNSS epoch after t = {t0:.3} with a horizontal speed of at least {min_speed_mps} m/s, so the initial yaw is unknown (give initial.attitude_deg)"
            ))
        })?;
            // The course is the vehicle's; the IMU yaw differs by the mounting yaw.
            (
                yaw_of_course(cfg, course),
                "static levelling + first GNSS course",
            )
        }
    };
    static_with(
        cfg,
        t0,
        window,
        fixes,
        Vector3::new(roll, pitch, yaw),
        method,
    )
}

/// The attitude 1-sigma to start with: the configuration's, widened to twice the
/// alignment's own (roll/pitch `tilt`, `yaw`) where that is larger.
fn widened(cfg: &NavConfig, tilt: f64, yaw: f64) -> Option<Vector3<f64>> {
    let a = cfg.initial.att_std;
    let w = Vector3::new(a.x.max(2.0 * tilt), a.y.max(2.0 * tilt), a.z.max(2.0 * yaw));
    (w != a).then_some(w)
}

/// Whether the first levelling window of an `auto` start is static, and why.
struct Stillness {
    is_static: bool,
    imu: Option<ImuStillness>,
    reason: String,
    /// Static only up to this time (a shorter levelling window): the end of the
    /// longest static beginning of the window.
    level_until: Option<f64>,
}

/// The GNSS of the window: (largest speed less 3 sigma, largest speed) \[m/s\] of the
/// epochs in [t0, t1]; with position-derived velocities also the mean speed of the
/// whole displacement less 3 sigma.
fn gnss_motion(ep: &Epochs, t0: f64, t1: f64) -> Option<(f64, f64)> {
    let ks: Vec<usize> = (0..ep.vel.len())
        .filter(|&k| ep.vel[k].t >= t0 - 0.5 && ep.vel[k].t <= t1)
        .collect();
    let (&a, &b) = (ks.first()?, ks.last()?);
    let mut excess = f64::NEG_INFINITY;
    let mut top: f64 = 0.0;
    for &k in &ks {
        let e = &ep.vel[k];
        let sd = (0.5 * (e.var_n.x + e.var_n.y)).sqrt();
        let v = e.v_n.xy().norm();
        top = top.max(v);
        excess = excess.max(v - 3.0 * sd);
    }
    let dt = ep.vel[b].t - ep.vel[a].t;
    if dt > 1.0 {
        let (fa, fb) = (&ep.fix[a], &ep.fix[b]);
        let d = lla_diff_ned(&fb.lla, &fa.lla).xy().norm();
        let sd = (fa.std_ned.xy().norm_squared() + fb.std_ned.xy().norm_squared()).sqrt();
        excess = excess.max((d - 3.0 * sd) / dt);
        top = top.max(d / dt);
    }
    Some((excess, top))
}

/// A static beginning shorter than this \[s\] does not level.
pub(crate) const MIN_STATIC_S: f64 = 2.0;

/// The verdict on the sub-windows `subs` spanning [t0, t1].
fn stillness_of(cfg: &NavConfig, t0: f64, t1: f64, subs: &[SubWindow], ep: &Epochs) -> Stillness {
    let z = &cfg.zupt;
    let imu = imu_stillness(subs, z.accel_std_max, z.gyro_max);
    let gnss = gnss_motion(ep, t0, t1);
    let gnss_still = gnss.is_none_or(|(excess, _)| excess <= STILL_SPEED_MPS);
    let span = t1 - t0;
    // With the GNSS at rest, steady means suffice (a hand or a passenger may shake
    // the IMU); without GNSS the vibration must also stay near its floor.
    let imu_ok = |m: &ImuStillness| m.means_steady && (m.is_static || gnss.is_some());
    match &imu {
        Some(m) if imu_ok(m) && gnss_still => {
            let g = match gnss {
                Some((_, top)) => format!(", GNSS speed at most {top:.2} m/s"),
                None => ", no GNSS in the window".into(),
            };
            Stillness {
                is_static: true,
                reason: format!(
                    "window {span:.1} s static: accel std {:.3} m/s² {} {:.3} calibrated, gyro std {:.2} deg/s {} {:.2} calibrated, mean specific force steady to {:.3} m/s², mean rate to {:.2} deg/s{g}",
                    m.accel_max,
                    if m.accel_max <= m.accel_threshold { "<=" } else { ">" },
                    m.accel_threshold,
                    m.gyro_max.to_degrees(),
                    if m.gyro_max <= m.gyro_threshold { "<=" } else { ">" },
                    m.gyro_threshold.to_degrees(),
                    m.mean_f_change,
                    m.mean_w_change.to_degrees()
                ),
                imu,
                level_until: None,
            }
        }
        _ => {
            let mut why = Vec::new();
            if let (Some((_, top)), false) = (gnss, gnss_still) {
                why.push(format!("GNSS speed up to {top:.1} m/s"));
            }
            match &imu {
                Some(m) if !imu_ok(m) => why.push(m.why_not.clone()),
                None => why.push("too few IMU samples".into()),
                _ => {}
            }
            Stillness {
                is_static: false,
                reason: format!("the first {span:.1} s moved ({})", why.join("; ")),
                imu,
                level_until: None,
            }
        }
    }
}

/// Whether the start window is static; if not, whether its beginning is (at least
/// [`MIN_STATIC_S`], cut at sub-window edges): then the levelling uses that.
fn assess_start_window(
    cfg: &NavConfig,
    t0: f64,
    window: &[ImuSample],
    ep: &Epochs,
    len_s: f64,
) -> Stillness {
    let comp: Vec<ImuSample> = window
        .iter()
        .map(|s| cfg.initial.imu_errors.compensate(s))
        .collect();
    let sub_s = cfg.zupt.window_s.min(len_s);
    let subs = sub_windows(&comp, sub_s);
    let t1 = window.last().map_or(t0, |s| s.t);
    let full = stillness_of(cfg, t0, t1, &subs, ep);
    if full.is_static {
        return full;
    }
    let t_start = window.first().map_or(t0, |s| s.t - s.dt);
    let n_min = (MIN_STATIC_S / sub_s).ceil().max(1.0) as usize;
    for n in (n_min..subs.len()).rev() {
        let t_n = t_start + sub_s * n as f64;
        let mut v = stillness_of(cfg, t0, t_n, &subs[..n], ep);
        if v.is_static {
            v.reason = format!(
                "{}; levelling on its first {:.1} s ({})",
                full.reason,
                t_n - t0,
                v.reason
            );
            v.level_until = Some(t_n);
            return v;
        }
    }
    full
}

/// The GNSS-IMU time offset the run starts with \[s\] (fix times + it = IMU times).
fn offset0(cfg: &NavConfig) -> f64 {
    cfg.filter.time_offset.map_or(0.0, |t| t.initial_s)
}

/// Rotation C_{b(t_b)}^{b(t_a)} from the compensated gyros less `rate` over `buf`.
fn rotation_between(
    cfg: &NavConfig,
    buf: &VecDeque<ImuSample>,
    t_a: f64,
    t_b: f64,
    rate: &Vector3<f64>,
) -> Matrix3<f64> {
    let mut r = UnitQuaternion::identity();
    for s in buf {
        let (a, e) = ((s.t - s.dt).max(t_a), s.t.min(t_b));
        if e > a && s.dt > 0.0 {
            let c = cfg.initial.imu_errors.compensate(s);
            r *= quat_from_rotvec(&((c.dtheta - rate * c.dt) * ((e - a) / s.dt)));
        }
    }
    r.to_rotation_matrix().into_inner()
}

/// `auto` on a static start (not gyrocompassing): levelling, then the yaw from the
/// first motion: velocity matching over the first window of GNSS epochs that
/// determines it (the fit's yaw, or the course held by a vehicle), carried back to
/// `t0` by the gyros. The IMU read meanwhile is navigated after the start. Without
/// motion within [`YAW_LOOKAHEAD_S`]: the first course; without any course:
/// gyrocompassing when the gyros can, else the yaw is unknown.
#[allow(clippy::too_many_arguments)]
fn auto_static_start<E: From<NavError>>(
    cfg: &NavConfig,
    t0: f64,
    window: Vec<ImuSample>,
    imu: &mut impl Iterator<Item = Result<ImuSample, E>>,
    ep: &Epochs,
    fixes: &[GnssFix],
    min_speed_mps: f64,
    still: Stillness,
) -> Result<Start, E> {
    let until = still.level_until.unwrap_or(f64::INFINITY);
    let level_part: Vec<ImuSample> = window.iter().copied().filter(|s| s.t <= until).collect();
    let (roll, pitch, w_mean) = level(cfg, &level_part)?;
    // The rate at rest (bias and Earth rate): the median of the sub-window means.
    let w_b = still.imu.as_ref().map_or(w_mean, |m| m.rate_median);
    let onset = ep.vel.iter().position(|e| {
        let sd = (0.5 * (e.var_n.x + e.var_n.y)).sqrt();
        e.t > t0 && e.v_n.xy().norm() - 3.0 * sd > STILL_SPEED_MPS
    });
    let mut buf: VecDeque<ImuSample> = window.into();
    let mut waits = Waits::default();
    let found = match onset {
        Some(k) => {
            let i0 = if k > 0 && ep.vel[k - 1].t >= t0 {
                k - 1
            } else {
                k
            };
            search(
                cfg,
                &mut buf,
                imu,
                ep,
                i0,
                min_speed_mps,
                true,
                Some(YAW_LOOKAHEAD_S),
                w_b,
                &mut waits,
            )?
        }
        None => SearchEnd::EndOfData,
    };
    let replay: Vec<ImuSample> = buf.iter().copied().collect();
    let mut reason = still.reason.clone();
    let mut att_std = None;
    let (yaw, method) = match found {
        SearchEnd::Found(found) => {
            let Aligned {
                fit,
                yaw_from_course,
                i,
                j,
            } = *found;
            let r = rotation_between(cfg, &buf, t0, ep.vel[i].t, &w_b);
            let yaw = euler_from_c_bn(&(fit.c_bn * r.transpose())).z;
            reason.push_str(&format!(
                "; yaw from the first motion, velocity matching over {} GNSS epochs {:.1}-{:.1} s ({} kept, residuals {:.1}x the noise): {} (1-sigma {:.1} deg)",
                fit.epochs,
                ep.vel[i].t,
                ep.vel[j].t,
                fit.inliers,
                fit.scale,
                if yaw_from_course { "the vehicle's course" } else { "the horizontal acceleration" },
                fit.yaw_std().to_degrees()
            ));
            if let Some(w) = waits.summary() {
                reason.push_str(&format!(" after {w}"));
            }
            att_std = widened(cfg, 0.0, fit.yaw_std());
            if yaw_from_course {
                (yaw, "static levelling + first GNSS course")
            } else {
                (yaw, "static levelling + GNSS velocity matching")
            }
        }
        end => {
            let why = match (&end, waits.summary()) {
                (SearchEnd::Limit, _) => {
                    format!("no motion determined the yaw within {YAW_LOOKAHEAD_S} s")
                }
                (_, Some(w)) => w,
                (_, None) if ep.vel.is_empty() => "no GNSS".into(),
                (_, None) => "the GNSS shows no motion".into(),
            };
            // A course only where the speed clears min_speed by 3 sigma of its noise,
            // at three consecutive epochs within 2 s whose courses agree to 10 deg (a
            // single wild velocity is no course).
            let clear = |e: &alignment::velocity_match::VelEpoch| {
                let sd = (0.5 * (e.var_n.x + e.var_n.y)).sqrt();
                e.t >= t0 && e.v_n.xy().norm() - 3.0 * sd >= min_speed_mps
            };
            let course_of = |e: &alignment::velocity_match::VelEpoch| e.v_n.y.atan2(e.v_n.x);
            let course = ep
                .vel
                .windows(3)
                .map(|w| &w[0])
                .zip(ep.vel.windows(3))
                .find_map(|(e, w)| {
                    let agree = w.iter().all(|x| {
                        clear(x)
                            && crate::attitude::wrap_pi(course_of(x) - course_of(e)).abs()
                                < 10f64.to_radians()
                    });
                    (agree && w[2].t - w[0].t <= 2.0).then_some(e)
                });
            if let Some(e) = course {
                reason.push_str(&format!(
                    "; {why}: yaw from the first GNSS course (at {:.1} s)",
                    e.t
                ));
                (
                    yaw_of_course(cfg, e.v_n.y.atan2(e.v_n.x)),
                    "static levelling + first GNSS course",
                )
            } else {
                // Gyrocompassing errs by bias / (Earth rate cos lat).
                let lat = cfg
                    .initial
                    .lla
                    .or(fixes.first().map(|f| f.lla))
                    .map_or(0.0, |l| l.x);
                let b = cfg.initial.imu_errors_std.gyro_bias.xy().norm();
                let err = (b / (OMEGA_IE * lat.cos()).max(1e-12)).atan();
                if err < 5f64.to_radians() {
                    reason.push_str(&format!(
                        "; {why}, no GNSS course of {min_speed_mps} m/s clear of the velocity noise: yaw by gyrocompassing (1-sigma about {:.1} deg from the gyro bias)",
                        err.to_degrees()
                    ));
                    att_std = widened(cfg, 0.0, err);
                    (
                        alignment::gyrocompass_yaw(&w_b, roll, pitch),
                        "static levelling + gyrocompassing",
                    )
                } else if let Some((t, course)) = alignment::first_course(fixes, t0, min_speed_mps)
                {
                    // A single epoch's course, maybe the velocity noise's: better than
                    // nothing, and said so.
                    reason.push_str(&format!(
                        "; {why}, no GNSS course of {min_speed_mps} m/s clear of the velocity noise, gyros too coarse to gyrocompass: YAW UNCERTAIN, from the course of the single epoch at {t:.1} s, 1-sigma {:.0} deg (give initial.attitude_deg)",
                        YAW_UNKNOWN_STD.to_degrees().max(cfg.initial.att_std.z.to_degrees())
                    ));
                    att_std = widened(cfg, 0.0, 0.5 * YAW_UNKNOWN_STD);
                    (
                        yaw_of_course(cfg, course),
                        "static levelling + first GNSS course, yaw uncertain",
                    )
                } else {
                    reason.push_str(&format!(
                        "; {why}, no GNSS course of {min_speed_mps} m/s, gyros too coarse to gyrocompass: YAW UNKNOWN, set to 0 deg with a 1-sigma of {:.0} deg (give initial.attitude_deg)",
                        YAW_UNKNOWN_STD.to_degrees().max(cfg.initial.att_std.z.to_degrees())
                    ));
                    att_std = widened(cfg, 0.0, 0.5 * YAW_UNKNOWN_STD);
                    (0.0, "static levelling, yaw unknown")
                }
            }
        }
    };
    let mut start = static_with(
        cfg,
        t0,
        replay,
        fixes,
        Vector3::new(roll, pitch, yaw),
        method,
    )?;
    start.reason = reason;
    start.att_std = att_std;
    start.zupt_thresholds = zupt_calibration(cfg, still.imu.as_ref(), &mut start.reason);
    start.bias = static_gyro_bias(cfg, &start, &w_b, still.imu.as_ref(), fixes);
    if let Some((b, _)) = start.bias {
        start.reason.push_str(&format!(
            "; gyro bias from the static window: {:.3} {:.3} {:.3} deg/s",
            b.x.to_degrees(),
            b.y.to_degrees(),
            b.z.to_degrees()
        ));
    }
    Ok(start)
}

/// The gyro bias of a static start: the window's mean rate less the Earth rate at the
/// aligned attitude, when the window gives it at least three times better than the
/// configured initial bias 1-sigma (the scatter of the sub-window means over their
/// square root of count; vibration averages out).
fn static_gyro_bias(
    cfg: &NavConfig,
    start: &Start,
    w_b: &Vector3<f64>,
    still: Option<&ImuStillness>,
    fixes: &[GnssFix],
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let m = still?;
    let lat = cfg.initial.lla.or(fixes.first().map(|f| f.lla))?.x;
    let n = m.sub_mean_w_std.len() as f64;
    let sd = m.sub_mean_w_std / n.max(1.0).sqrt();
    let prior = cfg.initial.imu_errors_std.gyro_bias;
    if n < 3.0 || (0..3).any(|i| sd[i] * 3.0 > prior[i]) {
        return None;
    }
    let earth_b = c_bn_from_euler(&start.rpy).transpose() * omega_ie_n(lat);
    Some((w_b - earth_b, Vector3::zeros()))
}

/// `[zupt]` thresholds raised to the static window's vibration (ZUPT enabled and the
/// vibration above the configured thresholds); noted in `reason`.
fn zupt_calibration(
    cfg: &NavConfig,
    still: Option<&ImuStillness>,
    reason: &mut String,
) -> Option<(f64, f64)> {
    let (z, m) = (&cfg.zupt, still?);
    let a = z.accel_std_max.max(ZUPT_VIBRATION_FACTOR * m.accel_median);
    let g = z.gyro_max.max(ZUPT_VIBRATION_FACTOR * m.gyro_median);
    if !z.enabled || (a == z.accel_std_max && g == z.gyro_max) {
        return None;
    }
    reason.push_str(&format!(
        "; [zupt] thresholds raised to the vibration: accel std {a:.3} m/s², gyro std {:.2} deg/s",
        g.to_degrees()
    ));
    Some((a, g))
}

/// In-motion alignment by velocity matching: the first window of GNSS epochs from the
/// start of `buf` on that determines the attitude; the run starts at its first epoch
/// (the first IMU epoch at or after it) with the GNSS velocity and position moved
/// there and to the IMU centre; the IMU samples after it are navigated, those before
/// it are not (said in the reason). `why`: why in motion.
fn in_motion<E: From<NavError>>(
    cfg: &NavConfig,
    mut buf: VecDeque<ImuSample>,
    imu: &mut impl Iterator<Item = Result<ImuSample, E>>,
    fixes: &[GnssFix],
    min_speed_mps: f64,
    why: &str,
) -> Result<Start, E> {
    let t_first = buf.front().map_or(f64::NEG_INFINITY, |s| s.t - s.dt);
    let ep = vel_epochs(fixes, offset0(cfg), t_first);
    let mut waits = Waits::default();
    let found = search(
        cfg,
        &mut buf,
        imu,
        &ep,
        0,
        min_speed_mps,
        false,
        None,
        Vector3::zeros(),
        &mut waits,
    )?;
    let SearchEnd::Found(found) = found else {
        let detail = waits.summary().unwrap_or_else(|| {
            format!(
                "{} GNSS epochs with a velocity after the IMU start",
                ep.vel.len()
            )
        });
        return Err(NavError(format!(
            "in-motion alignment: the data ended before a window of GNSS epochs determined the attitude ({why}; {detail}); give initial.attitude_deg, or align while static"
        ))
        .into());
    };
    let Aligned {
        fit,
        yaw_from_course,
        i,
        j,
    } = *found;
    let (e, fix) = (ep.vel[i], ep.fix[i]);
    // The first IMU epoch at or after the window start; the attitude there.
    let k = buf.iter().position(|s| s.t >= e.t - 1e-9).ok_or_else(|| {
        NavError("in-motion alignment: no IMU sample after the window start".into())
    })?;
    let s0 = buf[k];
    let c = cfg.initial.imu_errors.compensate(&s0);
    let frac = ((s0.t - e.t) / s0.dt).clamp(0.0, 1.0);
    let c_bn = fit.c_bn
        * quat_from_rotvec(&((c.dtheta - fit.gyro_bias * c.dt) * frac))
            .to_rotation_matrix()
            .into_inner();
    let w_b = c.dtheta / c.dt - fit.gyro_bias;
    let v_imu = e.v_n + fit.v0_correction - c_bn * w_b.cross(&cfg.gnss.lever_arm_b);
    let a_n = match ep.vel.get(i + 1) {
        Some(n) if n.t > e.t => (n.v_n - e.v_n) / (n.t - e.t),
        _ => Vector3::zeros(),
    };
    let dt = s0.t - e.t;
    let lla = match cfg.initial.lla {
        Some(l) => l,
        None => lla_add_ned(&fix.lla, &(v_imu * dt - c_bn * cfg.gnss.lever_arm_b)),
    };
    let replay: Vec<ImuSample> = buf.iter().skip(k + 1).copied().collect();
    let yaw = if yaw_from_course {
        format!(
            "the vehicle's GNSS course (1-sigma {:.1} deg)",
            fit.yaw_std().to_degrees()
        )
    } else {
        format!(
            "the horizontal acceleration (1-sigma {:.1} deg)",
            fit.yaw_std().to_degrees()
        )
    };
    let mut reason = format!(
        "{why}; velocity matching over {} GNSS epochs {:.1}-{:.1} s ({} kept, residuals {:.1}x the noise): roll/pitch 1-sigma {:.2} deg, yaw from {yaw}; IMU data from {t_first:.3} to {:.3} s ({:.1} s, before the window) not navigated",
        fit.epochs,
        e.t,
        ep.vel[j].t,
        fit.inliers,
        fit.scale,
        fit.tilt_std().to_degrees(),
        s0.t,
        s0.t - t_first
    );
    if let Some(w) = waits.summary() {
        reason.push_str(&format!("; {w}"));
    }
    Ok(Start {
        t0: s0.t,
        lla,
        rpy: euler_from_c_bn(&c_bn),
        v_n: v_imu + a_n * dt,
        replay,
        used_until: fix.t,
        method: "in motion (GNSS velocity matching)",
        reason,
        att_std: widened(cfg, fit.tilt_std(), fit.yaw_std()),
        zupt_thresholds: None,
        bias: Some((fit.gyro_bias, fit.accel_bias)),
    })
}

/// The start the configuration asks for, reading the IMU stream as far as the
/// alignment needs; None when the stream ends first. `first`: the first IMU sample
/// at or after the start time.
pub(crate) fn find_start<E: From<NavError>>(
    cfg: &NavConfig,
    first: ImuSample,
    imu: &mut impl Iterator<Item = Result<ImuSample, E>>,
    measurements: &[Measurement],
) -> Result<Option<Start>, E> {
    let t0 = first.t;
    let fixes = fixes_of(measurements);
    let read_window = |imu: &mut dyn Iterator<Item = Result<ImuSample, E>>,
                       len_s: f64|
     -> Result<Vec<ImuSample>, E> {
        let mut w = Vec::new();
        for r in imu {
            let s = r?;
            let full = s.t > t0 + len_s;
            w.push(s);
            if full {
                break;
            }
        }
        Ok(w)
    };
    let start = match cfg.initial.attitude {
        AttitudeInit::Given(rpy) => {
            let (lla, fix_t) = initial_position(cfg, t0, &fixes, &c_bn_from_euler(&rpy))?;
            Start {
                t0,
                lla,
                rpy,
                v_n: cfg.initial.v_n,
                replay: Vec::new(),
                used_until: fix_t.unwrap_or(f64::NEG_INFINITY),
                method: "given",
                reason: String::new(),
                att_std: None,
                zupt_thresholds: None,
                bias: None,
            }
        }
        AttitudeInit::LevelAndGnssCourse {
            level_window_s,
            min_speed_mps,
        } => {
            let w = read_window(imu, level_window_s)?;
            let mut s = static_start(cfg, t0, w, &fixes, YawFrom::FirstCourse { min_speed_mps })?;
            s.reason = "mode = \"level_and_course\"".into();
            s
        }
        AttitudeInit::StaticGyrocompass { level_window_s } => {
            let w = read_window(imu, level_window_s)?;
            let mut s = static_start(cfg, t0, w, &fixes, YawFrom::Gyrocompass)?;
            s.reason = "mode = \"static_gyrocompass\"".into();
            s
        }
        AttitudeInit::InMotion { min_speed_mps } => {
            let b = VecDeque::from([first]);
            in_motion(cfg, b, imu, &fixes, min_speed_mps, "mode = \"in_motion\"")?
        }
        AttitudeInit::Auto {
            level_window_s,
            min_speed_mps,
            gyrocompass,
        } => {
            let w = read_window(imu, level_window_s)?;
            if w.is_empty() {
                return Ok(None);
            }
            let ep = vel_epochs(&fixes, offset0(cfg), first.t - first.dt);
            let mut all = vec![first];
            all.extend_from_slice(&w);
            let still = assess_start_window(cfg, t0, &all, &ep, level_window_s);
            if still.is_static && gyrocompass {
                let until = still.level_until.unwrap_or(f64::INFINITY);
                let part: Vec<ImuSample> = w.iter().copied().filter(|s| s.t <= until).collect();
                let (roll, pitch, w_mean) = level(cfg, &part)?;
                let w_b = still.imu.as_ref().map_or(w_mean, |m| m.rate_median);
                let yaw = alignment::gyrocompass_yaw(&w_b, roll, pitch);
                let rpy = Vector3::new(roll, pitch, yaw);
                let mut s =
                    static_with(cfg, t0, w, &fixes, rpy, "static levelling + gyrocompassing")?;
                s.reason = still.reason.clone();
                s.zupt_thresholds = zupt_calibration(cfg, still.imu.as_ref(), &mut s.reason);
                s
            } else if still.is_static {
                auto_static_start(cfg, t0, w, imu, &ep, &fixes, min_speed_mps, still)?
            } else {
                let why = still.reason;
                in_motion(cfg, all.into(), imu, &fixes, min_speed_mps, &why)?
            }
        }
    };
    Ok(Some(start))
}
