//! BeiDou D1/D2 broadcast ephemeris (BeiDou SIS ICD B1I 3.0: §5.2.4.10 clock and
//! relativity, §5.2.4.11 TGD, §5.2.4.12 orbit with the GEO rotation; RINEX 3.05
//! Table A14 for the fields). BDT = GPST - 14 s, BDT week 0 = GPS week 1356
//! (ICD §4.2): toc and toe are kept in BDT, t is converted from GPST.

use super::kepler::{broadcast_state, KeplerOrbit, BEIDOU_CONSTANTS};
use super::SatState;
use crate::time::{wrap_half_week, GpsTime};

/// GPS week of BDT week 0 (2006-01-01 00:00:00 UTC; ICD B1I 3.0 §4.2).
pub const BDT_WEEK0_IN_GPS_WEEKS: i32 = 1356;
/// BDT - GPST \[s\] (the 14 leap seconds between 1980 and 2006).
pub const BDT_MINUS_GPST_S: f64 = -14.0;

/// GPST to BDT (week, seconds of week).
pub fn gpst_to_bdt(t: GpsTime) -> GpsTime {
    GpsTime::new(t.week - BDT_WEEK0_IN_GPS_WEEKS, t.sow).add_s(BDT_MINUS_GPST_S)
}

/// BDT to GPST.
pub fn bdt_to_gpst(t: GpsTime) -> GpsTime {
    GpsTime::new(t.week + BDT_WEEK0_IN_GPS_WEEKS, t.sow).add_s(-BDT_MINUS_GPST_S)
}

/// GEO satellites C01-C05 and C59-C63 (ICD B1I 3.0 §5.2.4.12 "GEO"; the PRN plan of
/// the BDS-2/3 GEOs).
pub fn is_geo(prn: u8) -> bool {
    prn <= 5 || prn >= 59
}

/// One BeiDou ephemeris, SI units, angles radians, times BDT.
#[derive(Clone, Debug, PartialEq)]
pub struct BeiDouEphemeris {
    /// PRN (C01-C63).
    pub prn: u8,
    /// Clock reference time toc (BDT).
    pub toc: GpsTime,
    pub af0_s: f64,
    pub af1_s_per_s: f64,
    pub af2_s_per_s2: f64,
    /// Age of data, ephemeris (AODE).
    pub aode: u16,
    /// Age of data, clock (AODC).
    pub aodc: u16,
    pub orbit: KeplerOrbit,
    /// Ephemeris reference time toe (BDT week + seconds).
    pub toe: GpsTime,
    /// SV accuracy (URA) \[m\].
    pub sv_accuracy_m: f64,
    /// SatH1 (0 = healthy; ICD §5.2.4.6).
    pub sat_h1: u32,
    /// TGD1, B1I \[s\].
    pub tgd1_s: f64,
    /// TGD2, B2I \[s\].
    pub tgd2_s: f64,
    /// Transmission time (BDT), when known.
    pub transmission_time: Option<GpsTime>,
}

impl BeiDouEphemeris {
    pub fn is_geo(&self) -> bool {
        is_geo(self.prn)
    }

    /// Position, velocity and clock at GPST t, ECEF (CGCS2000) at t; relativity
    /// included, TGD not (a B1I user subtracts TGD1, ICD §5.2.4.11).
    pub fn sat_state(&self, t_gpst: GpsTime) -> SatState {
        let t = gpst_to_bdt(t_gpst);
        let af = [self.af0_s, self.af1_s_per_s, self.af2_s_per_s2];
        broadcast_state(
            &self.orbit,
            &BEIDOU_CONSTANTS,
            wrap_half_week(t.diff_s(&self.toe)),
            self.is_geo(),
            af,
            wrap_half_week(t.diff_s(&self.toc)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bdt_conversion() {
        let t = GpsTime::new(2111, 345_600.0);
        let b = gpst_to_bdt(t);
        assert_eq!((b.week, b.sow), (755, 345_586.0));
        assert_eq!(bdt_to_gpst(b), t);
        assert!(is_geo(1) && is_geo(5) && is_geo(59) && !is_geo(6) && !is_geo(58));
    }
}
