//! Signals: RINEX 3 observation codes (RINEX 3.05 §5.1, Table 4-11: type C/L/D/S,
//! band digit, tracking attribute, e.g. `C1C`, `L5Q`, `C2W`, `C7I`), the carrier
//! frequency of each system's band, the documented code priority per system and
//! band, and the dual-frequency ionosphere-free pseudorange combination.

use crate::obs::{ObsValue, SatSignals};
use navfuse_core::sat::System;

/// A RINEX 3 observation code: three ASCII bytes, type + band + attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObsCode(pub [u8; 3]);

impl ObsCode {
    /// Parse `C1C`, `L5Q`, ...: type one of C L D S, band a digit 1-9, attribute an
    /// upper-case letter (RINEX 3.05 §5.1).
    pub fn parse(s: &str) -> Option<ObsCode> {
        match *s.as_bytes() {
            [t @ (b'C' | b'L' | b'D' | b'S'), b @ b'1'..=b'9', a] if a.is_ascii_uppercase() => {
                Some(ObsCode([t, b, a]))
            }
            _ => None,
        }
    }

    /// Type letter: C code \[m\], L phase \[cycles\], D Doppler \[Hz\], S signal strength.
    pub fn kind(self) -> u8 {
        self.0[0]
    }

    /// Band digit as a number (1 = L1/E1/G1/B1C, 2 = L2/G2/B1I, 5 = L5/E5a/B2a, ...).
    pub fn band(self) -> u8 {
        self.0[1] - b'0'
    }

    /// Tracking attribute letter (C, W, X, Q, I, P, ...).
    pub fn attribute(self) -> u8 {
        self.0[2]
    }

    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.0).unwrap_or("???")
    }
}

impl std::fmt::Display for ObsCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Carrier frequency \[Hz\] of `band` of `system` (RINEX 3.05 §5.1 Table 4-11 and the
/// systems' ICDs). GLONASS FDMA bands 1 and 2 need the frequency channel `k` (-7..6,
/// from `GLONASS SLOT / FRQ #`): G1 = 1602 + 0.5625 k MHz, G2 = 1246 + 0.4375 k MHz
/// (GLONASS ICD 5.1 §3.3.1.4); None when it is missing or the band unknown.
pub fn carrier_frequency_hz(system: System, band: u8, glonass_channel: Option<i8>) -> Option<f64> {
    let mhz = match (system, band) {
        (System::Gps | System::Qzss | System::Sbas | System::Galileo, 1) => 1575.42,
        (System::Gps | System::Qzss, 2) => 1227.60,
        (System::Gps | System::Qzss | System::Sbas | System::Galileo | System::Navic, 5) => 1176.45,
        (System::Qzss | System::Galileo, 6) => 1278.75,
        (System::Galileo | System::BeiDou, 7) => 1207.14,
        (System::Galileo | System::BeiDou, 8) => 1191.795,
        (System::BeiDou, 1) => 1575.42,
        (System::BeiDou, 2) => 1561.098,
        (System::BeiDou, 5) => 1176.45,
        (System::BeiDou, 6) => 1268.52,
        (System::Glonass, 1) => 1602.0 + 0.5625 * f64::from(glonass_channel?),
        (System::Glonass, 2) => 1246.0 + 0.4375 * f64::from(glonass_channel?),
        (System::Glonass, 3) => 1202.025,
        (System::Glonass, 4) => 1600.995,
        (System::Glonass, 6) => 1248.06,
        (System::Navic, 9) => 2492.028,
        _ => return None,
    };
    Some(mhz * 1e6)
}

/// Tracking attributes of `band` of `system` in order of preference (docs/GNSS.md
/// "Signal selection"); None for a band navfuse does not select from.
pub fn attribute_priority(system: System, band: u8) -> Option<&'static [u8]> {
    let p: &[u8] = match (system, band) {
        // GPS and QZSS (QZSS as GPS): L1 C/A first, then P(Y) semi-codeless, L1C.
        (System::Gps | System::Qzss, 1) => b"CWXPYLS",
        (System::Gps | System::Qzss, 2) => b"WLXSPYCD",
        (System::Gps | System::Qzss, 5) => b"QXI",
        (System::Galileo, 1) => b"CXB",
        (System::Galileo, 5 | 7 | 8) => b"QXI",
        (System::Galileo, 6) => b"CXB",
        // BeiDou: B1I (2), B3I (6), B2I (7) data+pilot; B1C (1) and B2a (5) pilot first.
        (System::BeiDou, 2 | 6 | 7) => b"IXQ",
        (System::BeiDou, 1 | 5) => b"PXD",
        (System::Glonass, 1 | 2) => b"CP",
        (System::Glonass, 3) => b"QXI",
        (System::Sbas, 1) => b"C",
        (System::Sbas, 5) => b"IQX",
        (System::Navic, 5 | 9) => b"ABCX",
        _ => return None,
    };
    Some(p)
}

/// The preferred observation of type `kind` (b'C', b'L', b'D', b'S') on `band` of a
/// satellite, by [`attribute_priority`]; only observations with a value count.
pub fn select(sat: &SatSignals, kind: u8, band: u8) -> Option<(ObsCode, ObsValue)> {
    let order = attribute_priority(sat.sat.system, band)?;
    order.iter().find_map(|&a| {
        let code = ObsCode([kind, b'0' + band, a]);
        sat.get(code)
            .filter(|v| v.value.is_some())
            .map(|v| (code, *v))
    })
}

/// Band pairs tried, in order, for the ionosphere-free code of each system.
pub fn iono_free_bands(system: System) -> &'static [(u8, u8)] {
    match system {
        System::Gps | System::Qzss => &[(1, 2), (1, 5)],
        System::Galileo => &[(1, 5), (1, 7)],
        System::BeiDou => &[(2, 6), (2, 7), (1, 5)],
        System::Glonass => &[(1, 2)],
        System::Sbas => &[(1, 5)],
        System::Navic => &[],
    }
}

/// Ionosphere-free pseudorange combination \[m\] of `p1_m` on `f1_hz` and `p2_m` on
/// `f2_hz` (IS-GPS-200 20.3.3.3.3.3): (f1² P1 − f2² P2) / (f1² − f2²). It removes
/// the first-order ionospheric delay (proportional to 1/f²) and amplifies the code
/// noise about 3 times for L1/L2.
pub fn iono_free_m(p1_m: f64, f1_hz: f64, p2_m: f64, f2_hz: f64) -> f64 {
    let (a, b) = (f1_hz * f1_hz, f2_hz * f2_hz);
    (a * p1_m - b * p2_m) / (a - b)
}

/// An ionosphere-free pseudorange of one satellite with the signals it combines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IonoFreeCode {
    pub pseudorange_m: f64,
    pub first: ObsCode,
    pub second: ObsCode,
}

/// The ionosphere-free code of a satellite from the first band pair of
/// [`iono_free_bands`] with a selected code on both bands; `glonass_channel` is the
/// satellite's frequency channel (GLONASS only). None when no pair is complete.
pub fn iono_free_code(sat: &SatSignals, glonass_channel: Option<i8>) -> Option<IonoFreeCode> {
    let sys = sat.sat.system;
    iono_free_bands(sys).iter().find_map(|&(b1, b2)| {
        let (c1, v1) = select(sat, b'C', b1)?;
        let (c2, v2) = select(sat, b'C', b2)?;
        let f1 = carrier_frequency_hz(sys, b1, glonass_channel)?;
        let f2 = carrier_frequency_hz(sys, b2, glonass_channel)?;
        Some(IonoFreeCode {
            pseudorange_m: iono_free_m(v1.value?, f1, v2.value?, f2),
            first: c1,
            second: c2,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use navfuse_core::sat::SatId;

    fn sat(system: System, obs: &[(&str, f64)]) -> SatSignals {
        SatSignals {
            sat: SatId::new(system, 1),
            signals: obs
                .iter()
                .map(|&(c, v)| (ObsCode::parse(c).unwrap(), ObsValue::new(v)))
                .collect(),
        }
    }

    #[test]
    fn codes_parse() {
        let c = ObsCode::parse("C7I").unwrap();
        assert_eq!((c.kind(), c.band(), c.attribute()), (b'C', 7, b'I'));
        assert_eq!(c.to_string(), "C7I");
        assert_eq!(ObsCode::parse("X1C"), None);
        assert_eq!(ObsCode::parse("C0C"), None);
        assert_eq!(ObsCode::parse("C1"), None);
    }

    #[test]
    fn priority_picks_the_first_present() {
        let s = sat(System::Gps, &[("C1W", 2.0), ("C1C", 1.0), ("C2L", 3.0)]);
        assert_eq!(select(&s, b'C', 1).unwrap().0.to_string(), "C1C");
        assert_eq!(select(&s, b'C', 2).unwrap().0.to_string(), "C2L");
        assert!(select(&s, b'C', 5).is_none());
        let s = sat(System::Gps, &[("C1W", 2.0), ("C2W", 3.0), ("C2L", 4.0)]);
        assert_eq!(select(&s, b'C', 1).unwrap().0.to_string(), "C1W");
        assert_eq!(select(&s, b'C', 2).unwrap().0.to_string(), "C2W");
    }

    #[test]
    fn iono_free_removes_a_1_over_f2_delay() {
        // A true range plus an ionospheric delay I1 on L1 scaled by (f1/f)^2.
        let (f1, f2) = (1575.42e6, 1227.60e6);
        let (rho, i1) = (2.2e7, 7.5);
        let p1 = rho + i1;
        let p2 = rho + i1 * (f1 / f2) * (f1 / f2);
        assert!((iono_free_m(p1, f1, p2, f2) - rho).abs() < 1e-6);
        let s = sat(System::Gps, &[("C1C", p1), ("C2W", p2)]);
        let f = iono_free_code(&s, None).unwrap();
        assert!((f.pseudorange_m - rho).abs() < 1e-6);
        assert_eq!(
            (f.first.to_string(), f.second.to_string()),
            ("C1C".into(), "C2W".into())
        );
        // GLONASS needs its channel.
        let g = sat(System::Glonass, &[("C1C", p1), ("C2C", p2)]);
        assert!(iono_free_code(&g, None).is_none());
        let fg1 = carrier_frequency_hz(System::Glonass, 1, Some(-7)).unwrap();
        assert!((fg1 - 1598.0625e6).abs() < 1.0);
        assert!(iono_free_code(&g, Some(1)).is_some());
    }
}
