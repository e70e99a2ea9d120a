//! Broadcast ephemerides of every system, one file per message family:
//! `gps` (GPS LNAV, also QZSS LNAV), `kepler` (the Keplerian orbit shared by GPS,
//! QZSS, Galileo and BeiDou, with each system's constants), `galileo` (I/NAV,
//! F/NAV), `beidou` (D1/D2, GEO rotation), `glonass` (FDMA state vectors, Runge-Kutta).
//! [`Ephemeris`] gives one face to all of them: `sat_state(t)` with t in GPST.
//! See docs/GNSS.md "Ephemerides of every system".

pub mod beidou;
pub mod galileo;
pub mod glonass;
mod gps;
pub mod kepler;

pub use beidou::BeiDouEphemeris;
pub use galileo::{GalileoEphemeris, GalileoMessage};
pub use glonass::GlonassEphemeris;
pub use gps::*;
use navfuse_core::sat::{SatId, System};

#[cfg(test)]
pub(crate) use gps::tests;

/// Largest |t - toe| used for a Galileo ephemeris \[s\]: 4 h, the validity RTKLIB uses
/// (MAXDTOE_GAL); batches are refreshed every 10 min (Galileo OS SDD §2.3).
pub const GALILEO_MAX_AGE_S: f64 = 4.0 * 3_600.0;
/// Largest |t - toe| for BeiDou \[s\]: 6 h (RTKLIB MAXDTOE_CMP; updated hourly, ICD
/// B1I 3.0 §5.2.4.8).
pub const BEIDOU_MAX_AGE_S: f64 = 6.0 * 3_600.0;
/// Largest |t - tb| for GLONASS \[s\]: 15 min, half the 30-min tb interval (ICD 5.1
/// §4.4: the immediate data refer to the middle of the interval).
pub const GLONASS_MAX_AGE_S: f64 = 15.0 * 60.0;

impl GpsEphemeris {
    /// `Ephemeris::band_group_delay_s` of an LNAV record of `system` (GPS or QZSS).
    pub fn band_group_delay_s(&self, system: System, band: u8) -> Option<f64> {
        let f = |b: u8| crate::signal::carrier_frequency_hz(system, b, None);
        match band {
            1 => Some(self.tgd_s),
            2 | 5 => Some((f(1)? / f(band)?).powi(2) * self.tgd_s),
            _ => None,
        }
    }
}

/// A broadcast ephemeris of any system.
#[derive(Clone, Debug, PartialEq)]
pub enum Ephemeris {
    Gps(GpsEphemeris),
    /// QZSS LNAV: the GPS message with QZSS constants (`prn` is the J number).
    Qzss(GpsEphemeris),
    Galileo(GalileoEphemeris),
    BeiDou(BeiDouEphemeris),
    Glonass(GlonassEphemeris),
}

impl Ephemeris {
    /// The satellite.
    pub fn sat(&self) -> SatId {
        match self {
            Ephemeris::Gps(e) => SatId::new(System::Gps, e.prn),
            Ephemeris::Qzss(e) => SatId::new(System::Qzss, e.prn),
            Ephemeris::Galileo(e) => SatId::new(System::Galileo, e.prn),
            Ephemeris::BeiDou(e) => SatId::new(System::BeiDou, e.prn),
            Ephemeris::Glonass(e) => SatId::new(System::Glonass, e.slot),
        }
    }

    /// Reference time of the orbit (toe; GLONASS tb) in GPST.
    pub fn toe_gpst(&self) -> GpsTime {
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => e.toe,
            Ephemeris::Galileo(e) => e.toe,
            Ephemeris::BeiDou(e) => beidou::bdt_to_gpst(e.toe),
            Ephemeris::Glonass(e) => e.tb,
        }
    }

    /// Transmission time in GPST, when the record gives it.
    pub fn transmission_time_gpst(&self) -> Option<GpsTime> {
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => e.transmission_time,
            Ephemeris::Galileo(e) => e.transmission_time,
            Ephemeris::BeiDou(e) => e.transmission_time.map(beidou::bdt_to_gpst),
            Ephemeris::Glonass(_) => None,
        }
    }

    /// Largest |t - toe| at which the record is used \[s\]: half the fit interval
    /// for GPS and QZSS (IS-GPS-200 20.3.4.4, IS-QZSS-PNT §4.1.2.7), else the
    /// constants above.
    pub fn max_age_s(&self) -> f64 {
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => 0.5 * e.fit_interval_s(),
            Ephemeris::Galileo(_) => GALILEO_MAX_AGE_S,
            Ephemeris::BeiDou(_) => BEIDOU_MAX_AGE_S,
            Ephemeris::Glonass(_) => GLONASS_MAX_AGE_S,
        }
    }

    /// Healthy: GPS/QZSS health 0, Galileo HS/DVS of the message's signals 0,
    /// BeiDou SatH1 0, GLONASS Bn 0.
    pub fn healthy(&self) -> bool {
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => e.health == 0,
            Ephemeris::Galileo(e) => e.healthy(),
            Ephemeris::BeiDou(e) => e.sat_h1 == 0,
            Ephemeris::Glonass(e) => e.health == 0,
        }
    }

    /// Issue of data: IODE (GPS, QZSS), IODnav (Galileo), AODE (BeiDou), tb index
    /// (GLONASS).
    pub fn iod(&self) -> u16 {
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => e.iode,
            Ephemeris::Galileo(e) => e.iodnav,
            Ephemeris::BeiDou(e) => e.aode,
            Ephemeris::Glonass(e) => e.iod(),
        }
    }

    /// Group delay a single-frequency user of the system's first civil signal
    /// subtracts from the clock \[s\]: TGD (GPS/QZSS L1 C/A), BGD (Galileo E1, per
    /// message), TGD1 (BeiDou B1I), 0 for GLONASS (tau_n refers to L1; RINEX 3 has no
    /// delta tau_n).
    pub fn group_delay_s(&self) -> f64 {
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => e.tgd_s,
            Ephemeris::Galileo(e) => e.group_delay_s(),
            Ephemeris::BeiDou(e) => e.tgd1_s,
            Ephemeris::Glonass(_) => 0.0,
        }
    }

    /// Group delay of a signal on `band` (RINEX band digit) relative to the clock
    /// the record broadcasts \[s\], subtracted from the clock by a single-frequency
    /// user: GPS/QZSS LNAV (clock of L1/L2 P(Y)) L1 TGD, L2 (f1/f2)^2 TGD
    /// (IS-GPS-200 20.3.3.3.3.2), L5 taken as (f1/f5)^2 TGD (its ISC is in CNAV, not
    /// in these records); Galileo I/NAV (clock of E1/E5b) E1 BGD_b, E5b (f1/f7)^2
    /// BGD_b, E5a BGD_b - BGD_a + (f1/f5)^2 BGD_a, and F/NAV the same with a and b
    /// exchanged (OS SIS ICD 2.1 §5.1.5); BeiDou D1/D2 (clock of B3I) B1I TGD1, B2I
    /// TGD2, B3I 0 (B1I ICD 3.0 §5.2.4.8); GLONASS 0. None for a band without a
    /// delay in the record (BeiDou B1C/B2a, Galileo E6).
    pub fn band_group_delay_s(&self, band: u8) -> Option<f64> {
        use crate::signal::carrier_frequency_hz;
        let sys = self.sat().system;
        let gamma = |b: u8| -> Option<f64> {
            let f1 = carrier_frequency_hz(sys, 1, None)?;
            Some((f1 / carrier_frequency_hz(sys, b, None)?).powi(2))
        };
        match self {
            Ephemeris::Gps(e) | Ephemeris::Qzss(e) => e.band_group_delay_s(sys, band),
            Ephemeris::Galileo(e) => {
                let (own, other, own_band) = match e.message() {
                    GalileoMessage::INav => (e.bgd_e1_e5b_s, e.bgd_e1_e5a_s, 7),
                    GalileoMessage::FNav => (e.bgd_e1_e5a_s, e.bgd_e1_e5b_s, 5),
                };
                match band {
                    1 => Some(own),
                    b if b == own_band => Some(gamma(b)? * own),
                    5 | 7 => Some(own - other + gamma(band)? * other),
                    _ => None,
                }
            }
            Ephemeris::BeiDou(e) => match band {
                2 => Some(e.tgd1_s),
                7 => Some(e.tgd2_s),
                6 => Some(0.0),
                _ => None,
            },
            Ephemeris::Glonass(_) => Some(0.0),
        }
    }

    /// Position, velocity and clock (bias incl. relativity, drift) at GPST t in the
    /// ECEF frame at t; the group delay is not applied.
    pub fn sat_state(&self, t: GpsTime) -> SatState {
        match self {
            Ephemeris::Gps(e) => e.sat_state(t),
            Ephemeris::Qzss(e) => e.sat_state_with(&kepler::QZSS_CONSTANTS, t),
            Ephemeris::Galileo(e) => e.sat_state(t),
            Ephemeris::BeiDou(e) => e.sat_state(t),
            Ephemeris::Glonass(e) => e.sat_state(t),
        }
    }
}

use crate::time::GpsTime;
