//! PX4 ULog inputs (docs/FORMATS.md "PX4 ULog"): the container in [`parse`], and
//! here the topics navfuse reads from it, all on one time scale.
//!
//! - IMU: `sensor_combined` (`gyro_rad` [rad/s], `accelerometer_m_s2` [m/s²]: means
//!   over `gyro_integral_dt` / `accelerometer_integral_dt`, so interval-mean rates),
//!   body frame FRD; without it, `sensor_gyro` + `sensor_accel` joined on the gyro
//!   sample times ([`separate_imu`]);
//! - GNSS: `vehicle_gps_position` (else `sensor_gps`): `lat`/`lon` [1e-7 deg] and
//!   `alt_ellipsoid` \[mm\] or `latitude_deg`/`longitude_deg`/`altitude_ellipsoid_m`
//!   (newer PX4), `eph`/`epv` \[m\] as position sigmas, `vel_n_m_s`.. with
//!   `s_variance_m_s` as velocity sigma (when `vel_ned_valid`), `fix_type` 3-6 kept;
//! - barometer: `sensor_baro.pressure` [Pa; hPa in PX4 before v1.11, told by its
//!   range], or `vehicle_air_data.baro_pressure_pa` when that has more records;
//! - EKF2's estimate: `vehicle_global_position` (`lat`, `lon` \[deg\], `alt_ellipsoid`
//!   or else `alt` \[m\]), `vehicle_attitude.q` (Hamilton, w x y z, body FRD to NED:
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
use crate::input::RateSampling;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use navfuse_core::attitude::euler_from_q_bn;
use navfuse_core::eval::TrajPoint;
use navfuse_core::time::{leap_seconds_at_utc, SECONDS_PER_WEEK};
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

/// Boot time \[µs\] -> navfuse time \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeMap {
    /// GPS week of the times; None: seconds since boot.
    pub week: Option<u32>,
    /// GPS time [µs since the GPS epoch] - boot time [µs], when known.
    offset_us: Option<i128>,
    /// The GPS records' latency \[µs\]: `timestamp` (publication) minus the fix's
    /// time of validity, from the log's `EKF2_GPS_DELAY` parameter (0 without it).
    pub gps_delay_us: i128,
}

impl TimeMap {
    /// The mapping of a log, one for all its topics: through the first GPS topic and
    /// instance (0 first) with `time_utc_usec`. `time_utc_usec - timestamp` is the
    /// GPS - boot offset less the GPS latency (a record is published after its fix),
    /// so the latency `EKF2_GPS_DELAY` \[ms\] (what PX4's own filter assumes) is added
    /// back: IMU and barometer samples get their true time, and a fix its time of
    /// validity ([`TimeMap::fix_t`]).
    pub fn of(u: &Ulog) -> TimeMap {
        let delay_ms = u
            .params
            .get("EKF2_GPS_DELAY")
            .copied()
            .filter(|v| (0.0..=1000.0).contains(v))
            .unwrap_or(0.0);
        let gps_delay_us = (delay_ms * 1e3).round() as i128;
        let none = TimeMap {
            week: None,
            offset_us: None,
            gps_delay_us,
        };
        let Some(t) = GPS_TOPICS
            .iter()
            .find_map(|n| (0..=3u8).find_map(|m| u.topic(n, m).filter(|t| !t.is_empty())))
        else {
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
        let utc_minus_boot = d[d.len() / 2] + gps_delay_us;
        // UTC µs since 1970 -> GPS µs since 1980-01-06, with the leap seconds of
        // the week of the first fix (an approximate week first).
        let epoch_us = navfuse_core::time::GPS_EPOCH_UNIX as i128 * 1_000_000;
        let first_utc_s =
            (utc_minus_boot - epoch_us + t.timestamp_us(0).unwrap_or(0) as i128) as f64 * 1e-6;
        let leap = leap_seconds_at_utc(first_utc_s);
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
            gps_delay_us,
        }
    }

    /// Time of validity \[s\] of a GPS record published at boot timestamp `us`.
    pub fn fix_t(&self, us: u64) -> f64 {
        self.t(us) - self.gps_delay_us as f64 * 1e-6
    }

    /// Time \[s\] of boot timestamp `us`.
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

/// The three fields `name(0)`, `name(1)`, `name(2)`.
fn fields3<'a>(
    path: &Path,
    t: &'a Topic<'_>,
    name: impl Fn(usize) -> String,
) -> Result<[&'a parse::Field; 3], InputError> {
    Ok([
        need(path, t, &name(0))?,
        need(path, t, &name(1))?,
        need(path, t, &name(2))?,
    ])
}

/// `base[0]`, `base[1]`, `base[2]`.
fn vec3_fields<'a>(
    path: &Path,
    t: &'a Topic<'_>,
    base: &str,
) -> Result<[&'a parse::Field; 3], InputError> {
    fields3(path, t, |i| format!("{base}[{i}]"))
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

/// IMU samples of a log, rates in the body frame (FRD).
#[derive(Clone, Debug)]
pub struct UlogImu {
    /// (t \[s\], gyro [rad/s], accel [m/s²]) in time order.
    pub samples: Vec<(f64, Vector3<f64>, Vector3<f64>)>,
    /// Records left out (no accelerometer sample, non-finite values, out of order).
    pub skipped: usize,
    /// How the rates relate to their time tags.
    pub sampling: RateSampling,
    /// Where they came from: `sensor_combined`, or `sensor_gyro + sensor_accel`.
    pub topics: &'static str,
}

/// IMU samples from `sensor_combined` instance `multi_id` (interval-mean rates);
/// without that topic, from `sensor_gyro` and `sensor_accel` of that instance
/// ([`separate_imu`]).
pub fn imu_rates(
    path: &Path,
    u: &Ulog,
    multi_id: u8,
    map: &TimeMap,
) -> Result<UlogImu, InputError> {
    if u.topic("sensor_combined", multi_id).is_none()
        && u.topic("sensor_gyro", multi_id).is_some()
        && u.topic("sensor_accel", multi_id).is_some()
    {
        return separate_imu(path, u, multi_id, map);
    }
    let t = topic(path, u, "sensor_combined", multi_id)?;
    let g = vec3_fields(path, &t, "gyro_rad")?;
    let a = vec3_fields(path, &t, "accelerometer_m_s2")?;
    let rel = t.field("accelerometer_timestamp_relative");
    let mut out = UlogImu {
        samples: Vec::with_capacity(t.len()),
        skipped: 0,
        sampling: RateSampling::IntervalMean,
        topics: "sensor_combined",
    };
    for k in 0..t.len() {
        let Some(ts) = t.timestamp_us(k) else {
            return Err(InputError::new(path, "sensor_combined: no u64 timestamp"));
        };
        // RELATIVE_TIMESTAMP_INVALID: no accelerometer sample in this record.
        if rel.is_some_and(|r| t.value(k, r) == i32::MAX as f64) {
            out.skipped += 1;
            continue;
        }
        let gv = Vector3::new(t.value(k, g[0]), t.value(k, g[1]), t.value(k, g[2]));
        let av = Vector3::new(t.value(k, a[0]), t.value(k, a[1]), t.value(k, a[2]));
        if gv.iter().chain(av.iter()).any(|v| !v.is_finite()) {
            out.skipped += 1;
            continue;
        }
        out.samples.push((map.t(ts), gv, av));
    }
    Ok(out)
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// One sensor topic's samples: (sample time [µs since boot], x y z).
struct SensorSeries {
    t_us: Vec<f64>,
    xyz: Vec<Vector3<f64>>,
    skipped: usize,
}

/// `sensor_gyro` or `sensor_accel`: PX4 v1.11+ (`timestamp_sample`, `x y z`:
/// instantaneous rates, board rotation applied) or older PX4 (`x_integral` over
/// `integral_dt` [µs]: interval means). The bool says whether the rates are means.
fn sensor_series(path: &Path, t: &Topic<'_>) -> Result<(SensorSeries, bool), InputError> {
    let integral = match (t.field("integral_dt"), t.field("x_integral")) {
        (Some(dt), Some(_)) => Some((dt, fields3(path, t, |i| format!("{}_integral", AXES[i]))?)),
        _ => None,
    };
    let xyz = [
        need(path, t, "x")?,
        need(path, t, "y")?,
        need(path, t, "z")?,
    ];
    let sample = t.field("timestamp_sample");
    let mut s = SensorSeries {
        t_us: Vec::with_capacity(t.len()),
        xyz: Vec::with_capacity(t.len()),
        skipped: 0,
    };
    for k in 0..t.len() {
        let Some(ts) = t.timestamp_us(k) else {
            return Err(InputError::new(
                path,
                format!("{}: no u64 timestamp", t.name),
            ));
        };
        let tk = sample.map_or(ts as f64, |f| t.value(k, f));
        let v = match &integral {
            Some((dt, f)) => {
                let dt_s = t.value(k, dt) * 1e-6;
                Vector3::new(t.value(k, f[0]), t.value(k, f[1]), t.value(k, f[2])) / dt_s
            }
            None => Vector3::new(t.value(k, xyz[0]), t.value(k, xyz[1]), t.value(k, xyz[2])),
        };
        let ordered = s.t_us.last().is_none_or(|&p| tk > p);
        if !tk.is_finite() || !ordered || v.iter().any(|x| !x.is_finite()) {
            s.skipped += 1;
            continue;
        }
        s.t_us.push(tk);
        s.xyz.push(v);
    }
    Ok((s, integral.is_some()))
}

/// IMU samples from `sensor_gyro` and `sensor_accel` instance `multi_id` (logs
/// without `sensor_combined`): one sample per gyro record, the accelerometer
/// interpolated linearly to the gyro sample time (instantaneous rates), or the
/// nearest accelerometer record (interval means, old PX4). A gyro record without
/// accelerometer records within 0.05 s on both sides (interpolation) or within
/// 0.05 s (nearest) is skipped. These topics are the drivers' output before PX4's
/// calibration: the filter's bias states take up what calibration would remove.
pub fn separate_imu(
    path: &Path,
    u: &Ulog,
    multi_id: u8,
    map: &TimeMap,
) -> Result<UlogImu, InputError> {
    const MAX_GAP_US: f64 = 50_000.0;
    let (gyro, gyro_mean) = sensor_series(path, &topic(path, u, "sensor_gyro", multi_id)?)?;
    let (acc, acc_mean) = sensor_series(path, &topic(path, u, "sensor_accel", multi_id)?)?;
    if gyro_mean != acc_mean {
        return Err(InputError::new(
            path,
            "sensor_gyro and sensor_accel of different PX4 versions (one integrated, one not)",
        ));
    }
    let mut out = UlogImu {
        samples: Vec::with_capacity(gyro.t_us.len()),
        skipped: gyro.skipped,
        sampling: if gyro_mean {
            RateSampling::IntervalMean
        } else {
            RateSampling::Instant
        },
        topics: "sensor_gyro + sensor_accel",
    };
    // A topic logged at a low rate (about 1 Hz in the SITL log here) is no
    // IMU: refuse it, saying the rate.
    for (name, s) in [("sensor_gyro", &gyro), ("sensor_accel", &acc)] {
        let n = s.t_us.len();
        let span_s = match (s.t_us.first(), s.t_us.last()) {
            (Some(a), Some(b)) if n > 1 => (b - a) * 1e-6,
            _ => 0.0,
        };
        let rate_hz = if span_s > 0.0 {
            (n - 1) as f64 / span_s
        } else {
            0.0
        };
        if rate_hz < 20.0 {
            return Err(InputError::new(
                path,
                format!(
                    "{name} instance {multi_id}: {n} records at {rate_hz:.1} Hz, too few for an IMU (at least 20 Hz); use a log with sensor_combined, or one with sensor_gyro and sensor_accel logged at the sensor rate"
                ),
            )
            .with_field(name));
        }
    }
    let mut j = 0; // first accel sample at or after the gyro time
    for (&tg, &wg) in gyro.t_us.iter().zip(&gyro.xyz) {
        while j < acc.t_us.len() && acc.t_us[j] < tg {
            j += 1;
        }
        let after = (j < acc.t_us.len()).then(|| (acc.t_us[j], acc.xyz[j]));
        let before = j.checked_sub(1).map(|i| (acc.t_us[i], acc.xyz[i]));
        let a = if gyro_mean {
            [before, after]
                .into_iter()
                .flatten()
                .filter(|(ta, _)| (ta - tg).abs() <= MAX_GAP_US)
                .min_by(|x, y| (x.0 - tg).abs().total_cmp(&(y.0 - tg).abs()))
                .map(|(_, a)| a)
        } else {
            match (before, after) {
                (_, Some((ta, a))) if ta == tg => Some(a),
                (Some((t0, a0)), Some((t1, a1)))
                    if tg - t0 <= MAX_GAP_US && t1 - tg <= MAX_GAP_US =>
                {
                    Some(a0 + (a1 - a0) * ((tg - t0) / (t1 - t0)))
                }
                _ => None,
            }
        };
        match a {
            Some(a) if tg >= 0.0 => out.samples.push((map.t(tg as u64), wg, a)),
            _ => out.skipped += 1,
        }
    }
    Ok(out)
}

/// GNSS fixes (fix_type 3-6) from the first GPS topic present, instance `multi_id`;
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
        // 3D, DGPS, RTK float, RTK fixed; not 8 (extrapolated: no measurement).
        let ok = (3.0..=6.0).contains(&t.value(k, fix_type))
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
                    // A 3D speed accuracy (u-blox sAcc): split over the axes.
                    (Some(v), Some(Vector3::repeat(s / 3f64.sqrt())))
                } else {
                    (None, None)
                }
            }
            _ => (None, None),
        };
        fixes.push(GnssFix {
            t: map.fix_t(ts),
            lla: Vector3::new(la.to_radians(), lo.to_radians(), h),
            // eph is a horizontal (2D) accuracy (u-blox hAcc): split over N and E,
            // as the UBX reader does.
            std_ned: Vector3::new(
                sh / std::f64::consts::SQRT_2,
                sh / std::f64::consts::SQRT_2,
                sv,
            ),
            vel_ned,
            vel_std_ned,
        });
    }
    Ok((fixes, skipped))
}

/// Barometric pressures (t \[s\], Pa) from `sensor_baro` instance `multi_id`, else
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
            // PX4 before v1.11 logged hPa (mbar); since then Pa. Told by the median
            // of the finite positive values (a first 0 while the sensor starts
            // does not decide it).
            let mut v: Vec<f64> = (0..t.len())
                .map(|k| t.value(k, &f))
                .filter(|x| x.is_finite() && *x > 0.0)
                .collect();
            v.sort_by(f64::total_cmp);
            let median = v.get(v.len() / 2).copied().unwrap_or(0.0);
            let scale = if median > 0.0 && median < 2000.0 {
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
    let map = TimeMap::of(u);
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
