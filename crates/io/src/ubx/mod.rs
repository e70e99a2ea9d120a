//! u-blox UBX binary logs (docs/FORMATS.md "u-blox UBX"): RXM-RAWX raw
//! measurements as [`MultiObsEpoch`]s, RXM-SFRBX navigation pages as ephemerides
//! of GPS, QZSS, Galileo, BeiDou and GLONASS (in a [`RinexNav`], so the GNSS layer
//! takes them as it takes a RINEX navigation file), NAV-PVT as receiver fixes,
//! ESF-RAW / ESF-MEAS sensor data (esf.rs) and NAV-RELPOSNED headings
//! (relposned.rs). Other messages are
//! skipped and counted. Damage (bytes outside frames, checksum errors, malformed
//! messages, a truncated last frame) never stops the read: it is counted and
//! reported as warnings with byte offsets.

pub mod aiding;
pub mod esf;
pub mod frame;
pub mod pvt;
pub mod rawx;
pub mod relposned;
pub mod sfrbx;
pub mod synth;

use crate::error::InputError;
use crate::rinex_nav::RinexNav;
use navfuse_core::GnssFix;
use navfuse_gnss::obs::{MultiObsEpoch, ObsSignalsHeader};
use std::collections::BTreeMap;
use std::path::Path;

/// At most this many individual warnings of one kind; the rest are counted.
const MAX_WARNINGS: usize = 5;

/// What a UBX log gave.
#[derive(Clone, Debug, Default)]
pub struct UbxLog {
    /// One epoch per valid RXM-RAWX, in file order (receiver time, GPST).
    pub epochs: Vec<MultiObsEpoch>,
    /// GLONASS frequency channels seen in RAWX (freqId - 7); no observation types.
    pub header: ObsSignalsHeader,
    /// Ephemerides of every system from RXM-SFRBX, GPS/QZSS/BeiDou Klobuchar and
    /// Galileo NeQuick coefficients, GPS-UTC leap seconds (page 18, else RAWX).
    pub nav: RinexNav,
    /// NAV-PVT fixes (t = GPS seconds of week), valid ones only.
    pub fixes: Vec<GnssFix>,
    /// The GPS week of the fixes (RAWX week, or the NAV-PVT UTC date).
    pub fix_week: Option<i32>,
    /// NAV-PVT messages whose fix the receiver flagged invalid or 2D/3D-less.
    pub pvt_invalid: usize,
    /// Receiver GPS-UTC leap seconds (RAWX leapS, when flagged valid).
    pub leap_seconds: Option<i8>,
    /// ESF-RAW / ESF-MEAS IMU samples, wheel ticks and speeds, with the time maps.
    pub esf: esf::EsfLog,
    /// Every well-formed NAV-RELPOSNED, in file order (`valid` says which are usable).
    pub relpos: Vec<relposned::RelPosHeading>,
    pub rawx: rawx::RawxCounts,
    pub sfrbx: sfrbx::SfrbxCounts,
    /// Verified frames of other messages, by (class, id).
    pub other_messages: BTreeMap<(u8, u8), usize>,
    pub scan: frame::ScanStats,
    /// Findings that did not stop the read, each naming the byte offset.
    pub warnings: Vec<String>,
}

impl UbxLog {
    /// A one-line account of what was read.
    pub fn summary(&self) -> String {
        let other: usize = self.other_messages.values().sum();
        format!(
            "{} RXM-RAWX epochs ({} measurements, {} of unknown signals), {} RXM-SFRBX ({}; taken/rejected: {}; {} not decoded) giving ephemerides G {} J {} E {} C {} R {}, {} NAV-PVT fixes ({} invalid), {} ESF-RAW and {} ESF-MEAS IMU samples, {} ESF-MEAS wheel tick / speed values, {} NAV-RELPOSNED ({} valid), {} other messages, {} bytes outside frames, {} checksum errors",
            self.epochs.len(),
            self.rawx.measurements,
            self.rawx.unknown_signals,
            self.sfrbx.messages,
            if self.nav.iono_alpha.is_some() {
                "GPS ionosphere"
            } else {
                "no GPS ionosphere"
            },
            self.sfrbx.per_system(),
            self.sfrbx.not_decoded,
            self.nav.gps.len(),
            self.nav.qzss.len(),
            self.nav.galileo.len(),
            self.nav.beidou.len(),
            self.nav.glonass.len(),
            self.fixes.len(),
            self.pvt_invalid,
            self.esf.raw_imu.len(),
            self.esf.meas_imu.len(),
            self.esf.odo.len(),
            self.relpos.len(),
            self.relpos.iter().filter(|r| r.valid).count(),
            other,
            self.scan.skipped_bytes,
            self.scan.bad_checksums.len()
        )
    }
}

/// NAV-PVT fixes (iTOW in `t`) on one time scale: seconds of the week of the first
/// fix, counting on past a week rollover. Each fix's week is the one that puts it
/// nearest the time reference it came with (the latest RAWX epoch or fully resolved
/// NAV-PVT date), else the first reference of the log; without any, a fall of more
/// than half a week in iTOW is a rollover. Fixes not after the previous one are
/// dropped (counted in the third value).
fn unwrap_pvt_weeks(pvt: Vec<(GnssFix, Option<(i32, f64)>)>) -> (Vec<GnssFix>, Option<i32>, usize) {
    const WEEK: f64 = 604_800.0;
    let first_ref = pvt.iter().find_map(|(_, r)| *r);
    let mut out: Vec<GnssFix> = Vec::with_capacity(pvt.len());
    let mut week0: Option<i32> = None;
    let mut prev_abs: Option<f64> = None;
    let mut dropped = 0;
    for (fx, r) in pvt {
        let abs = match r.or(first_ref) {
            Some((w, tow)) => {
                let w = w as f64 + ((tow - fx.t) / WEEK).round();
                w * WEEK + fx.t
            }
            // No week anywhere: weeks counted from 0 by rollovers.
            None => match prev_abs {
                Some(p) => {
                    let w = ((p - fx.t) / WEEK).round();
                    w * WEEK + fx.t
                }
                None => fx.t,
            },
        };
        if prev_abs.is_some_and(|p| abs <= p) {
            dropped += 1;
            continue;
        }
        prev_abs = Some(abs);
        let w0 = *week0.get_or_insert_with(|| (abs / WEEK).floor() as i32);
        out.push(GnssFix {
            t: abs - f64::from(w0) * WEEK,
            ..fx
        });
    }
    (out, week0.filter(|_| first_ref.is_some()), dropped)
}

/// Read a UBX file. Only an unreadable file is an error.
pub fn read_ubx(path: &Path) -> Result<UbxLog, InputError> {
    let data = std::fs::read(path).map_err(|e| InputError::read(path, &e))?;
    Ok(decode_ubx(&data, &path.display().to_string()))
}

/// Decode UBX bytes; `name` heads the warnings.
pub fn decode_ubx(data: &[u8], name: &str) -> UbxLog {
    let (frames, scan) = frame::scan(data);
    let mut log = UbxLog::default();
    let mut raw = rawx::RawxDecoder::default();
    let mut sf = sfrbx::SfrbxDecoder::default();
    let mut malformed: Vec<String> = Vec::new();
    // The receiver's week: RAWX, else the first NAV-PVT UTC date.
    let mut week: Option<i32> = None;
    let mut pvt_week: Option<i32> = None;
    // The latest (week, time of week) known, from RAWX or a NAV-PVT UTC date, and
    // each NAV-PVT fix with the reference known when it came.
    let mut time_ref: Option<(i32, f64)> = None;
    let mut pvt_fixes: Vec<(GnssFix, Option<(i32, f64)>)> = Vec::new();
    let mut last_t: Option<navfuse_gnss::GpsTime> = None;
    for f in &frames {
        let res = match (f.class, f.id) {
            (0x02, 0x15) => raw.decode(f.payload).and_then(|e| {
                if last_t.is_some_and(|t| e.t.diff_s(&t) <= 0.0) {
                    return Err(format!(
                        "RXM-RAWX: time {} s of week {} not after the previous epoch",
                        e.t.sow, e.t.week
                    ));
                }
                last_t = Some(e.t);
                week = Some(e.t.week);
                time_ref = Some((e.t.week, e.t.sow));
                log.epochs.push(e);
                Ok(())
            }),
            (0x02, 0x13) => sf.decode(
                f.payload,
                sfrbx::RxContext {
                    week: week.or(pvt_week),
                    time: last_t,
                    leap_seconds: raw.leap_seconds.map(i32::from),
                },
            ),
            (0x01, 0x07) => pvt::decode(f.payload).map(|p| {
                if let Some(w) = p.utc.and_then(|u| pvt::week_from_utc(u, p.itow_s)) {
                    pvt_week = pvt_week.or(Some(w));
                    time_ref = Some((w, p.itow_s));
                }
                match p.fix {
                    Some(fx) => pvt_fixes.push((fx, time_ref)),
                    None => log.pvt_invalid += 1,
                }
            }),
            // ESF-RAW, ESF-MEAS: decoded with their time maps after this loop.
            (0x10, 0x02) | (0x10, 0x03) => Ok(()),
            (0x01, 0x3C) => relposned::decode(f).map(|r| log.relpos.push(r)),
            key => {
                *log.other_messages.entry(key).or_default() += 1;
                Ok(())
            }
        };
        if let Err(why) = res {
            malformed.push(format!("{name}: byte {}: {why}: message skipped", f.offset));
        }
    }
    let (fixes, fix_week, dropped) = unwrap_pvt_weeks(pvt_fixes);
    log.fixes = fixes;
    log.fix_week = fix_week;
    log.pvt_invalid += dropped;
    log.esf = esf::decode(&frames, name);
    log.leap_seconds = raw.leap_seconds;
    log.header.glonass_channels = raw.glonass_channels.clone();
    log.rawx = raw.counts.clone();
    let (gps, qzss, galileo, beidou, glonass) = sf.take();
    log.sfrbx = sf.counts.clone();
    log.nav.gps = gps;
    log.nav.qzss = qzss;
    log.nav.galileo = galileo;
    log.nav.beidou = beidou;
    log.nav.glonass = glonass;
    let io = &sf.iono;
    if let Some((a, b)) = io.gps_klobuchar {
        log.nav.iono_alpha = Some(a);
        log.nav.iono_beta = Some(b);
    }
    log.nav.iono.qzss_klobuchar = io.qzss_klobuchar;
    log.nav.iono.beidou_klobuchar = io.beidou_klobuchar;
    log.nav.iono.galileo_nequick = io.galileo_nequick;
    // GPS-UTC: the broadcast delta t_LS (subframe 4 page 18), else RAWX leapS.
    log.nav.leap_seconds = io.gps_leap_seconds.or(log.leap_seconds.map(i32::from));
    let w = &mut log.warnings;
    let n_bad = scan.bad_checksums.len();
    for off in scan.bad_checksums.iter().take(MAX_WARNINGS) {
        w.push(format!(
            "{name}: byte {off}: UBX checksum error: frame skipped, resynchronised"
        ));
    }
    if n_bad > MAX_WARNINGS {
        w.push(format!(
            "{name}: {} more UBX checksum errors",
            n_bad - MAX_WARNINGS
        ));
    }
    let n_mal = malformed.len();
    w.extend(malformed.into_iter().take(MAX_WARNINGS));
    if n_mal > MAX_WARNINGS {
        w.push(format!(
            "{name}: {} more malformed UBX messages skipped",
            n_mal - MAX_WARNINGS
        ));
    }
    w.append(&mut log.esf.warnings);
    if let Some(off) = scan.truncated_at {
        w.push(format!(
            "{name}: byte {off}: last UBX frame truncated by the end of the file: dropped"
        ));
    }
    log.scan = scan;
    log
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn fix(t: f64) -> GnssFix {
        GnssFix {
            t,
            lla: Vector3::zeros(),
            std_ned: Vector3::repeat(1.0),
            vel_ned: None,
            vel_std_ned: None,
        }
    }

    /// Fixes across a GPS week rollover keep counting; the week is the reference's
    /// even when NAV-PVT starts before RAWX in the previous week.
    #[test]
    fn nav_pvt_fixes_across_a_week_rollover() {
        let ts = [604_798.0, 604_799.0, 0.0, 1.0, 1.0, 2.0];
        // No reference for the first two (RAWX starts in the new week, 2300).
        let refs = [None, None, Some((2300, 0.0)), Some((2300, 1.0)), None, None];
        let pvt = ts.iter().zip(refs).map(|(&t, r)| (fix(t), r)).collect();
        let (f, week, dropped) = unwrap_pvt_weeks(pvt);
        let t: Vec<f64> = f.iter().map(|x| x.t).collect();
        assert_eq!(week, Some(2299));
        assert_eq!(
            t,
            vec![604_798.0, 604_799.0, 604_800.0, 604_801.0, 604_802.0]
        );
        assert_eq!(dropped, 1); // the repeated 1.0
                                // No week anywhere: rollovers still counted.
        let pvt = [604_799.0, 0.5, 200_000.0, 400_000.0, 604_799.5, 3.0, 2.0]
            .iter()
            .map(|&t| (fix(t), None))
            .collect();
        let (f, week, dropped) = unwrap_pvt_weeks(pvt);
        let t: Vec<f64> = f.iter().map(|x| x.t).collect();
        assert_eq!((week, dropped), (None, 1)); // 2.0 after 3.0
        assert_eq!(
            t,
            vec![
                604_799.0,
                604_800.5,
                804_800.0,
                1_004_800.0,
                1_209_599.5,
                1_209_603.0
            ]
        );
    }
}
