//! BeiDou D1 and D2 navigation messages (BeiDou SIS ICD B1I 3.0: §5.2 D1,
//! Figures 5-4 to 5-6 for subframes 1-3; §5.3 D2, Figure 5-10 and Table 5-13 for
//! subframe 1 pages 1-10). u-blox gives each of a subframe's ten 30-bit words in
//! bits 29..0, de-interleaved: word 1 is 26 data bits + 4 parity, words 2-10 are
//! 22 data bits + 8 parity (two BCH(15,11) codes). The ICD numbers the 300 bits of
//! a subframe 1-300 with the parity in place, so an ICD bit N is position N - 1.
//!
//! D1 (MEO/IGSO): subframes 1-3 of one frame (SOWs 6 s apart, toc = toe) make an
//! ephemeris. D2 (GEO C01-C05, C59-C63): subframe 1 pages 1 and 3-10 of one
//! cycle (SOWs 3 s apart from page 3 on, page 3 six seconds after page 1).
//! Times are BDT (week = the broadcast 13-bit BDT week), as the RINEX reader keeps
//! them; the transmission time is subframe 1's (page 1's) SOW. The preamble
//! (0x712) and the BCH(15,11) parity of every word are checked.

use super::{near, p2, Bits, PageCounts, URA_M};
use navfuse_gnss::ephemeris::beidou::is_geo;
use navfuse_gnss::ephemeris::kepler::KeplerOrbit;
use navfuse_gnss::ephemeris::GPS_PI;
use navfuse_gnss::{BeiDouEphemeris, GpsTime};
use std::collections::HashMap;

const PREAMBLE: u64 = 0b111_0001_0010;

/// Klobuchar alpha, beta of a D1 subframe 1.
pub(super) type Klobuchar = ([f64; 4], [f64; 4]);

#[derive(Default)]
pub(super) struct BdsDecoder {
    d1: HashMap<u8, [Option<Bits>; 3]>,
    d2: HashMap<u8, [Option<Bits>; 10]>,
    pub(super) ephemerides: Vec<BeiDouEphemeris>,
}

/// ICD bit N (1-based) as a position.
fn b(n: usize) -> usize {
    n - 1
}

/// Remainder of the 11 information bits (MSB first) times x^4 modulo
/// g(x) = x^4 + x + 1 (ICD §5.1.3: BCH(15,11,1)).
fn bch_parity(info: u64) -> u64 {
    let mut r = info << 4;
    for k in (4..15).rev() {
        if (r >> k) & 1 == 1 {
            r ^= 0b10011 << (k - 4);
        }
    }
    r & 0xF
}

/// Every word's BCH(15,11) parity: word 1 bits 16-26 / 27-30; words 2-10 the two
/// 11-bit halves of the 22 data bits with their 4-bit parities after them.
fn parity_ok(sf: &Bits) -> bool {
    if bch_parity(sf.u(15, 11)) != sf.u(26, 4) {
        return false;
    }
    (1..10).all(|w| {
        let o = 30 * w;
        bch_parity(sf.u(o, 11)) == sf.u(o + 22, 4)
            && bch_parity(sf.u(o + 11, 11)) == sf.u(o + 26, 4)
    })
}

fn sow(sf: &Bits) -> u64 {
    sf.u2(b(19), 8, b(31), 12)
}

impl BdsDecoder {
    /// One subframe of satellite `prn`. Ok(Some) with the Klobuchar coefficients of
    /// a D1 subframe 1.
    pub(super) fn decode(
        &mut self,
        prn: u8,
        words: &[u32],
        c: &mut PageCounts,
        _not_decoded: &mut usize,
    ) -> Result<Option<Klobuchar>, String> {
        let sf = Bits::from_words(words, 30);
        if sf.u(0, 11) != PREAMBLE {
            c.rejected += 1;
            return Err(format!("RXM-SFRBX: C{prn:02}: no D1/D2 preamble"));
        }
        if !parity_ok(&sf) {
            c.rejected += 1;
            return Err(format!("RXM-SFRBX: C{prn:02}: BCH parity error"));
        }
        let fra = sf.u(b(16), 3) as usize;
        if is_geo(prn) {
            // D2: subframe 1 pages carry the ephemeris.
            let page = sf.u(b(43), 4) as usize;
            if fra != 1 || page == 0 || page > 10 || page == 2 {
                c.other += 1;
                return Ok(None);
            }
            c.pages += 1;
            let set = self.d2.entry(prn).or_default();
            set[page - 1] = Some(sf);
            if page == 10 {
                if let Some(e) = d2_ephemeris(prn, set) {
                    self.push(e);
                }
            }
            return Ok(None);
        }
        if !(1..=3).contains(&fra) {
            c.other += 1;
            return Ok(None);
        }
        c.pages += 1;
        let kl = (fra == 1).then(|| klobuchar(&sf));
        let set = self.d1.entry(prn).or_default();
        set[fra - 1] = Some(sf);
        if let [Some(s1), Some(s2), Some(s3)] = set {
            // One frame: consecutive subframes (the D1 message has no issue of data
            // in subframes 2-3), toc = toe.
            if sow(s2) == sow(s1) + 6 && sow(s3) == sow(s2) + 6 {
                if let Some(e) = d1_ephemeris(prn, s1, s2, s3) {
                    self.push(e);
                }
            }
        }
        Ok(kl)
    }

    /// Each (prn, toe, AODE, AODC) once, with the transmission time of its first
    /// complete set (as convbin).
    fn push(&mut self, e: BeiDouEphemeris) {
        if !self
            .ephemerides
            .iter()
            .any(|x| x.prn == e.prn && x.toe == e.toe && x.aode == e.aode && x.aodc == e.aodc)
        {
            self.ephemerides.push(e);
        }
    }
}

/// D1 subframe 1 alpha0-3 (2^-30, 2^-27, 2^-24, 2^-24 s/pi^n), beta0-3 (2^11, 2^14,
/// 2^16, 2^16 s/pi^n) (ICD §5.2.4.7).
fn klobuchar(s: &Bits) -> Klobuchar {
    let a = |n| s.s(b(n), 8) as f64;
    let alpha = [
        a(127) * p2(-30),
        a(135) * p2(-27),
        a(151) * p2(-24),
        a(159) * p2(-24),
    ];
    let beta = [
        s.s2(b(167), 6, b(181), 2) as f64 * p2(11),
        a(183) * p2(14),
        a(191) * p2(16),
        s.s2(b(199), 4, b(211), 4) as f64 * p2(16),
    ];
    (alpha, beta)
}

/// The common fields of D1 subframe 1 and D2 page 1, and the orbit: one record.
struct Clock {
    week: i32,
    sow1: f64,
    toc_s: f64,
    sat_h1: u32,
    aodc: u16,
    urai: usize,
    tgd1: i64,
    tgd2: i64,
    af: [f64; 3],
    aode: u16,
}

fn record(prn: u8, c: Clock, orbit: KeplerOrbit) -> Option<BeiDouEphemeris> {
    if c.toc_s != orbit.toe_sow_s
        || !(1000.0..10000.0).contains(&orbit.sqrt_a_sqrt_m)
        || orbit.e >= 0.5
    {
        return None;
    }
    let ttr = GpsTime::new(c.week, c.sow1);
    let toe = near(GpsTime::new(c.week, orbit.toe_sow_s), ttr);
    let toc = near(GpsTime::new(c.week, c.toc_s), ttr);
    Some(BeiDouEphemeris {
        prn,
        toc,
        af0_s: c.af[0],
        af1_s_per_s: c.af[1],
        af2_s_per_s2: c.af[2],
        aode: c.aode,
        aodc: c.aodc,
        orbit,
        toe,
        sv_accuracy_m: URA_M[c.urai],
        sat_h1: c.sat_h1,
        tgd1_s: c.tgd1 as f64 * 0.1e-9,
        tgd2_s: c.tgd2 as f64 * 0.1e-9,
        transmission_time: Some(ttr),
    })
}

/// D1 subframes 1-3 (ICD §5.2.4, Figures 5-4 to 5-6; pi = 3.1415926535898).
fn d1_ephemeris(prn: u8, s1: &Bits, s2: &Bits, s3: &Bits) -> Option<BeiDouEphemeris> {
    let sc = GPS_PI;
    let clock = Clock {
        week: s1.u(b(61), 13) as i32,
        sow1: sow(s1) as f64,
        toc_s: s1.u2(b(74), 9, b(91), 8) as f64 * 8.0,
        sat_h1: s1.u(b(43), 1) as u32,
        aodc: s1.u(b(44), 5) as u16,
        urai: s1.u(b(49), 4) as usize,
        tgd1: s1.s(b(99), 10),
        tgd2: s1.s2(b(109), 4, b(121), 6),
        af: [
            s1.s2(b(226), 7, b(241), 17) as f64 * p2(-33),
            s1.s2(b(258), 5, b(271), 17) as f64 * p2(-50),
            s1.s(b(215), 11) as f64 * p2(-66),
        ],
        aode: s1.u(b(288), 5) as u16,
    };
    let orbit = KeplerOrbit {
        delta_n_rad_per_s: s2.s2(b(43), 10, b(61), 6) as f64 * p2(-43) * sc,
        cuc_rad: s2.s2(b(67), 16, b(91), 2) as f64 * p2(-31),
        m0_rad: s2.s2(b(93), 20, b(121), 12) as f64 * p2(-31) * sc,
        e: s2.u2(b(133), 10, b(151), 22) as f64 * p2(-33),
        cus_rad: s2.s(b(181), 18) as f64 * p2(-31),
        crc_m: s2.s2(b(199), 4, b(211), 14) as f64 * p2(-6),
        crs_m: s2.s2(b(225), 8, b(241), 10) as f64 * p2(-6),
        sqrt_a_sqrt_m: s2.u2(b(251), 12, b(271), 20) as f64 * p2(-19),
        toe_sow_s: ((s2.u(b(291), 2) << 15) | s3.u2(b(43), 10, b(61), 5)) as f64 * 8.0,
        i0_rad: s3.s2(b(66), 17, b(91), 15) as f64 * p2(-31) * sc,
        cic_rad: s3.s2(b(106), 7, b(121), 11) as f64 * p2(-31),
        omega_dot_rad_per_s: s3.s2(b(132), 11, b(151), 13) as f64 * p2(-43) * sc,
        cis_rad: s3.s2(b(164), 9, b(181), 9) as f64 * p2(-31),
        idot_rad_per_s: s3.s2(b(190), 13, b(211), 1) as f64 * p2(-43) * sc,
        omega0_rad: s3.s2(b(212), 21, b(241), 11) as f64 * p2(-31) * sc,
        omega_rad: s3.s2(b(252), 11, b(271), 21) as f64 * p2(-31) * sc,
    };
    record(prn, clock, orbit)
}

/// Two's complement of an `n`-bit number.
fn signed(v: u64, n: usize) -> i64 {
    let mut b = Bits::default();
    b.push(v, n);
    b.s(0, n)
}

/// D2 subframe 1 pages 1, 3-10 (ICD §5.3.3, Table 5-13): parameters split across
/// pages are joined MSBs first.
fn d2_ephemeris(prn: u8, set: &[Option<Bits>; 10]) -> Option<BeiDouEphemeris> {
    let pg = |k: usize| set[k - 1].as_ref();
    let (p1, p3, p4, p5, p6) = (pg(1)?, pg(3)?, pg(4)?, pg(5)?, pg(6)?);
    let (p7, p8, p9, p10) = (pg(7)?, pg(8)?, pg(9)?, pg(10)?);
    // One cycle: page 3 six seconds after page 1, then 3 s per page.
    let s1 = sow(p1);
    let ok = sow(p3) == s1 + 6
        && [p4, p5, p6, p7, p8, p9, p10]
            .iter()
            .enumerate()
            .all(|(k, p)| sow(p) == s1 + 9 + 3 * k as u64);
    if !ok {
        return None;
    }
    let sc = GPS_PI;
    let join = |hi: u64, lo: u64, nlo: usize, n: usize| signed((hi << nlo) | lo, n);
    let clock = Clock {
        week: p1.u(b(65), 13) as i32,
        sow1: s1 as f64,
        toc_s: p1.u2(b(78), 5, b(91), 12) as f64 * 8.0,
        sat_h1: p1.u(b(47), 1) as u32,
        aodc: p1.u(b(48), 5) as u16,
        urai: p1.u(b(61), 4) as usize,
        tgd1: p1.s(b(103), 10),
        tgd2: p1.s(b(121), 10),
        af: [
            p3.s2(b(101), 12, b(121), 12) as f64 * p2(-33),
            join(p3.u(b(133), 4), p4.u2(b(47), 6, b(61), 12), 18, 22) as f64 * p2(-50),
            p4.s2(b(73), 10, b(91), 1) as f64 * p2(-66),
        ],
        aode: p4.u(b(92), 5) as u16,
    };
    let orbit = KeplerOrbit {
        delta_n_rad_per_s: p4.s(b(97), 16) as f64 * p2(-43) * sc,
        cuc_rad: join(p4.u(b(121), 14), p5.u(b(47), 4), 4, 18) as f64 * p2(-31),
        m0_rad: signed(
            (p5.u(b(51), 2) << 30) | (p5.u(b(61), 22) << 8) | p5.u(b(91), 8),
            32,
        ) as f64
            * p2(-31)
            * sc,
        cus_rad: p5.s2(b(99), 14, b(121), 4) as f64 * p2(-31),
        e: ((p5.u(b(125), 10) << 22) | p6.u2(b(47), 6, b(61), 16)) as f64 * p2(-33),
        sqrt_a_sqrt_m: ((p6.u(b(77), 6) << 26) | (p6.u(b(91), 22) << 4) | p6.u(b(121), 4)) as f64
            * p2(-19),
        cic_rad: join(p6.u(b(125), 10), p7.u2(b(47), 6, b(61), 2), 8, 18) as f64 * p2(-31),
        cis_rad: p7.s(b(63), 18) as f64 * p2(-31),
        toe_sow_s: p7.u2(b(81), 2, b(91), 15) as f64 * 8.0,
        i0_rad: join(
            p7.u2(b(106), 7, b(121), 14),
            p8.u2(b(47), 6, b(61), 5),
            11,
            32,
        ) as f64
            * p2(-31)
            * sc,
        crc_m: p8.s2(b(66), 17, b(91), 1) as f64 * p2(-6),
        crs_m: p8.s(b(92), 18) as f64 * p2(-6),
        omega_dot_rad_per_s: join(p8.u2(b(110), 3, b(121), 16), p9.u(b(47), 5), 5, 24) as f64
            * p2(-43)
            * sc,
        omega0_rad: signed(
            (p9.u(b(52), 1) << 31) | (p9.u(b(61), 22) << 9) | p9.u(b(91), 9),
            32,
        ) as f64
            * p2(-31)
            * sc,
        omega_rad: join(p9.u2(b(100), 13, b(121), 14), p10.u(b(47), 5), 5, 32) as f64
            * p2(-31)
            * sc,
        idot_rad_per_s: p10.s2(b(52), 1, b(61), 13) as f64 * p2(-43) * sc,
    };
    record(prn, clock, orbit)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BCH(15,11) with g = x^4 + x + 1: x^4 mod g = x + 1 (info 1 -> parity 0011),
    /// and a codeword divides evenly.
    #[test]
    fn bch_parity_of_known_words() {
        assert_eq!(bch_parity(1), 0b0011);
        assert_eq!(bch_parity(0), 0);
        // x^14 mod g: x^4 = x+1, x^8 = x^2+1, x^12 = x^3+x^2+x+1, x^14 = x^3+1 ...
        // parity of info 1<<10 is x^14 mod g.
        let mut r = 1u64 << 14;
        for k in (4..15).rev() {
            if (r >> k) & 1 == 1 {
                r ^= 0b10011 << (k - 4);
            }
        }
        assert_eq!(bch_parity(1 << 10), r & 0xF);
        assert_eq!(bch_parity(1 << 10), 0b1001);
    }
}
