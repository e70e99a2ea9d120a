//! UBX-NAV-PVT (class 0x01, id 0x07, 92 bytes) -> [`GnssFix`]: the receiver's own
//! solution, kept when gnssFixOK is set and fixType is 2D (2), 3D (3) or
//! GNSS + dead reckoning (4).

use super::frame::{i32_at, u16_at, u32_at};
use nalgebra::Vector3;
use navfuse_core::GnssFix;

/// NAV-PVT payload length (protocol 14 and later).
pub const LEN: usize = 92;

/// One NAV-PVT solution: GPS time of week \[s\] (iTOW) and the fix, or None when
/// the receiver marks it invalid.
pub struct Pvt {
    pub itow_s: f64,
    /// UTC date and time (when validDate, validTime and fullyResolved): year, month,
    /// day, h, m, s.
    pub utc: Option<(i32, u32, u32, u32, u32, u32)>,
    pub fix: Option<GnssFix>,
}

/// Decode a NAV-PVT payload. Err(reason) for a payload of the wrong size.
pub fn decode(p: &[u8]) -> Result<Pvt, String> {
    if p.len() != LEN {
        return Err(format!("NAV-PVT: {} bytes, expected {LEN}", p.len()));
    }
    let itow_s = f64::from(u32_at(p, 0)) * 1e-3;
    let valid = p[11];
    // validDate, validTime and fullyResolved: a date the receiver vouches for.
    let utc = (valid & 7 == 7).then(|| {
        (
            i32::from(u16_at(p, 4)),
            u32::from(p[6]),
            u32::from(p[7]),
            u32::from(p[8]),
            u32::from(p[9]),
            u32::from(p[10]),
        )
    });
    let fix_type = p[20];
    let fix_ok = p[21] & 1 == 1;
    let mm = 1e-3;
    let h_acc = f64::from(u32_at(p, 40)) * mm;
    let v_acc = f64::from(u32_at(p, 44)) * mm;
    let s_acc = f64::from(u32_at(p, 68)) * mm;
    let lon = f64::from(i32_at(p, 24)) * 1e-7;
    let lat = f64::from(i32_at(p, 28)) * 1e-7;
    let usable = fix_ok
        && (2..=4).contains(&fix_type)
        && itow_s < 604_800.0
        && lat.abs() <= 90.0
        && lon.abs() <= 180.0
        && h_acc > 0.0
        && v_acc > 0.0
        && s_acc > 0.0;
    let fix = usable.then(|| GnssFix {
        t: itow_s,
        lla: Vector3::new(
            lat.to_radians(),
            lon.to_radians(),
            f64::from(i32_at(p, 32)) * mm,
        ),
        // hAcc is a horizontal (2D) accuracy: split evenly over north and east.
        std_ned: Vector3::new(
            h_acc / std::f64::consts::SQRT_2,
            h_acc / std::f64::consts::SQRT_2,
            v_acc,
        ),
        vel_ned: Some(Vector3::new(
            f64::from(i32_at(p, 48)) * mm,
            f64::from(i32_at(p, 52)) * mm,
            f64::from(i32_at(p, 56)) * mm,
        )),
        // sAcc is a 3D speed accuracy: split evenly over the three axes.
        vel_std_ned: Some(Vector3::repeat(s_acc / 3f64.sqrt())),
    });
    Ok(Pvt { itow_s, utc, fix })
}

/// The GPS week of a UTC calendar date and time near GPS time of week `itow_s`
/// (GPS - UTC is under a minute, far less than half a week).
pub fn week_from_utc(utc: (i32, u32, u32, u32, u32, u32), itow_s: f64) -> Option<i32> {
    let (y, m, d, hh, mi, ss) = utc;
    if !(1..=12).contains(&m) || !(1..=31).contains(&d) || y < 1980 {
        return None;
    }
    // Days from 1970-01-01 (H. Hinnant's days_from_civil).
    let (y, m) = (i64::from(if m <= 2 { y - 1 } else { y }), i64::from(m));
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + i64::from(d) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    let days = era * 146_097 + doe - 719_468;
    // GPS epoch 1980-01-06 is day 3657 of the Unix count.
    let secs = (days - 3657) as f64 * 86_400.0 + f64::from(hh * 3600 + mi * 60 + ss);
    Some(((secs - itow_s) / 604_800.0).round() as i32)
}
