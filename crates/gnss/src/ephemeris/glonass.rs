//! GLONASS FDMA broadcast ephemeris: PZ-90.11 state vectors at tb integrated with
//! 4th-order Runge-Kutta (GLONASS ICD 2008 ed. 5.1, Appendix A.3.1.2: central field,
//! J2 and the broadcast luni-solar accelerations, constant over the interval),
//! clock -tau_n + gamma_n (t - tb) (ICD §4.4: t_sv - t_GLONASS; relativity is
//! included in the broadcast clock, §3.3.3). RINEX 3.05 Table A10: the epoch is UTC,
//! the record holds -tau_n, +gamma_n, x, x', x'' in km, km/s, km/s^2, health, the
//! frequency channel and the age of the data.
//!
//! GLONASS time is UTC(SU) + 3 h; a record's epoch (UTC) becomes GPST by adding the
//! GPS-UTC leap seconds (the RINEX header's, or `navfuse_core::time::leap_seconds`).
//! PZ-90.11 and WGS-84 (G1762) agree to a few centimetres: no transformation.

use super::SatState;
use crate::time::GpsTime;
use nalgebra::Vector3;

/// Earth gravitational constant GM [m^3/s^2] (ICD 5.1 §3.1.3 Table 3.2, PZ-90.11).
pub const GLO_MU_M3_PER_S2: f64 = 3.986_004_418e14;
/// Semi-major axis of the PZ-90.11 ellipsoid a_e \[m\].
pub const GLO_AE_M: f64 = 6_378_136.0;
/// Second zonal harmonic J2 (= -C20).
pub const GLO_J2: f64 = 1.082_625_75e-3;
/// Earth rotation rate [rad/s].
pub const GLO_OMEGA_E_RAD_PER_S: f64 = 7.292_115e-5;
/// Largest Runge-Kutta step \[s\] (ICD A.3.1.2 suggests steps of a minute or less).
pub const GLO_MAX_STEP_S: f64 = 60.0;

/// One GLONASS ephemeris (immediate data), SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct GlonassEphemeris {
    /// Slot number (R01-R24).
    pub slot: u8,
    /// tb as GPST (the record's UTC epoch + leap seconds).
    pub tb: GpsTime,
    /// tb as the UTC seconds of day of the record (for the IOD: tb index, ICD §4.4).
    pub tb_utc_sod_s: f64,
    /// tau_n \[s\] (RINEX stores -tau_n): t_GLONASS - t_sv at tb.
    pub tau_n_s: f64,
    /// gamma_n, relative frequency offset [-].
    pub gamma_n: f64,
    /// Message frame time, UTC seconds of the week as RINEX gives it \[s\].
    pub frame_time_s: f64,
    /// Position at tb, PZ-90.11 \[m\].
    pub pos_m: Vector3<f64>,
    /// Velocity at tb, PZ-90.11 (rotating) [m/s].
    pub vel_mps: Vector3<f64>,
    /// Luni-solar acceleration [m/s^2].
    pub acc_mps2: Vector3<f64>,
    /// Health Bn (0 = OK).
    pub health: u32,
    /// FDMA frequency channel k (-7..+6; L1 = 1602 + 0.5625 k MHz).
    pub freq_channel: i8,
    /// Age of the operational information E_n \[days\].
    pub age_days: f64,
}

/// d/dt (x, v) in the rotating PZ-90 frame (ICD A.3.1.2, eq. of motion).
fn deriv(x: &[f64; 6], acc: &Vector3<f64>) -> [f64; 6] {
    let (p, v) = (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    );
    let r2 = p.norm_squared();
    let r = r2.sqrt();
    let r3 = r2 * r;
    let w = GLO_OMEGA_E_RAD_PER_S;
    let mu_r3 = GLO_MU_M3_PER_S2 / r3;
    // 3/2 J2 mu a_e^2 / r^5
    let j = 1.5 * GLO_J2 * GLO_MU_M3_PER_S2 * GLO_AE_M * GLO_AE_M / (r3 * r2);
    let z2 = 5.0 * p.z * p.z / r2;
    let ax = -mu_r3 * p.x - j * p.x * (1.0 - z2) + w * w * p.x + 2.0 * w * v.y + acc.x;
    let ay = -mu_r3 * p.y - j * p.y * (1.0 - z2) + w * w * p.y - 2.0 * w * v.x + acc.y;
    let az = -mu_r3 * p.z - j * p.z * (3.0 - z2) + acc.z;
    [v.x, v.y, v.z, ax, ay, az]
}

fn rk4(x: &[f64; 6], h: f64, acc: &Vector3<f64>) -> [f64; 6] {
    let add = |a: &[f64; 6], b: &[f64; 6], s: f64| {
        let mut o = *a;
        for i in 0..6 {
            o[i] += s * b[i];
        }
        o
    };
    let k1 = deriv(x, acc);
    let k2 = deriv(&add(x, &k1, h / 2.0), acc);
    let k3 = deriv(&add(x, &k2, h / 2.0), acc);
    let k4 = deriv(&add(x, &k3, h), acc);
    let mut o = *x;
    for i in 0..6 {
        o[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    o
}

impl GlonassEphemeris {
    /// L1 carrier frequency \[Hz\] (ICD §3.3.1.4: 1602 MHz + k 562.5 kHz).
    pub fn l1_frequency_hz(&self) -> f64 {
        1_602.0e6 + f64::from(self.freq_channel) * 562.5e3
    }

    /// Issue of data: the tb index within the Moscow day, tb / 15 min (ICD §4.4).
    pub fn iod(&self) -> u16 {
        (((self.tb_utc_sod_s + 10_800.0).rem_euclid(86_400.0)) / 900.0).round() as u16
    }

    /// Position and velocity at GPST t (ECEF PZ-90.11 at t) by Runge-Kutta from tb in
    /// steps of at most 60 s; clock -tau_n + gamma_n (t - tb), drift gamma_n.
    pub fn sat_state(&self, t: GpsTime) -> SatState {
        let dt = t.diff_s(&self.tb);
        let n = (dt.abs() / GLO_MAX_STEP_S).ceil().max(1.0);
        let h = dt / n;
        let mut x = [
            self.pos_m.x,
            self.pos_m.y,
            self.pos_m.z,
            self.vel_mps.x,
            self.vel_mps.y,
            self.vel_mps.z,
        ];
        if dt != 0.0 {
            for _ in 0..n as usize {
                x = rk4(&x, h, &self.acc_mps2);
            }
        }
        SatState {
            pos_ecef_m: Vector3::new(x[0], x[1], x[2]),
            vel_ecef_mps: Vector3::new(x[3], x[4], x[5]),
            clock_bias_s: -self.tau_n_s + self.gamma_n * dt,
            clock_drift_s_per_s: self.gamma_n,
            relativistic_s: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R01 of the ESBC day (2020-06-24 23:15:00 UTC), typed in.
    pub(crate) fn r01() -> GlonassEphemeris {
        GlonassEphemeris {
            slot: 1,
            tb: GpsTime::new(2111, 342_918.0),
            tb_utc_sod_s: 83_700.0,
            tau_n_s: -6.355904042721e-05,
            gamma_n: 0.0,
            frame_time_s: 342_000.0,
            pos_m: Vector3::new(1.090894238281e7, -2.885726074219e6, 2.288353955078e7),
            vel_mps: Vector3::new(1.407806396484e3, 2.795855522156e3, -3.169984817505e2),
            acc_mps2: Vector3::new(-1.862645149231e-6, 0.0, -2.793967723846e-6),
            health: 0,
            freq_channel: 1,
            age_days: 0.0,
        }
    }

    #[test]
    fn integration_converges_and_velocity_is_derivative() {
        let e = r01();
        let t = e.tb.add_s(900.0);
        let s = e.sat_state(t);
        let h = 0.5;
        let fd =
            (e.sat_state(t.add_s(h)).pos_ecef_m - e.sat_state(t.add_s(-h)).pos_ecef_m) / (2.0 * h);
        assert!(
            (fd - s.vel_ecef_mps).norm() < 1e-3,
            "{}",
            (fd - s.vel_ecef_mps).norm()
        );
        let r = s.pos_ecef_m.norm();
        assert!((r - 25_500e3).abs() < 100e3, "r = {r}");
        assert_eq!(e.sat_state(e.tb).pos_ecef_m, e.pos_m);
        assert!((s.clock_bias_s - 6.355904042721e-05).abs() < 1e-15);
        // 23:15 UTC = 02:15 Moscow time: the 9th quarter hour.
        assert_eq!(e.iod(), 9);
    }
}
