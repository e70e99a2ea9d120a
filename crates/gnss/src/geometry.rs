//! Signal geometry: light-time iteration, Earth rotation during transit (Sagnac),
//! range, range rate, line of sight, azimuth and elevation.

use crate::ephemeris::{
    Ephemeris, GpsEphemeris, SatState, GPS_OMEGA_E_RAD_PER_S, SPEED_OF_LIGHT_MPS,
};
use crate::time::GpsTime;
use nalgebra::{Matrix3, Vector3};
use navfuse_core::earth::c_ne;

/// Convergence limit of the light-time iteration [s].
const LIGHT_TIME_TOL_S: f64 = 1e-12;
const LIGHT_TIME_MAX_ITER: usize = 20;

/// One satellite-to-receiver signal, everything in the ECEF frame at reception.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SignalPath {
    /// Transmission time (GPST): t_rx - transit_time_s (no clock terms). Its sow is
    /// an f64, so it resolves ~6e-11 s late in the week; use `transit_time_s` for
    /// the exact light time.
    pub t_tx: GpsTime,
    /// Light time tau = geometric_range_m / c, converged to < 1e-12 s \[s\].
    pub transit_time_s: f64,
    /// Satellite position at t_tx, rotated into the ECEF frame at t_rx \[m\].
    pub sat_pos_ecef_m: Vector3<f64>,
    /// d(sat_pos_ecef_m)/d(t_rx) for the given receiver motion [m/s]: the satellite's
    /// ECEF velocity at t_tx rotated like the position and scaled by (1 - dtau/dt),
    /// plus the frame-rotation term We dtau/dt (dR/dtheta) x. With this choice
    /// `range_rate_mps = los_unit . (sat_vel_ecef_mps - rx_vel)` exactly.
    pub sat_vel_ecef_mps: Vector3<f64>,
    /// |sat_pos_ecef_m - rx_pos| \[m\].
    pub geometric_range_m: f64,
    /// Unit vector from the receiver to the satellite (ECEF at t_rx).
    pub los_unit: Vector3<f64>,
    /// d(geometric_range_m)/d(t_rx) for the given receiver velocity [m/s].
    pub range_rate_mps: f64,
    /// Satellite clock bias at t_tx (relativistic term included, TGD not) \[s\].
    pub sat_clock_bias_s: f64,
    /// Satellite clock drift at t_tx [s/s].
    pub sat_clock_drift_s_per_s: f64,
}

/// Rotation about z by theta: ECEF frame at t_tx -> ECEF frame at t_tx + theta/We.
fn rot_z(theta: f64) -> Matrix3<f64> {
    let (s, c) = theta.sin_cos();
    Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0)
}

/// d(rot_z)/d(theta).
fn rot_z_deriv(theta: f64) -> Matrix3<f64> {
    let (s, c) = theta.sin_cos();
    Matrix3::new(-s, c, 0.0, -c, -s, 0.0, 0.0, 0.0, 0.0)
}

/// Anything that gives a satellite's position, velocity and clock at GPST t in the
/// ECEF frame at t: a broadcast record of any system, or precise products.
pub trait SatOrbit {
    fn sat_state(&self, t: GpsTime) -> SatState;
}

impl SatOrbit for GpsEphemeris {
    fn sat_state(&self, t: GpsTime) -> SatState {
        GpsEphemeris::sat_state(self, t)
    }
}

impl SatOrbit for Ephemeris {
    fn sat_state(&self, t: GpsTime) -> SatState {
        Ephemeris::sat_state(self, t)
    }
}

impl<T: SatOrbit + ?Sized> SatOrbit for &T {
    fn sat_state(&self, t: GpsTime) -> SatState {
        (**self).sat_state(t)
    }
}

/// Solve the light-time equation t_tx = t_rx - |R(We tau) x_sat(t_tx) - x_rx| / c
/// (tau = t_rx - t_tx) to < 1e-12 s, for a receiver at `rx_pos_ecef_m` moving with
/// `rx_vel_ecef_mps` (both ECEF at t_rx). The Earth rotation of the Sagnac term is
/// the WGS-84 (GPS) value for every system (the systems' values differ by 1.5e-12
/// rad/s: < 1e-5 m).
pub fn signal_path(
    eph: &(impl SatOrbit + ?Sized),
    rx_pos_ecef_m: &Vector3<f64>,
    rx_vel_ecef_mps: &Vector3<f64>,
    t_rx: GpsTime,
) -> SignalPath {
    let mut tau = 0.075; // typical GPS transit time [s]
    for _ in 0..LIGHT_TIME_MAX_ITER {
        let st = eph.sat_state(t_rx.add_s(-tau));
        let p = rot_z(GPS_OMEGA_E_RAD_PER_S * tau) * st.pos_ecef_m;
        let tau_new = (p - rx_pos_ecef_m).norm() / SPEED_OF_LIGHT_MPS;
        let done = (tau_new - tau).abs() < LIGHT_TIME_TOL_S;
        tau = tau_new;
        if done {
            break;
        }
    }
    let st = eph.sat_state(t_rx.add_s(-tau));
    let theta = GPS_OMEGA_E_RAD_PER_S * tau;
    let r = rot_z(theta);
    let pos = r * st.pos_ecef_m;
    let d = pos - rx_pos_ecef_m;
    let range = d.norm();
    let los = if range > 0.0 {
        d / range
    } else {
        Vector3::zeros()
    };
    // d(range)/dt_rx with tau_dot = range_rate / c:
    // pos_dot = R v (1 - tau_dot) + We tau_dot R' x  =>  range_rate (1 + b) = a.
    let rv = r * st.vel_ecef_mps;
    let rot_term = GPS_OMEGA_E_RAD_PER_S * (rot_z_deriv(theta) * st.pos_ecef_m);
    let a = los.dot(&(rv - rx_vel_ecef_mps));
    let b = los.dot(&(rv - rot_term)) / SPEED_OF_LIGHT_MPS;
    let range_rate = a / (1.0 + b);
    let tau_dot = range_rate / SPEED_OF_LIGHT_MPS;
    let sat_vel = rv * (1.0 - tau_dot) + rot_term * tau_dot;
    SignalPath {
        t_tx: t_rx.add_s(-tau),
        transit_time_s: tau,
        sat_pos_ecef_m: pos,
        sat_vel_ecef_mps: sat_vel,
        geometric_range_m: range,
        los_unit: los,
        range_rate_mps: range_rate,
        sat_clock_bias_s: st.clock_bias_s,
        sat_clock_drift_s_per_s: st.clock_drift_s_per_s,
    }
}

/// Azimuth (from north, clockwise, [0, 2 pi)) and elevation \[rad\] of an ECEF unit
/// line of sight seen from `rx_lla` = (lat rad, lon rad, h m).
pub fn az_el(rx_lla: &Vector3<f64>, los_unit_ecef: &Vector3<f64>) -> (f64, f64) {
    let ned = c_ne(rx_lla.x, rx_lla.y).transpose() * los_unit_ecef;
    let horiz = (ned.x * ned.x + ned.y * ned.y).sqrt();
    let el = (-ned.z).atan2(horiz);
    let mut az = ned.y.atan2(ned.x);
    if az < 0.0 {
        az += 2.0 * std::f64::consts::PI;
    }
    (az, el)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ephemeris::tests::g32;
    use navfuse_core::earth::lla_to_ecef;

    fn site() -> Vector3<f64> {
        lla_to_ecef(&Vector3::new(
            35.0f64.to_radians(),
            139.0f64.to_radians(),
            50.0,
        ))
    }

    #[test]
    fn light_time_equation_holds() {
        let eph = g32();
        let rx = site();
        let t_rx = eph.toe.add_s(1_234.5);
        let sp = signal_path(&eph, &rx, &Vector3::zeros(), t_rx);
        let tau = sp.transit_time_s;
        assert!((tau * SPEED_OF_LIGHT_MPS - sp.geometric_range_m).abs() < 1e-3);
        assert!((t_rx.diff_s(&sp.t_tx) - tau).abs() < 1e-9);
        assert!((0.06..0.095).contains(&tau));
        // Sagnac: the rotated position differs from the unrotated one by We tau |r_xy|.
        let raw = eph.sat_state(sp.t_tx).pos_ecef_m;
        let shift = (sp.sat_pos_ecef_m - raw).norm();
        let expect = GPS_OMEGA_E_RAD_PER_S * tau * (raw.x.hypot(raw.y));
        assert!((shift - expect).abs() < 1e-3, "{shift} vs {expect}");
        assert!((sp.los_unit.norm() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn range_rate_and_sat_velocity_are_derivatives() {
        let eph = g32();
        let rx0 = site();
        let v_rx = Vector3::new(12.0, -30.0, 4.0);
        let t0 = eph.toe.add_s(-2_000.0);
        let h = 0.005;
        let at = |dt: f64| signal_path(&eph, &(rx0 + v_rx * dt), &v_rx, t0.add_s(dt));
        let sp = at(0.0);
        let fd_range = (at(h).geometric_range_m - at(-h).geometric_range_m) / (2.0 * h);
        assert!(
            (fd_range - sp.range_rate_mps).abs() < 1e-4,
            "{fd_range} {}",
            sp.range_rate_mps
        );
        let fd_pos = (at(h).sat_pos_ecef_m - at(-h).sat_pos_ecef_m) / (2.0 * h);
        assert!((fd_pos - sp.sat_vel_ecef_mps).norm() < 1e-3);
        let rr = sp.los_unit.dot(&(sp.sat_vel_ecef_mps - v_rx));
        assert!((rr - sp.range_rate_mps).abs() < 1e-9);
    }

    #[test]
    fn az_el_cardinal_directions() {
        let lla = Vector3::new(0.5, 1.0, 0.0);
        let c = c_ne(lla.x, lla.y);
        let up = c * Vector3::new(0.0, 0.0, -1.0);
        let (_, el) = az_el(&lla, &up);
        assert!((el - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let east = c * Vector3::new(0.0, 1.0, 0.0);
        let (az, el) = az_el(&lla, &east);
        assert!((az - std::f64::consts::FRAC_PI_2).abs() < 1e-12 && el.abs() < 1e-12);
        let nw_up = c * Vector3::new(1.0, -1.0, -2f64.sqrt()).normalize();
        let (az, el) = az_el(&lla, &nw_up);
        assert!((az.to_degrees() - 315.0).abs() < 1e-9 && (el.to_degrees() - 45.0).abs() < 1e-9);
    }
}
