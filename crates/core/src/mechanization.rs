//! Strapdown INS mechanization in NED on the rotating WGS-84 Earth, from angle and
//! velocity increments with two-sample coning and sculling corrections.
//! SYSTEM.md §1 (seed 000 eq. 8-10): p_dot = D^-1 v, v_dot = C_b^n f - (2 w_ie + w_en) x v + g,
//! C_dot = C_b^n (W_ib - W_in).

use crate::attitude::{quat_from_rotvec, skew};
use crate::earth::{gravity_normal_sc, OMEGA_IE, WGS84_A, WGS84_E2};
use crate::types::{ImuSample, NavState};
use nalgebra::{Matrix3, Vector3};

/// What one mechanization step exposes to the error model.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepInfo {
    /// Specific-force velocity increment resolved in n over the step \[m/s\].
    pub dv_f_n: Vector3<f64>,
}

/// Strapdown integrator. Holds the previous increments (for coning/sculling) and the
/// previous state (to extrapolate Earth-rate, transport-rate and gravity terms to the
/// middle of each interval).
#[derive(Clone, Debug, Default)]
pub struct Mechanizer {
    prev_imu: Option<ImuSample>,
    prev_nav: Option<NavState>,
    earth: Option<EarthAt>,
}

/// Earth quantities at a latitude and height. They change by less than 1e-7 of their
/// value over 0.6 m of latitude or 5 cm of height, so they are recomputed only when
/// the position moves that much (gravity error < 2e-7 m/s², radius error < 1e-7).
#[derive(Clone, Copy, Debug)]
struct EarthAt {
    lat: f64,
    h: f64,
    sin_lat: f64,
    cos_lat: f64,
    rm: f64,
    rn: f64,
    g: f64,
}

impl EarthAt {
    fn new(lat: f64, h: f64) -> Self {
        let (sin_lat, cos_lat) = lat.sin_cos();
        let w2 = 1.0 - WGS84_E2 * sin_lat * sin_lat;
        let rn = WGS84_A / w2.sqrt();
        let rm = rn * (1.0 - WGS84_E2) / w2;
        EarthAt {
            lat,
            h,
            sin_lat,
            cos_lat,
            rm,
            rn,
            g: gravity_normal_sc(sin_lat, h),
        }
    }

    fn near(&self, lat: f64, h: f64) -> bool {
        (lat - self.lat).abs() < 1e-7 && (h - self.h).abs() < 0.05
    }
}

impl Mechanizer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Advance `nav` over one compensated IMU interval ending at `imu.t`. Backward
    /// (`imu.dt` < 0, increments negated: the compensated interval (t, t - dt]
    /// traversed from t - dt down to t) the same equations integrate towards the
    /// past: Earth rate, transport rate, gravity and Coriolis terms scale with the
    /// signed dt.
    pub fn step(&mut self, nav: &NavState, imu: &ImuSample) -> (NavState, StepInfo) {
        let dt = imu.dt;
        let (dth_prev, dv_prev) = match &self.prev_imu {
            // Scale the previous increments to this interval's length so a split
            // interval does not distort the two-sample corrections. Backward (dt < 0,
            // increments negated) the previous sample is the later one; the
            // corrections keep their form (docs/ALGORITHMS.md "Backward filter").
            Some(p) if p.dt * dt > 0.0 => {
                let s = dt / p.dt;
                (p.dtheta * s, p.dvel * s)
            }
            _ => (imu.dtheta, imu.dvel),
        };
        let dth = imu.dtheta;
        let dv = imu.dvel;

        // Mid-interval extrapolation of latitude, height and velocity from the last two
        // states (backward: from the later two, towards the past).
        let (lat_m, h_m, v_m) = match &self.prev_nav {
            Some(p) if (nav.t - p.t) * dt > 0.0 => {
                let k = 0.5 * dt / (nav.t - p.t);
                (
                    nav.lla.x + k * (nav.lla.x - p.lla.x),
                    nav.lla.z + k * (nav.lla.z - p.lla.z),
                    nav.v_n + (nav.v_n - p.v_n) * k,
                )
            }
            _ => (nav.lla.x, nav.lla.z, nav.v_n),
        };
        // One set of Earth quantities at mid-interval serves the velocity, position
        // and attitude updates (latitude moves < 1e-7 rad per IMU interval).
        let e = match self.earth {
            Some(e) if e.near(lat_m, h_m) => e,
            _ => {
                let e = EarthAt::new(lat_m, h_m);
                self.earth = Some(e);
                e
            }
        };
        let (sl, cl) = (e.sin_lat, e.cos_lat);
        let w_ie = Vector3::new(OMEGA_IE * cl, 0.0, -OMEGA_IE * sl);
        let (k_n, k_m) = (1.0 / (e.rn + h_m), 1.0 / (e.rm + h_m));
        let k_t = k_n * sl / cl;
        let en = |v: &Vector3<f64>| Vector3::new(v.y * k_n, -v.x * k_m, -v.y * k_t);
        let w_en = en(&v_m);
        let g_n = Vector3::new(0.0, 0.0, e.g);

        // Velocity: rotation and sculling corrections (two-sample).
        let dv_f_b = dv + 0.5 * dth.cross(&dv) + (dth_prev.cross(&dv) + dv_prev.cross(&dth)) / 12.0;
        let zeta = (w_ie + w_en) * dt;
        let c_bn_prev: Matrix3<f64> = nav.q_bn.to_rotation_matrix().into_inner();
        let dv_f_n = (Matrix3::identity() - 0.5 * skew(&zeta)) * (c_bn_prev * dv_f_b);
        let dv_gcor = (g_n - (2.0 * w_ie + w_en).cross(&v_m)) * dt;
        let v_new = nav.v_n + dv_f_n + dv_gcor;

        // Position: trapezoidal velocity.
        let v_avg = 0.5 * (nav.v_n + v_new);
        let h_new = nav.lla.z - v_avg.z * dt;
        let lat_new = nav.lla.x + v_avg.x * k_m * dt;
        let mut lon_new = nav.lla.y + v_avg.y * k_n / cl * dt;
        if lon_new.abs() > std::f64::consts::PI {
            lon_new = crate::attitude::wrap_pi(lon_new);
        }

        // Attitude: body rotation with coning correction, n-frame rotation at mid-interval.
        let phi_b = dth + dth_prev.cross(&dth) / 12.0;
        let w_in_mid = w_ie + en(&v_avg);
        let q_bb = quat_from_rotvec(&phi_b);
        let q_nn = quat_from_rotvec(&(-w_in_mid * dt));
        let mut q_bn = q_nn * nav.q_bn * q_bb;
        q_bn.renormalize_fast();

        self.prev_imu = Some(*imu);
        self.prev_nav = Some(*nav);
        let out = NavState {
            t: imu.t,
            lla: Vector3::new(lat_new, lon_new, h_new),
            v_n: v_new,
            q_bn,
        };
        (out, StepInfo { dv_f_n })
    }

    /// After a closed-loop correction the stored previous state would make the
    /// mid-interval extrapolation see a jump; shift it by the same correction.
    pub fn shift_previous(&mut self, d_lla: &Vector3<f64>, d_v: &Vector3<f64>) {
        if let Some(p) = &mut self.prev_nav {
            p.lla += d_lla;
            p.v_n += d_v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::q_bn_from_euler;
    use crate::earth::{gravity_normal, omega_ie_n};
    use nalgebra::UnitQuaternion;

    /// A stationary IMU on the rotating Earth senses -g (up) and the Earth rate;
    /// fed exactly, the mechanization must stay put.
    #[test]
    fn stationary_stays_put() {
        let lla = Vector3::new(30f64.to_radians(), 114f64.to_radians(), 20.0);
        let rpy = Vector3::new(0.02, -0.03, 1.2);
        let q = q_bn_from_euler(&rpy);
        let c_nb = q.to_rotation_matrix().into_inner().transpose();
        let g = gravity_normal(lla.x, lla.z);
        let f_b = c_nb * Vector3::new(0.0, 0.0, -g);
        let w_b = c_nb * omega_ie_n(lla.x);
        let dt = 0.005;
        let mut nav = NavState {
            t: 0.0,
            lla,
            v_n: Vector3::zeros(),
            q_bn: q,
        };
        let mut mech = Mechanizer::new();
        for k in 1..=(200 * 600) {
            let s = ImuSample {
                t: k as f64 * dt,
                dt,
                dtheta: w_b * dt,
                dvel: f_b * dt,
            };
            nav = mech.step(&nav, &s).0;
        }
        let d = crate::earth::lla_diff_ned(&nav.lla, &lla);
        assert!(d.norm() < 1e-3, "drift {d:?}");
        assert!(nav.v_n.norm() < 1e-5, "{:?}", nav.v_n);
        let dq: UnitQuaternion<f64> = nav.q_bn * q.inverse();
        assert!(dq.angle() < 1e-8);
    }
}
