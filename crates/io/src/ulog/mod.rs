//! PX4 ULog inputs (docs/FORMATS.md "PX4 ULog"): the container in [`parse`], and
//! here the topics navfuse reads from it, all on one time scale.
//!
//! - IMU: `sensor_combined` (`gyro_rad` [rad/s], `accelerometer_m_s2` [m/s²]: means
//!   over `gyro_integral_dt` / `accelerometer_integral_dt`, so interval-mean rates),
//!   body frame FRD;
//! - GNSS: `vehicle_gps_position` (else `sensor_gps`): `lat`/`lon` [1e-7 deg] and
//!   `alt_ellipsoid` [mm] or `latitude_deg`/`longitude_deg`/`altitude_ellipsoid_m`
//!   (newer PX4), `eph`/`epv` [m] as position sigmas, `vel_n_m_s`.. with
//!   `s_variance_m_s` as velocity sigma (when `vel_ned_valid`), `fix_type` >= 3 kept;
//! - barometer: `sensor_baro.pressure` [Pa; hPa in PX4 before v1.11, told by its
//!   range], or `vehicle_air_data.baro_pressure_pa` when that has more records;
//! - EKF2's estimate: `vehicle_global_position` (`lat`, `lon` [deg], `alt_ellipsoid`
//!   or else `alt` [m]), `vehicle_attitude.q` (Hamilton, w x y z, body FRD to NED:
//!   navfuse's q_bn) and `vehicle_local_position` `vx vy vz` (NED), nearest record.
//!
//! Time: ULog timestamps count microseconds since boot. When the log has GPS messages
//! with `time_utc_usec` > 0, boot time is mapped to GPS time by the median of
//! (time_utc_usec - timestamp) over them plus GPS - UTC leap seconds, and every time
//! is in seconds of the GPS week of the first such message. Without them, times are
//! seconds since boot and the week is unknown.

pub mod parse;
pub mod synth;

pub use parse::{Topic, Ulog, UlogError, MAGIC};

use crate::error::InputError;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use navfuse_core::attitude::euler_from_q_bn;
use navfuse_core::eval::TrajPoint;
use navfuse_core::time::{leap_seconds, SECONDS_PER_WEEK};
use navfuse_core::GnssFix;
use std::path::Path;

/// The GPS topics, in the order they are looked for.
pub const GPS_TOPICS: [&str; 2] = ["vehicle_gps_position", "sensor_gps"];

/// Read and parse a ULog file; its warnings (a cut last message) go to `warnings`
/// prefixed with the path.
pub fn open(path: &Path, warnings: &mut Vec<String>) -> Result<Ulog, InputError> {
    let bytes = std::fs::read(path).map_err(|e| InputError::open(path, &e))?;
    let u = Ulog::parse(bytes).map_err(|e| InputError::new(path, e.to_string()))?;
    warnings.extend(
        u.warnings
            .iter()
            .map(|w| format!("{}: {w}", path.display())),
    );
    Ok(u)
}

/// Whether `path` starts with the ULog magic.
pub fn is_ulog(path: &Path) -> bool {
    use std::io::Read;
    let mut b = [0u8; 7];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut b))
        .is_ok_and(|_| b == MAGIC)
}

/// Boot time [µs] -> navfuse time [s].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeMap {
    /// GPS week of the times; None: seconds since boot.
    pub week: Option<u32>,
    /// GPS time [µs since the GPS epoch] - boot time [µs], when known.
    offset_us: Option<i128>,
}

impl TimeMap {
    /// The mapping through the first GPS topic with `time_utc_usec` (instance
    /// `multi_id`, else 0).
    pub fn of(u: &Ulog, multi_id: u8) -> TimeMap {
        let none = TimeMap {
            week: None,
            offset_us: None,
        };
        let Some(t) = GPS_TOPICS.iter().find_map(|n| {
            [multi_id, 0]
                .into_iter()
                .find_map(|m| u.topic(n, m).filter(|t| !t.is_empty()))
        }) else {
            return none;
        };
        let Some(fu) = t.field("time_utc_usec") else {
            return none;
        };
        // i128 throughout: damaged timestamps may be anywhere in u64.
        let mut d: Vec<i128> = (0..t.len())
            .filter_map(|k| {
                let ts = t.timestamp_us(k)? as i128;
                let utc = t.value(k, fu);
                (utc > 1e15 && utc < 1e17).then(|| utc as i128 - ts)
            })
            .collect();
        if d.is_empty() {
            return none;
        }
        d.sort_unstable();
        let utc_minus_boot = d[d.len() / 2];
        // UTC µs since 1970 -> GPS µs since 1980-01-06, with the leap seconds of
        // the week of the first fix (an approximate week first).
        let epoch_us = navfuse_core::time::GPS_EPOCH_UNIX as i128 * 1_000_000;
        let approx = (utc_minus_boot - epoch_us) as f64 * 1e-6 / SECONDS_PER_WEEK;
        let leap = leap_seconds(Some(approx.clamp(0.0, 1e6) as u32));
        let offset = utc_minus_boot - epoch_us + (leap * 1e6) as i128;
        let first = t.timestamp_us(0).unwrap_or(0) as i128 + offset;
        let week = (first.max(0) as f64 * 1e-6 / SECONDS_PER_WEEK).floor();
        if !(0.0..1e6).contains(&week) {
            return none;
        }
        let week = week as u32;
        TimeMap {
            week: Some(week),
            offset_us: Some(offset - week as i128 * 604_800_000_000),
        }
    }

    /// Time [s] of boot timestamp `us`.
    pub fn t(&self, us: u64) -> f64 {
        match self.offset_us {
            Some(o) => (us as i128 + o) as f64 * 1e-6,
            None => us as f64 * 1e-6,
        }
    }
}

fn need<'a>(path: &Path, t: &'a Topic<'_>, name: &str) -> Result<&'a parse::Field, InputError> {
    t.field(name).ok_or_else(|| {
        InputError::new(
            path,
            format!("topic {}: no field {name} in its format", t.name),
        )
        .with_field(name)
    })
}

fn vec3_fields<'a>(
    path: &Path,
    t: &'a Topic<'_>,
    base: &str,
) -> Result<[&'a parse::Field; 3], InputError> {
    Ok([
        need(path, t, &format!("{base}[0]"))?,
        need(path, t, &format!("{base}[1]"))?,
        need(path, t, &format!("{base}[2]"))?,
    ])
}

fn topic<'a>(path: &Path, u: &'a Ulog, name: &str, multi_id: u8) -> Result<Topic<'a>, InputError> {
    u.topic(name, multi_id).ok_or_else(|| {
        let have: Vec<String> = u
            .topic_counts()
            .into_iter()
            .filter(|(n, _, _)| n == name)
            .map(|(n, m, _)| format!("{n}/{m}"))
            .collect();
        InputError::new(
            path,
            format!(
                "no topic {name} instance {multi_id} in the log{}",
                if have.is_empty() {
                    String::new()
                } else {
                    format!(" (it has {})", have.join(", "))
                }
            ),
        )
    })
}

/// IMU samples from `sensor_combined` instance `multi_id`: (t [s], gyro [rad/s],
/// accel [m/s²]) in the body frame (FRD), interval-mean rates. Records whose
/// accelerometer time is marked invalid, or with non-finite values, are skipped
/// and counted in the second value.
pub fn imu_rates(
    path: &Path,
    u: &Ulog,
    multi_id: u8,
    map: &TimeMap,
) -> Result<(Vec<(f64, Vector3<f64>, Vector3<f64>)>, usize), InputError> {
    let t = topic(path, u, "sensor_combined", multi_id)?;
    let g = vec3_fields(path, &t, "gyro_rad")?;
    let a = vec3_fields(path, &t, "accelerometer_m_s2")?;
    let rel = t.field("accelerometer_timestamp_relative");
    let mut out = Vec::with_capacity(t.len());
    let mut skipped = 0;
    for k in 0..t.len() {
        let Some(ts) = t.timestamp_us(k) else {
            return Err(InputError::new(path, "sensor_combined: no u64 timestamp"));
        };
        // RELATIVE_TIMESTAMP_INVALID: no accelerometer sample in this record.
        if rel.is_some_and(|r| t.value(k, r) == i32::MAX as f64) {
            skipped += 1;
            continue;
        }
        let gv = Vector3::new(t.value(k, g[0]), t.value(k, g[1]), t.value(k, g[2]));
        let av = Vector3::new(t.value(k, a[0]), t.value(k, a[1]), t.value(k, a[2]));
        if gv.iter().chain(av.iter()).any(|v| !v.is_finite()) {
            skipped += 1;
            continue;
        }
        out.push((map.t(ts), gv, av));
    }
    Ok((out, skipped))
}

/// GNSS fixes (fix_type >= 3) from the first GPS topic present, instance `multi_id`;
/// repeated timestamps are dropped. The second value counts the records left out.
pub fn gnss_fixes(
    path: &Path,
    u: &Ulog,
    multi_id: u8,
    map: &TimeMap,
) -> Result<(Vec<GnssFix>, usize), InputError> {
    let name = GPS_TOPICS
        .iter()
        .find(|n| u.topic(n, multi_id).is_some_and(|t| !t.is_empty()))
        .ok_or_else(|| {
            InputError::new(
                path,
                format!(
                    "no GPS topic (vehicle_gps_position or sensor_gps) instance {multi_id} \
                     with records"
                ),
            )
        })?;
    let t = topic(path, u, name, multi_id)?;
    let f = |n: &str| t.field(n);
    // Position: 1e-7 deg integers and mm, or degrees and metres (PX4 >= 1.14).
    let (lat, lon, alt, deg_scale, alt_scale) = match (f("lat"), f("latitude_deg")) {
        (Some(la), _) => (
            la,
            need(path, &t, "lon")?,
            need(path, &t, "alt_ellipsoid")?,
            1e-7,
            1e-3,
        ),
        (None, Some(la)) => (
            la,
            need(path, &t, "longitude_deg")?,
            need(path, &t, "altitude_ellipsoid_m")?,
            1.0,
            1.0,
        ),
        (None, None) => {
            return Err(InputError::new(
                path,
                format!("topic {name}: neither lat nor latitude_deg"),
            ))
        }
    };
    let eph = need(path, &t, "eph")?;
    let epv = need(path, &t, "epv")?;
    let fix_type = need(path, &t, "fix_type")?;
    let vel = match (
        f("vel_n_m_s"),
        f("vel_e_m_s"),
        f("vel_d_m_s"),
        f("s_variance_m_s"),
    ) {
        (Some(n), Some(e), Some(d), Some(s)) => Some((n, e, d, s)),
        _ => None,
    };
    let vel_valid = f("vel_ned_valid");
    let mut fixes: Vec<GnssFix> = Vec::new();
    let mut skipped = 0;
    let mut prev: Option<u64> = None;
    for k in 0..t.len() {
        let ts = t.timestamp_us(k).unwrap_or(0);
        let (la, lo, h) = (
            t.value(k, lat) * deg_scale,
            t.value(k, lon) * deg_scale,
            t.value(k, alt) * alt_scale,
        );
        let (sh, sv) = (t.value(k, eph), t.value(k, epv));
        let ok = t.value(k, fix_type) >= 3.0
            && prev.is_none_or(|p| ts > p)
            && (-90.0..=90.0).contains(&la)
            && (-360.0..=360.0).contains(&lo)
            && h.is_finite()
            && sh > 0.0
            && sv > 0.0
            && sh.is_finite()
            && sv.is_finite();
        if !ok {
            skipped += 1;
            continue;
        }
        prev = Some(ts);
        let (vel_ned, vel_std_ned) = match vel {
            Some((n, e, d, s))
                if vel_valid.is_none_or(|v| t.value(k, v) != 0.0)
                    && t.value(k, s) > 0.0
                    && t.value(k, s).is_finite() =>
            {
                let v = Vector3::new(t.value(k, n), t.value(k, e), t.value(k, d));
                let s = t.value(k, s);
                if v.iter().all(|x| x.is_finite()) {
                    (Some(v), Some(Vector3::new(s, s, s)))
                } else {
                    (None, None)
                }
            }
            _ => (None, None),
        };
        fixes.push(GnssFix {
            t: map.t(ts),
            lla: Vector3::new(la.to_radians(), lo.to_radians(), h),
            std_ned: Vector3::new(sh, sh, sv),
            vel_ned,
            vel_std_ned,
        });
    }
    Ok((fixes, skipped))
}

/// Barometric pressures (t [s], Pa) from `sensor_baro` instance `multi_id`, else
/// `vehicle_air_data`; repeated timestamps dropped.
pub fn baro_pressures(
    path: &Path,
    u: &Ulog,
    multi_id: u8,
    map: &TimeMap,
) -> Result<Vec<(f64, f64)>, InputError> {
    // sensor_baro is often logged subsampled (1 Hz in the SITL sample): the topic
    // with more records wins.
    let air = u.topic("vehicle_air_data", multi_id).map_or(0, |t| t.len());
    let (t, field, scale) = match u.topic("sensor_baro", multi_id).filter(|t| t.len() >= air) {
        Some(t) => {
            let f = need(path, &t, "pressure")?.clone();
            // PX4 before v1.11 logged hPa (mbar); since then Pa.
            let first = (!t.is_empty()).then(|| t.value(0, &f)).unwrap_or(0.0);
            let scale = if first > 0.0 && first < 2000.0 {
                100.0
            } else {
                1.0
            };
            (t, f, scale)
        }
        None => {
            let t = topic(path, u, "vehicle_air_data", multi_id).map_err(|_| {
                InputError::new(
                    path,
                    format!(
                        "no barometer topic (sensor_baro or vehicle_air_data) instance {multi_id}"
                    ),
                )
            })?;
            let f = need(path, &t, "baro_pressure_pa")?.clone();
            (t, f, 1.0)
        }
    };
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(t.len());
    let mut prev: Option<u64> = None;
    for k in 0..t.len() {
        let ts = t.timestamp_us(k).unwrap_or(0);
        if prev.is_some_and(|p| ts <= p) {
            continue;
        }
        prev = Some(ts);
        out.push((map.t(ts), t.value(k, &field) * scale));
    }
    Ok(out)
}

/// Index of the record of `times` (sorted) nearest to `x`.
fn nearest(times: &[f64], x: f64) -> Option<usize> {
    if times.is_empty() {
        return None;
    }
    let i = times.partition_point(|&t| t < x);
    Some(match i {
        0 => 0,
        i if i == times.len() => i - 1,
        i if x - times[i - 1] <= times[i] - x => i - 1,
        i => i,
    })
}

/// EKF2's estimate as a trajectory: one point per `vehicle_global_position` record,
/// with the nearest `vehicle_attitude` (within 0.1 s) and `vehicle_local_position`
/// velocity (within 0.1 s). The week (None: boot seconds) and warnings come with it.
pub fn ekf2_track(
    path: &Path,
    u: &Ulog,
) -> Result<(Vec<TrajPoint>, TimeMap, Vec<String>), InputError> {
    let map = TimeMap::of(u, 0);
    let mut warnings = Vec::new();
    let gp = topic(path, u, "vehicle_global_position", 0)?;
    let lat = need(path, &gp, "lat")?;
    let lon = need(path, &gp, "lon")?;
    let alt = match gp.field("alt_ellipsoid") {
        Some(f) => f,
        None => {
            warnings.push(format!(
                "{}: vehicle_global_position has no alt_ellipsoid: heights are EKF2's alt (AMSL)",
                path.display()
            ));
            need(path, &gp, "alt")?
        }
    };
    let att: Option<(Vec<f64>, Vec<Vector3<f64>>)> = u.topic("vehicle_attitude", 0).and_then(|a| {
        let q: Vec<_> = (0..4)
            .map(|i| a.field(&format!("q[{i}]")))
            .collect::<Option<_>>()?;
        let mut ts = Vec::new();
        let mut rpy = Vec::new();
        for k in 0..a.len() {
            let qq = Quaternion::new(
                a.value(k, q[0]),
                a.value(k, q[1]),
                a.value(k, q[2]),
                a.value(k, q[3]),
            );
            if !qq.coords.iter().all(|v| v.is_finite()) || qq.norm() < 0.5 {
                continue;
            }
            ts.push(map.t(a.timestamp_us(k)?));
            rpy.push(euler_from_q_bn(&UnitQuaternion::from_quaternion(qq)));
        }
        Some((ts, rpy))
    });
    let vel: Option<(Vec<f64>, Vec<Vector3<f64>>)> =
        u.topic("vehicle_local_position", 0).and_then(|l| {
            let (x, y, z) = (l.field("vx")?, l.field("vy")?, l.field("vz")?);
            let mut ts = Vec::new();
            let mut v = Vec::new();
            for k in 0..l.len() {
                ts.push(map.t(l.timestamp_us(k)?));
                v.push(Vector3::new(l.value(k, x), l.value(k, y), l.value(k, z)));
            }
            Some((ts, v))
        });
    let pick = |s: &Option<(Vec<f64>, Vec<Vector3<f64>>)>, t: f64| -> Option<Vector3<f64>> {
        let (ts, vs) = s.as_ref()?;
        let i = nearest(ts, t)?;
        ((ts[i] - t).abs() <= 0.1 && vs[i].iter().all(|x| x.is_finite())).then(|| vs[i])
    };
    let mut points: Vec<TrajPoint> = Vec::with_capacity(gp.len());
    for k in 0..gp.len() {
        let t = map.t(gp.timestamp_us(k).unwrap_or(0));
        let (la, lo, h) = (gp.value(k, lat), gp.value(k, lon), gp.value(k, alt));
        if points.last().is_some_and(|p| t <= p.t)
            || !(-90.0..=90.0).contains(&la)
            || !lo.is_finite()
            || !h.is_finite()
        {
            continue;
        }
        points.push(TrajPoint {
            t,
            lla: Vector3::new(la.to_radians(), lo.to_radians(), h),
            v_n: pick(&vel, t),
            rpy: pick(&att, t),
        });
    }
    Ok((points, map, warnings))
}
