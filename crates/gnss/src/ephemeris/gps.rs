//! GPS LNAV broadcast ephemeris and the satellite state it gives (IS-GPS-200,
//! 20.3.3.3 clock, 20.3.3.4 ephemeris, Table 20-IV algorithm).
//!
//! Angles are radians and rates radians per second, as RINEX stores them (RINEX 3.04
//! Table A4 gives "radians"; the navigation message itself uses semicircles, which a
//! decoder multiplies by pi before filling this struct).

use super::kepler::{broadcast_state, KeplerConstants, KeplerOrbit, GPS_CONSTANTS};
use crate::time::{wrap_half_week, GpsTime};
use nalgebra::Vector3;

/// WGS-84 gravitational constant as used by GPS, mu [m^3/s^2] (IS-GPS-200 Table 20-IV).
pub const GPS_MU_M3_PER_S2: f64 = GPS_CONSTANTS.mu_m3_per_s2;
/// WGS-84 Earth rotation rate as used by GPS [rad/s] (IS-GPS-200 Table 20-IV).
pub const GPS_OMEGA_E_RAD_PER_S: f64 = GPS_CONSTANTS.omega_e_rad_per_s;
/// Relativistic constant F = -2 sqrt(mu)/c^2 [s/sqrt(m)] (IS-GPS-200 20.3.3.3.3.1).
pub const GPS_F_S_PER_SQRT_M: f64 = GPS_CONSTANTS.f_s_per_sqrt_m;
/// Speed of light [m/s] (IS-GPS-200 20.3.4.3).
pub const SPEED_OF_LIGHT_MPS: f64 = 299_792_458.0;
/// pi exactly as IS-GPS-200 20.3.3.4.3 specifies it for semicircle conversion.
#[allow(clippy::approx_constant)] // the ICD's truncated value, on purpose
pub const GPS_PI: f64 = 3.141_592_653_589_8;

/// One GPS LNAV broadcast ephemeris (subframes 1-3), units SI, angles radians.
#[derive(Clone, Debug, PartialEq)]
pub struct GpsEphemeris {
    /// PRN 1-32 (up to 63 accepted).
    pub prn: u8,
    /// Clock reference time toc (GPST).
    pub toc: GpsTime,
    /// Clock bias af0 \[s\].
    pub af0_s: f64,
    /// Clock drift af1 [s/s].
    pub af1_s_per_s: f64,
    /// Clock drift rate af2 [s/s^2].
    pub af2_s_per_s2: f64,
    /// Issue of data, ephemeris.
    pub iode: u16,
    /// Sine harmonic correction to the orbit radius Crs \[m\].
    pub crs_m: f64,
    /// Mean motion difference Delta n [rad/s].
    pub delta_n_rad_per_s: f64,
    /// Mean anomaly at toe M0 \[rad\].
    pub m0_rad: f64,
    /// Cosine harmonic correction to the argument of latitude Cuc \[rad\].
    pub cuc_rad: f64,
    /// Eccentricity e [-].
    pub e: f64,
    /// Sine harmonic correction to the argument of latitude Cus \[rad\].
    pub cus_rad: f64,
    /// Square root of the semi-major axis [sqrt(m)].
    pub sqrt_a_sqrt_m: f64,
    /// Ephemeris reference time toe (GPS week of the ephemeris + toe seconds of week).
    pub toe: GpsTime,
    /// Cosine harmonic correction to inclination Cic \[rad\].
    pub cic_rad: f64,
    /// Longitude of the ascending node at the weekly epoch, Omega0 \[rad\].
    pub omega0_rad: f64,
    /// Sine harmonic correction to inclination Cis \[rad\].
    pub cis_rad: f64,
    /// Inclination at toe i0 \[rad\].
    pub i0_rad: f64,
    /// Cosine harmonic correction to the orbit radius Crc \[m\].
    pub crc_m: f64,
    /// Argument of perigee omega \[rad\].
    pub omega_rad: f64,
    /// Rate of right ascension Omega_dot [rad/s].
    pub omega_dot_rad_per_s: f64,
    /// Rate of inclination IDOT [rad/s].
    pub idot_rad_per_s: f64,
    /// Codes on L2 channel (RINEX field).
    pub codes_l2: f64,
    /// L2 P data flag (RINEX field).
    pub l2p_flag: f64,
    /// SV accuracy (URA) \[m\].
    pub sv_accuracy_m: f64,
    /// SV health (0 = all signals OK; IS-GPS-200 20.3.3.3.1.4).
    pub health: u32,
    /// Group delay TGD \[s\] (IS-GPS-200 20.3.3.3.3.2): L1 C/A users subtract it from
    /// the clock bias; it is not included in [`SatState::clock_bias_s`].
    pub tgd_s: f64,
    /// Issue of data, clock.
    pub iodc: u16,
    /// Transmission time of the message (GPST), when known.
    pub transmission_time: Option<GpsTime>,
    /// Fit interval \[h\] (RINEX 3.04 gives hours; 0 = unknown, read as 4 h).
    pub fit_interval_h: f64,
}

/// Satellite state at one instant (ECEF at time t = the ECEF frame at that instant).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SatState {
    /// Antenna phase centre position in ECEF at t \[m\] (LNAV refers to the APC).
    pub pos_ecef_m: Vector3<f64>,
    /// Velocity relative to the rotating ECEF frame at t [m/s].
    pub vel_ecef_mps: Vector3<f64>,
    /// af0 + af1 dt + af2 dt^2 + relativistic \[s\]; TGD not included.
    pub clock_bias_s: f64,
    /// Time derivative of clock_bias_s (including the relativistic term) [s/s].
    pub clock_drift_s_per_s: f64,
    /// Relativistic term F e sqrt(A) sin(Ek) \[s\] (IS-GPS-200 20.3.3.3.3.1).
    pub relativistic_s: f64,
}

impl GpsEphemeris {
    /// A healthy ephemeris with every field zero except `prn`, `toc` and `toe`.
    pub fn zeroed(prn: u8, toe: GpsTime) -> Self {
        GpsEphemeris {
            prn,
            toc: toe,
            af0_s: 0.0,
            af1_s_per_s: 0.0,
            af2_s_per_s2: 0.0,
            iode: 0,
            crs_m: 0.0,
            delta_n_rad_per_s: 0.0,
            m0_rad: 0.0,
            cuc_rad: 0.0,
            e: 0.0,
            cus_rad: 0.0,
            sqrt_a_sqrt_m: 0.0,
            toe,
            cic_rad: 0.0,
            omega0_rad: 0.0,
            cis_rad: 0.0,
            i0_rad: 0.0,
            crc_m: 0.0,
            omega_rad: 0.0,
            omega_dot_rad_per_s: 0.0,
            idot_rad_per_s: 0.0,
            codes_l2: 0.0,
            l2p_flag: 0.0,
            sv_accuracy_m: 0.0,
            health: 0,
            tgd_s: 0.0,
            iodc: 0,
            transmission_time: None,
            fit_interval_h: 4.0,
        }
    }

    /// Fit interval \[s\]; 0 (unknown) is read as 4 h (IS-GPS-200 20.3.4.4, fit flag 0).
    pub fn fit_interval_s(&self) -> f64 {
        if self.fit_interval_h > 0.0 {
            self.fit_interval_h * 3_600.0
        } else {
            4.0 * 3_600.0
        }
    }

    /// Satellite clock polynomial without the relativistic term, and its derivative,
    /// at t (IS-GPS-200 20.3.3.3.3.1; t - toc wrapped to +-302400 s). The polynomial
    /// is evaluated at GPST t rather than at the SV time, a < 1e-12 s difference.
    pub fn clock_poly(&self, t: GpsTime) -> (f64, f64) {
        let dt = wrap_half_week(t.diff_s(&self.toc));
        let bias = self.af0_s + (self.af1_s_per_s + self.af2_s_per_s2 * dt) * dt;
        let drift = self.af1_s_per_s + 2.0 * self.af2_s_per_s2 * dt;
        (bias, drift)
    }

    /// The Keplerian elements (shared with QZSS, Galileo and BeiDou: `kepler`).
    pub fn orbit(&self) -> KeplerOrbit {
        KeplerOrbit {
            sqrt_a_sqrt_m: self.sqrt_a_sqrt_m,
            e: self.e,
            i0_rad: self.i0_rad,
            omega0_rad: self.omega0_rad,
            omega_rad: self.omega_rad,
            m0_rad: self.m0_rad,
            delta_n_rad_per_s: self.delta_n_rad_per_s,
            omega_dot_rad_per_s: self.omega_dot_rad_per_s,
            idot_rad_per_s: self.idot_rad_per_s,
            cuc_rad: self.cuc_rad,
            cus_rad: self.cus_rad,
            crc_m: self.crc_m,
            crs_m: self.crs_m,
            cic_rad: self.cic_rad,
            cis_rad: self.cis_rad,
            toe_sow_s: self.toe.sow,
        }
    }

    /// This ephemeris with the Keplerian elements of `o` (its `toe_sow_s` is not
    /// used: `toe` carries the week too).
    pub fn with_orbit(mut self, o: &KeplerOrbit) -> Self {
        self.sqrt_a_sqrt_m = o.sqrt_a_sqrt_m;
        self.e = o.e;
        self.i0_rad = o.i0_rad;
        self.omega0_rad = o.omega0_rad;
        self.omega_rad = o.omega_rad;
        self.m0_rad = o.m0_rad;
        self.delta_n_rad_per_s = o.delta_n_rad_per_s;
        self.omega_dot_rad_per_s = o.omega_dot_rad_per_s;
        self.idot_rad_per_s = o.idot_rad_per_s;
        self.cuc_rad = o.cuc_rad;
        self.cus_rad = o.cus_rad;
        self.crc_m = o.crc_m;
        self.crs_m = o.crs_m;
        self.cic_rad = o.cic_rad;
        self.cis_rad = o.cis_rad;
        self
    }

    /// Position, velocity and clock at GPST t in the ECEF frame at t
    /// (IS-GPS-200 Table 20-IV; velocity by the analytic time derivative of each step).
    pub fn sat_state(&self, t: GpsTime) -> SatState {
        self.sat_state_with(&GPS_CONSTANTS, t)
    }

    /// [`Self::sat_state`] with another system's constants (QZSS LNAV: IS-QZSS-PNT
    /// §4.1.2, the same algorithm; t and the message's times in the same time scale).
    pub fn sat_state_with(&self, k: &KeplerConstants, t: GpsTime) -> SatState {
        // Clock (20.3.3.3.3.1): polynomial + relativistic F e sqrt(A) sin Ek.
        let af = [self.af0_s, self.af1_s_per_s, self.af2_s_per_s2];
        let dt = wrap_half_week(t.diff_s(&self.toc));
        broadcast_state(
            &self.orbit(),
            k,
            wrap_half_week(t.diff_s(&self.toe)),
            false,
            af,
            dt,
        )
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// G32 of the walk_0827 navigation file (2025-08-28 18:00 GPST), typed in.
    pub(crate) fn g32() -> GpsEphemeris {
        let toe = GpsTime::new(2381, 410_400.0);
        GpsEphemeris {
            prn: 32,
            toc: toe,
            af0_s: -0.344484578818e-03,
            af1_s_per_s: 0.131876731757e-10,
            af2_s_per_s2: 0.0,
            iode: 83,
            crs_m: -0.167812500000e+02,
            delta_n_rad_per_s: 0.471448209139e-08,
            m0_rad: 0.273480178381e+01,
            cuc_rad: -0.897794961929e-06,
            e: 0.863428541925e-02,
            cus_rad: 0.561214983463e-05,
            sqrt_a_sqrt_m: 0.515364527702e+04,
            toe,
            cic_rad: 0.111758708954e-07,
            omega0_rad: 0.224492021439e+01,
            cis_rad: -0.162050127983e-06,
            i0_rad: 0.965781992719e+00,
            crc_m: 0.271718750000e+03,
            omega_rad: -0.206125929204e+01,
            omega_dot_rad_per_s: -0.795997442203e-08,
            idot_rad_per_s: 0.971469037013e-10,
            codes_l2: 1.0,
            l2p_flag: 0.0,
            sv_accuracy_m: 2.0,
            health: 0,
            tgd_s: 0.931322574615e-09,
            iodc: 83,
            transmission_time: Some(GpsTime::new(2381, 408_756.0)),
            fit_interval_h: 4.0,
        }
    }

    #[test]
    fn orbit_radius_and_speed() {
        let eph = g32();
        for k in -8..=8 {
            let s = eph.sat_state(eph.toe.add_s(f64::from(k) * 900.0));
            let r = s.pos_ecef_m.norm();
            assert!((r - 26_560e3).abs() < 250e3, "r = {r}");
            // Inertial speed ~3.87 km/s; ECEF speed 1.8-4.2 km/s for a GPS orbit.
            let v = s.vel_ecef_mps.norm();
            assert!((1_500.0..4_500.0).contains(&v), "v = {v}");
        }
    }

    #[test]
    fn velocity_is_derivative_of_position() {
        let eph = g32();
        let h = 0.01;
        for k in -7..=7 {
            let t = eph.toe.add_s(f64::from(k) * 1_000.0 + 0.3);
            let s = eph.sat_state(t);
            let p1 = eph.sat_state(t.add_s(h)).pos_ecef_m;
            let p0 = eph.sat_state(t.add_s(-h)).pos_ecef_m;
            let fd = (p1 - p0) / (2.0 * h);
            assert!(
                (fd - s.vel_ecef_mps).norm() < 1e-3,
                "k={k}: {}",
                (fd - s.vel_ecef_mps).norm()
            );
            let c1 = eph.sat_state(t.add_s(h)).clock_bias_s;
            let c0 = eph.sat_state(t.add_s(-h)).clock_bias_s;
            assert!(((c1 - c0) / (2.0 * h) - s.clock_drift_s_per_s).abs() < 1e-14);
        }
    }

    #[test]
    fn clock_terms() {
        let mut eph = g32();
        eph.af2_s_per_s2 = 1e-18;
        let t = eph.toc.add_s(1_000.0);
        let s = eph.sat_state(t);
        let poly = eph.af0_s + eph.af1_s_per_s * 1_000.0 + 1e-18 * 1e6;
        assert!((s.clock_bias_s - s.relativistic_s - poly).abs() < 1e-18);
        // |F e sqrt(A)| bounds the relativistic term: 2.0e-8 s for e = 0.0086.
        let bound = GPS_F_S_PER_SQRT_M.abs() * eph.e * eph.sqrt_a_sqrt_m;
        assert!(s.relativistic_s.abs() <= bound && bound < 2.0e-8);
        // toc across a week boundary: t - toc wraps.
        eph.toc = GpsTime::new(2381, 604_000.0);
        let (b, _) = eph.clock_poly(GpsTime::new(2382, 200.0));
        let dt = 1_000.0;
        assert!((b - (eph.af0_s + eph.af1_s_per_s * dt + 1e-18 * dt * dt)).abs() < 1e-18);
    }

    #[test]
    fn circular_equatorial_orbit_closed_form() {
        // e = 0, i = 0, no corrections: r = A, angle = M0 + n tk + Omega0 - We (tk + toe).
        let toe = GpsTime::new(2000, 0.0);
        let mut eph = GpsEphemeris::zeroed(1, toe);
        eph.sqrt_a_sqrt_m = 5_153.6;
        let a = 5_153.6f64 * 5_153.6;
        let n = (GPS_MU_M3_PER_S2 / (a * a * a)).sqrt();
        let tk = 600.0;
        let s = eph.sat_state(toe.add_s(tk));
        let ang = n * tk - GPS_OMEGA_E_RAD_PER_S * tk;
        assert!((s.pos_ecef_m - Vector3::new(a * ang.cos(), a * ang.sin(), 0.0)).norm() < 1e-6);
        let speed = a * (n - GPS_OMEGA_E_RAD_PER_S);
        assert!((s.vel_ecef_mps.norm() - speed).abs() < 1e-9);
    }
}
