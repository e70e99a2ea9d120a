//! A UBX log as an IMU, odometer or heading input (`[imu]` / `[odometer]` /
//! `[heading]` `format = "ubx"`): the ESF and NAV-RELPOSNED decodings turned into
//! the inputs' forms on GPS time. Errors name the file, the byte offset where one
//! is known, and the field; a log without the messages names what was expected.

use super::esf::{EsfKind, EsfOdo, TimeMap, NOMINAL_TICK_S};
use super::UbxLog;
use crate::error::InputError;
use crate::input::{UbxHeading, UbxOdometer};
use nalgebra::Vector3;
use navfuse_core::{HeadingObs, OdometerSample};
use std::path::Path;

/// One IMU rate sample: t [s of GPS week], gyro [rad/s], accel [m/s^2], sensor frame.
pub type Rate = (f64, Vector3<f64>, Vector3<f64>);

/// The time map of `kind`, or an error naming what is missing.
fn map_of(path: &Path, log: &UbxLog, kind: EsfKind, field: &str) -> Result<TimeMap, InputError> {
    match log.esf.map(kind) {
        Some(Ok(m)) => Ok(*m),
        Some(Err(why)) => Err(InputError::new(path, why.clone()).with_field(field)),
        None => Err(InputError::new(
            path,
            format!("no {} sensor data in the log", kind.name()),
        )),
    }
}

/// A note on the mapping, and a warning when the tick is not the documented 1 ms
/// or had to be assumed.
fn map_findings(path: &Path, m: &TimeMap, kind: EsfKind, warnings: &mut Vec<String>) -> String {
    let p = path.display();
    if m.fitted_tick_s.is_none() {
        warnings.push(format!(
            "{p}: {}: the navigation epochs span too little (or are too few: {}) to fit the sensor time tag unit: the u-blox default 1 ms is assumed",
            kind.name(),
            m.anchors
        ));
    } else if m.tick_s != NOMINAL_TICK_S {
        warnings.push(format!(
            "{p}: {}: the sensor time tags count {:.6} ms, not the u-blox default 1 ms (CFG-SFCORE-SEN_TTAG_FACT): the fitted unit is used",
            kind.name(),
            m.tick_s * 1e3
        ));
    }
    format!("{p}: {}", m.describe(kind))
}

/// The IMU of a UBX log: ESF-RAW samples when the log has any, else ESF-MEAS, on
/// GPS time; with a note on the source and mapping. Read warnings go to
/// `warnings`.
pub fn imu_rates(
    path: &Path,
    log: &UbxLog,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Rate>, String), InputError> {
    let kind = if !log.esf.raw_imu.is_empty() {
        EsfKind::Raw
    } else if !log.esf.meas_imu.is_empty() {
        EsfKind::Meas
    } else {
        return Err(InputError::new(
            path,
            format!(
                "no IMU samples in the UBX log: expected ESF-RAW (0x10 0x03) or ESF-MEAS (0x10 0x02) messages with gyro (data types 14, 13, 5) and accelerometer (16, 17, 18) data of one time tag ({} ESF-RAW and {} ESF-MEAS messages seen; {})",
                log.esf.counts.raw_messages,
                log.esf.counts.meas_messages,
                log.summary()
            ),
        ));
    };
    let field = if kind == EsfKind::Raw {
        "sTtag"
    } else {
        "timeTag"
    };
    let m = map_of(path, log, kind, field)?;
    let note = map_findings(path, &m, kind, warnings);
    let out = log
        .esf
        .imu(kind)
        .iter()
        .map(|s| (m.t(s.tag), Vector3::from(s.gyro), Vector3::from(s.accel)))
        .collect();
    Ok((out, format!("{} IMU samples; {note}", kind.name())))
}

fn series(odo: &[EsfOdo], ty: u8) -> Vec<(u64, u32)> {
    odo.iter()
        .filter(|o| o.data_type == ty)
        .map(|o| (o.tag, o.field))
        .collect()
}

/// Signed tick increment from `prev` to `cur` (23-bit counts, wrapping; bit 23
/// backward): |count change| signed by the direction bit.
pub fn tick_delta(prev: u32, cur: u32) -> f64 {
    let m = 1u32 << 23;
    let mut d = (cur.wrapping_sub(prev) & (m - 1)) as i64;
    if d >= i64::from(m / 2) {
        d -= i64::from(m); // a counter counting down
    }
    let mag = d.unsigned_abs() as f64;
    if cur & m != 0 {
        -mag
    } else {
        mag
    }
}

/// The odometer of a UBX log (ESF-MEAS, on GPS time). A note goes to `notes`.
pub fn odometer(
    path: &Path,
    log: &UbxLog,
    how: UbxOdometer,
    warnings: &mut Vec<String>,
) -> Result<Vec<OdometerSample>, InputError> {
    let odo = &log.esf.odo;
    let have: Vec<u8> = (6..=11u8)
        .filter(|t| odo.iter().any(|o| o.data_type == *t))
        .collect();
    let missing = |what: &str| {
        InputError::new(
            path,
            format!(
                "no {what} in the UBX log: expected ESF-MEAS (0x10 0x02) messages with {what} (data types present: {have:?}; {} ESF-MEAS messages)",
                log.esf.counts.meas_messages
            ),
        )
    };
    match how {
        UbxOdometer::Speed => {
            let s = series(odo, 11);
            if s.is_empty() {
                return Err(missing("speed (data type 11)"));
            }
            let m = map_of(path, log, EsfKind::Meas, "timeTag")?;
            map_findings(path, &m, EsfKind::Meas, warnings);
            Ok(s.iter()
                .map(|&(tag, f)| OdometerSample {
                    t: m.t(tag),
                    speed_mps: f64::from(super::esf::signed24(f)) * super::esf::SPEED_MPS_PER_COUNT,
                    interval_s: 0.0,
                })
                .collect())
        }
        UbxOdometer::Ticks { meters_per_pulse } => {
            // (previous tag, tag, signed ticks in between)
            let deltas: Vec<(u64, u64, f64)> = if have.contains(&10) {
                let s = series(odo, 10);
                s.windows(2)
                    .map(|w| (w[0].0, w[1].0, tick_delta(w[0].1, w[1].1)))
                    .collect()
            } else {
                let (a, b) = if have.contains(&8) && have.contains(&9) {
                    (8, 9)
                } else if have.contains(&6) && have.contains(&7) {
                    (6, 7)
                } else {
                    return Err(missing(
                        "wheel ticks (data type 10, or 8 and 9, or 6 and 7)",
                    ));
                };
                let (sa, sb) = (series(odo, a), series(odo, b));
                // both wheels at the same tags
                let mut j = 0;
                let mut pairs = Vec::new();
                for &(tag, fa) in &sa {
                    while j < sb.len() && sb[j].0 < tag {
                        j += 1;
                    }
                    if j < sb.len() && sb[j].0 == tag {
                        pairs.push((tag, fa, sb[j].1));
                    }
                }
                if pairs.len() < sa.len().max(sb.len()) {
                    warnings.push(format!(
                        "{}: ESF-MEAS: {} of {} wheel tick time tags have data types {a} and {b} together; the others are not used",
                        path.display(),
                        pairs.len(),
                        sa.len().max(sb.len())
                    ));
                }
                pairs
                    .windows(2)
                    .map(|w| {
                        let d = 0.5 * (tick_delta(w[0].1, w[1].1) + tick_delta(w[0].2, w[1].2));
                        (w[0].0, w[1].0, d)
                    })
                    .collect()
            };
            if deltas.is_empty() {
                return Err(missing("two or more wheel tick records"));
            }
            let m = map_of(path, log, EsfKind::Meas, "timeTag")?;
            map_findings(path, &m, EsfKind::Meas, warnings);
            let mut out = Vec::with_capacity(deltas.len());
            for (tag_prev, tag, d) in deltas {
                let t = m.t(tag);
                let dt = t - m.t(tag_prev);
                let speed = meters_per_pulse * d / dt;
                if dt.is_nan() || dt <= 0.0 || !speed.is_finite() {
                    warnings.push(format!(
                        "{}: ESF-MEAS: wheel ticks at sensor time tag {tag}: {d} ticks in {dt} s: record dropped",
                        path.display()
                    ));
                    continue;
                }
                out.push(OdometerSample {
                    t,
                    speed_mps: speed,
                    interval_s: dt,
                });
            }
            Ok(out)
        }
    }
}

/// NAV-RELPOSNED headings, in time order (a repeated or backwards iTOW is dropped
/// with a warning), on GPS seconds of the week of the first (continuing past a
/// rollover).
pub fn headings(
    path: &Path,
    log: &UbxLog,
    how: UbxHeading,
    warnings: &mut Vec<String>,
) -> Result<Vec<HeadingObs>, InputError> {
    if log.relpos.is_empty() {
        return Err(InputError::new(
            path,
            format!(
                "no NAV-RELPOSNED (0x01 0x3C) messages in the UBX log: expected the moving-base headings of a dual-antenna receiver ({})",
                log.summary()
            ),
        ));
    }
    let mut out: Vec<HeadingObs> = Vec::new();
    let (mut week_add, mut prev_tow, mut unusable, mut float) = (0.0, None::<f64>, 0, 0);
    let mut order = 0;
    for r in &log.relpos {
        if prev_tow.is_some_and(|p| r.itow_s < p - 302_400.0) {
            week_add += 604_800.0;
        }
        prev_tow = Some(r.itow_s);
        if !r.valid {
            unusable += 1;
            continue;
        }
        if r.carr_soln < 2 && !(how.float_ok && r.carr_soln == 1) {
            float += 1;
            continue;
        }
        let t = r.itow_s + week_add;
        if let Some(last) = out.last().filter(|h| t <= h.t) {
            if order < super::MAX_WARNINGS {
                warnings.push(format!(
                    "{}: byte {}: NAV-RELPOSNED: field 'iTOW': {t} s not after the previous heading ({} s): dropped",
                    path.display(),
                    r.offset,
                    last.t
                ));
            }
            order += 1;
            continue;
        }
        out.push(HeadingObs {
            t,
            heading_rad: r.heading_rad,
            std_rad: r.std_rad,
        });
    }
    if unusable + float > 0 {
        warnings.push(format!(
            "{}: NAV-RELPOSNED: {unusable} headings flagged invalid (gnssFixOK, relPosValid, relPosHeadingValid or accHeading) and {float} without {} ambiguities not used, of {}",
            path.display(),
            if how.float_ok { "float or fixed" } else { "fixed" },
            log.relpos.len()
        ));
    }
    if order > super::MAX_WARNINGS {
        warnings.push(format!(
            "{}: {} more NAV-RELPOSNED out of time order",
            path.display(),
            order - super::MAX_WARNINGS
        ));
    }
    Ok(out)
}
