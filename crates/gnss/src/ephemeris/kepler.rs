//! The Keplerian broadcast orbit shared by GPS LNAV, QZSS LNAV, Galileo I/NAV and
//! F/NAV and BeiDou D1/D2: IS-GPS-200 Table 20-IV, Galileo OS SIS ICD 2.1 §5.1.1
//! Table 58, BeiDou SIS ICD B1I 3.0 §5.2.4.12 Table 5-11, IS-QZSS-PNT §4.1.2
//! (the GPS algorithm). Each system has its own mu, Omega_e and relativistic F.
//!
//! The velocity is the analytic time derivative of every step (docs/GNSS.md).

use nalgebra::{Matrix3, Vector3};

/// Convergence limit of the Kepler iteration [rad].
const KEPLER_TOL_RAD: f64 = 1e-13;
const KEPLER_MAX_ITER: usize = 30;

/// A system's constants for the Keplerian orbit and its relativistic clock term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeplerConstants {
    /// Gravitational constant mu [m^3/s^2].
    pub mu_m3_per_s2: f64,
    /// Earth rotation rate Omega_e [rad/s].
    pub omega_e_rad_per_s: f64,
    /// Relativistic constant F = -2 sqrt(mu) / c^2 [s/sqrt(m)].
    pub f_s_per_sqrt_m: f64,
}

/// GPS (IS-GPS-200 Table 20-IV and 20.3.3.3.3.1).
pub const GPS_CONSTANTS: KeplerConstants = KeplerConstants {
    mu_m3_per_s2: 3.986_005e14,
    omega_e_rad_per_s: 7.292_115_146_7e-5,
    f_s_per_sqrt_m: -4.442_807_633e-10,
};
/// QZSS: the GPS values (IS-QZSS-PNT §4.1.2.3 Table 4.1.2-4 uses WGS-84 as GPS).
pub const QZSS_CONSTANTS: KeplerConstants = GPS_CONSTANTS;
/// Galileo (OS SIS ICD 2.1 §5.1.1 Table 58; F from §5.1.4: -2 sqrt(mu)/c^2).
pub const GALILEO_CONSTANTS: KeplerConstants = KeplerConstants {
    mu_m3_per_s2: 3.986_004_418e14,
    omega_e_rad_per_s: 7.292_115_146_7e-5,
    f_s_per_sqrt_m: -4.442_807_309e-10,
};
/// BeiDou, CGCS2000 (SIS ICD B1I 3.0 §5.2.4.12 Table 5-11; F from §5.2.4.10).
pub const BEIDOU_CONSTANTS: KeplerConstants = KeplerConstants {
    mu_m3_per_s2: 3.986_004_418e14,
    omega_e_rad_per_s: 7.292_115_0e-5,
    f_s_per_sqrt_m: -4.442_807_309e-10,
};

/// BeiDou GEO inclination of the intermediate frame: -5 deg about x (SIS ICD B1I 3.0
/// §5.2.4.12, R_X(-5 deg)).
const BDS_GEO_TILT_RAD: f64 = -5.0 * std::f64::consts::PI / 180.0;

/// The Keplerian elements of one broadcast message, angles radians, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeplerOrbit {
    pub sqrt_a_sqrt_m: f64,
    pub e: f64,
    pub i0_rad: f64,
    pub omega0_rad: f64,
    pub omega_rad: f64,
    pub m0_rad: f64,
    pub delta_n_rad_per_s: f64,
    pub omega_dot_rad_per_s: f64,
    pub idot_rad_per_s: f64,
    pub cuc_rad: f64,
    pub cus_rad: f64,
    pub crc_m: f64,
    pub crs_m: f64,
    pub cic_rad: f64,
    pub cis_rad: f64,
    /// toe, seconds of the system's week \[s\] (enters Omega_k as -Omega_e toe).
    pub toe_sow_s: f64,
}

impl KeplerOrbit {
    /// Every element zero (a start for `KeplerOrbit { sqrt_a_sqrt_m, .., ..ZERO }`).
    pub const ZERO: KeplerOrbit = KeplerOrbit {
        sqrt_a_sqrt_m: 0.0,
        e: 0.0,
        i0_rad: 0.0,
        omega0_rad: 0.0,
        omega_rad: 0.0,
        m0_rad: 0.0,
        delta_n_rad_per_s: 0.0,
        omega_dot_rad_per_s: 0.0,
        idot_rad_per_s: 0.0,
        cuc_rad: 0.0,
        cus_rad: 0.0,
        crc_m: 0.0,
        crs_m: 0.0,
        cic_rad: 0.0,
        cis_rad: 0.0,
        toe_sow_s: 0.0,
    };
}

/// Position and velocity (ECEF at t) with what the clock's relativistic term needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeplerState {
    pub pos_ecef_m: Vector3<f64>,
    pub vel_ecef_mps: Vector3<f64>,
    /// sin E_k, cos E_k and dE_k/dt [rad/s].
    pub sin_e: f64,
    pub cos_e: f64,
    pub ek_dot_rad_per_s: f64,
}

/// Eccentric anomaly from mean anomaly by Newton iteration (IS-GPS-200 Table 20-IV,
/// Kepler's equation M = E - e sin E) to 1e-13 rad.
pub(crate) fn solve_kepler(m_rad: f64, e: f64) -> f64 {
    let mut ek = m_rad;
    for _ in 0..KEPLER_MAX_ITER {
        let f = ek - e * ek.sin() - m_rad;
        let d = f / (1.0 - e * ek.cos());
        ek -= d;
        if d.abs() < KEPLER_TOL_RAD {
            break;
        }
    }
    ek
}

impl KeplerOrbit {
    /// Relativistic clock term F e sqrt(A) sin E_k and its rate (IS-GPS-200
    /// 20.3.3.3.3.1; Galileo OS SIS ICD §5.1.4; BeiDou B1I ICD §5.2.4.10) [s, s/s].
    pub fn relativistic(&self, k: &KeplerConstants, s: &KeplerState) -> (f64, f64) {
        let c = k.f_s_per_sqrt_m * self.e * self.sqrt_a_sqrt_m;
        (c * s.sin_e, c * s.cos_e * s.ek_dot_rad_per_s)
    }

    /// The state tk seconds after toe (tk already wrapped to +-half a week).
    /// `bds_geo`: a BeiDou GEO satellite, computed in the ICD's intermediate frame and
    /// rotated by R_Z(Omega_e tk) R_X(-5 deg) (SIS ICD B1I 3.0 §5.2.4.12).
    pub fn state(&self, k: &KeplerConstants, tk: f64, bds_geo: bool) -> KeplerState {
        let we = k.omega_e_rad_per_s;
        let a = self.sqrt_a_sqrt_m * self.sqrt_a_sqrt_m;
        let n0 = (k.mu_m3_per_s2 / (a * a * a)).sqrt();
        let n = n0 + self.delta_n_rad_per_s;
        let mk = self.m0_rad + n * tk;
        let ek = solve_kepler(mk, self.e);
        let (sin_e, cos_e) = ek.sin_cos();
        let one_m_ecos = 1.0 - self.e * cos_e;
        let sq1me2 = (1.0 - self.e * self.e).sqrt();
        // True anomaly and argument of latitude (Table 20-IV).
        let vk = (sq1me2 * sin_e).atan2(cos_e - self.e);
        let phik = vk + self.omega_rad;
        let (s2p, c2p) = (2.0 * phik).sin_cos();
        let duk = self.cus_rad * s2p + self.cuc_rad * c2p;
        let drk = self.crs_m * s2p + self.crc_m * c2p;
        let dik = self.cis_rad * s2p + self.cic_rad * c2p;
        let uk = phik + duk;
        let rk = a * one_m_ecos + drk;
        let ik = self.i0_rad + dik + self.idot_rad_per_s * tk;
        let (sin_u, cos_u) = uk.sin_cos();
        let xp = rk * cos_u;
        let yp = rk * sin_u;
        // Corrected longitude of the ascending node: in the ECEF frame at t, or (GEO)
        // in the intermediate inertial-like frame without -Omega_e tk.
        let omega_dot_k = if bds_geo {
            self.omega_dot_rad_per_s
        } else {
            self.omega_dot_rad_per_s - we
        };
        let omk = self.omega0_rad + omega_dot_k * tk - we * self.toe_sow_s;
        let (sin_o, cos_o) = omk.sin_cos();
        let (sin_i, cos_i) = ik.sin_cos();
        let pos = Vector3::new(
            xp * cos_o - yp * cos_i * sin_o,
            xp * sin_o + yp * cos_i * cos_o,
            yp * sin_i,
        );

        // Time derivatives of each quantity above.
        let ek_dot = n / one_m_ecos;
        let phik_dot = sq1me2 * ek_dot / one_m_ecos; // dv/dt
        let uk_dot = phik_dot * (1.0 + 2.0 * (self.cus_rad * c2p - self.cuc_rad * s2p));
        let rk_dot =
            a * self.e * sin_e * ek_dot + 2.0 * phik_dot * (self.crs_m * c2p - self.crc_m * s2p);
        let ik_dot =
            self.idot_rad_per_s + 2.0 * phik_dot * (self.cis_rad * c2p - self.cic_rad * s2p);
        let xp_dot = rk_dot * cos_u - yp * uk_dot;
        let yp_dot = rk_dot * sin_u + xp * uk_dot;
        let vel = Vector3::new(
            xp_dot * cos_o - yp_dot * cos_i * sin_o + yp * sin_i * sin_o * ik_dot
                - pos.y * omega_dot_k,
            xp_dot * sin_o + yp_dot * cos_i * cos_o - yp * sin_i * cos_o * ik_dot
                + pos.x * omega_dot_k,
            yp_dot * sin_i + yp * cos_i * ik_dot,
        );
        let (pos, vel) = if bds_geo {
            geo_rotate(pos, vel, we * tk, we)
        } else {
            (pos, vel)
        };
        KeplerState {
            pos_ecef_m: pos,
            vel_ecef_mps: vel,
            sin_e,
            cos_e,
            ek_dot_rad_per_s: ek_dot,
        }
    }
}

/// x = R_Z(phi) R_X(-5 deg) x_GK with phi = Omega_e tk (BeiDou B1I ICD 3.0
/// §5.2.4.12; R_X(a) = [1 0 0; 0 cos a sin a; 0 -sin a cos a], R_Z(a) = [cos a sin a 0;
/// -sin a cos a 0; 0 0 1]); the velocity adds dR_Z/dt = Omega_e R_Z'(phi).
fn geo_rotate(p: Vector3<f64>, v: Vector3<f64>, phi: f64, we: f64) -> (Vector3<f64>, Vector3<f64>) {
    let (sx, cx) = BDS_GEO_TILT_RAD.sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cx, sx, 0.0, -sx, cx);
    let (sz, cz) = phi.sin_cos();
    let rz = Matrix3::new(cz, sz, 0.0, -sz, cz, 0.0, 0.0, 0.0, 1.0);
    let rz_dot = Matrix3::new(-sz, cz, 0.0, -cz, -sz, 0.0, 0.0, 0.0, 0.0) * we;
    let q = rx * p;
    (rz * q, rz * (rx * v) + rz_dot * q)
}

/// The broadcast satellite state at `tk` from toe and `dt_clock_s` from toc: the
/// orbit, and the clock polynomial af0 + af1 dt + af2 dt^2 (IS-GPS-200 20.3.3.3.3.1,
/// the same form in the Galileo, BeiDou and QZSS ICDs) plus the relativistic term.
pub fn broadcast_state(
    orbit: &KeplerOrbit,
    k: &KeplerConstants,
    tk: f64,
    bds_geo: bool,
    af_s: [f64; 3],
    dt_clock_s: f64,
) -> crate::ephemeris::SatState {
    let s = orbit.state(k, tk, bds_geo);
    let (rel, rel_dot) = orbit.relativistic(k, &s);
    let dt = dt_clock_s;
    let poly = af_s[0] + (af_s[1] + af_s[2] * dt) * dt;
    let poly_dot = af_s[1] + 2.0 * af_s[2] * dt;
    crate::ephemeris::SatState {
        pos_ecef_m: s.pos_ecef_m,
        vel_ecef_mps: s.vel_ecef_mps,
        clock_bias_s: poly + rel,
        clock_drift_s_per_s: poly_dot + rel_dot,
        relativistic_s: rel,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kepler_solution_satisfies_equation() {
        for &e in &[0.0, 0.001, 0.02, 0.3, 0.9] {
            for k in 0..64 {
                let m = -7.0 + 0.23 * f64::from(k);
                let ek = solve_kepler(m, e);
                assert!((ek - e * ek.sin() - m).abs() < 1e-12, "e={e} M={m}");
            }
        }
        assert_eq!(solve_kepler(1.25, 0.0), 1.25);
    }

    /// A GEO-like orbit (elements of C01's size, rounded): with the GEO rotation the
    /// satellite moves at hundreds of m/s at most in ECEF, not the km/s of a MEO, and
    /// the velocity is the derivative of the position.
    #[test]
    fn beidou_geo_velocity_is_derivative() {
        let o = KeplerOrbit {
            sqrt_a_sqrt_m: 6_493.4,
            e: 5.6e-4,
            i0_rad: 0.0884,
            omega0_rad: -2.95,
            omega_rad: -2.31,
            m0_rad: 0.46,
            delta_n_rad_per_s: 2.6e-9,
            omega_dot_rad_per_s: 4.5e-10,
            idot_rad_per_s: 1.0e-10,
            cuc_rad: 6.6e-6,
            cus_rad: 3.0e-6,
            crc_m: -80.0,
            crs_m: 210.0,
            cic_rad: 2.8e-8,
            cis_rad: -1.1e-8,
            toe_sow_s: 338_400.0,
        };
        let h = 0.01;
        for k in -6..=6 {
            let tk = 600.0 * f64::from(k) + 0.3;
            let s = o.state(&BEIDOU_CONSTANTS, tk, true);
            let fd = (o.state(&BEIDOU_CONSTANTS, tk + h, true).pos_ecef_m
                - o.state(&BEIDOU_CONSTANTS, tk - h, true).pos_ecef_m)
                / (2.0 * h);
            assert!(
                (fd - s.vel_ecef_mps).norm() < 1e-3,
                "{}",
                (fd - s.vel_ecef_mps).norm()
            );
            assert!(
                s.vel_ecef_mps.norm() < 500.0,
                "GEO speed {}",
                s.vel_ecef_mps.norm()
            );
        }
    }
}
