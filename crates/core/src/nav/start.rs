//! Where and how the navigation starts: the initial position (given, or the first
//! fix moved to the IMU centre), the initial attitude (given, static levelling with
//! gyrocompassing or the first GNSS course, or in-motion alignment from GNSS) and the
//! IMU samples read while aligning (REFERENCES \[SYS\] §1 "Initial alignment").

use crate::alignment;
use crate::attitude::{c_bn_from_euler, euler_from_c_bn};
use crate::config::{AttitudeInit, NavConfig};
use crate::earth::{lla_add_ned, lla_diff_ned};
use crate::nav::navigator::NavError;
use crate::static_detect::StaticDetector;
use crate::types::{GnssFix, ImuSample, Measurement};
use nalgebra::{Matrix3, Vector3};
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
}

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

/// Static start over the buffered `window`: levelling, yaw by gyrocompassing or from
/// the first GNSS course. SYSTEM.md §1 "Initial alignment".
fn static_start(
    cfg: &NavConfig,
    t0: f64,
    window: Vec<ImuSample>,
    fixes: &[GnssFix],
    yaw_from: YawFrom,
) -> Result<Start, NavError> {
    let used = &window[..window.len().saturating_sub(1)];
    let compensated: Vec<ImuSample> = used
        .iter()
        .map(|s| cfg.initial.imu_errors.compensate(s))
        .collect();
    let (f_b, w_b) = alignment::mean_motion(&compensated)
        .ok_or_else(|| NavError("alignment: no IMU samples in the levelling window".into()))?;
    let (roll, pitch) = alignment::level(&f_b);
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
            let c_mn = c_bn_from_euler(&Vector3::new(0.0, 0.0, course));
            let yaw = euler_from_c_bn(&(c_mn * c_bn_from_euler(&cfg.vehicle.mounting_rpy))).z;
            (yaw, "static levelling + first GNSS course")
        }
    };
    let rpy = Vector3::new(roll, pitch, yaw);
    let (lla, fix_t) = initial_position(cfg, t0, fixes, &c_bn_from_euler(&rpy))?;
    Ok(Start {
        t0,
        lla,
        rpy,
        v_n: cfg.initial.v_n,
        replay: window,
        used_until: fix_t.unwrap_or(f64::NEG_INFINITY),
        method,
    })
}

/// In-motion alignment: find the first fix (with a predecessor at most 2 s before)
/// whose horizontal speed is at least `min_speed_mps`, consume the IMU stream up to
/// it, and start there with the GNSS velocity, the course as vehicle yaw and roll /
/// pitch from the acceleration-corrected specific force (alignment::in_motion_attitude).
fn in_motion_start<E: From<NavError>>(
    cfg: &NavConfig,
    mut buffered: VecDeque<ImuSample>,
    imu: &mut impl Iterator<Item = Result<ImuSample, E>>,
    fixes: &[GnssFix],
    min_speed_mps: f64,
) -> Result<Option<Start>, E> {
    // Velocity of fix k: its own, or the displacement from the previous fix.
    let vel = |k: usize| -> Option<Vector3<f64>> {
        fixes[k].vel_ned.or_else(|| {
            let p = fixes.get(k.checked_sub(1)?)?;
            let dt = fixes[k].t - p.t;
            (dt > 0.0 && dt <= 2.0).then(|| lla_diff_ned(&fixes[k].lla, &p.lla) / dt)
        })
    };
    let t_first = buffered.front().map_or(f64::NEG_INFINITY, |s| s.t);
    let mut candidates = (1..fixes.len()).filter(|&k| {
        let dt = fixes[k].t - fixes[k - 1].t;
        fixes[k - 1].t >= t_first
            && dt > 0.0
            && dt <= 2.0
            && vel(k).is_some_and(|v| v.x.hypot(v.y) >= min_speed_mps)
            && vel(k - 1).is_some()
    });
    let Some(k) = candidates.next() else {
        return Err(NavError(format!(
            "in-motion alignment: no pair of GNSS epochs at most 2 s apart with a horizontal speed of at least {min_speed_mps} m/s (give initial.attitude_deg, or align while static)"
        ))
        .into());
    };
    let (fa, fb) = (fixes[k - 1], fixes[k]);
    // Read the IMU up to the aligning epoch; keep the samples since the previous fix.
    let mut kept: Vec<ImuSample> = Vec::new();
    let s0 = loop {
        let s = match buffered.pop_front() {
            Some(s) => s,
            None => match imu.next() {
                Some(r) => r?,
                None => return Ok(None),
            },
        };
        if s.t >= fb.t - 1e-9 {
            break s;
        }
        if s.t - s.dt >= fa.t - 1e-9 {
            kept.push(s);
        }
    };
    let compensated: Vec<ImuSample> = kept
        .iter()
        .map(|s| cfg.initial.imu_errors.compensate(s))
        .collect();
    let (va, vb) = (vel(k - 1).expect("filtered"), vel(k).expect("filtered"));
    let a_n = (vb - va) / (fb.t - fa.t);
    let (f_b, _) = alignment::mean_motion(&compensated).ok_or_else(|| {
        NavError(format!(
            "in-motion alignment: no IMU samples between the GNSS epochs at {:.3} and {:.3}",
            fa.t, fb.t
        ))
    })?;
    let course = vb.y.atan2(vb.x);
    let c_bm = c_bn_from_euler(&cfg.vehicle.mounting_rpy);
    let c_bn = alignment::in_motion_attitude(course, &f_b, &a_n, &c_bm);
    let rpy = euler_from_c_bn(&c_bn);
    // Start at the IMU epoch s0.t: move the fix there with its velocity.
    let dt = s0.t - fb.t;
    let lla = match cfg.initial.lla {
        Some(l) => l,
        None => lla_add_ned(&fb.lla, &(vb * dt - c_bn * cfg.gnss.lever_arm_b)),
    };
    Ok(Some(Start {
        t0: s0.t,
        lla,
        rpy,
        v_n: vb + a_n * dt,
        replay: Vec::new(),
        used_until: fb.t,
        method: "in motion (GNSS course, velocity and acceleration)",
    }))
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
            }
        }
        AttitudeInit::LevelAndGnssCourse {
            level_window_s,
            min_speed_mps,
        } => {
            let w = read_window(imu, level_window_s)?;
            static_start(cfg, t0, w, &fixes, YawFrom::FirstCourse { min_speed_mps })?
        }
        AttitudeInit::StaticGyrocompass { level_window_s } => {
            let w = read_window(imu, level_window_s)?;
            static_start(cfg, t0, w, &fixes, YawFrom::Gyrocompass)?
        }
        AttitudeInit::InMotion { min_speed_mps } => {
            let b = VecDeque::from([first]);
            match in_motion_start(cfg, b, imu, &fixes, min_speed_mps)? {
                Some(s) => s,
                None => return Ok(None),
            }
        }
        AttitudeInit::Auto {
            level_window_s,
            min_speed_mps,
            gyrocompass,
        } => {
            let w = read_window(imu, level_window_s)?;
            let z = &cfg.zupt;
            let mut det = StaticDetector::new(level_window_s);
            for s in w.iter().map(|s| cfg.initial.imu_errors.compensate(s)) {
                if s.dt > 0.0 {
                    det.push(s.t, s.dt, &(s.dvel / s.dt), &(s.dtheta / s.dt));
                }
            }
            if det.static_mean_rate(z.accel_std_max, z.gyro_max).is_some() {
                let yaw_from = if gyrocompass {
                    YawFrom::Gyrocompass
                } else {
                    YawFrom::FirstCourse { min_speed_mps }
                };
                static_start(cfg, t0, w, &fixes, yaw_from)?
            } else {
                let mut b = VecDeque::from([first]);
                b.extend(w);
                match in_motion_start(cfg, b, imu, &fixes, min_speed_mps)? {
                    Some(s) => s,
                    None => return Ok(None),
                }
            }
        }
    };
    Ok(Some(start))
}
