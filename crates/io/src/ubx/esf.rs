//! UBX-ESF-RAW (0x10 0x03) and UBX-ESF-MEAS (0x10 0x02): the IMU and the wheel
//! ticks / speed of u-blox dead-reckoning receivers (ZED-F9R, NEO-M8U, ...), and the
//! mapping of their receiver-local sensor time tags to GPS time
//! (docs/FORMATS.md "ESF-RAW and ESF-MEAS").
//!
//! Layouts (u-blox interface descriptions, "UBX-ESF-RAW", "UBX-ESF-MEAS" and "ESF
//! measurement data"):
//! - ESF-RAW: 4 reserved bytes, then blocks of 8 bytes: `data` (bits 0-23 the value,
//!   bits 24-31 the data type) and `sTtag` (u32 sensor time tag).
//! - ESF-MEAS: `timeTag` u32, `flags` u16 (bit 3 calibTtagValid, bits 11-15
//!   numMeas), `id` u16, numMeas x `data` (bits 0-23 value, bits 24-29 type), and a
//!   u32 `calibTtag` when calibTtagValid.
//! - Data types: 14 / 13 / 5 gyro x / y / z [deg/s x 2^-12], 16 / 17 / 18 accel
//!   x / y / z [m/s^2 x 2^-10] (24-bit signed), 12 gyro temperature (ignored), 6 / 7
//!   / 8 / 9 front-left / front-right / rear-left / rear-right wheel ticks and 10 a
//!   single tick (bits 0-22 count, bit 23 direction: 1 backward), 11 speed [m/s x
//!   1e-3] (24-bit signed).
//!
//! Time: the tags count receiver-local sensor time (1 ms by default,
//! CFG-SFCORE-SEN_TTAG_FACT), with no GPS time in the message. The mapping is a
//! straight line fitted to anchors: each navigation epoch's GPS time (NAV-PVT iTOW
//! with validTime, NAV-RELPOSNED iTOW with gnssFixOK, RXM-RAWX rcvTow with a week;
//! the first message of each epoch) paired with
//! the last sensor tag of the same message kind seen before it in the file. See
//! [`fit_time_map`] for the rules and what the fit cannot know.

use super::frame::{u16_at, u32_at, Frame};
use std::f64::consts::PI;

/// Gyro scale: 2^-12 deg/s per count.
pub const GYRO_DPS_PER_COUNT: f64 = 1.0 / 4096.0;
/// Accelerometer scale: 2^-10 m/s^2 per count.
pub const ACCEL_MPS2_PER_COUNT: f64 = 1.0 / 1024.0;
/// Speed (type 11) scale: 1e-3 m/s per count.
pub const SPEED_MPS_PER_COUNT: f64 = 1e-3;
/// The documented default sensor time tag unit (CFG-SFCORE-SEN_TTAG_FACT = 1000 us).
pub const NOMINAL_TICK_S: f64 = 1e-3;
/// A fitted tick further than this (relative) from 1 ms is warned about.
pub const TICK_TOLERANCE: f64 = 1e-3;
/// Anchors must span this long for the tick to be fitted; else 1 ms is assumed.
pub const MIN_FIT_SPAN_S: f64 = 10.0;
/// A mapping whose anchors scatter more than this (RMS after outlier rejection)
/// is refused: the tags are not one steady clock.
pub const MAX_RESIDUAL_RMS_S: f64 = 0.2;

/// Gyro x, y, z and accel x, y, z data types, in that order.
pub const IMU_TYPES: [u8; 6] = [14, 13, 5, 16, 17, 18];

/// The two message kinds carrying sensor data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EsfKind {
    Raw,
    Meas,
}

impl EsfKind {
    pub fn name(self) -> &'static str {
        match self {
            EsfKind::Raw => "ESF-RAW",
            EsfKind::Meas => "ESF-MEAS",
        }
    }
}

/// One IMU sample: the six axes of one time tag.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EsfImu {
    /// Unwrapped sensor time tag (counts).
    pub tag: u64,
    /// Byte offset of the message that completed the sample.
    pub offset: usize,
    /// Angular rate x, y, z [rad/s], sensor frame.
    pub gyro: [f64; 3],
    /// Specific force x, y, z [m/s^2], sensor frame.
    pub accel: [f64; 3],
}

/// One wheel-tick or speed value (data types 6-11) of ESF-MEAS.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EsfOdo {
    pub tag: u64,
    pub offset: usize,
    /// Data type 6-11.
    pub data_type: u8,
    /// The raw 24-bit field.
    pub field: u32,
}

/// Sensor time (counts) -> GPS seconds: t = t0_s + (tag - tag0) * tick_s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeMap {
    pub tag0: u64,
    pub t0_s: f64,
    pub tick_s: f64,
    /// Anchors used (after outlier rejection), the RMS of their offsets about the
    /// median and the spread (largest - smallest) \[s\].
    pub anchors: usize,
    pub rejected: usize,
    pub rms_s: f64,
    pub max_s: f64,
    /// The least-squares tick; None: too few anchors or too short a span (1 ms
    /// assumed). Within [`TICK_TOLERANCE`] of 1 ms the tick is 1 ms.
    pub fitted_tick_s: Option<f64>,
}

impl TimeMap {
    pub fn t(&self, tag: u64) -> f64 {
        self.t0_s + (tag as f64 - self.tag0 as f64) * self.tick_s
    }

    /// A one-line account for the run notes.
    pub fn describe(&self, kind: EsfKind) -> String {
        format!(
            "{} sensor time -> GPST: tick {:.6} ms ({}), {} anchors ({} rejected), offsets {:.1} ms RMS, spread {:.1} ms (the receiver's output latency is not in these figures)",
            kind.name(),
            self.tick_s * 1e3,
            match self.fitted_tick_s {
                None => "assumed: the u-blox default".to_string(),
                Some(f) if self.tick_s == NOMINAL_TICK_S =>
                    format!("the u-blox default; the fit gives {:.6} ms", f * 1e3),
                Some(_) => "fitted".to_string(),
            },
            self.anchors,
            self.rejected,
            self.rms_s * 1e3,
            self.max_s * 1e3
        )
    }
}

/// Counts of what the ESF messages held.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EsfCounts {
    pub raw_messages: usize,
    pub meas_messages: usize,
    /// Samples of unknown or unused data types (temperature included).
    pub other_types: usize,
    /// Time tags dropped: incomplete (an axis missing or repeated), duplicated or
    /// out of order.
    pub dropped_imu: usize,
    pub dropped_odo: usize,
}

/// What the ESF messages of a log gave, with the time maps.
#[derive(Clone, Debug, Default)]
pub struct EsfLog {
    pub raw_imu: Vec<EsfImu>,
    pub meas_imu: Vec<EsfImu>,
    pub odo: Vec<EsfOdo>,
    /// Sensor time -> GPS time of ESF-RAW / ESF-MEAS tags: Err(reason) when it
    /// cannot be established (None: no sensor data of that kind).
    pub raw_map: Option<Result<TimeMap, String>>,
    pub meas_map: Option<Result<TimeMap, String>>,
    pub counts: EsfCounts,
    /// Findings (byte offsets named), at most a few of each kind then a count.
    pub warnings: Vec<String>,
}

impl EsfLog {
    pub fn imu(&self, kind: EsfKind) -> &[EsfImu] {
        match kind {
            EsfKind::Raw => &self.raw_imu,
            EsfKind::Meas => &self.meas_imu,
        }
    }
    pub fn map(&self, kind: EsfKind) -> Option<&Result<TimeMap, String>> {
        match kind {
            EsfKind::Raw => self.raw_map.as_ref(),
            EsfKind::Meas => self.meas_map.as_ref(),
        }
    }
}

/// Sign-extend a 24-bit field.
pub fn signed24(field: u32) -> i32 {
    ((field << 8) as i32) >> 8
}

/// Unwraps a u32 tag counter (a backwards jump of more than half the range is a
/// rollover).
#[derive(Default)]
struct Unwrap {
    last: Option<u32>,
    high: u64,
}

impl Unwrap {
    fn next(&mut self, v: u32) -> u64 {
        if let Some(l) = self.last {
            if v < l && l - v > u32::MAX / 2 {
                self.high += 1 << 32;
            } else if v > l && v - l > u32::MAX / 2 && self.high > 0 {
                // a late sample from before the rollover
                return self.high - (1 << 32) + u64::from(v);
            }
        }
        self.last = Some(v);
        self.high + u64::from(v)
    }
}

/// Collects warnings of one kind: the first few in full, then a count.
struct Warn {
    what: &'static str,
    shown: Vec<String>,
    more: usize,
}

impl Warn {
    fn new(what: &'static str) -> Self {
        Warn {
            what,
            shown: Vec::new(),
            more: 0,
        }
    }
    fn push(&mut self, s: String) {
        if self.shown.len() < super::MAX_WARNINGS {
            self.shown.push(s);
        } else {
            self.more += 1;
        }
    }
    fn flush(self, name: &str, out: &mut Vec<String>) {
        out.extend(self.shown);
        if self.more > 0 {
            out.push(format!("{name}: {} more {}", self.more, self.what));
        }
    }
}

/// Groups the axis values of one time tag into IMU samples (one stream per
/// message kind).
struct Grouper {
    kind: EsfKind,
    cur: Option<(u64, usize, [Option<i32>; 6], bool)>,
    last_done: Option<u64>,
    out: Vec<EsfImu>,
    /// Values dropped (a late time tag: each axis) and samples dropped (incomplete).
    dropped: usize,
    last_warned: Option<u64>,
}

impl Grouper {
    fn new(kind: EsfKind) -> Self {
        Grouper {
            kind,
            cur: None,
            last_done: None,
            out: Vec::new(),
            dropped: 0,
            last_warned: None,
        }
    }

    fn add(&mut self, tag: u64, offset: usize, axis: usize, v: i32, w: &mut Warn, name: &str) {
        if self.cur.as_ref().is_some_and(|c| c.0 != tag) {
            self.close(w, name);
        }
        if let Some(ld) = self.last_done.filter(|&ld| tag <= ld) {
            let how = if tag == ld {
                "duplicated"
            } else {
                "out of order"
            };
            self.dropped += 1;
            if self.last_warned == Some(tag) {
                return; // one warning per time tag
            }
            self.last_warned = Some(tag);
            w.push(format!(
                "{name}: byte {offset}: {}: sensor time tag {tag} {how} (previous sample {ld}): value dropped",
                self.kind.name()
            ));
            return;
        }
        let c = self.cur.get_or_insert((tag, offset, [None; 6], false));
        c.1 = offset;
        if c.2[axis].is_some() {
            c.3 = true;
        }
        c.2[axis] = Some(v);
    }

    /// Finish the current tag: a complete sample, or a warning.
    fn close(&mut self, w: &mut Warn, name: &str) -> bool {
        let Some((tag, offset, ax, repeated)) = self.cur.take() else {
            return true;
        };
        self.last_done = Some(tag);
        let missing: Vec<u8> = (0..6)
            .filter(|&k| ax[k].is_none())
            .map(|k| IMU_TYPES[k])
            .collect();
        if repeated || !missing.is_empty() {
            w.push(format!(
                "{name}: byte {offset}: {}: sensor time tag {tag}: {}: sample dropped",
                self.kind.name(),
                if repeated {
                    "an axis duplicated (given twice)".to_string()
                } else {
                    format!("no data type {missing:?}")
                }
            ));
            self.dropped += 1;
            return false;
        }
        let g = |k: usize| f64::from(ax[k].unwrap_or(0)) * GYRO_DPS_PER_COUNT * PI / 180.0;
        let a = |k: usize| f64::from(ax[k].unwrap_or(0)) * ACCEL_MPS2_PER_COUNT;
        self.out.push(EsfImu {
            tag,
            offset,
            gyro: [g(0), g(1), g(2)],
            accel: [a(3), a(4), a(5)],
        });
        true
    }
}

/// A navigation epoch's GPS time [s of week] from a message that carries one.
fn epoch_time(f: &Frame<'_>) -> Option<f64> {
    let p = f.payload;
    match (f.class, f.id) {
        // NAV-PVT with validTime; NAV-RELPOSNED with gnssFixOK; RXM-RAWX with a week.
        (0x01, 0x07) if p.len() == super::pvt::LEN && p[11] & 2 != 0 => {
            Some(f64::from(u32_at(p, 0)) * 1e-3)
        }
        (0x01, 0x3C)
            if (p.len() == 40 && p[0] == 0 && p[36] & 1 != 0)
                || (p.len() == 64 && p[0] == 1 && p[60] & 1 != 0) =>
        {
            Some(f64::from(u32_at(p, 4)) * 1e-3)
        }
        (0x02, 0x15) if p.len() >= 16 && u16_at(p, 8) > 0 => {
            let tow = super::frame::f64_at(p, 0);
            tow.is_finite().then_some(tow)
        }
        _ => None,
    }
    .filter(|t| (0.0..604_800.0).contains(t))
}

/// Decode every ESF message of `frames` and fit the time maps; `name` heads the
/// warnings.
pub fn decode(frames: &[Frame<'_>], name: &str) -> EsfLog {
    let mut log = EsfLog::default();
    let mut malformed = Warn::new("malformed ESF messages skipped");
    let mut order = Warn::new("ESF samples dropped (incomplete, duplicated or out of order)");
    let mut raw = Grouper::new(EsfKind::Raw);
    let mut meas = Grouper::new(EsfKind::Meas);
    let (mut uw_raw, mut uw_meas) = (Unwrap::default(), Unwrap::default());
    let (mut last_raw, mut last_meas): (Option<u64>, Option<u64>) = (None, None);
    let (mut anchors_raw, mut anchors_meas) = (Vec::new(), Vec::new());
    // Epoch times unwrapped over week rollovers.
    let (mut prev_tow, mut week_add, mut last_epoch): (Option<f64>, f64, Option<f64>) =
        (None, 0.0, None);
    let mut last_odo: [Option<u64>; 12] = [None; 12];
    for f in frames {
        let p = f.payload;
        match (f.class, f.id) {
            (0x10, 0x03) => {
                log.counts.raw_messages += 1;
                if p.len() < 4 || (p.len() - 4) % 8 != 0 {
                    malformed.push(format!(
                        "{name}: byte {}: ESF-RAW: {} bytes, expected 4 + 8 x N: message skipped",
                        f.offset,
                        p.len()
                    ));
                    continue;
                }
                for b in p[4..].chunks_exact(8) {
                    let data = u32_at(b, 0);
                    let tag = uw_raw.next(u32_at(b, 4));
                    let ty = (data >> 24) as u8;
                    match IMU_TYPES.iter().position(|&t| t == ty) {
                        Some(axis) => {
                            raw.add(tag, f.offset, axis, signed24(data), &mut order, name);
                            last_raw = Some(last_raw.map_or(tag, |l| l.max(tag)));
                        }
                        None => log.counts.other_types += 1,
                    }
                }
            }
            (0x10, 0x02) => {
                log.counts.meas_messages += 1;
                if p.len() < 8 {
                    malformed.push(format!(
                        "{name}: byte {}: ESF-MEAS: {} bytes, expected at least 8: message skipped",
                        f.offset,
                        p.len()
                    ));
                    continue;
                }
                let flags = u16_at(p, 4);
                let n = usize::from(flags >> 11);
                let calib = usize::from(flags & 8 != 0) * 4;
                if p.len() != 8 + 4 * n + calib {
                    malformed.push(format!(
                        "{name}: byte {}: ESF-MEAS: field 'numMeas': {n} measurements{} need {} bytes, the message has {}: message skipped",
                        f.offset,
                        if calib > 0 { " and calibTtag" } else { "" },
                        8 + 4 * n + calib,
                        p.len()
                    ));
                    continue;
                }
                let tag = uw_meas.next(u32_at(p, 0));
                for k in 0..n {
                    let data = u32_at(p, 8 + 4 * k);
                    let ty = ((data >> 24) & 0x3F) as u8;
                    let field = data & 0x00FF_FFFF;
                    if let Some(axis) = IMU_TYPES.iter().position(|&t| t == ty) {
                        meas.add(tag, f.offset, axis, signed24(field), &mut order, name);
                    } else if (6..=11).contains(&ty) {
                        let last = &mut last_odo[usize::from(ty)];
                        if let Some(lt) = last.filter(|&lt| tag <= lt) {
                            order.push(format!(
                                "{name}: byte {}: ESF-MEAS: data type {ty} at sensor time tag {tag} {} (previous {lt}): value dropped",
                                f.offset,
                                if tag == lt { "duplicated" } else { "out of order" }
                            ));
                            log.counts.dropped_odo += 1;
                            continue;
                        }
                        *last = Some(tag);
                        log.odo.push(EsfOdo {
                            tag,
                            offset: f.offset,
                            data_type: ty,
                            field,
                        });
                    } else {
                        log.counts.other_types += 1;
                        continue;
                    }
                }
                last_meas = Some(last_meas.map_or(tag, |l| l.max(tag)));
            }
            _ => {
                let Some(tow) = epoch_time(f) else { continue };
                if prev_tow.is_some_and(|p| tow < p - 302_400.0) {
                    week_add += 604_800.0;
                }
                prev_tow = Some(tow);
                let t = tow + week_add;
                // The first message of each epoch only.
                if last_epoch.is_some_and(|l| t <= l) {
                    continue;
                }
                last_epoch = Some(t);
                if let Some(x) = last_raw {
                    anchors_raw.push((x, t));
                }
                if let Some(x) = last_meas {
                    anchors_meas.push((x, t));
                }
            }
        }
    }
    raw.close(&mut order, name);
    meas.close(&mut order, name);
    let imu_tags = |g: &Grouper| g.last_done.is_some();
    log.counts.dropped_imu = raw.dropped + meas.dropped;
    if imu_tags(&raw) {
        log.raw_map = Some(fit_time_map(&anchors_raw, EsfKind::Raw));
    }
    if imu_tags(&meas) || !log.odo.is_empty() {
        log.meas_map = Some(fit_time_map(&anchors_meas, EsfKind::Meas));
    }
    log.raw_imu = raw.out;
    log.meas_imu = meas.out;
    malformed.flush(name, &mut log.warnings);
    order.flush(name, &mut log.warnings);
    log
}

/// Fit t = t0 + (tag - tag0) tick to the (tag, GPS time) anchors.
///
/// - No anchor: Err (the log has no navigation message after sensor data).
/// - Anchors spanning less than [`MIN_FIT_SPAN_S`] or fewer than 3: the tick is the
///   documented 1 ms, the offset the median of t - tag x 1 ms.
/// - Else the tick by least squares, then once more without the anchors further
///   than max(4 x 1.4826 MAD, 5 ms) from the line; within [`TICK_TOLERANCE`] of
///   1 ms it is 1 ms (a short fit takes the drift of the pairing's latency, below,
///   for a rate: 0.026 % on the demo), else kept (another unit; the caller warns).
/// - The offset: the 10th percentile of t - tag x tick over the anchors kept (the
///   epochs whose message followed a sensor output most closely).
/// - A non-positive tick or offsets scattering more than [`MAX_RESIDUAL_RMS_S`]
///   RMS: Err.
///
/// Accuracy: the anchors pair an epoch with the last sensor tag *output* before the
/// epoch's message, so the mapped times carry the difference between the
/// navigation output latency and the sensor output delay as a constant bias (tens
/// of ms on real receivers; not observable from the log: correct it with
/// `imu.time_offset_s` or estimate it with `[filter] time_offset`). With sensor
/// data output in batches, that latency varies from epoch to epoch by up to a
/// batch period; the low percentile takes its smallest value, which does not
/// depend on the batches' phase.
pub fn fit_time_map(anchors: &[(u64, f64)], kind: EsfKind) -> Result<TimeMap, String> {
    let what = kind.name();
    let Some(&(tag0, _)) = anchors.first() else {
        return Err(format!(
            "{what}: cannot map the sensor time tags to GPS time: no navigation message (NAV-PVT, NAV-RELPOSNED or RXM-RAWX) follows {what} data in the log"
        ));
    };
    let xs: Vec<f64> = anchors.iter().map(|a| a.0 as f64 - tag0 as f64).collect();
    let ys: Vec<f64> = anchors.iter().map(|a| a.1).collect();
    let span = ys.iter().cloned().fold(f64::MIN, f64::max) - ys[0];
    let median = |mut v: Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let residuals = |t0: f64, tick: f64, keep: &[bool]| -> Vec<f64> {
        xs.iter()
            .zip(&ys)
            .zip(keep)
            .filter(|(_, &k)| k)
            .map(|((x, y), _)| y - (t0 + x * tick))
            .collect()
    };
    let all = vec![true; xs.len()];
    let (tick, keep, fitted_tick_s) = if anchors.len() < 3 || span < MIN_FIT_SPAN_S {
        (NOMINAL_TICK_S, all, None)
    } else {
        let lsq = |keep: &[bool]| -> Option<(f64, f64)> {
            let pts: Vec<(f64, f64)> = xs
                .iter()
                .zip(&ys)
                .zip(keep)
                .filter(|(_, &k)| k)
                .map(|((x, y), _)| (*x, *y))
                .collect();
            let n = pts.len() as f64;
            let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
            let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
            let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
            let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
            (pts.len() >= 2 && sxx > 0.0).then(|| {
                let b = sxy / sxx;
                (my - b * mx, b)
            })
        };
        let Some((a, b)) = lsq(&all) else {
            return Err(format!(
                "{what}: cannot map the sensor time tags to GPS time: the sensor time tag does not advance between the navigation epochs"
            ));
        };
        let r = residuals(a, b, &all);
        let mad = median(r.iter().map(|v| v.abs()).collect());
        let lim = (4.0 * 1.4826 * mad).max(0.005);
        let keep: Vec<bool> = r.iter().map(|v| v.abs() <= lim).collect();
        let b = lsq(&keep).map_or(b, |f| f.1);
        // The pairing's bias drifts with the phase of the sensor batches against the
        // epochs, which a short fit takes for a rate: near 1 ms, 1 ms it is.
        let tick = if (b / NOMINAL_TICK_S - 1.0).abs() <= TICK_TOLERANCE {
            NOMINAL_TICK_S
        } else {
            b
        };
        (tick, keep, Some(b))
    };
    if !(tick > 0.0 && tick.is_finite()) {
        return Err(format!(
            "{what}: cannot map the sensor time tags to GPS time: the fitted tick is {tick} s (time tags not increasing with GPS time)"
        ));
    }
    // Offsets y - x tick of the anchors kept: each is the true offset minus the
    // pairing's latency; the 10th percentile is the epochs whose message followed
    // a sensor output most closely (the least latency, robust to a few late ones).
    let mut o: Vec<f64> = xs
        .iter()
        .zip(&ys)
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|((x, y), _)| y - x * tick)
        .collect();
    o.sort_by(f64::total_cmp);
    let used = o.len();
    let t0 = o[(used - 1) / 10];
    let mid = o[used / 2];
    let rms = (o.iter().map(|v| (v - mid).powi(2)).sum::<f64>() / used as f64).sqrt();
    let max = o[used - 1] - o[0];
    if !t0.is_finite() || rms > MAX_RESIDUAL_RMS_S {
        return Err(format!(
            "{what}: cannot map the sensor time tags to GPS time: the {used} anchors scatter {:.3} s RMS about the line (more than {MAX_RESIDUAL_RMS_S} s): the tags are not one steady clock (a receiver reset or a merged log?)",
            rms
        ));
    }
    Ok(TimeMap {
        tag0,
        t0_s: t0,
        tick_s: tick,
        anchors: used,
        rejected: anchors.len() - used,
        rms_s: rms,
        max_s: max,
        fitted_tick_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sign_extension() {
        assert_eq!(signed24(0x7F_FFFF), 8_388_607);
        assert_eq!(signed24(0xFF_FFFF), -1);
        assert_eq!(signed24(0x80_0000), -8_388_608);
    }

    #[test]
    fn fit_recovers_tick_and_offset_and_rejects_outliers() {
        // 1.0001 ms tick, 100 s of 1 Hz anchors, one 0.5 s outlier.
        let mut a: Vec<(u64, f64)> = (0..100)
            .map(|k| {
                (
                    5_000 + (k as f64 * 1000.0 / 1.0001) as u64,
                    1000.0 + k as f64,
                )
            })
            .collect();
        a[40].1 += 0.5;
        let m = fit_time_map(&a, EsfKind::Raw).unwrap();
        assert_eq!(m.rejected, 1);
        // within 0.1 % of 1 ms: 1 ms
        assert!((m.fitted_tick_s.unwrap() - 1.0001e-3).abs() < 1e-8, "{m:?}");
        assert_eq!(m.tick_s, NOMINAL_TICK_S);
        // another unit (0.5 ms): kept
        let h: Vec<(u64, f64)> = a.iter().map(|&(x, y)| (2 * x, y)).collect();
        let m = fit_time_map(&h, EsfKind::Raw).unwrap();
        assert!((m.tick_s - 0.50005e-3).abs() < 1e-8, "{m:?}");
        assert!((m.t(h[10].0) - 1010.0).abs() < 1e-3);
        // too short: the documented 1 ms
        let m = fit_time_map(&a[..3], EsfKind::Raw).unwrap();
        assert!(m.fitted_tick_s.is_none() && m.tick_s == NOMINAL_TICK_S);
        assert!(fit_time_map(&[], EsfKind::Meas).is_err());
        // scattered: refused
        let s: Vec<(u64, f64)> = (0..50)
            .map(|k| (k * 1000, k as f64 + if k % 2 == 0 { 0.0 } else { 0.9 }))
            .collect();
        assert!(fit_time_map(&s, EsfKind::Raw).is_err());
    }
}
