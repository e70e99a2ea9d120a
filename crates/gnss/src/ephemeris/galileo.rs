//! Galileo I/NAV and F/NAV broadcast ephemeris (Galileo OS SIS ICD 2.1: §5.1.1
//! orbit, §5.1.3-5.1.4 clock and relativity, §5.1.5 BGD, §5.1.9.3 health and data
//! validity; RINEX 3.05 Table A8 for the fields and the "data sources" bits).
//! GST is aligned to GPST (same week numbering in RINEX, the GGTO of a few ns is
//! ignored here): toc, toe and t are GPS times.

use super::kepler::{broadcast_state, KeplerOrbit, GALILEO_CONSTANTS};
use super::SatState;
use crate::time::{wrap_half_week, GpsTime};

/// Which Galileo message a record came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GalileoMessage {
    /// I/NAV (E1-B and/or E5b-I): clock for E1/E5b, BGD(E1,E5b) for E1 users.
    INav,
    /// F/NAV (E5a-I): clock for E1/E5a, BGD(E1,E5a).
    FNav,
}

/// Health and data-validity bits of the RINEX "SV health" field (RINEX 3.05 Table
/// A8): bit 0 E1-B DVS, 1-2 E1-B HS, 3 E5a DVS, 4-5 E5a HS, 6 E5b DVS, 7-8 E5b HS.
const HEALTH_INAV_MASK: u32 = 0b1_1100_0111;
const HEALTH_FNAV_MASK: u32 = 0b0_0011_1000;

/// One Galileo ephemeris, SI units, angles radians.
#[derive(Clone, Debug, PartialEq)]
pub struct GalileoEphemeris {
    /// PRN (E01-E36).
    pub prn: u8,
    /// Clock reference time toc (GST = GPST).
    pub toc: GpsTime,
    pub af0_s: f64,
    pub af1_s_per_s: f64,
    pub af2_s_per_s2: f64,
    /// Issue of data of the navigation batch, IODnav.
    pub iodnav: u16,
    pub orbit: KeplerOrbit,
    /// Ephemeris reference time toe (GST week + seconds).
    pub toe: GpsTime,
    /// RINEX "data sources" bits (0: I/NAV E1-B, 1: F/NAV E5a-I, 2: I/NAV E5b-I,
    /// 8: clock for E5a,E1, 9: clock for E5b,E1).
    pub data_sources: u32,
    /// Signal-in-space accuracy SISA \[m\] (RINEX gives metres; -1 / 0 = unknown, NAPA).
    pub sisa_m: f64,
    /// RINEX "SV health" bits (see `HEALTH_INAV_MASK`).
    pub health: u32,
    /// BGD(E1,E5a) \[s\].
    pub bgd_e1_e5a_s: f64,
    /// BGD(E1,E5b) \[s\].
    pub bgd_e1_e5b_s: f64,
    /// Transmission time of the message (GST), when known.
    pub transmission_time: Option<GpsTime>,
}

impl GalileoEphemeris {
    /// F/NAV when data-source bit 1 is set, else I/NAV (RINEX 3.05 Table A8).
    pub fn message(&self) -> GalileoMessage {
        if self.data_sources & 0b10 != 0 {
            GalileoMessage::FNav
        } else {
            GalileoMessage::INav
        }
    }

    /// Healthy and valid on the message's signals: HS = 0 and DVS = 0 on E1-B and E5b
    /// for I/NAV, on E5a for F/NAV (OS SIS ICD 2.1 §5.1.9.3, §2.3 of the SDD).
    pub fn healthy(&self) -> bool {
        let mask = match self.message() {
            GalileoMessage::INav => HEALTH_INAV_MASK,
            GalileoMessage::FNav => HEALTH_FNAV_MASK,
        };
        self.health & mask == 0
    }

    /// The E1 single-frequency group delay: BGD(E1,E5b) for I/NAV, BGD(E1,E5a) for
    /// F/NAV (OS SIS ICD 2.1 §5.1.5: dt_sv(E1) = dt_sv - BGD).
    pub fn group_delay_s(&self) -> f64 {
        match self.message() {
            GalileoMessage::INav => self.bgd_e1_e5b_s,
            GalileoMessage::FNav => self.bgd_e1_e5a_s,
        }
    }

    /// Position, velocity and clock at GPST (= GST) t, ECEF at t; the clock includes
    /// the relativistic term, not the BGD.
    pub fn sat_state(&self, t: GpsTime) -> SatState {
        let af = [self.af0_s, self.af1_s_per_s, self.af2_s_per_s2];
        broadcast_state(
            &self.orbit,
            &GALILEO_CONSTANTS,
            wrap_half_week(t.diff_s(&self.toe)),
            false,
            af,
            wrap_half_week(t.diff_s(&self.toc)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ephemeris::kepler::KeplerOrbit;

    fn eph(data_sources: u32, health: u32) -> GalileoEphemeris {
        let t = GpsTime::new(2111, 345_600.0);
        GalileoEphemeris {
            prn: 1,
            toc: t,
            af0_s: 0.0,
            af1_s_per_s: 0.0,
            af2_s_per_s2: 0.0,
            iodnav: 0,
            orbit: KeplerOrbit {
                sqrt_a_sqrt_m: 5_440.6,
                i0_rad: 0.98,
                toe_sow_s: t.sow,
                ..KeplerOrbit::ZERO
            },
            toe: t,
            data_sources,
            sisa_m: 3.12,
            health,
            bgd_e1_e5a_s: 1e-9,
            bgd_e1_e5b_s: 2e-9,
            transmission_time: None,
        }
    }

    #[test]
    fn message_health_and_bgd() {
        // 258 = I/NAV E5b + clock for E5b,E1; 513 = I/NAV E1-B + E5b,E1.
        let inav = eph(513, 0);
        assert_eq!(inav.message(), GalileoMessage::INav);
        assert_eq!(inav.group_delay_s(), 2e-9);
        let fnav = eph(258, 0);
        assert_eq!(fnav.message(), GalileoMessage::FNav);
        assert_eq!(fnav.group_delay_s(), 1e-9);
        // E5a unhealthy (bits 4-5) does not concern I/NAV; E1-B DVS (bit 0) does.
        assert!(eph(513, 0b11_0000).healthy() && !eph(258, 0b11_0000).healthy());
        assert!(!eph(513, 1).healthy() && eph(258, 1).healthy());
        // Circular orbit: radius A.
        let s = inav.sat_state(inav.toe.add_s(600.0));
        assert!((s.pos_ecef_m.norm() - 5_440.6f64.powi(2)).abs() < 1e-3);
    }
}
