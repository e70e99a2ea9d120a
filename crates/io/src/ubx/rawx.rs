//! UBX-RXM-RAWX (class 0x02, id 0x15) -> [`MultiObsEpoch`]: receiver time of week and
//! week as GPST, per measurement the satellite, the RINEX 3 code of its signal
//! ([`signal_code`]), pseudorange, carrier phase, Doppler, C/N0 and loss-of-lock
//! flags, decided as RTKLIB's convbin decides them (docs/FORMATS.md "u-blox UBX").

use super::frame::{f32_at, f64_at, u16_at};
use navfuse_core::sat::{SatId, System};
use navfuse_gnss::obs::{MultiObsEpoch, SatSignals};
use navfuse_gnss::{GpsTime, ObsCode, ObsValue};
use std::collections::HashMap;

/// Header bytes before the first 32-byte measurement block.
pub const HEADER_LEN: usize = 16;
/// Bytes per measurement block.
pub const BLOCK_LEN: usize = 32;

/// The largest cpStdev index (0.004 m units) whose phase is kept (convbin 2.4.3's
/// `CPSTD_VALID`).
const CPSTD_VALID: u8 = 5;

/// System of a UBX gnssId (0 GPS, 1 SBAS, 2 Galileo, 3 BeiDou, 5 QZSS, 6 GLONASS).
pub fn system(gnss_id: u8) -> Option<System> {
    Some(match gnss_id {
        0 => System::Gps,
        1 => System::Sbas,
        2 => System::Galileo,
        3 => System::BeiDou,
        5 => System::Qzss,
        6 => System::Glonass,
        _ => return None,
    })
}

/// The RINEX 3 band and attribute of a UBX (gnssId, sigId) (the interface
/// description's signal table; the codes convbin writes with `-MULTICODE`).
pub fn signal_code(gnss_id: u8, sig_id: u8) -> Option<[u8; 2]> {
    Some(match (gnss_id, sig_id) {
        (0, 0) => *b"1C",          // GPS L1C/A
        (0, 3) => *b"2L",          // L2 CL
        (0, 4) => *b"2S",          // L2 CM
        (0, 6) => *b"5I",          // L5 I
        (0, 7) => *b"5Q",          // L5 Q
        (1, 0) => *b"1C",          // SBAS L1C/A
        (2, 0) => *b"1C",          // Galileo E1 C
        (2, 1) => *b"1B",          // E1 B
        (2, 3) => *b"5I",          // E5a I
        (2, 4) => *b"5Q",          // E5a Q
        (2, 5) => *b"7I",          // E5b I
        (2, 6) => *b"7Q",          // E5b Q
        (3, 0) | (3, 1) => *b"2I", // BeiDou B1I D1 / D2
        (3, 2) | (3, 3) => *b"7I", // B2I D1 / D2
        (3, 7) => *b"5X",          // B2a (convbin's code)
        (5, 0) => *b"1C",          // QZSS L1C/A
        (5, 1) => *b"1Z",          // L1S
        (5, 4) => *b"2S",          // L2 CM
        (5, 5) => *b"2L",          // L2 CL
        (5, 8) => *b"5I",          // L5 I
        (5, 9) => *b"5Q",          // L5 Q
        (6, 0) => *b"1C",          // GLONASS L1 OF
        (6, 2) => *b"2C",          // L2 OF
        _ => return None,
    })
}

/// The RINEX satellite number of a UBX svId: SBAS PRN - 100 (S20-S58), QZSS 1-10,
/// GLONASS slot 1-24 (255 = unknown slot: not used), others as given.
pub fn sat_id(system: System, sv_id: u8) -> Option<SatId> {
    let prn = match system {
        System::Sbas if (120..=158).contains(&sv_id) => sv_id - 100,
        System::Sbas => return None,
        System::Glonass if !(1..=32).contains(&sv_id) => return None,
        System::Qzss if !(1..=10).contains(&sv_id) => return None,
        _ if !(1..=63).contains(&sv_id) => return None,
        _ => sv_id,
    };
    Some(SatId { system, prn })
}

/// Per-signal lock state carried between epochs (convbin's lockt / halfc).
#[derive(Clone, Copy, Default)]
struct Lock {
    locktime_ms: u16,
    half_subtracted: bool,
    /// A loss of lock not yet flagged on a kept phase.
    pending_slip: bool,
}

/// Counts of what the RAWX decoding left out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RawxCounts {
    pub messages: usize,
    pub measurements: usize,
    /// Measurements of a system, satellite or signal without a RINEX code.
    pub unknown_signals: usize,
    /// RAWX messages whose length does not match numMeas, or with week 0.
    pub malformed: usize,
}

/// RAWX decoder with the lock state of every signal.
#[derive(Default)]
pub struct RawxDecoder {
    locks: HashMap<(SatId, ObsCode), Lock>,
    /// Epochs decoded so far.
    epochs: usize,
    pub counts: RawxCounts,
    /// GLONASS slot -> frequency channel (freqId - 7), first seen.
    pub glonass_channels: Vec<(u8, i8)>,
    /// Receiver GPS-UTC leap seconds of the last message, when flagged valid.
    pub leap_seconds: Option<i8>,
}

impl RawxDecoder {
    /// One RAWX payload; Err(reason) if it is malformed (nothing is kept of it).
    pub fn decode(&mut self, p: &[u8]) -> Result<MultiObsEpoch, String> {
        self.counts.messages += 1;
        if p.len() < HEADER_LEN {
            self.counts.malformed += 1;
            return Err(format!(
                "RXM-RAWX: {} bytes, the header alone is {HEADER_LEN}",
                p.len()
            ));
        }
        let n = usize::from(p[11]);
        if p.len() != HEADER_LEN + BLOCK_LEN * n {
            self.counts.malformed += 1;
            return Err(format!(
                "RXM-RAWX: numMeas {n} needs {} bytes, the message has {}",
                HEADER_LEN + BLOCK_LEN * n,
                p.len()
            ));
        }
        let tow = f64_at(p, 0);
        let week = u16_at(p, 8);
        if week == 0 || !(0.0..604_800.0 + 1.0).contains(&tow) {
            self.counts.malformed += 1;
            return Err(format!("RXM-RAWX: week {week}, rcvTow {tow} s: no time"));
        }
        if p[12] & 1 == 1 {
            self.leap_seconds = Some(p[10] as i8);
        }
        let first_epoch = self.epochs == 0;
        self.epochs += 1;
        let mut sats: Vec<SatSignals> = Vec::new();
        for k in 0..n {
            let m = &p[HEADER_LEN + BLOCK_LEN * k..HEADER_LEN + BLOCK_LEN * (k + 1)];
            self.counts.measurements += 1;
            let (gnss_id, sv_id, sig_id) = (m[20], m[21], m[22]);
            let code = signal_code(gnss_id, sig_id);
            let sys = system(gnss_id);
            let (Some(code), Some(sat)) = (code, sys.and_then(|s| sat_id(s, sv_id))) else {
                self.counts.unknown_signals += 1;
                continue;
            };
            self.one(m, sat, code, first_epoch, &mut sats);
        }
        Ok(MultiObsEpoch {
            t: GpsTime::new(i32::from(week), tow),
            flag: 0,
            rx_clock_offset_s: None,
            sats,
        })
    }

    fn one(
        &mut self,
        m: &[u8],
        sat: SatId,
        band_attr: [u8; 2],
        first_epoch: bool,
        sats: &mut Vec<SatSignals>,
    ) {
        let pr = f64_at(m, 0);
        let cp = f64_at(m, 8);
        let dop = f32_at(m, 16);
        let freq_id = m[23];
        let locktime_ms = u16_at(m, 24);
        let cno = m[26];
        let cp_std = m[28] & 0x0F;
        let trk = m[30];
        let pr = (trk & 1 == 1 && pr.is_finite()).then_some(pr);
        let cp =
            (trk & 2 == 2 && cp != -0.5 && cp_std <= CPSTD_VALID && cp.is_finite()).then_some(cp);
        if sat.system == System::Glonass
            && !self.glonass_channels.iter().any(|(s, _)| *s == sat.prn)
            && freq_id <= 13
        {
            self.glonass_channels.push((sat.prn, freq_id as i8 - 7));
        }
        let half_valid = trk & 4 == 4;
        let half_subtracted = trk & 8 == 8;
        let phase_code = ObsCode([b'L', band_attr[0], band_attr[1]]);
        // Loss of lock: lock time zero or shorter than at the previous epoch, or the
        // half-cycle subtraction changed. Flagged whether or not the phase is kept
        // (convbin writes the flags beside a blank phase too), and carried to the
        // next kept phase.
        let lock = self.locks.entry((sat, phase_code)).or_default();
        let slip = locktime_ms == 0
            || locktime_ms < lock.locktime_ms
            || half_subtracted != lock.half_subtracted;
        lock.locktime_ms = locktime_ms;
        lock.half_subtracted = half_subtracted;
        lock.pending_slip |= slip;
        let mut lli = u8::from(slip) | if half_valid { 0 } else { 2 };
        // The first kept phase after a loss of lock carries it; so does every kept
        // phase of the log's first epoch (what convbin writes; a signal whose phase
        // is first kept later starts without the flag).
        if cp.is_some() {
            if lock.pending_slip || first_epoch {
                lli |= 1;
            }
            lock.pending_slip = false;
        }
        let value = |v: Option<f64>| ObsValue {
            value: v,
            lli: None,
            ssi: None,
        };
        let [b, a] = band_attr;
        let signals = [
            (ObsCode([b'C', b, a]), value(pr)),
            (
                phase_code,
                ObsValue {
                    value: cp,
                    lli: (lli != 0).then_some(lli),
                    ssi: None,
                },
            ),
            (ObsCode([b'D', b, a]), value(Some(f64::from(dop)))),
            (ObsCode([b'S', b, a]), value(Some(f64::from(cno)))),
        ];
        match sats.iter_mut().find(|s| s.sat == sat) {
            Some(s) => {
                // A second measurement of the same signal replaces the first.
                s.signals.retain(|(c, _)| c.0[1..] != band_attr);
                s.signals.extend(signals);
            }
            None => sats.push(SatSignals {
                sat,
                signals: signals.to_vec(),
            }),
        }
    }
}
