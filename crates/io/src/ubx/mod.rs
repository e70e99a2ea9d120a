//! u-blox UBX binary logs (docs/FORMATS.md "u-blox UBX"): RXM-RAWX raw
//! measurements as [`MultiObsEpoch`]s, RXM-SFRBX GPS LNAV subframes as
//! [`GpsEphemeris`] records (in a [`RinexNav`], so the GNSS layer takes them as it
//! takes a RINEX navigation file), NAV-PVT as receiver fixes, ESF-RAW / ESF-MEAS
//! sensor data (esf.rs) and NAV-RELPOSNED headings (relposned.rs). Other messages are
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
    /// GPS ephemerides from RXM-SFRBX (no ionosphere: subframe 4 is not read).
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
            "{} RXM-RAWX epochs ({} measurements, {} of unknown signals), {} GPS ephemerides from {} RXM-SFRBX, {} NAV-PVT fixes ({} invalid), {} ESF-RAW and {} ESF-MEAS IMU samples, {} ESF-MEAS wheel tick / speed values, {} NAV-RELPOSNED ({} valid), {} other messages, {} bytes outside frames, {} checksum errors",
            self.epochs.len(),
            self.rawx.measurements,
            self.rawx.unknown_signals,
            self.nav.gps.len(),
            self.sfrbx.messages,
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
    let mut pvt_fixes: Vec<GnssFix> = Vec::new();
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
                log.epochs.push(e);
                Ok(())
            }),
            (0x02, 0x13) => sf.decode(f.payload, week.or(pvt_week)),
            (0x01, 0x07) => pvt::decode(f.payload).map(|p| {
                if pvt_week.is_none() {
                    pvt_week = p.utc.and_then(|u| pvt::week_from_utc(u, p.itow_s));
                }
                match p.fix {
                    Some(fx) => pvt_fixes.push(fx),
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
    // Fixes in time order only (a repeated or backwards iTOW is dropped).
    let mut prev: Option<f64> = None;
    for fx in pvt_fixes {
        if prev.is_some_and(|p| fx.t <= p) {
            log.pvt_invalid += 1;
            continue;
        }
        prev = Some(fx.t);
        log.fixes.push(fx);
    }
    log.esf = esf::decode(&frames, name);
    log.fix_week = log.epochs.first().map(|e| e.t.week).or(pvt_week);
    log.leap_seconds = raw.leap_seconds;
    log.header.glonass_channels = raw.glonass_channels.clone();
    log.rawx = raw.counts.clone();
    log.sfrbx = sf.counts.clone();
    log.nav.gps = std::mem::take(&mut sf.ephemerides);
    log.nav.leap_seconds = log.leap_seconds.map(i32::from);
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
