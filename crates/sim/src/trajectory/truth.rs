//! The truth generator: the IMU rig in the vehicle, the ODE of position, velocity,
//! attitude and IMU increments, and its RK4 integration into truth samples.

use super::{Compiled, Mode, Trajectory, G_BANK, MAX_SUBSTEP_S};
use nalgebra::{Matrix3, SVector, Vector3};
use navfuse_core::attitude::c_bn_from_euler;
use navfuse_core::earth::{gravity_normal, omega_en_n, omega_ie_n, radii};
use navfuse_core::types::ImuSample;

/// How the IMU sits in the vehicle. The trajectory moves the vehicle frame m (x along
/// the velocity of the vehicle reference point, e.g. the rear-axle centre, where the
/// non-holonomic constraint holds); the IMU frame b is rotated from m by the mounting
/// angles and sits at `-lever_b` from the reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rig {
    /// C_b^m: IMU frame to vehicle frame (SYSTEM.md §4b: C_b^m = I - (dalpha x)).
    pub c_bm: Matrix3<f64>,
    /// Lever arm from the IMU to the vehicle reference point, IMU frame \[m\]
    /// (SYSTEM.md §4b l^b).
    pub lever_b: Vector3<f64>,
}

impl Default for Rig {
    fn default() -> Self {
        Rig {
            c_bm: Matrix3::identity(),
            lever_b: Vector3::zeros(),
        }
    }
}

impl Rig {
    /// From mounting angles (roll, pitch, yaw of the IMU frame relative to the vehicle
    /// frame, ZYX) \[rad\] and the lever arm \[m\].
    pub fn new(mount_rpy_rad: &Vector3<f64>, lever_b: Vector3<f64>) -> Self {
        Rig {
            c_bm: c_bn_from_euler(mount_rpy_rad),
            lever_b,
        }
    }
}

/// The integrated state: IMU position, IMU velocity (body-profile mode), Euler angles
/// of the vehicle frame, speed, and the running IMU integrals over the current span.
pub(super) type Y = SVector<f64, 16>;
const LAT: usize = 0;
const VEL: usize = 3;
const EUL: usize = 6;
const SPD: usize = 9;
const DTH: usize = 10;
const DV: usize = 13;

/// Truth at one instant. Position, velocity and attitude are those of the IMU
/// (body frame b = IMU frame); `c_mn`, `speed` describe the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSample {
    /// GPS time [s of week].
    pub t: f64,
    /// IMU latitude, longitude \[rad\], ellipsoidal height \[m\].
    pub lla: Vector3<f64>,
    /// IMU NED velocity [m/s].
    pub v_n: Vector3<f64>,
    /// C_b^n of the IMU.
    pub c_bn: Matrix3<f64>,
    /// C_m^n of the vehicle frame.
    pub c_mn: Matrix3<f64>,
    /// Angular rate of the body w.r.t. inertial space, IMU frame [rad/s].
    pub w_ib_b: Vector3<f64>,
    /// Angular rate of the body w.r.t. the Earth, IMU frame [rad/s].
    pub w_eb_b: Vector3<f64>,
    /// Forward speed of the vehicle reference point (speed mode); |v| of the IMU in
    /// body-profile mode [m/s].
    pub speed: f64,
}

impl TruthSample {
    /// Velocity [m/s] (NED) of a point at `lever_b` \[m\] (IMU frame) from the IMU.
    pub fn velocity_at(&self, lever_b: &Vector3<f64>) -> Vector3<f64> {
        self.v_n + self.c_bn * self.w_eb_b.cross(lever_b)
    }

    /// Roll, pitch, yaw of the IMU \[rad\] (yaw in (-pi, pi]).
    pub fn euler(&self) -> Vector3<f64> {
        navfuse_core::attitude::euler_from_c_bn(&self.c_bn)
    }
}

/// Rates at time t for state y in segment c.
pub(super) struct Eval {
    dy: Y,
    sample: TruthSample,
    /// C_n^b v^n: the boundary term of the velocity-increment integral.
    v_b: Vector3<f64>,
}

/// `t_sel`: a time strictly inside the smooth span being integrated (selects the
/// profile pieces).
fn evaluate(c: &Compiled, rig: &Rig, t: f64, t_sel: f64, y: &Y) -> Eval {
    let tau = t - c.t_start;
    let tau_sel = t_sel - c.t_start;
    let lla = Vector3::new(y[LAT], y[LAT + 1], y[LAT + 2]);
    let (roll, pitch, yaw) = (y[EUL], y[EUL + 1], y[EUL + 2]);
    let speed = y[SPD];
    let accel = c.accel.rate(tau, tau_sel);
    let roll_rate = c.roll_rate.rate(tau, tau_sel);
    let pitch_rate = c.pitch_rate.rate(tau, tau_sel);
    let yaw_rate = match &c.yaw_rate {
        Some(p) => p.rate(tau, tau_sel),
        None => G_BANK * roll.tan() / speed,
    };
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    let c_mn = c_bn_from_euler(&Vector3::new(roll, pitch, yaw));
    let c_bn = c_mn * rig.c_bm;
    let c_nb = c_bn.transpose();
    let g_n = Vector3::new(0.0, 0.0, gravity_normal(lla.x, lla.z));
    let w_ie = omega_ie_n(lla.x);
    // Vehicle rate w.r.t. n from Euler-angle rates (ZYX), vehicle frame.
    let w_nm_m = Vector3::new(
        roll_rate - yaw_rate * sp,
        pitch_rate * cr + yaw_rate * sr * cp,
        -pitch_rate * sr + yaw_rate * cr * cp,
    );
    let w_nb_b = rig.c_bm.transpose() * w_nm_m;

    let mut dy = Y::zeros();
    let (v_n, speed_out) = match &c.mode {
        Mode::Speed => {
            // Reference point along the vehicle x axis; the IMU at -lever from it:
            // v_imu = v_ref - C_b^n (w_eb^b x l^b).
            let v_ref = Vector3::new(cp * cy, cp * sy, -sp) * speed;
            let w_eb_ref = w_nb_b + c_nb * omega_en_n(lla.x, lla.z, &v_ref);
            (v_ref - c_bn * w_eb_ref.cross(&rig.lever_b), speed)
        }
        Mode::Force(a_b) => {
            let v = Vector3::new(y[VEL], y[VEL + 1], y[VEL + 2]);
            dy.fixed_rows_mut::<3>(VEL).copy_from(&(c_bn * a_b));
            (v, v.norm())
        }
    };
    let w_en = omega_en_n(lla.x, lla.z, &v_n);
    let w_ib_b = w_nb_b + c_nb * (w_ie + w_en);
    let w_eb_b = w_nb_b + c_nb * w_en;
    let v_b = c_nb * v_n;
    // Integrand of the velocity increment. Force mode: f^b itself. Speed mode, by parts
    // so no acceleration is needed: ∫ C_n^b a dt = [C_n^b v] + ∫ w_nb^b x (C_n^b v) dt,
    // hence f^b -> w_nb^b x v^b + C_n^b (-g + (2 w_ie + w_en) x v); the boundary term is
    // added per span in `TruthGenerator::step`.
    let dv_integrand = match &c.mode {
        // f^b = a^b - C_n^b (g - (2 w_ie + w_en) x v)  (SYSTEM.md §1, rearranged)
        Mode::Force(a_b) => a_b + c_nb * (-g_n + (2.0 * w_ie + w_en).cross(&v_n)),
        Mode::Speed => w_nb_b.cross(&v_b) + c_nb * (-g_n + (2.0 * w_ie + w_en).cross(&v_n)),
    };

    let (m, n) = radii(lla.x);
    dy[LAT] = v_n.x / (m + lla.z);
    dy[LAT + 1] = v_n.y / ((n + lla.z) * lla.x.cos());
    dy[LAT + 2] = -v_n.z;
    dy[EUL] = roll_rate;
    dy[EUL + 1] = pitch_rate;
    dy[EUL + 2] = yaw_rate;
    dy[SPD] = accel;
    dy.fixed_rows_mut::<3>(DTH).copy_from(&w_ib_b);
    dy.fixed_rows_mut::<3>(DV).copy_from(&dv_integrand);
    Eval {
        dy,
        v_b,
        sample: TruthSample {
            t,
            lla,
            v_n,
            c_bn,
            c_mn,
            w_ib_b,
            w_eb_b,
            speed: speed_out,
        },
    }
}

/// Steps a [`Trajectory`] at a fixed IMU interval, producing the truth at each
/// sample time and the exact increments over each interval.
pub struct TruthGenerator<'a> {
    traj: &'a Trajectory,
    rig: Rig,
    dt: f64,
    /// Index of the next sample (sample k is at t0 + k dt).
    k: u64,
    y: Y,
    next_break: usize,
    /// C_n^b v^n of the IMU at the end of the last integrated span.
    v_b_last: Vector3<f64>,
}

impl<'a> TruthGenerator<'a> {
    /// `rate_hz`: IMU output rate.
    pub fn new(traj: &'a Trajectory, rig: Rig, rate_hz: f64) -> Self {
        let s = &traj.start;
        let mut y = Y::zeros();
        y[LAT] = s.lla.x;
        y[LAT + 1] = s.lla.y;
        y[LAT + 2] = s.lla.z;
        y[EUL + 2] = s.heading_rad;
        y[SPD] = s.speed_mps;
        let mut g = TruthGenerator {
            traj,
            rig,
            dt: 1.0 / rate_hz,
            k: 0,
            y,
            next_break: 0,
            v_b_last: Vector3::zeros(),
        };
        // Body-profile mode integrates the IMU velocity: start it from the truth.
        let s0 = g.current();
        g.y.fixed_rows_mut::<3>(VEL).copy_from(&s0.v_n);
        g.v_b_last = s0.c_bn.transpose() * s0.v_n;
        g
    }

    /// IMU interval \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    fn time(&self, k: u64) -> f64 {
        self.traj.start.t0 + k as f64 * self.dt
    }

    /// Truth at the current sample time.
    pub fn current(&self) -> TruthSample {
        let t = self.time(self.k);
        let t_sel = t.min(self.traj.t_end() - 1e-9);
        evaluate(self.traj.seg_at(t_sel), &self.rig, t, t_sel, &self.y).sample
    }

    /// Advance one IMU interval. Returns the increments over it (IMU frame) and the
    /// truth at its end, or None once the next sample would pass the end of the
    /// trajectory (the run ends at the last whole IMU interval).
    pub fn step(&mut self) -> Option<(ImuSample, TruthSample)> {
        let t_a = self.time(self.k);
        let t_b = self.time(self.k + 1);
        if t_b > self.traj.t_end() + 1e-9 {
            return None;
        }
        for i in DTH..DTH + 6 {
            self.y[i] = 0.0;
        }
        let breaks = &self.traj.breaks;
        while self.next_break < breaks.len() && breaks[self.next_break] <= t_a + 1e-9 {
            self.next_break += 1;
        }
        let rig = self.rig;
        let mut t = t_a;
        while t < t_b - 1e-12 {
            let mut t_next = t_b;
            if self.next_break < breaks.len() && breaks[self.next_break] < t_b - 1e-9 {
                t_next = breaks[self.next_break];
            }
            // RK4 sub-steps over [t, t_next], no discontinuity inside; the segment and
            // profile pieces are fixed for the span (chosen at its middle).
            let span = t_next - t;
            let n = (span / MAX_SUBSTEP_S).ceil().max(1.0) as usize;
            let h = span / n as f64;
            let t_sel = t + 0.5 * span;
            let seg = self.traj.seg_at(t_sel);
            for j in 0..n {
                let ts = t + j as f64 * h;
                let k1 = evaluate(seg, &rig, ts, t_sel, &self.y).dy;
                let k2 = evaluate(seg, &rig, ts + 0.5 * h, t_sel, &(self.y + k1 * (0.5 * h))).dy;
                let k3 = evaluate(seg, &rig, ts + 0.5 * h, t_sel, &(self.y + k2 * (0.5 * h))).dy;
                let k4 = evaluate(seg, &rig, ts + h, t_sel, &(self.y + k3 * h)).dy;
                self.y += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            }
            let end = evaluate(seg, &rig, t_next, t_sel, &self.y);
            if seg.mode == Mode::Speed {
                // Boundary term against the previous span's end, so a velocity step of
                // the IMU (a step in angular rate times the lever arm) is an impulse in
                // this interval's velocity increment.
                let dv = end.v_b - self.v_b_last;
                for i in 0..3 {
                    self.y[DV + i] += dv[i];
                }
                // Keep the integrated velocity current for a later body profile.
                self.y.fixed_rows_mut::<3>(VEL).copy_from(&end.sample.v_n);
            }
            self.v_b_last = end.v_b;
            t = t_next;
            if t_next < t_b {
                self.next_break += 1;
            }
        }
        self.k += 1;
        let imu = ImuSample {
            t: t_b,
            dt: t_b - t_a,
            dtheta: Vector3::new(self.y[DTH], self.y[DTH + 1], self.y[DTH + 2]),
            dvel: Vector3::new(self.y[DV], self.y[DV + 1], self.y[DV + 2]),
        };
        Some((imu, self.current()))
    }
}
