//! Test data for the alignment: a smooth random motion in a local NED frame (fixed
//! latitude), the IMU increments it gives on the rotating Earth and GNSS fixes with
//! velocity, with noise, biases and outliers.

use crate::attitude::c_bn_from_euler;
use crate::earth::{gravity_normal, lla_add_ned, omega_en_n, omega_ie_n};
use crate::types::{GnssFix, ImuSample};
use nalgebra::{Matrix3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;

/// Sums of sinusoids: x(t) = x0 + sum a_i sin(w_i t + p_i).
#[derive(Clone, Debug)]
pub struct Wave {
    pub x0: f64,
    pub terms: Vec<(f64, f64, f64)>,
}

impl Wave {
    pub fn constant(x0: f64) -> Self {
        Wave {
            x0,
            terms: Vec::new(),
        }
    }
    pub fn at(&self, t: f64) -> f64 {
        self.x0
            + self
                .terms
                .iter()
                .map(|(a, w, p)| a * (w * t + p).sin())
                .sum::<f64>()
    }
    pub fn rate(&self, t: f64) -> f64 {
        self.terms
            .iter()
            .map(|(a, w, p)| a * w * (w * t + p).cos())
            .sum()
    }
}

/// The motion: Euler angles and NED velocity as waves, from `t0` (GPS seconds).
#[derive(Clone, Debug)]
pub struct Motion {
    pub t0: f64,
    pub lla0: Vector3<f64>,
    pub rpy: [Wave; 3],
    pub vel: [Wave; 3],
    /// Some(offset): the yaw is the course of the velocity plus `offset` (a land
    /// vehicle with its IMU mounted at that yaw), not `rpy[2]`.
    pub yaw_course_offset: Option<f64>,
}

impl Motion {
    /// Yaw and yaw rate at `t`.
    fn yaw(&self, t: f64) -> (f64, f64) {
        let tt = t - self.t0;
        match self.yaw_course_offset {
            None => (self.rpy[2].at(tt), self.rpy[2].rate(tt)),
            Some(off) => {
                let (v, a) = (self.v_n(t), self.a_n(t));
                let rate = (v.x * a.y - v.y * a.x) / (v.x * v.x + v.y * v.y);
                (v.y.atan2(v.x) + off, rate)
            }
        }
    }
    pub fn c_bn(&self, t: f64) -> Matrix3<f64> {
        let tt = t - self.t0;
        c_bn_from_euler(&Vector3::new(
            self.rpy[0].at(tt),
            self.rpy[1].at(tt),
            self.yaw(t).0,
        ))
    }
    pub fn v_n(&self, t: f64) -> Vector3<f64> {
        let tt = t - self.t0;
        Vector3::new(self.vel[0].at(tt), self.vel[1].at(tt), self.vel[2].at(tt))
    }
    fn a_n(&self, t: f64) -> Vector3<f64> {
        let tt = t - self.t0;
        Vector3::new(
            self.vel[0].rate(tt),
            self.vel[1].rate(tt),
            self.vel[2].rate(tt),
        )
    }
    /// Position by integrating the velocity (Simpson on 10 ms steps).
    pub fn lla(&self, t: f64) -> Vector3<f64> {
        let n = ((t - self.t0) / 0.01).ceil().max(1.0) as usize;
        let h = (t - self.t0) / n as f64;
        let mut d = Vector3::zeros();
        for i in 0..n {
            let a = self.t0 + i as f64 * h;
            d += (self.v_n(a) + 4.0 * self.v_n(a + 0.5 * h) + self.v_n(a + h)) * (h / 6.0);
        }
        lla_add_ned(&self.lla0, &d)
    }
    /// True specific force and angular rate in the body frame.
    pub fn f_w_b(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let lat = self.lla0.x;
        let v = self.v_n(t);
        let g = Vector3::new(0.0, 0.0, gravity_normal(lat, self.lla0.z));
        let w_ie = omega_ie_n(lat);
        let w_en = omega_en_n(lat, self.lla0.z, &v);
        let c_nb = self.c_bn(t).transpose();
        let f = c_nb * (self.a_n(t) - g + (2.0 * w_ie + w_en).cross(&v));
        let tt = t - self.t0;
        let (r, p) = (self.rpy[0].at(tt), self.rpy[1].at(tt));
        let (dr, dp, dy) = (self.rpy[0].rate(tt), self.rpy[1].rate(tt), self.yaw(t).1);
        let w_nb = Vector3::new(
            dr - dy * p.sin(),
            dp * r.cos() + dy * r.sin() * p.cos(),
            -dp * r.sin() + dy * r.cos() * p.cos(),
        );
        (f, w_nb + c_nb * (w_ie + w_en))
    }
}

/// Sensor errors and rates of a synthetic data set.
#[derive(Clone, Debug)]
pub struct Sensors {
    pub imu_rate_hz: f64,
    pub gnss_rate_hz: f64,
    pub gyro_bias: Vector3<f64>,
    pub accel_bias: Vector3<f64>,
    /// Gyro scale factor errors \[-\].
    pub gyro_scale: Vector3<f64>,
    /// ARW \[rad/sqrt(s)\] and VRW \[m/s/sqrt(s)\].
    pub arw: f64,
    pub vrw: f64,
    /// Vibration: amplitudes of sinusoids at 23 and 41 Hz on every axis (accel
    /// \[m/s²\], gyro \[rad/s\]).
    pub vib_accel: f64,
    pub vib_gyro: f64,
    pub lever_arm_b: Vector3<f64>,
    pub vel_std: f64,
    pub pos_std: f64,
    /// Fraction of GNSS epochs with a gross velocity (and position) error.
    pub outliers: f64,
}

/// The IMU samples and GNSS fixes of `motion` over `duration_s`.
pub fn generate(
    m: &Motion,
    s: &Sensors,
    duration_s: f64,
    seed: u64,
) -> (Vec<ImuSample>, Vec<GnssFix>) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let nrm = Normal::new(0.0, 1.0).unwrap();
    let dt = 1.0 / s.imu_rate_hz;
    let n = (duration_s * s.imu_rate_hz).round() as usize;
    let sub = 8;
    let mut imu = Vec::with_capacity(n);
    let vib_phase: Vec<f64> = (0..12).map(|_| rng.random_range(0.0..2.0 * PI)).collect();
    // Exact integral of a sin(2 pi f t + p) over [a, b].
    let vib_int = |amp: f64, f: f64, p: f64, a: f64, b: f64| {
        let w = 2.0 * PI * f;
        amp * ((w * a + p).cos() - (w * b + p).cos()) / w
    };
    for i in 0..n {
        let a = m.t0 + i as f64 * dt;
        let h = dt / sub as f64;
        let (mut dth, mut dv) = (Vector3::zeros(), Vector3::zeros());
        for j in 0..sub {
            let tm = a + (j as f64 + 0.5) * h;
            let (f, w) = m.f_w_b(tm);
            dth += w.component_mul(&s.gyro_scale.add_scalar(1.0)) * h;
            dv += f * h;
        }
        for ax in 0..3 {
            for (k, freq) in [23.0, 41.0].iter().enumerate() {
                let (pa, pg) = (vib_phase[ax * 4 + k], vib_phase[ax * 4 + 2 + k]);
                dv[ax] += vib_int(s.vib_accel, *freq, pa, a - m.t0, a - m.t0 + dt);
                dth[ax] += vib_int(s.vib_gyro, *freq, pg, a - m.t0, a - m.t0 + dt);
            }
            dth[ax] += s.gyro_bias[ax] * dt + s.arw * dt.sqrt() * nrm.sample(&mut rng);
            dv[ax] += s.accel_bias[ax] * dt + s.vrw * dt.sqrt() * nrm.sample(&mut rng);
        }
        imu.push(ImuSample {
            t: a + dt,
            dt,
            dtheta: dth,
            dvel: dv,
        });
    }
    let mut fixes = Vec::new();
    let dg = 1.0 / s.gnss_rate_hz;
    let mut k = 0;
    while k as f64 * dg <= duration_s + 1e-9 {
        let t = m.t0 + k as f64 * dg;
        k += 1;
        let c = m.c_bn(t);
        let (_, w) = m.f_w_b(t);
        let v_ant = m.v_n(t) + c * (w - c.transpose() * omega_ie_n(m.lla0.x)).cross(&s.lever_arm_b);
        let mut p_err = Vector3::from_fn(|_, _| s.pos_std * nrm.sample(&mut rng));
        let mut v_err = Vector3::from_fn(|_, _| s.vel_std * nrm.sample(&mut rng));
        if rng.random::<f64>() < s.outliers {
            v_err += Vector3::from_fn(|_, _| rng.random_range(-8.0..8.0));
            p_err += Vector3::from_fn(|_, _| rng.random_range(-30.0..30.0));
        }
        fixes.push(GnssFix {
            t,
            lla: lla_add_ned(&m.lla(t), &(c * s.lever_arm_b + p_err)),
            std_ned: Vector3::repeat(s.pos_std.max(0.01)),
            vel_ned: Some(v_ant + v_err),
            vel_std_ned: Some(Vector3::repeat(s.vel_std.max(0.005))),
        });
    }
    (imu, fixes)
}

/// A random motion: a car (heading = course plus a mounting yaw of up to 10 deg,
/// small tilts) or, with `uav`, a flying body whose heading is not its course (tilts
/// up to 20 deg). `moving`: about 8 m/s with accelerations of about 1 m/s² (else at
/// rest).
pub fn random_motion(seed: u64, uav: bool, moving: bool) -> Motion {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed ^ 0x5eed);
    let mut wave = |x0: f64, amp: f64, wmin: f64, wmax: f64, n: usize| Wave {
        x0,
        terms: (0..n)
            .map(|_| {
                (
                    amp * rng.random_range(0.3..1.0),
                    rng.random_range(wmin..wmax),
                    rng.random_range(0.0..2.0 * PI),
                )
            })
            .collect(),
    };
    let tilt = if uav { 0.35 } else { 0.06 };
    let yaw0 = (seed as f64 * 1.7) % (2.0 * PI) - PI;
    let speed = if moving { 8.0 } else { 0.0 };
    let course = yaw0 + if uav { 1.2 } else { 0.0 };
    let lat = ((seed % 7) as f64 * 23.0 - 70.0).to_radians();
    let lon = ((seed % 11) as f64 * 30.0 - 150.0).to_radians();
    let acc = if moving { 1.0 } else { 0.0 };
    let mount_yaw = ((seed % 5) as f64 - 2.0) * 0.08;
    let mut w = |x0: f64, a: f64| wave(x0, a, 0.1, 0.5, 2);
    Motion {
        yaw_course_offset: (moving && !uav).then_some(mount_yaw),
        t0: 345_600.0 + (seed % 100) as f64,
        lla0: Vector3::new(lat, lon, 100.0 + (seed % 13) as f64 * 150.0),
        rpy: [
            if moving {
                w(0.0, tilt)
            } else {
                Wave::constant(0.02)
            },
            if moving {
                w(0.0, tilt)
            } else {
                Wave::constant(-0.03)
            },
            if moving {
                w(yaw0, 0.5)
            } else {
                Wave::constant(yaw0)
            },
        ],
        vel: [
            w(speed * course.cos(), 3.0 * acc),
            w(speed * course.sin(), 3.0 * acc),
            w(0.0, 0.3 * acc),
        ],
    }
}
