//! Galileo I/NAV (Galileo OS SIS ICD 2.1: §4.3.2 nominal page, Table 40 word
//! types, §5.1 parameters, §4.3.2.1 CRC-24Q). u-blox gives one page pair in 8
//! words: words 0-3 the even part (120 bits, MSB first, then 8 padding bits),
//! words 4-7 the odd part. The even part is even/odd (0), page type, 112 data
//! bits, tail; the odd part even/odd (1), page type, 16 data bits, OSNMA/reserved
//! 40, SAR 22, spare 2, CRC 24, ... The CRC-24Q covers even bits 0-113 and odd bits
//! 0-81 (196 bits). The 128-bit data word is even bits 2-113 and odd bits 2-17.
//!
//! Word types 1-4 with one IODnav and a word type 5 make an ephemeris (tried at
//! each page of types 1-5); the transmission time is the set's word 5 WN/TOW (GST, the week + 1024 as RINEX counts
//! GAL weeks). Data sources (RINEX 3.05 Table A8): I/NAV E1-B 0x201, E5b-I 0x204.

use super::{near, p2, Bits, SfrbxCounts};
use navfuse_gnss::ephemeris::kepler::KeplerOrbit;
use navfuse_gnss::ephemeris::GPS_PI;
use navfuse_gnss::{GalileoEphemeris, GpsTime};
use std::collections::HashMap;

/// CRC-24Q (generator 0x1864CFB, initial 0) of a bit string.
pub(crate) fn crc24q(bits: &Bits) -> u32 {
    let mut crc: u32 = 0;
    for k in 0..bits.len() {
        let inb = (bits.u(k, 1) as u32) ^ ((crc >> 23) & 1);
        crc = (crc << 1) & 0xFF_FFFF;
        if inb == 1 {
            crc ^= 0x86_4CFB;
        }
    }
    crc
}

/// SISA index -> metres (OS SIS ICD 2.1 Table 89); 255 (NAPA) and spare -> -1.
fn sisa_m(i: u64) -> f64 {
    let i = i as f64;
    match i as u64 {
        0..=49 => i * 0.01,
        50..=74 => 0.5 + (i - 50.0) * 0.02,
        75..=99 => 1.0 + (i - 75.0) * 0.04,
        100..=125 => 2.0 + (i - 100.0) * 0.16,
        _ => -1.0,
    }
}

#[derive(Default)]
pub(super) struct InavDecoder {
    /// Latest data words of types 1-5 per satellite, with the E5b flag of type 1's.
    words: HashMap<u8, ([Option<Bits>; 5], bool)>,
    pub(super) ephemerides: Vec<GalileoEphemeris>,
}

impl InavDecoder {
    /// One page pair of E`prn` (`e5b`: from E5b-I, else E1-B). Ok(Some) with the
    /// NeQuick-G coefficients of a word type 5.
    pub(super) fn decode(
        &mut self,
        prn: u8,
        e5b: bool,
        words: &[u32],
        c: &mut SfrbxCounts,
    ) -> Result<Option<[f64; 3]>, String> {
        let all = Bits::from_words(words, 32);
        let (even, odd) = (all.slice(0, 120), all.slice(128, 120));
        if even.u(0, 1) != 0 || odd.u(0, 1) != 1 {
            c.galileo.rejected += 1;
            return Err(format!(
                "RXM-SFRBX: E{prn:02}: I/NAV even/odd parts out of order"
            ));
        }
        let mut crc_in = Bits::default();
        crc_in.push(0, 4);
        crc_in.extend(&even.slice(0, 114));
        crc_in.extend(&odd.slice(0, 82));
        if crc24q(&crc_in) != odd.u(82, 24) as u32 {
            c.galileo.rejected += 1;
            c.galileo_crc_failures += 1;
            return Err(format!("RXM-SFRBX: E{prn:02}: I/NAV CRC-24Q error"));
        }
        if even.u(1, 1) == 1 || odd.u(1, 1) == 1 {
            // Alert page.
            c.galileo.other += 1;
            return Ok(None);
        }
        let mut data = even.slice(2, 112);
        data.extend(&odd.slice(2, 16));
        let wt = data.u(0, 6) as usize;
        if !(1..=5).contains(&wt) {
            c.galileo.other += 1;
            return Ok(None);
        }
        c.galileo.pages += 1;
        let nequick = (wt == 5).then(|| {
            [
                data.u(6, 11) as f64 * p2(-2),
                data.s(17, 11) as f64 * p2(-8),
                data.s(28, 14) as f64 * p2(-15),
            ]
        });
        let entry = self.words.entry(prn).or_default();
        entry.0[wt - 1] = Some(data);
        if wt == 1 {
            entry.1 = e5b;
        }
        if let [Some(w1), Some(w2), Some(w3), Some(w4), Some(w5)] = &entry.0 {
            let iod = w1.u(6, 10);
            if [w2, w3, w4].iter().all(|w| w.u(6, 10) == iod) {
                match ephemeris(prn, [w1, w2, w3, w4, w5], entry.1) {
                    Some(e) => {
                        if !self.ephemerides.iter().any(|x| {
                            x.prn == e.prn
                                && x.iodnav == e.iodnav
                                && x.toe == e.toe
                                && x.toc == e.toc
                        }) {
                            self.ephemerides.push(e);
                        }
                    }
                    None => {
                        c.galileo.rejected += 1;
                        return Err(format!("RXM-SFRBX: E{prn:02}: implausible I/NAV ephemeris"));
                    }
                }
            }
        }
        Ok(nequick)
    }
}

/// Word types 1-5 of one IODnav (OS SIS ICD 2.1 Tables 40, 60, 61, 63, 68;
/// pi = 3.1415926535898).
fn ephemeris(prn: u8, w: [&Bits; 5], e5b: bool) -> Option<GalileoEphemeris> {
    let sc = GPS_PI;
    let [w1, w2, w3, w4, w5] = w;
    let svid = w4.u(16, 6) as u8;
    if svid != prn {
        return None;
    }
    let week = w5.u(73, 12) as i32 + 1024;
    let ttr = GpsTime::new(week, w5.u(85, 20) as f64);
    let orbit = KeplerOrbit {
        toe_sow_s: w1.u(16, 14) as f64 * 60.0,
        m0_rad: w1.s(30, 32) as f64 * p2(-31) * sc,
        e: w1.u(62, 32) as f64 * p2(-33),
        sqrt_a_sqrt_m: w1.u(94, 32) as f64 * p2(-19),
        omega0_rad: w2.s(16, 32) as f64 * p2(-31) * sc,
        i0_rad: w2.s(48, 32) as f64 * p2(-31) * sc,
        omega_rad: w2.s(80, 32) as f64 * p2(-31) * sc,
        idot_rad_per_s: w2.s(112, 14) as f64 * p2(-43) * sc,
        omega_dot_rad_per_s: w3.s(16, 24) as f64 * p2(-43) * sc,
        delta_n_rad_per_s: w3.s(40, 16) as f64 * p2(-43) * sc,
        cuc_rad: w3.s(56, 16) as f64 * p2(-29),
        cus_rad: w3.s(72, 16) as f64 * p2(-29),
        crc_m: w3.s(88, 16) as f64 * p2(-5),
        crs_m: w3.s(104, 16) as f64 * p2(-5),
        cic_rad: w4.s(22, 16) as f64 * p2(-29),
        cis_rad: w4.s(38, 16) as f64 * p2(-29),
    };
    if !(1000.0..10000.0).contains(&orbit.sqrt_a_sqrt_m) || orbit.e >= 0.5 {
        return None;
    }
    let toe = near(GpsTime::new(week, orbit.toe_sow_s), ttr);
    let toc = near(GpsTime::new(week, w4.u(54, 14) as f64 * 60.0), ttr);
    // RINEX "SV health": E1-B DVS bit 0, HS bits 1-2; E5b DVS bit 6, HS bits 7-8.
    let (e5b_hs, e1b_hs) = (w5.u(67, 2) as u32, w5.u(69, 2) as u32);
    let (e5b_dvs, e1b_dvs) = (w5.u(71, 1) as u32, w5.u(72, 1) as u32);
    Some(GalileoEphemeris {
        prn,
        toc,
        af0_s: w4.s(68, 31) as f64 * p2(-34),
        af1_s_per_s: w4.s(99, 21) as f64 * p2(-46),
        af2_s_per_s2: w4.s(120, 6) as f64 * p2(-59),
        iodnav: w1.u(6, 10) as u16,
        orbit,
        toe,
        data_sources: if e5b { 0x204 } else { 0x201 },
        sisa_m: sisa_m(w3.u(120, 8)),
        health: (e5b_hs << 7) | (e5b_dvs << 6) | (e1b_hs << 1) | e1b_dvs,
        bgd_e1_e5a_s: w5.s(47, 10) as f64 * p2(-32),
        bgd_e1_e5b_s: w5.s(57, 10) as f64 * p2(-32),
        transmission_time: Some(ttr),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CRC-24Q check value of "123456789" is 0xCDE703 (the catalogue value of
    /// CRC-24/LTE-A, the same polynomial with init 0 and no reflection).
    #[test]
    fn crc24q_check_value() {
        let mut b = Bits::default();
        for c in b"123456789" {
            b.push(u64::from(*c), 8);
        }
        assert_eq!(crc24q(&b), 0xCDE703);
    }
}
