//! UBX-NAV-RELPOSNED (class 0x01, id 0x3C): the moving-base relative position of a
//! dual-antenna u-blox setup, as a heading of the baseline from the reference
//! (primary) to the rover (secondary) antenna (docs/FORMATS.md "NAV-RELPOSNED").
//!
//! Layouts (u-blox interface descriptions):
//! - version 0 (u-blox M8, 40 bytes): version, reserved, refStationId u16, iTOW u32
//!   \[ms\], relPosN/E/D i32 \[cm\] (8, 12, 16), relPosHPN/E/D i8 [0.1 mm] (20-22), accN/E/D
//!   u32 [0.1 mm] (24, 28, 32), flags u32 (36). No heading field: the heading is
//!   atan2(E, N) of the vector, its std (N^2 accE^2 + E^2 accN^2)^(1/2) / (N^2 + E^2).
//! - version 1 (u-blox F9, 64 bytes): ..., relPosN/E/D (8, 12, 16), relPosLength
//!   (20), relPosHeading i32 [1e-5 deg] (24), relPosHP N/E/D/Length (32-35), accN/E/D/
//!   Length u32 [0.1 mm] (36-48), accHeading u32 [1e-5 deg] (52), flags u32 (60).
//! - flags: bit 0 gnssFixOK, 2 relPosValid, 3-4 carrSoln (1 float, 2 fixed), 8
//!   relPosHeadingValid (version 1).

use super::frame::{u32_at, Frame};

/// What one NAV-RELPOSNED gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelPosHeading {
    /// GPS time of week \[s\] (iTOW).
    pub itow_s: f64,
    /// Byte offset of the message.
    pub offset: usize,
    /// Baseline heading \[rad\], [0, 2 pi).
    pub heading_rad: f64,
    /// Its 1-sigma \[rad\] (accHeading, or propagated from accN / accE for version 0).
    pub std_rad: f64,
    /// carrSoln: 0 none, 1 float, 2 fixed.
    pub carr_soln: u8,
    /// gnssFixOK, relPosValid and (version 1) relPosHeadingValid all set.
    pub valid: bool,
    pub version: u8,
}

fn i8_at(p: &[u8], o: usize) -> f64 {
    f64::from(p[o] as i8)
}

fn i32f(p: &[u8], o: usize) -> f64 {
    f64::from(u32_at(p, o) as i32)
}

/// Decode one NAV-RELPOSNED. Err(reason) for a layout it cannot be.
pub fn decode(f: &Frame<'_>) -> Result<RelPosHeading, String> {
    let p = f.payload;
    let (version, need) = match p.first() {
        Some(0) => (0u8, 40usize),
        Some(1) => (1, 64),
        Some(v) => {
            return Err(format!(
                "NAV-RELPOSNED: field 'version': {v}, expected 0 or 1"
            ))
        }
        None => return Err("NAV-RELPOSNED: empty payload".into()),
    };
    if p.len() != need {
        return Err(format!(
            "NAV-RELPOSNED: version {version} has {need} bytes, the message has {}",
            p.len()
        ));
    }
    let itow_s = f64::from(u32_at(p, 4)) * 1e-3;
    let flags = u32_at(p, if version == 0 { 36 } else { 60 });
    let carr_soln = ((flags >> 3) & 3) as u8;
    let fix_ok = flags & 1 != 0;
    let rel_valid = flags & 4 != 0;
    let (heading_deg, std_deg, heading_valid) = if version == 1 {
        (
            i32f(p, 24) * 1e-5,
            f64::from(u32_at(p, 52)) * 1e-5,
            flags & 0x100 != 0,
        )
    } else {
        // cm + 0.1 mm high-precision part, in metres
        let n = i32f(p, 8) * 1e-2 + i8_at(p, 20) * 1e-4;
        let e = i32f(p, 12) * 1e-2 + i8_at(p, 21) * 1e-4;
        let (acc_n, acc_e) = (
            f64::from(u32_at(p, 24)) * 1e-4,
            f64::from(u32_at(p, 28)) * 1e-4,
        );
        let l2 = n * n + e * e;
        let std = (n * n * acc_e * acc_e + e * e * acc_n * acc_n).sqrt() / l2;
        (e.atan2(n).to_degrees(), std.to_degrees(), l2 > 0.0)
    };
    let mut heading_rad = heading_deg.to_radians().rem_euclid(std::f64::consts::TAU);
    if heading_rad >= std::f64::consts::TAU {
        heading_rad = 0.0;
    }
    let std_rad = std_deg.to_radians();
    let std_ok = std_rad > 0.0 && (std_rad * std_rad).is_finite() && std_rad * std_rad > 0.0;
    Ok(RelPosHeading {
        itow_s,
        offset: f.offset,
        heading_rad,
        std_rad,
        carr_soln,
        valid: fix_ok
            && rel_valid
            && heading_valid
            && std_ok
            && heading_rad.is_finite()
            && itow_s < 604_800.0,
        version,
    })
}
