//! Continuous error dynamics x_dot = F x + G w of the INS error state and their
//! discretisation. SYSTEM.md §2 (seed 002 eq. 9-10, seed 004 eq. 13); the full
//! NED blocks (position error in metres) follow from linearising SYSTEM.md §1.
//!
//!   dr_dot   = F_rr dr + dv
//!   dv_dot   = F_vr dr + F_vv dv + (f^n x) phi + C_b^n (b_a + diag(f^b) s_a) + C_b^n w_a
//!   phi_dot  = F_pr dr + F_pv dv - (w_in^n x) phi - C_b^n (b_g + diag(w^b) s_g) - C_b^n w_g
//!   b_dot, s_dot = -x / T + w  (first-order Gauss-Markov, driving PSD 2 sigma² / T)

use crate::attitude::skew;
use crate::config::ImuNoise;
use crate::earth::{gravity_normal, omega_en_n, omega_ie_n, radii, OMEGA_IE};
use crate::state::{Block, StateLayout, ATT, BA, BG, POS, SA, SG, VEL};
use crate::types::NavState;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// Mean inertial quantities over a propagation interval.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeanMotion {
    /// Specific force in n \[m/s²\].
    pub f_n: Vector3<f64>,
    /// Specific force in b \[m/s²\].
    pub f_b: Vector3<f64>,
    /// Angular rate w_ib^b \[rad/s\].
    pub w_b: Vector3<f64>,
}

fn set3(m: &mut DMatrix<f64>, r: usize, c: usize, b: &Matrix3<f64>) {
    for i in 0..3 {
        for j in 0..3 {
            m[(r + i, c + j)] = b[(i, j)];
        }
    }
}

/// Fill `f` (n x n, zeroed here) with the continuous dynamics matrix F.
pub fn fill_f(
    f: &mut DMatrix<f64>,
    layout: &StateLayout,
    nav: &NavState,
    mm: &MeanMotion,
    corr_time_s: f64,
) {
    // Slice operations: nalgebra's element iterators are slow at this size.
    f.as_mut_slice().fill(0.0);
    let (lat, h) = (nav.lla.x, nav.lla.z);
    let (vn, ve, vd) = (nav.v_n.x, nav.v_n.y, nav.v_n.z);
    let (rm, rn) = radii(lat);
    let (rmh, rnh) = (rm + h, rn + h);
    let (s, c) = lat.sin_cos();
    let t = s / c;
    let sec2 = 1.0 / (c * c);
    let we = OMEGA_IE;
    let g = gravity_normal(lat, h);
    let c_bn = nav.q_bn.to_rotation_matrix().into_inner();

    let f_rr = Matrix3::new(
        -vd / rmh,
        0.0,
        vn / rmh,
        ve * t / rnh,
        -(vd + vn * t) / rnh,
        ve / rnh,
        0.0,
        0.0,
        0.0,
    );
    let f_vr = Matrix3::new(
        -2.0 * ve * we * c / rmh - ve * ve * sec2 / (rmh * rnh),
        0.0,
        vn * vd / (rmh * rmh) - ve * ve * t / (rnh * rnh),
        2.0 * we * (vn * c - vd * s) / rmh + vn * ve * sec2 / (rmh * rnh),
        0.0,
        (ve * vd + vn * ve * t) / (rnh * rnh),
        2.0 * we * ve * s / rmh,
        0.0,
        -ve * ve / (rnh * rnh) - vn * vn / (rmh * rmh) + 2.0 * g / ((rm * rn).sqrt() + h),
    );
    let f_vv = Matrix3::new(
        vd / rmh,
        -2.0 * (we * s + ve * t / rnh),
        vn / rmh,
        2.0 * we * s + ve * t / rnh,
        (vd + vn * t) / rnh,
        2.0 * we * c + ve / rnh,
        -2.0 * vn / rmh,
        -2.0 * (we * c + ve / rnh),
        0.0,
    );
    let f_pr = Matrix3::new(
        -we * s / rmh,
        0.0,
        ve / (rnh * rnh),
        0.0,
        0.0,
        -vn / (rmh * rmh),
        -we * c / rmh - ve * sec2 / (rmh * rnh),
        0.0,
        -ve * t / (rnh * rnh),
    );
    let f_pv = Matrix3::new(
        0.0,
        1.0 / rnh,
        0.0,
        -1.0 / rmh,
        0.0,
        0.0,
        0.0,
        -t / rnh,
        0.0,
    );
    let w_in = omega_ie_n(lat) + omega_en_n(lat, h, &nav.v_n);

    set3(f, POS, POS, &f_rr);
    set3(f, POS, VEL, &Matrix3::identity());
    set3(f, VEL, POS, &f_vr);
    set3(f, VEL, VEL, &f_vv);
    set3(f, VEL, ATT, &skew(&mm.f_n));
    set3(f, VEL, BA, &c_bn);
    set3(f, VEL, SA, &(c_bn * Matrix3::from_diagonal(&mm.f_b)));
    set3(f, ATT, POS, &f_pr);
    set3(f, ATT, VEL, &f_pv);
    set3(f, ATT, ATT, &(-skew(&w_in)));
    set3(f, ATT, BG, &(-c_bn));
    set3(f, ATT, SG, &(-(c_bn * Matrix3::from_diagonal(&mm.w_b))));
    let decay = if corr_time_s > 0.0 {
        -1.0 / corr_time_s
    } else {
        0.0
    };
    for i in BG..SA + 3 {
        f[(i, i)] = decay;
    }
    // Time offset: tau_dot = tau_rate. Other blocks are random walks or constants.
    if let (Some(i), Some(j)) = (
        layout.index(Block::TimeOffset),
        layout.index(Block::TimeOffsetRate),
    ) {
        f[(i, j)] = 1.0;
    }
    // Receiver clock: bias_dot = drift.
    if let (Some(i), Some(j)) = (
        layout.index(Block::ClockBias),
        layout.index(Block::ClockDrift),
    ) {
        f[(i, j)] = 1.0;
    }
}

/// Diagonal of the continuous process noise G Qc G^T where G maps white noise into
/// the state; the velocity/attitude parts are rotated by C_b^n (for equal per-axis
/// noise this is rotation invariant, otherwise we keep the full 3x3 block).
pub fn fill_qc(
    qc: &mut DMatrix<f64>,
    layout: &StateLayout,
    nav: &NavState,
    noise: &ImuNoise,
    random_walks: &[(Block, f64)],
) {
    qc.as_mut_slice().fill(0.0);
    let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
    let va = Matrix3::from_diagonal(&noise.vrw.component_mul(&noise.vrw));
    let ag = Matrix3::from_diagonal(&noise.arw.component_mul(&noise.arw));
    set3(qc, VEL, VEL, &(c_bn * va * c_bn.transpose()));
    set3(qc, ATT, ATT, &(c_bn * ag * c_bn.transpose()));
    let tc = noise.corr_time_s;
    let gm = |sigma: f64| {
        if tc > 0.0 {
            2.0 * sigma * sigma / tc
        } else {
            0.0
        }
    };
    for k in 0..3 {
        qc[(BG + k, BG + k)] = gm(noise.gyro_bias_std[k]);
        qc[(BA + k, BA + k)] = gm(noise.accel_bias_std[k]);
        qc[(SG + k, SG + k)] = gm(noise.gyro_scale_std[k]);
        qc[(SA + k, SA + k)] = gm(noise.accel_scale_std[k]);
    }
    // Random-walk PSDs of the appended blocks (time offset, odometer scale, ...).
    for &(b, psd) in random_walks {
        if let Some(i) = layout.index(b) {
            for k in i..i + b.len() {
                qc[(k, k)] = psd;
            }
        }
    }
}

/// Discretise over `dt` (SYSTEM.md §2): Phi = I + F dt, Qd = Qc |dt| (first order;
/// the propagation interval is at most a few tenths of a second). A backward run
/// (nav/backward.rs) has dt < 0: the kinematic couplings take the signed dt, the
/// noise grows with |dt|, and the Gauss-Markov rows are set by
/// [`Discretizer::reverse_gauss_markov`].
pub struct Discretizer {
    pub f: DMatrix<f64>,
    pub qc: DMatrix<f64>,
    pub phi: DMatrix<f64>,
    pub qd: DMatrix<f64>,
}

impl Discretizer {
    pub fn new(n: usize) -> Self {
        let z = || DMatrix::zeros(n, n);
        Discretizer {
            f: z(),
            qc: z(),
            phi: z(),
            qd: z(),
        }
    }

    /// Build Phi and Qd from the current `f` and `qc`.
    pub fn discretize(&mut self, dt: f64) {
        let n = self.f.nrows();
        for (p, f) in self.phi.as_mut_slice().iter_mut().zip(self.f.as_slice()) {
            *p = f * dt;
        }
        for i in 0..n {
            self.phi.as_mut_slice()[i * n + i] += 1.0;
        }
        let adt = dt.abs();
        for (q, c) in self.qd.as_mut_slice().iter_mut().zip(self.qc.as_slice()) {
            *q = c * adt;
        }
    }

    /// Backward (dt < 0): the first-order Gauss-Markov states among `states` (F
    /// diagonal -1/T < 0) decay with |dt| as forward, exactly: Phi = exp(-|dt|/T),
    /// Qd = sigma² (1 - exp(-2|dt|/T)) with sigma² = Qc T / 2 (a stationary
    /// Gauss-Markov process has the same law reversed in time). I + F dt would grow
    /// them by |dt|/T per step.
    pub fn reverse_gauss_markov(&mut self, states: std::ops::Range<usize>, dt: f64) {
        for i in states {
            let a = self.f[(i, i)];
            if a < 0.0 {
                let e = (a * dt.abs()).exp();
                self.phi[(i, i)] = e;
                self.qd[(i, i)] = self.qc[(i, i)] / (-2.0 * a) * (1.0 - e * e);
            }
        }
    }
}
