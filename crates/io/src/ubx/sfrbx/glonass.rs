//! GLONASS L1/L2 OF navigation strings (GLONASS ICD 5.1 2008: §4.3 string
//! structure, Table 4.5 immediate data of strings 1-4, §4.7 Hamming code, §4.4
//! parameter definitions). u-blox gives one 85-bit string (ICD bits 85..1, the
//! idle bit first, without the time mark) MSB-first from bit 31 of word 0 over
//! words 0-2; word 3 carries the receiver's superframe / frame numbers (bits
//! 31..16). An ICD bit N is position 85 - N.
//!
//! Strings 1-4 of one frame make an ephemeris. tb (string 2, 15-minute index of the
//! Moscow day, UTC(SU) + 3 h) is dated from the receiver's time (the latest RAWX
//! epoch, within half a day) and converted to GPST with the GPS-UTC leap seconds,
//! as the RINEX reader converts a record's UTC epoch. The message frame time is
//! string 1's tk, in UTC seconds of the week (RINEX 3.05 Table A10).

use super::{Bits, RxContext, SfrbxCounts};
use nalgebra::Vector3;
use navfuse_gnss::{GlonassEphemeris, GpsTime};
use std::collections::HashMap;

const DAY_S: f64 = 86_400.0;
const MOSCOW_S: f64 = 10_800.0;

/// ICD bit N (85..1) as a position.
fn b(n: usize) -> usize {
    85 - n
}

/// The Hamming check (ICD §4.7): the check bits beta1-7 are the parities of the
/// data bits b9..b85 placed, in order, at the positions of a Hamming code that
/// are not powers of two (b9 at 3, b10 at 5, ...): C_j covers the positions whose
/// bit j-1 is set; C_sigma is the parity of the whole string. A string is good
/// when every C is 0, or when exactly one of C1-C7 (or only C_sigma) is 1 and
/// C_sigma is 1: a single error in a check bit (rule a). A single data-bit error
/// (correctable by rule b) is rejected here, not corrected.
pub(crate) fn hamming_ok(s: &Bits) -> bool {
    let bit = |n: usize| s.u(b(n), 1);
    let mut c = [0u64; 7];
    let mut pos = 2usize;
    for n in 9..=85 {
        pos += 1;
        while pos.is_power_of_two() {
            pos += 1;
        }
        for (j, cj) in c.iter_mut().enumerate() {
            if (pos >> j) & 1 == 1 {
                *cj ^= bit(n);
            }
        }
    }
    for (j, cj) in c.iter_mut().enumerate() {
        *cj ^= bit(j + 1);
    }
    let sigma = (1..=85).fold(0, |a, n| a ^ bit(n));
    let ones = c.iter().filter(|x| **x == 1).count();
    (ones == 0 && sigma == 0) || (ones <= 1 && sigma == 1)
}

/// The 85 bits of a string.
pub(crate) fn string_bits(words: &[u32]) -> Bits {
    Bits::from_words(&words[..3], 32).slice(0, 85)
}

#[derive(Default)]
pub(super) struct GloDecoder {
    /// Strings 1-4 per slot (each with the receiver time it came at) and the frame
    /// number they were received in.
    #[allow(clippy::type_complexity)]
    strings: HashMap<u8, ([Option<(Bits, f64)>; 4], u32)>,
    pub(super) ephemerides: Vec<GlonassEphemeris>,
}

impl GloDecoder {
    pub(super) fn decode(
        &mut self,
        slot: u8,
        channel: i32,
        words: &[u32],
        rx: RxContext,
        c: &mut SfrbxCounts,
    ) -> Result<(), String> {
        let s = string_bits(words);
        if !hamming_ok(&s) {
            c.glonass.rejected += 1;
            c.glonass_hamming_failures += 1;
            return Err(format!("RXM-SFRBX: R{slot:02}: Hamming check failed"));
        }
        let m = s.u(b(84), 4) as usize;
        if !(1..=4).contains(&m) {
            c.glonass.other += 1;
            return Ok(());
        }
        let Some(t_rx) = rx.time else {
            // No receiver time yet to date tb.
            c.not_decoded += 1;
            return Ok(());
        };
        c.glonass.pages += 1;
        let frame = words[3] >> 16;
        let entry = self.strings.entry(slot).or_default();
        if entry.1 != frame {
            *entry = (Default::default(), frame);
        }
        let t_s = secs(t_rx);
        entry.0[m - 1] = Some((s, t_s));
        // One frame (30 s) whatever word 3 says: strings 1-4 are sent within 8 s.
        if let [Some((s1, t1)), Some((s2, t2)), Some((s3, t3)), Some((s4, t4))] = &entry.0 {
            let ts = [*t1, *t2, *t3, *t4];
            let span = ts.iter().cloned().fold(f64::MIN, f64::max)
                - ts.iter().cloned().fold(f64::MAX, f64::min);
            if span > 30.0 {
                return Ok(());
            }
            let leap = rx.leap_seconds.map_or_else(
                || navfuse_gnss::time::leap_seconds(u32::try_from(t_rx.week).ok()),
                f64::from,
            );
            match ephemeris(slot, channel, [s1, s2, s3, s4], t_rx, leap) {
                Some(e) => {
                    if !self
                        .ephemerides
                        .iter()
                        .any(|x| x.slot == e.slot && x.tb == e.tb)
                    {
                        self.ephemerides.push(e);
                    }
                }
                None => {
                    c.glonass.rejected += 1;
                    return Err(format!("RXM-SFRBX: R{slot:02}: implausible strings 1-4"));
                }
            }
        }
        Ok(())
    }
}

/// Seconds since the GPS epoch (1980-01-06 00:00, a midnight) of a time counted
/// like GPST.
fn secs(t: GpsTime) -> f64 {
    f64::from(t.week) * 604_800.0 + t.sow
}

/// `t` (seconds since the epoch) moved by whole days to within half a day of `r`.
fn near_day(t: f64, r: f64) -> f64 {
    t - ((t - r) / DAY_S).round() * DAY_S
}

/// Strings 1-4 (ICD 5.1 Table 4.5: sign-magnitude x, x', x'' in 2^-11 km,
/// 2^-20 km/s, 2^-30 km/s^2; tau_n 2^-30 s, gamma_n 2^-40).
fn ephemeris(
    slot: u8,
    channel: i32,
    s: [&Bits; 4],
    t_rx: GpsTime,
    leap: f64,
) -> Option<GlonassEphemeris> {
    let [s1, s2, s3, s4] = s;
    let n = s4.u(b(15), 5) as u8;
    if n != 0 && n != slot {
        return None;
    }
    let axis = |st: &Bits| {
        (
            st.sm(b(35), 27) as f64 * 2f64.powi(-11) * 1e3,
            st.sm(b(64), 24) as f64 * 2f64.powi(-20) * 1e3,
            st.sm(b(40), 5) as f64 * 2f64.powi(-30) * 1e3,
        )
    };
    let (x, y, z) = (axis(s1), axis(s2), axis(s3));
    // tb on the Moscow day of the receiver's time.
    let msk_rx = secs(t_rx) - leap + MOSCOW_S;
    let tb_msk = near_day(
        (msk_rx / DAY_S).floor() * DAY_S + s2.u(b(76), 7) as f64 * 900.0,
        msk_rx,
    );
    let tb_utc = tb_msk - MOSCOW_S;
    let tk_s = s1.u(b(76), 5) as f64 * 3600.0
        + s1.u(b(71), 6) as f64 * 60.0
        + s1.u(b(65), 1) as f64 * 30.0;
    let tk_utc = near_day((tb_msk / DAY_S).floor() * DAY_S + tk_s, tb_msk) - MOSCOW_S;
    let pos = Vector3::new(x.0, y.0, z.0);
    if !(1.9e7..3.0e7).contains(&pos.norm()) {
        return None;
    }
    Some(GlonassEphemeris {
        slot,
        tb: GpsTime::new(0, tb_utc + leap),
        tb_utc_sod_s: tb_utc.rem_euclid(DAY_S),
        tau_n_s: s4.sm(b(80), 22) as f64 * 2f64.powi(-30),
        gamma_n: s3.sm(b(79), 11) as f64 * 2f64.powi(-40),
        frame_time_s: tk_utc.rem_euclid(604_800.0),
        pos_m: pos,
        vel_mps: Vector3::new(x.1, y.1, z.1),
        acc_mps2: Vector3::new(x.2, y.2, z.2),
        health: s2.u(b(80), 3) as u32,
        freq_channel: channel.clamp(-7, 13) as i8,
        age_days: s4.u(b(53), 5) as f64,
    })
}
