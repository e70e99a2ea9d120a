//! UBX-RXM-SFRBX (class 0x02, id 0x13): the broadcast navigation pages of every
//! system the receiver tracks, collected per satellite into ephemerides
//! (docs/FORMATS.md "RXM-SFRBX"):
//!
//! - GPS and QZSS L1 C/A LNAV subframes 1-3 (`gps`), subframe 4 page 18
//!   (SV ID 56: Klobuchar and GPS-UTC leap seconds);
//! - BeiDou D1 (MEO/IGSO, subframes 1-3) and D2 (GEO, subframe 1 pages 1-10)
//!   (`beidou`), times BDT;
//! - Galileo I/NAV E1-B and E5b-I word types 1-5 (`galileo`), CRC-24Q checked;
//! - GLONASS L1/L2 OF strings 1-4 (`glonass`), Hamming checked, tb in GPST.
//!
//! Everything else (SBAS, CNAV, B-CNAV, F/NAV, E6, almanac pages) is counted in
//! [`SfrbxCounts::not_decoded`]. Malformed input is counted and reported, never a
//! panic: every bit read is inside the words the message carries.

mod beidou;
mod galileo;
mod glonass;
mod gps;

use super::frame::u32_at;
use navfuse_gnss::{BeiDouEphemeris, GalileoEphemeris, GlonassEphemeris, GpsEphemeris, GpsTime};

/// The nominal URA \[m\] of URA index N (IS-GPS-200 20.3.3.3.1.3; BeiDou B1I ICD
/// §5.2.4.5 uses the same table; RINEX and RTKLIB write these values). Index 15:
/// no accuracy prediction.
pub(crate) const URA_M: [f64; 16] = [
    2.0, 2.8, 4.0, 5.7, 8.0, 11.3, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0, 2048.0, 4096.0,
    8192.0,
];

/// A bit string, one bit per element, MSB first as transmitted. Reads past the
/// end give zero bits (never a panic); callers build it from a fixed number of
/// words, so every field position is inside.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Bits(Vec<u8>);

impl Bits {
    /// The low `n` bits of each word, MSB first.
    pub(crate) fn from_words(words: &[u32], n: usize) -> Bits {
        let mut b = Bits(Vec::with_capacity(words.len() * n));
        for w in words {
            b.push(u64::from(*w), n);
        }
        b
    }

    /// Append the low `n` bits of `v`, MSB first.
    pub(crate) fn push(&mut self, v: u64, n: usize) {
        for k in (0..n).rev() {
            self.0.push(((v >> k) & 1) as u8);
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.0.len()
    }

    /// `len` (<= 64) bits from `pos` as an unsigned number.
    pub(crate) fn u(&self, pos: usize, len: usize) -> u64 {
        (pos..pos + len).fold(0u64, |acc, k| {
            (acc << 1) | u64::from(self.0.get(k).copied().unwrap_or(0))
        })
    }

    /// Two's complement of `len` bits.
    pub(crate) fn s(&self, pos: usize, len: usize) -> i64 {
        twos(self.u(pos, len), len)
    }

    /// Sign-magnitude (GLONASS): the first bit is the sign (1 = negative).
    pub(crate) fn sm(&self, pos: usize, len: usize) -> i64 {
        let mag = self.u(pos + 1, len - 1) as i64;
        if self.u(pos, 1) == 1 {
            -mag
        } else {
            mag
        }
    }

    /// Two fields joined, the first the most significant (BeiDou splits most
    /// parameters over two words).
    pub(crate) fn u2(&self, p1: usize, l1: usize, p2: usize, l2: usize) -> u64 {
        (self.u(p1, l1) << l2) | self.u(p2, l2)
    }

    pub(crate) fn s2(&self, p1: usize, l1: usize, p2: usize, l2: usize) -> i64 {
        twos(self.u2(p1, l1, p2, l2), l1 + l2)
    }

    /// Bits `pos..pos + len` as a new string.
    pub(crate) fn slice(&self, pos: usize, len: usize) -> Bits {
        Bits(
            (pos..pos + len)
                .map(|k| self.0.get(k).copied().unwrap_or(0))
                .collect(),
        )
    }

    pub(crate) fn extend(&mut self, other: &Bits) {
        self.0.extend_from_slice(&other.0);
    }
}

fn twos(v: u64, len: usize) -> i64 {
    if len > 0 && len < 64 && (v >> (len - 1)) & 1 == 1 {
        v as i64 - (1i64 << len)
    } else {
        v as i64
    }
}

pub(crate) fn p2(n: i32) -> f64 {
    2f64.powi(n)
}

/// `t` moved by whole weeks to within half a week of `reference`.
pub(crate) fn near(t: GpsTime, reference: GpsTime) -> GpsTime {
    let dt = t.diff_s(&reference);
    let week = if dt > 302_400.0 {
        t.week - 1
    } else if dt < -302_400.0 {
        t.week + 1
    } else {
        t.week
    };
    GpsTime::new(week, t.sow)
}

/// Pages of one system: taken into an ephemeris or ionosphere collection, or
/// rejected (bad preamble, parity / CRC / Hamming check, inconsistent set,
/// implausible values).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PageCounts {
    /// Pages taken (ephemeris, clock, ionosphere pages).
    pub pages: usize,
    /// Valid pages of other kinds (almanac, GLONASS string 5 and strings 6-15, ...).
    pub other: usize,
    pub rejected: usize,
    /// Distinct ephemerides decoded.
    pub ephemerides: usize,
}

/// Counts of the SFRBX decoding.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SfrbxCounts {
    pub messages: usize,
    pub gps: PageCounts,
    pub qzss: PageCounts,
    pub galileo: PageCounts,
    pub beidou: PageCounts,
    pub glonass: PageCounts,
    /// Pages of signals or kinds not decoded: SBAS, GPS/QZSS CNAV, BeiDou B-CNAV,
    /// Galileo F/NAV and E6, almanac pages, Galileo alert pages, GLONASS strings of
    /// an unknown slot or before the receiver's time is known.
    pub not_decoded: usize,
    /// Messages whose length does not match numWords, or too short for their
    /// signal's page.
    pub malformed: usize,
    /// GPS/QZSS subframe sets whose IODC / IODE did not agree (waited for a
    /// consistent set).
    pub iode_mismatch: usize,
    /// Galileo page pairs whose CRC-24Q failed (also in `galileo.rejected`).
    pub galileo_crc_failures: usize,
    /// GLONASS strings whose Hamming check failed (also in `glonass.rejected`).
    pub glonass_hamming_failures: usize,
}

impl SfrbxCounts {
    /// "GPS 12 pages (0 rejected) ..." for the summary line.
    pub fn per_system(&self) -> String {
        [
            ("GPS", &self.gps),
            ("QZSS", &self.qzss),
            ("Galileo", &self.galileo),
            ("BeiDou", &self.beidou),
            ("GLONASS", &self.glonass),
        ]
        .iter()
        .map(|(n, c)| format!("{n} {}/{} pages", c.pages, c.rejected))
        .collect::<Vec<_>>()
        .join(", ")
    }
}

/// What the pages gave, besides the ephemerides.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SfrbxIono {
    /// GPS Klobuchar alpha, beta (subframe 4 page 18).
    pub gps_klobuchar: Option<([f64; 4], [f64; 4])>,
    /// GPS-UTC leap seconds delta t_LS (subframe 4 page 18).
    pub gps_leap_seconds: Option<i32>,
    /// QZSS Klobuchar (its own page with SV ID 56).
    pub qzss_klobuchar: Option<([f64; 4], [f64; 4])>,
    /// BeiDou Klobuchar (D1 subframe 1).
    pub beidou_klobuchar: Option<([f64; 4], [f64; 4])>,
    /// Galileo NeQuick-G a_i0, a_i1, a_i2 (word type 5).
    pub galileo_nequick: Option<[f64; 3]>,
}

/// Collects the pages of every satellite; the ephemerides in decoding order, each
/// issue once.
pub struct SfrbxDecoder {
    gps: gps::LnavDecoder,
    qzss: gps::LnavDecoder,
    beidou: beidou::BdsDecoder,
    galileo: galileo::InavDecoder,
    glonass: glonass::GloDecoder,
    pub counts: SfrbxCounts,
    pub iono: SfrbxIono,
}

/// The receiver's context of a message: the GPS week (RAWX, else NAV-PVT) to
/// resolve 10-bit weeks, the latest RAWX time and GPS-UTC leap seconds (GLONASS
/// dates its tb by them).
#[derive(Clone, Copy, Debug, Default)]
pub struct RxContext {
    pub week: Option<i32>,
    pub time: Option<GpsTime>,
    pub leap_seconds: Option<i32>,
}

impl Default for SfrbxDecoder {
    fn default() -> Self {
        SfrbxDecoder {
            gps: gps::LnavDecoder::default(),
            qzss: gps::LnavDecoder {
                qzss: true,
                ..Default::default()
            },
            beidou: beidou::BdsDecoder::default(),
            galileo: galileo::InavDecoder::default(),
            glonass: glonass::GloDecoder::default(),
            counts: SfrbxCounts::default(),
            iono: SfrbxIono::default(),
        }
    }
}

impl SfrbxDecoder {
    /// One SFRBX payload. Err(reason) for a malformed or rejected page (counted).
    pub fn decode(&mut self, p: &[u8], rx: RxContext) -> Result<(), String> {
        self.counts.messages += 1;
        if p.len() < 8 {
            self.counts.malformed += 1;
            return Err(format!("RXM-SFRBX: {} bytes, the header is 8", p.len()));
        }
        let (gnss_id, sv_id, sig_id, freq_id, n) = (p[0], p[1], p[2], p[3], usize::from(p[4]));
        if p.len() != 8 + 4 * n {
            self.counts.malformed += 1;
            return Err(format!(
                "RXM-SFRBX: numWords {n} needs {} bytes, the message has {}",
                8 + 4 * n,
                p.len()
            ));
        }
        let words: Vec<u32> = (0..n).map(|k| u32_at(p, 8 + 4 * k)).collect();
        // The broadcast GPS-UTC first.
        let rx = RxContext {
            leap_seconds: self.iono.gps_leap_seconds.or(rx.leap_seconds),
            ..rx
        };
        let c = &mut self.counts;
        match (gnss_id, sig_id) {
            // GPS L1 C/A LNAV (ten 30-bit words).
            (0, 0) if n == 10 && (1..=32).contains(&sv_id) => self
                .gps
                .decode(sv_id, &words, rx.week, &mut c.gps, &mut c.iode_mismatch)
                .map(|io| {
                    if let Some((kl, leap)) = io {
                        self.iono.gps_klobuchar = Some(kl);
                        self.iono.gps_leap_seconds = Some(leap);
                    }
                }),
            // QZSS L1 C/A LNAV: the GPS layout (IS-QZSS-PNT §5.2), J01-J10.
            (5, 0) if n == 10 && (1..=10).contains(&sv_id) => self
                .qzss
                .decode(sv_id, &words, rx.week, &mut c.qzss, &mut c.iode_mismatch)
                .map(|io| {
                    if let Some((kl, _)) = io {
                        self.iono.qzss_klobuchar = Some(kl);
                    }
                }),
            // BeiDou D1/D2 on B1I (0/1), B2I (2/3) and B3I (4, 10: the sigIds this
            // receiver gives B3I, whose pages carry the same D1/D2 messages).
            (3, 0..=4 | 10) if n == 10 && (1..=63).contains(&sv_id) => self
                .beidou
                .decode(sv_id, &words, &mut c.beidou, &mut c.not_decoded)
                .map(|kl| {
                    if let Some(kl) = kl {
                        self.iono.beidou_klobuchar = Some(kl);
                    }
                }),
            // Galileo I/NAV E1-B (1) and E5b-I (5): one page pair in 8 words (older
            // firmware adds a ninth, ignored).
            (2, 1 | 5) if n >= 8 && (1..=36).contains(&sv_id) => self
                .galileo
                .decode(sv_id, sig_id == 5, &words[..8], c)
                .map(|nq| {
                    if let Some(nq) = nq {
                        self.iono.galileo_nequick = Some(nq);
                    }
                }),
            // GLONASS L1 OF (0) / L2 OF (2): one string in 4 words.
            (6, 0 | 2) if n >= 4 && (1..=32).contains(&sv_id) => {
                self.glonass
                    .decode(sv_id, i32::from(freq_id) - 7, &words[..4], rx, c)
            }
            _ => {
                c.not_decoded += 1;
                Ok(())
            }
        }
    }

    /// The decoded ephemerides: GPS, QZSS, Galileo, BeiDou, GLONASS.
    #[allow(clippy::type_complexity)]
    pub fn take(
        &mut self,
    ) -> (
        Vec<GpsEphemeris>,
        Vec<GpsEphemeris>,
        Vec<GalileoEphemeris>,
        Vec<BeiDouEphemeris>,
        Vec<GlonassEphemeris>,
    ) {
        let out = (
            std::mem::take(&mut self.gps.ephemerides),
            std::mem::take(&mut self.qzss.ephemerides),
            std::mem::take(&mut self.galileo.ephemerides),
            std::mem::take(&mut self.beidou.ephemerides),
            std::mem::take(&mut self.glonass.ephemerides),
        );
        self.counts.gps.ephemerides = out.0.len();
        self.counts.qzss.ephemerides = out.1.len();
        self.counts.galileo.ephemerides = out.2.len();
        self.counts.beidou.ephemerides = out.3.len();
        self.counts.glonass.ephemerides = out.4.len();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_read_fields_and_never_past_the_end() {
        let b = Bits::from_words(&[0x8000_0001, 0xFFFF_FFFF], 32);
        assert_eq!(b.u(0, 1), 1);
        assert_eq!(b.u(31, 1), 1);
        assert_eq!(b.s(32, 8), -1);
        assert_eq!(b.sm(0, 8), 0);
        assert_eq!(b.sm(32, 4), -7);
        assert_eq!(b.u2(30, 2, 32, 2), 0b0111);
        assert_eq!(b.u(60, 10), 0b11_1100_0000);
        assert_eq!(b.s2(0, 1, 1, 3), -8);
    }
}
