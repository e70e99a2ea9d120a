//! UBX-RXM-SFRBX (class 0x02, id 0x13), GPS L1 C/A LNAV: subframes 1-3 of each
//! satellite collected into a [`GpsEphemeris`] (IS-GPS-200 20.3.3.3-20.3.3.4, Tables
//! 20-I, 20-III). u-blox gives each of the ten 30-bit words in bits 29..0 of a
//! 32-bit little-endian number: data bits 29..6 (24 bits, not inverted), parity
//! bits 5..0. Parity is not recomputed; the TLM preamble (0x8B), the subframe ID
//! and the issue-of-data match across the three subframes are checked.

use super::frame::u32_at;
use navfuse_gnss::ephemeris::{GpsEphemeris, GPS_PI};
use navfuse_gnss::GpsTime;
use std::collections::HashMap;

/// The nominal URA \[m\] of URA index N (IS-GPS-200 20.3.3.3.1.3; RINEX and RTKLIB
/// write these values). Index 15: no accuracy prediction.
const URA_M: [f64; 16] = [
    2.0, 2.8, 4.0, 5.7, 8.0, 11.3, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0, 2048.0, 4096.0,
    8192.0,
];

/// The 240 data bits of one subframe (10 words x 24 bits), MSB first.
#[derive(Clone, Copy)]
struct Subframe([u8; 30]);

impl Subframe {
    fn from_words(words: &[u32]) -> Subframe {
        let mut b = [0u8; 30];
        for (i, w) in words.iter().take(10).enumerate() {
            let d = (w >> 6) & 0x00FF_FFFF;
            b[3 * i] = (d >> 16) as u8;
            b[3 * i + 1] = (d >> 8) as u8;
            b[3 * i + 2] = d as u8;
        }
        Subframe(b)
    }

    /// `len` bits from bit `pos` (0 = first data bit of word 1).
    fn u(&self, pos: usize, len: usize) -> u32 {
        (pos..pos + len).fold(0u32, |acc, k| {
            (acc << 1) | u32::from((self.0[k / 8] >> (7 - k % 8)) & 1)
        })
    }

    /// Two's complement of `len` bits.
    fn s(&self, pos: usize, len: usize) -> i32 {
        let v = self.u(pos, len);
        if len < 32 && v >> (len - 1) == 1 {
            (v as i64 - (1i64 << len)) as i32
        } else {
            v as i32
        }
    }

    /// ICD "word W bit B" (1-based, data bits 1-24) as a stream position.
    fn at(word: usize, bit: usize) -> usize {
        24 * (word - 1) + (bit - 1)
    }

    fn id(&self) -> u32 {
        self.u(Self::at(2, 20), 3)
    }

    /// HOW time-of-week count x 6 s: the GPST of the start of the next subframe.
    fn how_tow_s(&self) -> f64 {
        f64::from(self.u(Self::at(2, 1), 17)) * 6.0
    }
}

fn p2(n: i32) -> f64 {
    2f64.powi(n)
}

/// Counts of the SFRBX decoding.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SfrbxCounts {
    pub messages: usize,
    /// GPS L1 C/A subframes 1-3 taken.
    pub gps_subframes: usize,
    /// Subframes 4-5 and the other systems' pages (not decoded).
    pub not_decoded: usize,
    /// Messages of the wrong size or without the 0x8B preamble.
    pub malformed: usize,
    /// Subframe sets whose IODC / IODE did not agree (waited for a consistent set).
    pub iode_mismatch: usize,
}

/// Collects subframes 1-3 per satellite; an ephemeris is complete when the three
/// carry the same issue of data.
#[derive(Default)]
pub struct SfrbxDecoder {
    pending: HashMap<u8, [Option<Subframe>; 3]>,
    pub counts: SfrbxCounts,
    /// Complete ephemerides, each (prn, IODE, toe) once, in decoding order, with the
    /// transmission time of the last complete set.
    pub ephemerides: Vec<GpsEphemeris>,
}

impl SfrbxDecoder {
    /// One SFRBX payload; `week` is the receiver's GPS week (RAWX) to resolve the
    /// 10-bit broadcast week, if known. Err(reason) for a malformed message.
    pub fn decode(&mut self, p: &[u8], week: Option<i32>) -> Result<(), String> {
        self.counts.messages += 1;
        if p.len() < 8 {
            self.counts.malformed += 1;
            return Err(format!("RXM-SFRBX: {} bytes, the header is 8", p.len()));
        }
        let (gnss_id, sv_id, n) = (p[0], p[1], usize::from(p[4]));
        if p.len() != 8 + 4 * n {
            self.counts.malformed += 1;
            return Err(format!(
                "RXM-SFRBX: numWords {n} needs {} bytes, the message has {}",
                8 + 4 * n,
                p.len()
            ));
        }
        // GPS L1 C/A (sigId 0) LNAV only: ten words.
        if gnss_id != 0 || p[2] != 0 || n != 10 || !(1..=32).contains(&sv_id) {
            self.counts.not_decoded += 1;
            return Ok(());
        }
        let words: Vec<u32> = (0..n).map(|k| u32_at(p, 8 + 4 * k)).collect();
        let sf = Subframe::from_words(&words);
        if sf.u(0, 8) != 0x8B {
            self.counts.malformed += 1;
            return Err(format!("RXM-SFRBX: G{sv_id:02}: no 0x8B preamble"));
        }
        let id = sf.id();
        if !(1..=3).contains(&id) {
            self.counts.not_decoded += 1;
            return Ok(());
        }
        self.counts.gps_subframes += 1;
        let set = self.pending.entry(sv_id).or_default();
        set[id as usize - 1] = Some(sf);
        if let [Some(s1), Some(s2), Some(s3)] = *set {
            let iodc = (s1.u(Subframe::at(3, 23), 2) << 8) | s1.u(Subframe::at(8, 1), 8);
            let iode2 = s2.u(Subframe::at(3, 1), 8);
            let iode3 = s3.u(Subframe::at(10, 1), 8);
            if iode2 != iode3 || iodc & 0xFF != iode2 {
                // Wait for the subframes of one issue; a new subframe 1 or 2
                // replaces the older one.
                self.counts.iode_mismatch += 1;
                return Ok(());
            }
            let Some(eph) = ephemeris(sv_id, &s1, &s2, &s3, week) else {
                self.counts.malformed += 1;
                return Err(format!("RXM-SFRBX: G{sv_id:02}: implausible ephemeris"));
            };
            // The same issue again: keep the latest transmission time (as convbin).
            match self
                .ephemerides
                .iter_mut()
                .find(|e| e.prn == eph.prn && e.iode == eph.iode && e.toe == eph.toe)
            {
                Some(e) => e.transmission_time = eph.transmission_time,
                None => self.ephemerides.push(eph),
            }
        }
        Ok(())
    }
}

/// The ephemeris of three consistent subframes.
fn ephemeris(
    prn: u8,
    s1: &Subframe,
    s2: &Subframe,
    s3: &Subframe,
    week: Option<i32>,
) -> Option<GpsEphemeris> {
    let at = Subframe::at;
    let sc = GPS_PI;
    // Subframe 1's transmission time: its HOW count is the start of subframe 2,
    // so subframe 1 began 6 s earlier (RTKLIB writes the count itself; see below).
    let tow1 = s1.how_tow_s();
    let week10 = s1.u(at(3, 1), 10) as i32;
    // Resolve the 10-bit week next to the receiver's week (or the 2019 rollover era).
    let week = match week {
        Some(w) => week10 + 1024 * ((w - week10) as f64 / 1024.0).round() as i32,
        None => week10 + 2048,
    };
    let ttr = GpsTime::new(week, tow1);
    let toe_s = f64::from(s2.u(at(10, 1), 16)) * 16.0;
    let toc_s = f64::from(s1.u(at(8, 9), 16)) * 16.0;
    let toe = near(GpsTime::new(week, toe_s), ttr);
    let toc = near(GpsTime::new(week, toc_s), ttr);
    let fit_flag = s2.u(at(10, 17), 1);
    let iodc = (s1.u(at(3, 23), 2) << 8) | s1.u(at(8, 1), 8);
    let e = GpsEphemeris {
        prn,
        toc,
        af0_s: f64::from(s1.s(at(10, 1), 22)) * p2(-31),
        af1_s_per_s: f64::from(s1.s(at(9, 9), 16)) * p2(-43),
        af2_s_per_s2: f64::from(s1.s(at(9, 1), 8)) * p2(-55),
        iode: s2.u(at(3, 1), 8) as u16,
        crs_m: f64::from(s2.s(at(3, 9), 16)) * p2(-5),
        delta_n_rad_per_s: f64::from(s2.s(at(4, 1), 16)) * p2(-43) * sc,
        m0_rad: f64::from(s2.s(at(4, 17), 32)) * p2(-31) * sc,
        cuc_rad: f64::from(s2.s(at(6, 1), 16)) * p2(-29),
        e: f64::from(s2.u(at(6, 17), 32)) * p2(-33),
        cus_rad: f64::from(s2.s(at(8, 1), 16)) * p2(-29),
        sqrt_a_sqrt_m: f64::from(s2.u(at(8, 17), 32)) * p2(-19),
        toe,
        cic_rad: f64::from(s3.s(at(3, 1), 16)) * p2(-29),
        omega0_rad: f64::from(s3.s(at(3, 17), 32)) * p2(-31) * sc,
        cis_rad: f64::from(s3.s(at(5, 1), 16)) * p2(-29),
        i0_rad: f64::from(s3.s(at(5, 17), 32)) * p2(-31) * sc,
        crc_m: f64::from(s3.s(at(7, 1), 16)) * p2(-5),
        omega_rad: f64::from(s3.s(at(7, 17), 32)) * p2(-31) * sc,
        omega_dot_rad_per_s: f64::from(s3.s(at(9, 1), 24)) * p2(-43) * sc,
        idot_rad_per_s: f64::from(s3.s(at(10, 9), 14)) * p2(-43) * sc,
        codes_l2: f64::from(s1.u(at(3, 11), 2)),
        l2p_flag: f64::from(s1.u(at(4, 1), 1)),
        sv_accuracy_m: URA_M[s1.u(at(3, 13), 4) as usize],
        health: s1.u(at(3, 17), 6),
        tgd_s: f64::from(s1.s(at(7, 17), 8)) * p2(-31),
        iodc: iodc as u16,
        // As RTKLIB: the HOW count of subframe 1.
        transmission_time: Some(ttr),
        // Fit interval flag 0: 4 hours; 1: more than 4 h (IS-GPS-200 20.3.4.4, by
        // IODC; RTKLIB writes 8 h for the common case).
        fit_interval_h: if fit_flag == 0 { 4.0 } else { 8.0 },
    };
    (e.sqrt_a_sqrt_m > 1000.0 && e.e < 0.1).then_some(e)
}

/// `t` moved by whole weeks to within half a week of `reference`.
fn near(t: GpsTime, reference: GpsTime) -> GpsTime {
    let dt = f64::from(t.week - reference.week) * 604_800.0 + t.sow - reference.sow;
    let week = if dt > 302_400.0 {
        t.week - 1
    } else if dt < -302_400.0 {
        t.week + 1
    } else {
        t.week
    };
    GpsTime::new(week, t.sow)
}
