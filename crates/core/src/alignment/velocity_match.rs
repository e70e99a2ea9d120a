//! In-motion alignment by velocity matching: the attitude C_b^n of the IMU at the first
//! of a window of GNSS epochs t_0 .. t_K, from the gyro-rotated specific force
//! integrated between the epochs against the GNSS velocity changes and gravity
//! (docs/ALGORITHMS.md "In-motion alignment"; REFERENCES [WU11], [WU13], [SILSON11]).
//!
//! With R(t) = C_{b(t)}^{b(t_0)} from the gyros, each interval k = (t_{k-1}, t_k] gives
//!
//!   y_k = Δv_k - g^n Δt_k + ∫ (2 ω_ie^n + ω_en^n) × v^n dt = C_b^n(t_0) u_k,     (1)
//!   u_k = ∫ R f^b dt + R(t_k)(ω_k × l^b) - R(t_{k-1})(ω_{k-1} × l^b),
//!
//! (Δv_k of the antenna at lever arm l^b; y_k is then turned into the navigation frame
//! of t_0, which rotates at ω_in = ω_ie + ω_en, to first order). (1) over all k is
//! Wahba's problem [WAHBA65], solved in closed form by SVD [MARKLEY88] for a start.
//! Summed from t_0 it is the velocity-matching equation per epoch k = 0..K
//!
//!   Y_k = sum_{i<=k} y_i = C_b^n(t_0) (U_k - Q_k b_a) + δv_0 + e_k,                 (2)
//!   U_k = sum_{i<=k} u_i,  Q_k = integral of R from t_0 to t_k,
//!
//! with δv_0 the error of the first GNSS velocity, b_a an accelerometer bias and e_k
//! the error of the k-th velocity (independent per epoch; interval differences would be
//! correlated). Gauss-Newton solves (2) for the attitude, δv_0, b_a and the gyro bias
//! and scale factor (R depends on them), the IMU errors with the configuration's
//! priors; the epochs are reweighted by Huber's weights, then Tukey's biweight, on
//! their normalised residuals (iteratively reweighted least squares, [HOLLAND77],
//! [BT74]) so that a bad GNSS velocity does not tilt the fit. For a vehicle whose
//! heading is its course, the vehicle yaw at epochs at speed can be held to the course
//! (pseudo-measurements).

use crate::attitude::{quat_from_rotvec, skew, wrap_pi};
use crate::earth::{gravity_normal, omega_en_n, omega_ie_n};
use crate::types::ImuSample;
use nalgebra::{Matrix3, Rotation3, SMatrix, SVector, UnitQuaternion, Vector3};

/// A GNSS antenna velocity at an epoch on the IMU time scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelEpoch {
    /// Time of validity on the IMU time scale \[s\].
    pub t: f64,
    /// Antenna velocity NED \[m/s\].
    pub v_n: Vector3<f64>,
    /// Its variance per axis \[m²/s²\].
    pub var_n: Vector3<f64>,
}

/// Hold the vehicle yaw to the GNSS course (a land vehicle's heading is its course).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CourseHold {
    /// C_b^m: IMU frame to vehicle frame (the nominal mounting).
    pub c_bm: Matrix3<f64>,
    /// Epochs at or above this horizontal speed give a course \[m/s\].
    pub min_speed_mps: f64,
    /// 1-sigma of the vehicle yaw against the course beyond the velocity noise
    /// (sideslip, mounting) \[rad\].
    pub std_rad: f64,
    /// In a turn the course of the antenna is not the heading: it differs by about
    /// atan(turn rate x lever / speed) with the antenna this far \[m\] ahead of or
    /// behind the point that does not slip (the rear axle); added to the 1-sigma.
    pub turn_lever_m: f64,
}

/// What the fit needs.
#[derive(Clone, Copy, Debug)]
pub struct FitSetup<'a> {
    /// Compensated IMU samples covering `epochs[0].t ..= epochs[K].t` (contiguous).
    pub samples: &'a [ImuSample],
    /// At least two GNSS epochs, increasing in time.
    pub epochs: &'a [VelEpoch],
    /// Site (gravity, Earth rate): latitude, longitude \[rad\], height \[m\].
    pub lla: Vector3<f64>,
    /// GNSS antenna from the IMU, body frame \[m\].
    pub lever_arm_b: Vector3<f64>,
    /// Velocity random walk of the accelerometers \[m/s/sqrt(s)\].
    pub vrw: f64,
    /// Prior 1-sigma of the gyro bias left after compensation \[rad/s\]; 0 = known.
    pub gyro_bias_std: Vector3<f64>,
    /// Prior 1-sigma of the accelerometer bias left after compensation \[m/s²\].
    pub accel_bias_std: Vector3<f64>,
    /// Prior 1-sigma of the gyro scale factor error \[-\]; 0 = known.
    pub gyro_scale_std: Vector3<f64>,
    pub course: Option<CourseHold>,
}

/// The fitted attitude and how well the data determine it.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// C_b^n at `epochs[0].t`.
    pub c_bn: Matrix3<f64>,
    /// Gyro and accelerometer biases found (beyond the compensation) \[rad/s, m/s²\].
    pub gyro_bias: Vector3<f64>,
    pub accel_bias: Vector3<f64>,
    /// Gyro scale factor error found \[-\].
    pub gyro_scale: Vector3<f64>,
    /// Correction of the first epoch's GNSS velocity, δv_0 \[m/s\].
    pub v0_correction: Vector3<f64>,
    /// Covariance of the attitude error as a small rotation in NED \[rad²\].
    pub cov_att: Matrix3<f64>,
    /// GNSS epochs in the fit, and those not rejected by the reweighting.
    pub epochs: usize,
    pub inliers: usize,
    /// Course pseudo-measurements used (0 without [`CourseHold`]).
    pub courses: usize,
    /// Robust residual scale of the epochs: 1 when the residuals are as large as the
    /// GNSS velocity noise and the VRW predict.
    pub scale: f64,
}

impl Fit {
    /// 1-sigma of roll and pitch \[rad\] (the larger axis of the horizontal block).
    pub fn tilt_std(&self) -> f64 {
        let (a, b, c) = (
            self.cov_att[(0, 0)],
            self.cov_att[(1, 1)],
            self.cov_att[(0, 1)],
        );
        let l = 0.5 * (a + b) + (0.25 * (a - b).powi(2) + c * c).sqrt();
        l.max(0.0).sqrt()
    }

    /// 1-sigma of the yaw \[rad\] (rotation about down).
    pub fn yaw_std(&self) -> f64 {
        self.cov_att[(2, 2)].max(0.0).sqrt()
    }
}

/// Gyro errors of a pass: bias \[rad/s\] and scale factor \[-\] (compensation as
/// `ImuErrors::compensate`).
#[derive(Clone, Copy, Debug, Default)]
struct Gyro {
    bias: Vector3<f64>,
    scale: Vector3<f64>,
}

/// One integration of the window with gyro errors: u_k and R at every epoch.
struct Pass {
    /// u_k per interval (K).
    u: Vec<Vector3<f64>>,
    /// U_k = sum of u_1 .. u_k per epoch (K + 1, U_0 = 0).
    big_u: Vec<Vector3<f64>>,
    /// Q_k = integral of R from t_0 to t_k per epoch (K + 1): U_k moves by -Q_k b_a
    /// with an accelerometer bias b_a.
    q: Vec<Matrix3<f64>>,
    /// R at every epoch (K + 1).
    r_at: Vec<UnitQuaternion<f64>>,
}

const EPS_T: f64 = 1e-9;
/// Unknowns: attitude correction, gyro bias, first velocity error, accelerometer bias,
/// gyro scale factor.
const NP: usize = 15;
/// Finite-difference steps of the gyro bias \[rad/s\] and scale factor \[-\].
const H: f64 = 1e-5;
const H_SCALE: f64 = 1e-4;
/// Tukey's biweight constant (95 % efficiency at the normal, [HOLLAND77]).
const TUKEY_C: f64 = 4.685;
/// Median of sqrt(chi²_3 / 3): the robust scale of 3-vector residuals is
/// median(z) / this.
const MEDIAN_Z3: f64 = 0.8880;

/// Mean compensated angular rate \[rad/s\] of the samples overlapping t ± 25 ms (the
/// lever-arm velocity ω × l at an epoch; averaging keeps vibration out).
fn rate_near(samples: &[ImuSample], t: f64) -> Vector3<f64> {
    let (lo, hi) = (t - 0.025, t + 0.025);
    let (mut sum, mut time) = (Vector3::zeros(), 0.0);
    let mut nearest: Option<&ImuSample> = None;
    for s in samples {
        let (a, e) = (s.t - s.dt, s.t);
        if e >= t && a <= t {
            nearest = Some(s);
        }
        let ov = e.min(hi) - a.max(lo);
        if ov > 0.0 && s.dt > 0.0 {
            sum += s.dtheta * (ov / s.dt);
            time += ov;
        }
        if a > hi {
            break;
        }
    }
    if time > 0.0 {
        sum / time
    } else {
        nearest.map_or(Vector3::zeros(), |s| s.dtheta / s.dt)
    }
}

fn integrate(s: &FitSetup, g: &Gyro, rates: &[Vector3<f64>]) -> Option<Pass> {
    let b = &g.bias;
    let ep = s.epochs;
    let k_max = ep.len() - 1;
    let first = s.samples.first()?;
    if first.t - first.dt > ep[0].t + 1e-6 {
        return None;
    }
    let lever = |k: usize, r: &UnitQuaternion<f64>| r * (rates[k] - b).cross(&s.lever_arm_b);
    let mut r = UnitQuaternion::identity();
    let mut r_at = Vec::with_capacity(ep.len());
    r_at.push(r);
    let mut q_sum = Matrix3::zeros();
    let mut q = Vec::with_capacity(ep.len());
    q.push(q_sum);
    let mut u = Vec::with_capacity(k_max);
    let mut acc = Vector3::zeros();
    let mut k = 0;
    for smp in s.samples {
        if smp.t <= ep[0].t + EPS_T || smp.dt <= 0.0 {
            continue;
        }
        let mut lo = (smp.t - smp.dt).max(ep[0].t);
        loop {
            let t_next = ep[k + 1].t;
            let hi = smp.t.min(t_next);
            if hi > lo {
                let f = (hi - lo) / smp.dt;
                let dth = (smp.dtheta - b * smp.dt).component_div(&g.scale.add_scalar(1.0)) * f;
                let dv = smp.dvel * f;
                // Velocity increment in b(t_0) with the rotation within the piece.
                acc += r * (dv + 0.5 * dth.cross(&dv));
                let r_mid = r * quat_from_rotvec(&(0.5 * dth));
                q_sum += r_mid.to_rotation_matrix().into_inner() * (hi - lo);
                r *= quat_from_rotvec(&dth);
            }
            if hi >= t_next - EPS_T {
                u.push(acc + lever(k + 1, &r) - lever(k, &r_at[k]));
                r_at.push(r);
                q.push(q_sum);
                acc = Vector3::zeros();
                k += 1;
                if k == k_max {
                    let mut big_u = Vec::with_capacity(u.len() + 1);
                    big_u.push(Vector3::zeros());
                    for x in &u {
                        big_u.push(big_u[big_u.len() - 1] + x);
                    }
                    return Some(Pass { u, big_u, q, r_at });
                }
                lo = hi;
                if hi >= smp.t - EPS_T {
                    break;
                }
            } else {
                break;
            }
        }
    }
    None
}

/// Wahba's problem: the rotation C minimising sum w_k |y_k - C u_k|², by SVD of
/// B = sum w_k y_k u_k^T: C = U diag(1, 1, det U det V) V^T [MARKLEY88].
pub fn wahba(pairs: impl Iterator<Item = (f64, Vector3<f64>, Vector3<f64>)>) -> Matrix3<f64> {
    let mut b = Matrix3::zeros();
    for (w, y, u) in pairs {
        b += w * y * u.transpose();
    }
    let svd = b.svd(true, true);
    let (u, v_t) = (svd.u.expect("requested"), svd.v_t.expect("requested"));
    let d = u.determinant() * v_t.determinant();
    u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d.signum())) * v_t
}

/// Vehicle yaw \[rad\] of the IMU attitude `c_bn` with the mounting C_b^m.
fn vehicle_yaw(c_bn: &Matrix3<f64>, c_bm: &Matrix3<f64>) -> f64 {
    let c_mn = c_bn * c_bm.transpose();
    c_mn[(1, 0)].atan2(c_mn[(0, 0)])
}

/// Horizontal speed and course \[rad\] of an epoch.
fn course_of(e: &VelEpoch) -> (f64, f64) {
    (e.v_n.x.hypot(e.v_n.y), e.v_n.y.atan2(e.v_n.x))
}

/// Per epoch k = 0..K the left side of (2) and its variance (diagonal): the
/// velocity change since t_0 less gravity plus the Coriolis terms (trapezoid), in the
/// navigation frame of t_0 (C_n(t)^n(t_0) ~ I + [(t - t_0) ω_in ×], first order).
fn targets(s: &FitSetup) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let g_n = Vector3::new(0.0, 0.0, gravity_normal(s.lla.x, s.lla.z));
    let w_ie = omega_ie_n(s.lla.x);
    let e0 = &s.epochs[0];
    let mut y_sum = Vector3::zeros();
    let mut out = vec![(Vector3::zeros(), e0.var_n)];
    for p in s.epochs.windows(2) {
        let dt = p[1].t - p[0].t;
        let v_mid = 0.5 * (p[0].v_n + p[1].v_n);
        let w_en = omega_en_n(s.lla.x, s.lla.z, &v_mid);
        let y = p[1].v_n - p[0].v_n - g_n * dt + (2.0 * w_ie + w_en).cross(&v_mid) * dt;
        y_sum += y + ((0.5 * (p[0].t + p[1].t) - e0.t) * (w_ie + w_en)).cross(&y);
        let var = p[1].var_n + Vector3::repeat(s.vrw * s.vrw * (p[1].t - e0.t));
        out.push((y_sum, var));
    }
    out
}

/// Fit the attitude at `epochs[0].t` (None: fewer than two epochs, samples that do
/// not cover the window, or a degenerate solve).
pub fn fit(s: &FitSetup) -> Option<Fit> {
    if s.epochs.len() < 2 {
        return None;
    }
    let rates: Vec<Vector3<f64>> = s.epochs.iter().map(|e| rate_near(s.samples, e.t)).collect();
    let tg = targets(s);
    let n_ep = tg.len();
    let mut gyro = Gyro::default();
    let mut pass = integrate(s, &gyro, &rates)?;
    // Closed-form start from the intervals (Wahba).
    let mut c = wahba(tg.windows(2).zip(&pass.u).map(|(p, u)| {
        let var = p[0].1 + p[1].1;
        (3.0 / var.sum(), p[1].0 - p[0].0, *u)
    }));
    // Course epochs: (epoch, course, variance).
    let courses: Vec<(usize, f64, f64)> = match &s.course {
        Some(h) => s
            .epochs
            .iter()
            .enumerate()
            .filter_map(|(k, e)| {
                let (speed, course) = course_of(e);
                (speed >= h.min_speed_mps).then(|| {
                    let var_v = 0.5 * (e.var_n.x + e.var_n.y) / (speed * speed);
                    // Turn rate from the neighbouring courses.
                    let (a, b) = (
                        &s.epochs[k.saturating_sub(1)],
                        &s.epochs[(k + 1).min(s.epochs.len() - 1)],
                    );
                    let turn = if b.t > a.t {
                        wrap_pi(course_of(b).1 - course_of(a).1) / (b.t - a.t)
                    } else {
                        0.0
                    };
                    let slip = (turn * h.turn_lever_m / speed).atan();
                    (k, course, h.std_rad * h.std_rad + var_v + slip * slip)
                })
            })
            .collect(),
        None => Vec::new(),
    };
    if let (Some(h), Some(&(k, course, _))) = (&s.course, courses.first()) {
        // Start from the course: turn about down so that the vehicle yaw at epoch k is
        // the course.
        let d = wrap_pi(course - vehicle_yaw(&(c * pass.r_at[k].to_rotation_matrix()), &h.c_bm));
        c = Rotation3::from_axis_angle(&Vector3::z_axis(), d).into_inner() * c;
    }
    let info = |x: f64| if x > 0.0 { 1.0 / (x * x) } else { 1e18 };
    let prior_b = s.gyro_bias_std.map(info);
    let prior_ba = s.accel_bias_std.map(info);
    let prior_k = s.gyro_scale_std.map(info);
    // Unknowns: attitude correction (3), gyro bias (3), error of the first GNSS
    // velocity (3), accelerometer bias (3), gyro scale factor (3).
    let mut d_v0 = Vector3::zeros();
    let mut b_a = Vector3::zeros();
    let mut robust_w = vec![1.0; n_ep];
    let mut scale = 1.0;
    let mut normal = SMatrix::<f64, NP, NP>::zeros();
    for iter in 0..20 {
        // Sensitivities of U and R to the gyro bias and scale (finite differences;
        // the columns 3..6 and 12..15).
        let perturbed: Vec<(usize, Pass)> = (0..6)
            .map(|j| {
                let mut g = gyro;
                let col = if j < 3 {
                    g.bias[j] += H;
                    3 + j
                } else {
                    g.scale[j - 3] += H_SCALE;
                    12 + j - 3
                };
                integrate(s, &g, &rates).map(|p| (col, p))
            })
            .collect::<Option<_>>()?;
        let mut n = SMatrix::<f64, NP, NP>::zeros();
        let mut rhs = SVector::<f64, NP>::zeros();
        let mut z = Vec::with_capacity(n_ep);
        for k in 0..n_ep {
            let (y, var) = &tg[k];
            let cq = c * pass.q[k];
            let cu = c * pass.big_u[k] - cq * b_a;
            let r = y - cu - d_v0;
            let w_inv = Matrix3::from_diagonal(&var.map(|v| 1.0 / v));
            z.push((r.transpose() * w_inv * r)[0].sqrt() / 3f64.sqrt());
            let mut j = SMatrix::<f64, 3, NP>::zeros();
            j.fixed_view_mut::<3, 3>(0, 0).copy_from(&skew(&cu));
            for (col, p) in &perturbed {
                let h = if *col < 12 { H } else { H_SCALE };
                let du = (p.big_u[k] - pass.big_u[k]) / h;
                j.fixed_view_mut::<3, 1>(0, *col).copy_from(&(-(c * du)));
            }
            j.fixed_view_mut::<3, 3>(0, 6)
                .copy_from(&(-Matrix3::identity()));
            j.fixed_view_mut::<3, 3>(0, 9).copy_from(&cq);
            let wk = robust_w[k] * w_inv;
            n += j.transpose() * wk * j;
            rhs -= j.transpose() * wk * r;
        }
        if let Some(h) = &s.course {
            for &(k, course, var) in &courses {
                let yaw_of = |c: &Matrix3<f64>, r: &UnitQuaternion<f64>| {
                    vehicle_yaw(&(c * r.to_rotation_matrix()), &h.c_bm)
                };
                let r = wrap_pi(course - yaw_of(&c, &pass.r_at[k]));
                let mut j = SMatrix::<f64, 1, NP>::zeros();
                for m in 0..3 {
                    let mut e = Vector3::zeros();
                    e[m] = H;
                    let cp = Rotation3::new(e).into_inner() * c;
                    j[m] = -wrap_pi(yaw_of(&cp, &pass.r_at[k]) - yaw_of(&c, &pass.r_at[k])) / H;
                }
                for (col, p) in &perturbed {
                    let h = if *col < 12 { H } else { H_SCALE };
                    j[*col] = -wrap_pi(yaw_of(&c, &p.r_at[k]) - yaw_of(&c, &pass.r_at[k])) / h;
                }
                n += j.transpose() * j / var;
                rhs -= j.transpose() * r / var;
            }
        }
        // Priors: the biases about zero, a weak one (180 deg) on the attitude
        // correction (keeps an unobservable yaw in place).
        for m in 0..3 {
            n[(m, m)] += 1.0 / (std::f64::consts::PI * std::f64::consts::PI);
            n[(3 + m, 3 + m)] += prior_b[m];
            rhs[3 + m] -= prior_b[m] * gyro.bias[m];
            n[(12 + m, 12 + m)] += prior_k[m];
            rhs[12 + m] -= prior_k[m] * gyro.scale[m];
            n[(9 + m, 9 + m)] += prior_ba[m];
            rhs[9 + m] -= prior_ba[m] * b_a[m];
        }
        // Robust scale of the normalised residuals, then the weights for the next
        // iteration: Huber's at first (a safe start), Tukey's biweight after.
        let mut sorted = z.clone();
        sorted.sort_by(f64::total_cmp);
        scale = sorted[sorted.len() / 2] / MEDIAN_Z3;
        let s_eff = scale.max(1.0);
        let dx = n.cholesky()?.solve(&rhs);
        normal = n;
        let phi = Vector3::new(dx[0], dx[1], dx[2]);
        c = Rotation3::new(phi).into_inner() * c;
        gyro.bias += Vector3::new(dx[3], dx[4], dx[5]);
        gyro.scale += Vector3::new(dx[12], dx[13], dx[14]);
        d_v0 += Vector3::new(dx[6], dx[7], dx[8]);
        b_a += Vector3::new(dx[9], dx[10], dx[11]);
        pass = integrate(s, &gyro, &rates)?;
        for k in 0..n_ep {
            let u = z[k] / s_eff;
            robust_w[k] = if iter < 2 {
                if u <= 2.0 {
                    1.0
                } else {
                    2.0 / u
                }
            } else if u < TUKEY_C {
                (1.0 - (u / TUKEY_C).powi(2)).powi(2)
            } else {
                0.0
            };
        }
        if iter >= 3 && phi.norm() < 1e-7 && dx.fixed_rows::<3>(3).norm() < 1e-8 {
            break;
        }
    }
    let inliers = robust_w.iter().filter(|w| **w > 0.0).count();
    if inliers < 3 {
        return None;
    }
    let cov = normal.try_inverse()?;
    let s2 = scale.max(1.0).powi(2);
    let c = Rotation3::from_matrix(&c).into_inner();
    Some(Fit {
        c_bn: c,
        gyro_bias: gyro.bias,
        accel_bias: b_a,
        gyro_scale: gyro.scale,
        v0_correction: d_v0,
        cov_att: cov.fixed_view::<3, 3>(0, 0).into_owned() * s2,
        epochs: n_ep,
        inliers,
        courses: courses.len(),
        scale,
    })
}

/// An upper bound of the yaw information of a window, sum_k |v_k,h - mean v_h|² /
/// var_k \[1/rad²\]: a rotation about down moves the horizontal velocity changes
/// (the mean goes into δv_0), so the fit's yaw 1-sigma is at least its inverse square
/// root (a cheap test before fitting).
pub fn yaw_information_bound(epochs: &[VelEpoch]) -> f64 {
    let n = epochs.len().max(1) as f64;
    let mean = epochs
        .iter()
        .map(|e| e.v_n.xy())
        .sum::<nalgebra::Vector2<f64>>()
        / n;
    epochs
        .iter()
        .map(|e| (e.v_n.xy() - mean).norm_squared() / (0.5 * (e.var_n.x + e.var_n.y)).max(1e-12))
        .sum()
}

#[cfg(test)]
#[path = "velocity_match_tests.rs"]
mod tests;
