//! GPS and QZSS L1 C/A LNAV (IS-GPS-200 20.3.3.3-20.3.3.5, Tables 20-I, 20-III,
//! 20-VI; IS-QZSS-PNT §5.2 uses the same layout). u-blox gives each of the ten
//! 30-bit words in bits 29..0 of a 32-bit number: data bits 29..6 (24 bits, not
//! inverted), parity bits 5..0. Parity is not recomputed; the TLM preamble (0x8B),
//! the subframe ID and the issue-of-data match across subframes 1-3 are checked.
//! Subframe 4 page 18 (SV ID 56) gives the Klobuchar coefficients and delta t_LS.

use super::{near, p2, Bits, PageCounts, URA_M};
use navfuse_gnss::ephemeris::{GpsEphemeris, GPS_PI};
use navfuse_gnss::GpsTime;
use std::collections::HashMap;

/// The 240 data bits of one subframe (10 words x 24 bits), MSB first.
#[derive(Clone)]
pub(super) struct Subframe(Bits);

impl Subframe {
    fn from_words(words: &[u32]) -> Subframe {
        let data: Vec<u32> = words
            .iter()
            .take(10)
            .map(|w| (w >> 6) & 0x00FF_FFFF)
            .collect();
        Subframe(Bits::from_words(&data, 24))
    }
    fn u(&self, pos: usize, len: usize) -> u32 {
        self.0.u(pos, len) as u32
    }
    fn s(&self, pos: usize, len: usize) -> i32 {
        self.0.s(pos, len) as i32
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

/// Klobuchar alpha, beta and delta t_LS of a page 18.
pub(super) type Page18 = (([f64; 4], [f64; 4]), i32);

/// Collects subframes 1-3 per satellite; an ephemeris is complete when the three
/// carry the same issue of data.
#[derive(Default)]
pub(super) struct LnavDecoder {
    /// QZSS: the fit interval flag is given as RINEX's reader reads a QZSS record
    /// holding the flag (4 h for 0 and 1).
    pub(super) qzss: bool,
    pub(super) pending: HashMap<u8, [Option<Subframe>; 3]>,
    /// Complete ephemerides, each (prn, IODE, toe) once, in decoding order, with the
    /// transmission time of the last complete set.
    pub(super) ephemerides: Vec<GpsEphemeris>,
}

impl LnavDecoder {
    /// One subframe of satellite `prn`; `week` is the receiver's GPS week to
    /// resolve the 10-bit broadcast week. Ok(Some) for a page 18.
    pub(super) fn decode(
        &mut self,
        prn: u8,
        words: &[u32],
        week: Option<i32>,
        c: &mut PageCounts,
        iode_mismatch: &mut usize,
    ) -> Result<Option<Page18>, String> {
        let sf = Subframe::from_words(words);
        if sf.u(0, 8) != 0x8B {
            c.rejected += 1;
            return Err(format!("RXM-SFRBX: LNAV {prn:02}: no 0x8B preamble"));
        }
        let id = sf.id();
        match id {
            1..=3 => {}
            4 | 5 => {
                // Page 18 (SV ID 56) in subframe 4 (GPS; QZSS sends it there too).
                let at = Subframe::at;
                if id == 4 && sf.u(at(3, 3), 6) == 56 {
                    c.pages += 1;
                    return Ok(Some(page18(&sf)));
                }
                // Almanac and other pages: not decoded.
                c.other += 1;
                return Ok(None);
            }
            _ => {
                c.rejected += 1;
                return Err(format!("RXM-SFRBX: LNAV {prn:02}: subframe ID {id}"));
            }
        }
        c.pages += 1;
        let set = self.pending.entry(prn).or_default();
        set[id as usize - 1] = Some(sf);
        if let [Some(s1), Some(s2), Some(s3)] = set {
            let at = Subframe::at;
            let iodc = (s1.u(at(3, 23), 2) << 8) | s1.u(at(8, 1), 8);
            let iode2 = s2.u(at(3, 1), 8);
            let iode3 = s3.u(at(10, 1), 8);
            if iode2 != iode3 || iodc & 0xFF != iode2 {
                // Wait for the subframes of one issue; a new subframe 1 or 2
                // replaces the older one.
                *iode_mismatch += 1;
                return Ok(None);
            }
            let Some(mut eph) = ephemeris(prn, s1, s2, s3, week) else {
                c.rejected += 1;
                return Err(format!("RXM-SFRBX: LNAV {prn:02}: implausible ephemeris"));
            };
            if self.qzss {
                eph.fit_interval_h = 4.0;
            }
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
        Ok(None)
    }
}

/// Subframe 4 page 18 (IS-GPS-200 20.3.3.5.1.6-7, Table 20-X): alpha0-3 (2^-30,
/// 2^-27, 2^-24, 2^-24 s/sc^n), beta0-3 (2^11, 2^14, 2^16, 2^16 s/sc^n), delta t_LS.
fn page18(sf: &Subframe) -> Page18 {
    let at = Subframe::at;
    let b = |w, bit| f64::from(sf.s(at(w, bit), 8));
    let alpha = [
        b(3, 9) * p2(-30),
        b(3, 17) * p2(-27),
        b(4, 1) * p2(-24),
        b(4, 9) * p2(-24),
    ];
    let beta = [
        b(4, 17) * p2(11),
        b(5, 1) * p2(14),
        b(5, 9) * p2(16),
        b(5, 17) * p2(16),
    ];
    ((alpha, beta), sf.s(at(9, 1), 8))
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
    // Subframe 1's transmission time: RTKLIB writes its HOW count itself.
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
        transmission_time: Some(ttr),
        // Fit interval flag 0: 4 hours; 1: more than 4 h (IS-GPS-200 20.3.4.4, by
        // IODC; RTKLIB writes 8 h for the common case).
        fit_interval_h: if fit_flag == 0 { 4.0 } else { 8.0 },
    };
    (e.sqrt_a_sqrt_m > 1000.0 && e.e < 0.1).then_some(e)
}
