//! Six-state fusion of GNSS fixes with the dead-reckoning (INS/odometer/NHC) output.
//! SYSTEM.md §5; seed 004 §3: "a 6-state KF, X = \[r^n, v^n\], H = I_6, dynamics
//! r_dot = v, v_dot = C_b^n f^b - 2 Omega_ie v + g, updated every N GNSS periods."
//!
//! The error-state filter (engine.rs) then runs as a pure dead-reckoning (DR)
//! navigator: IMU + odometer + NHC + ZUPT, no GNSS after its start. This filter sits
//! on top of it (a cascade, "loose coupling of the second kind"):
//!
//! - **State.** x = \[r, v^n\]: r is the position of the IMU centre, kept as geodetic
//!   latitude/longitude \[rad\] and ellipsoidal height \[m\] (`lla`); its covariance rows
//!   are in local NED metres at that position, as in the error-state filter (state.rs
//!   POS). v^n is the NED velocity \[m/s\]. P is 6 x 6 over (r_N, r_E, r_D, v_N, v_E, v_D).
//! - **Prediction.** The DR solves the stated dynamics with the same specific force
//!   (mechanization.rs, plus its odometer/NHC corrections), so the prediction takes the
//!   DR's increments over the step, Δr_DR and Δv_DR, as the known input:
//!
//!   ```text
//!   r_{k+1} = r_k + Δr_DR + (v_k - v_DR,k) dt      (r_dot = v)
//!   v_{k+1} = v_k + Δv_DR                          (v_dot = C_b^n f^b - 2 Ω_ie v + g)
//!   Phi = [\[I, I dt\], \[0, I\]]
//!   ```
//!
//!   (the Coriolis and transport-rate terms of a velocity difference of a few cm/s
//!   are below 1e-5 m/s² and left out of Phi).
//! - **Process noise** ([`DrIncrementNoise`]): the covariance of the error of the
//!   DR increments over the interval since the previous six-state prediction, from
//!   the DR filter's own error model. With e = the DR's position/velocity error (its
//!   error states 0..6, NED m and m/s) at the start (1) and end (2) of the interval,
//!   the increment error is e_2 - Phi e_1, so
//!
//!   ```text
//!   Q = P_DR,2 + Phi P_DR,1 Phi^T - C Phi^T - Phi C^T,   C = Cov(e_2, e_1)
//!   ```
//!
//!   where C is carried through the DR's covariance steps (C <- Phi_DR C) and its
//!   measurement updates (C <- (I - K H) C; odometer, NHC, ZUPT). So Q holds the
//!   growth of the DR errors the six-state Phi does not explain (attitude, bias and
//!   scale errors through f^n, VRW; correlated over the interval) and the jumps of the
//!   DR's own corrections (an update that removes a drift the six-state filter had
//!   already removed with GNSS is an increment error too: it contributes P - P+).
//!   The increment errors of successive intervals are treated as uncorrelated.
//! - **Update** with a fix moved to the IMU centre through the DR attitude (antenna
//!   lever arm, [`ImuFix::from_antenna`]): z = \[r_GNSS; v_GNSS\], H = I_6 (I_3 when
//!   the fix has no velocity), R = diag of the fix's std columns; Joseph form. Only
//!   every N-th GNSS epoch is used (`every` = N; the first epoch is always used).
//!
//! No file I/O; the engine owns the cadence of calls (engine.rs, `GnssFusion::SixState`).

use crate::earth::{lla_add_ned, omega_en_n, omega_ie_n, radii};
use crate::types::{GnssFix, NavState};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3, Vector6};
use std::num::NonZeroU32;

/// A GNSS fix moved from the antenna to the IMU centre (what H = I maps onto).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuFix {
    /// Time of validity \[s\].
    pub t: f64,
    /// IMU-centre position: latitude \[rad\], longitude \[rad\], ellipsoidal height \[m\].
    pub lla: Vector3<f64>,
    /// Position 1-sigma N, E, D \[m\].
    pub pos_std_ned_m: Vector3<f64>,
    /// IMU-centre velocity NED \[m/s\] and its 1-sigma, when the fix has them.
    pub vel_ned_mps: Option<Vector3<f64>>,
    pub vel_std_ned_mps: Option<Vector3<f64>>,
}

impl ImuFix {
    /// SYSTEM.md §3a with the DR attitude `c_bn` (C_b^n), the body rate `w_ib_b`
    /// \[rad/s\] and the antenna lever arm `lever_arm_b` \[m, body F R D\]:
    /// r_IMU = r_ant - C_b^n l^b,
    /// v_IMU = v_ant - (C_b^n (w_ib^b x l^b) - w_in^n x (C_b^n l^b)).
    /// The velocity is kept only with its std (both finite).
    pub fn from_antenna(
        fix: &GnssFix,
        c_bn: &Matrix3<f64>,
        w_ib_b: &Vector3<f64>,
        lever_arm_b: &Vector3<f64>,
        v_n_mps: &Vector3<f64>,
    ) -> ImuFix {
        let lever_n_m = c_bn * lever_arm_b;
        let lla = lla_add_ned(&fix.lla, &(-lever_n_m));
        let w_in_n = omega_ie_n(lla.x) + omega_en_n(lla.x, lla.z, v_n_mps);
        let lever_vel_n_mps = c_bn * w_ib_b.cross(lever_arm_b) - w_in_n.cross(&lever_n_m);
        let (vel_ned_mps, vel_std_ned_mps) = match (fix.vel_ned, fix.vel_std_ned) {
            (Some(v), Some(s)) => (Some(v - lever_vel_n_mps), Some(s)),
            _ => (None, None),
        };
        ImuFix {
            t: fix.t,
            lla,
            pos_std_ned_m: fix.std_ned,
            vel_ned_mps,
            vel_std_ned_mps,
        }
    }

    /// Rows in the update: 6 with velocity, 3 without.
    pub fn dof(&self) -> usize {
        if self.vel_ned_mps.is_some() {
            6
        } else {
            3
        }
    }
}

/// What [`SixState::update`] did with a fix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SixStateOutcome {
    /// Fused; normalised innovation squared and its degrees of freedom.
    Applied { nis: f64, dof: usize },
    /// Failed the chi-square gate (normalised innovation squared > threshold).
    Rejected { nis: f64, threshold: f64 },
    /// Not an N-th epoch (`every` = N > 1): not used.
    Skipped,
    /// Innovation covariance not positive definite, or non-finite numbers in the
    /// fix: not used.
    Invalid,
}

/// Why a six-state filter could not be created.
#[derive(Clone, Debug, PartialEq)]
pub struct SixStateError(pub String);

impl std::fmt::Display for SixStateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SixStateError {}

/// The 6-state filter and the DR state it last followed.
#[derive(Clone, Debug)]
pub struct SixState {
    /// Time of the state \[s\] (the DR's time scale).
    t: f64,
    /// IMU-centre position: latitude \[rad\], longitude \[rad\], height \[m\].
    lla: Vector3<f64>,
    v_ned_mps: Vector3<f64>,
    /// Covariance of (r NED \[m\], v NED \[m/s\]).
    p: Matrix6<f64>,
    every: NonZeroU32,
    /// GNSS epochs offered to `update` so far.
    epochs_seen: u64,
    /// The DR position and velocity the last increment ended at.
    dr_lla: Vector3<f64>,
    dr_v_ned_mps: Vector3<f64>,
    /// Process noise from the DR filter's covariance, when tracked.
    dr_noise: Option<DrIncrementNoise>,
}

/// Longitude difference wrapped into (-pi, pi].
fn wrap_dlon(d: f64) -> f64 {
    use std::f64::consts::PI;
    if d > PI {
        d - 2.0 * PI
    } else if d <= -PI {
        d + 2.0 * PI
    } else {
        d
    }
}

/// NED displacement \[m\] from `lla_ref` to `lla` (first order, metre-scale).
fn ned_between(lla: &Vector3<f64>, lla_ref: &Vector3<f64>) -> Vector3<f64> {
    let (m, n) = radii(lla_ref.x);
    Vector3::new(
        (lla.x - lla_ref.x) * (m + lla_ref.z),
        wrap_dlon(lla.y - lla_ref.y) * (n + lla_ref.z) * lla_ref.x.cos(),
        -(lla.z - lla_ref.z),
    )
}

impl SixState {
    /// Start from the DR state `dr` (the six-state solution equals it) with the
    /// position/velocity covariance `p0` (NED m, m/s), using every `every`-th GNSS
    /// epoch. Errors on non-finite input or a `p0` that is not symmetric positive
    /// semi-definite (negative diagonal).
    pub fn new(dr: &NavState, p0: Matrix6<f64>, every: NonZeroU32) -> Result<Self, SixStateError> {
        if !(dr.t.is_finite() && dr.lla.iter().chain(dr.v_n.iter()).all(|x| x.is_finite())) {
            return Err(SixStateError(format!(
                "six-state filter: the initial position/velocity is not finite (t = {})",
                dr.t
            )));
        }
        if !p0.iter().all(|x| x.is_finite()) || (0..6).any(|i| p0[(i, i)] < 0.0) {
            return Err(SixStateError(
                "six-state filter: the initial covariance must be finite with a non-negative diagonal"
                    .into(),
            ));
        }
        Ok(SixState {
            t: dr.t,
            lla: dr.lla,
            v_ned_mps: dr.v_n,
            p: 0.5 * (p0 + p0.transpose()),
            every,
            epochs_seen: 0,
            dr_lla: dr.lla,
            dr_v_ned_mps: dr.v_n,
            dr_noise: None,
        })
    }

    /// Take the process noise from the DR error-state filter from now on
    /// ([`DrIncrementNoise`]); `p_dr` is its current n x n covariance with position
    /// and velocity errors in states 0..6. False (nothing tracked) when the shape
    /// does not fit.
    pub fn track_dr_covariance(&mut self, p_dr: &DMatrix<f64>) -> bool {
        self.dr_noise = DrIncrementNoise::new(p_dr, self.t);
        self.dr_noise.is_some()
    }

    /// The DR filter propagated its covariance with `phi_dr` (n x n).
    pub fn on_dr_predict(&mut self, phi_dr: &DMatrix<f64>) {
        if let Some(d) = self.dr_noise.as_mut() {
            d.after_dr_predict(phi_dr);
        }
    }

    /// The DR filter applied a measurement update with gain `k` (n x m) and
    /// Jacobian `h` (m x n).
    pub fn on_dr_update(&mut self, k: &DMatrix<f64>, h: &DMatrix<f64>) {
        if let Some(d) = self.dr_noise.as_mut() {
            d.after_dr_update(k, h);
        }
    }

    /// Covariance prediction from the last one to the current time (after
    /// [`SixState::follow_dr`]) with the DR increment noise; `p_dr_now` is the DR
    /// filter's covariance now. Without DR tracking, Q = 0. Returns the diagonal of
    /// Q's position block (variance of the DR position increment, NED \[m²\]).
    pub fn predict_covariance_from_dr(&mut self, p_dr_now: &DMatrix<f64>) -> Vector3<f64> {
        let Some(d) = self.dr_noise.as_mut() else {
            return Vector3::zeros();
        };
        let dt_s = self.t - d.t_ref;
        let q = d.noise(p_dr_now, dt_s);
        d.restart(p_dr_now, self.t);
        self.predict_covariance(dt_s, &q);
        Vector3::new(q[(0, 0)], q[(1, 1)], q[(2, 2)])
    }

    /// 1-sigma as [`SixState::std`] but predicted to the current time with the DR
    /// increment noise so far (for output between updates), without changing state.
    pub fn std_now(&self, p_dr_now: &DMatrix<f64>) -> [f64; 6] {
        let mut f = SixState {
            dr_noise: self.dr_noise.clone(),
            ..*self
        };
        f.predict_covariance_from_dr(p_dr_now);
        f.std()
    }

    #[cfg(test)]
    /// IMU-centre position: latitude \[rad\], longitude \[rad\], height \[m\].
    pub fn lla(&self) -> Vector3<f64> {
        self.lla
    }

    #[cfg(test)]
    /// NED velocity \[m/s\].
    pub fn v_ned_mps(&self) -> Vector3<f64> {
        self.v_ned_mps
    }

    /// 1-sigma of (r_N, r_E, r_D \[m\], v_N, v_E, v_D \[m/s\]).
    pub fn std(&self) -> [f64; 6] {
        std::array::from_fn(|i| self.p[(i, i)].max(0.0).sqrt())
    }

    /// The DR state `dr` with this filter's position and velocity (the output
    /// solution: attitude and time stay the DR's).
    pub fn solution(&self, dr: &NavState) -> NavState {
        NavState {
            lla: self.lla,
            v_n: self.v_ned_mps,
            ..*dr
        }
    }

    /// State prediction: apply the DR's increments since the last call (SYSTEM.md
    /// §5; seed 004 §3: r_dot = v, v_dot = C_b^n f^b - 2 Omega_ie v + g, integrated by
    /// the DR with the same specific force). Δt = dr.t - t; the velocity offset
    /// v - v_DR integrates into the position. Includes the DR's own aiding
    /// corrections (odometer, NHC, ZUPT), so call it after every change of the DR
    /// state or at least before each update and each output. Non-finite DR states
    /// are ignored (the engine stops the run on them).
    pub fn follow_dr(&mut self, dr: &NavState) {
        if !(dr.t.is_finite() && dr.lla.iter().chain(dr.v_n.iter()).all(|x| x.is_finite())) {
            return;
        }
        let dt_s = (dr.t - self.t).max(0.0);
        let d_lla = Vector3::new(
            dr.lla.x - self.dr_lla.x,
            wrap_dlon(dr.lla.y - self.dr_lla.y),
            dr.lla.z - self.dr_lla.z,
        );
        let dv_offset_mps = self.v_ned_mps - self.dr_v_ned_mps;
        self.lla = lla_add_ned(&(self.lla + d_lla), &(dv_offset_mps * dt_s));
        self.v_ned_mps += dr.v_n - self.dr_v_ned_mps;
        self.dr_lla = dr.lla;
        self.dr_v_ned_mps = dr.v_n;
        self.t = self.t.max(dr.t);
    }

    /// Covariance prediction over `dt_s`: P = Phi P Phi^T + Q, Phi = [\[I, I dt\], \[0, I\]]
    /// (SYSTEM.md §2 with §5's dynamics); `q` e.g. from [`DrIncrementNoise`]. Ignored
    /// when dt or Q is not finite or dt < 0.
    pub fn predict_covariance(&mut self, dt_s: f64, q: &Matrix6<f64>) {
        if !(dt_s.is_finite() && dt_s >= 0.0 && q.iter().all(|x| x.is_finite())) {
            return;
        }
        let mut phi = Matrix6::identity();
        phi.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(Matrix3::identity() * dt_s));
        let p = phi * self.p * phi.transpose() + q;
        self.p = 0.5 * (p + p.transpose());
    }

    /// Innovation of `fix` against the current prediction, for an integrity test:
    /// y = z - H x (position NED \[m\], then velocity NED \[m/s\] when the fix has one)
    /// and its covariance S = H P H^T + R (3 x 3 or 6 x 6). Distance test: |y_pos|;
    /// NIS: y^T S^-1 y with y.len() dof. None for a fix that is not finite. Call
    /// after [`SixState::follow_dr`] for the fix time.
    pub fn innovation(&self, fix: &ImuFix) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let (y, r) = self.measurement(fix)?;
        let dof = y.len();
        let p = DMatrix::from_column_slice(6, 6, self.p.as_slice());
        Some((y, p.view((0, 0), (dof, dof)).into_owned() + r))
    }

    /// y = z - H x and R for `fix` (H = I_6, or I_3 without a velocity); None when the
    /// fix is not finite or its stds are not positive.
    fn measurement(&self, fix: &ImuFix) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let finite3 = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
        let std_ok = |s: &Vector3<f64>| s.iter().all(|x| x.is_finite() && *x > 0.0);
        if !(finite3(&fix.lla) && std_ok(&fix.pos_std_ned_m)) {
            return None;
        }
        let vel = match (fix.vel_ned_mps, fix.vel_std_ned_mps) {
            (Some(v), Some(s)) if finite3(&v) && std_ok(&s) => Some((v, s)),
            _ => None,
        };
        let dof = if vel.is_some() { 6 } else { 3 };
        // z - H x (SYSTEM.md §2 update; H = I).
        let mut y = DVector::<f64>::zeros(dof);
        let mut r = DMatrix::<f64>::zeros(dof, dof);
        let y_pos_m = ned_between(&fix.lla, &self.lla);
        for i in 0..3 {
            y[i] = y_pos_m[i];
            r[(i, i)] = fix.pos_std_ned_m[i].powi(2);
        }
        if let Some((v, s)) = vel {
            for i in 0..3 {
                y[3 + i] = v[i] - self.v_ned_mps[i];
                r[(3 + i, 3 + i)] = s[i].powi(2);
            }
        }
        Some((y, r))
    }

    /// True when the next epoch offered to [`SixState::update`] will be fused (not
    /// skipped by the every-N cadence).
    pub fn next_epoch_due(&self) -> bool {
        self.epochs_seen.is_multiple_of(u64::from(self.every.get()))
    }

    /// Offer one GNSS epoch: every N-th (the 1st, N+1-th, ...) is fused with
    /// H = I_6 (position and velocity) or I_3 (position only), R from the fix's stds,
    /// Joseph form; `gate` is a chi-square threshold on the normalised innovation
    /// squared for the fix's dof (None: no test).
    pub fn update(&mut self, fix: &ImuFix, gate: Option<f64>) -> SixStateOutcome {
        let due = self.next_epoch_due();
        self.epochs_seen += 1;
        if !due {
            return SixStateOutcome::Skipped;
        }
        self.fuse(fix, gate)
    }

    /// The measurement update itself, without the every-N cadence.
    fn fuse(&mut self, fix: &ImuFix, gate: Option<f64>) -> SixStateOutcome {
        let Some((y, r)) = self.measurement(fix) else {
            return SixStateOutcome::Invalid;
        };
        let dof = y.len();
        let p = DMatrix::from_column_slice(6, 6, self.p.as_slice());
        let h = DMatrix::<f64>::identity(dof, 6);
        let ph_t = &p * h.transpose();
        let s = &h * &ph_t + &r;
        let Some(chol) = s.cholesky() else {
            return SixStateOutcome::Invalid;
        };
        let s_inv_y = chol.solve(&y);
        let nis = (y.transpose() * &s_inv_y)[(0, 0)];
        if !nis.is_finite() {
            return SixStateOutcome::Invalid;
        }
        if let Some(threshold) = gate {
            if nis > threshold {
                return SixStateOutcome::Rejected { nis, threshold };
            }
        }
        // K = P H^T S^-1; x += K y; P = (I - K H) P (I - K H)^T + K R K^T.
        let k = chol.solve(&ph_t.transpose()).transpose();
        let dx = &k * &y;
        let ikh = DMatrix::<f64>::identity(6, 6) - &k * &h;
        let p_new = &ikh * &p * ikh.transpose() + &k * &r * k.transpose();
        let dx6 = Vector6::from_iterator(dx.iter().copied());
        self.lla = lla_add_ned(&self.lla, &dx6.fixed_rows::<3>(0).into_owned());
        self.v_ned_mps += dx6.fixed_rows::<3>(3);
        let p6 = Matrix6::from_column_slice(p_new.as_slice());
        self.p = 0.5 * (p6 + p6.transpose());
        SixStateOutcome::Applied { nis, dof }
    }
}

/// The six-state process noise from the DR error-state filter (module docs):
/// Q = P_DR,2 + Phi P_DR,1 Phi^T - C Phi^T - Phi C^T over the interval from t_ref,
/// with C = Cov(dx_DR(now), e(t_ref)) carried through the DR's steps and updates.
/// The DR filter's position (NED m) and velocity (NED m/s) errors are its states
/// 0..6 (state.rs POS, VEL).
#[derive(Clone, Debug)]
pub struct DrIncrementNoise {
    /// Cov(dx_DR(now), e(t_ref)), n x 6.
    c: DMatrix<f64>,
    /// Cov(e(t_ref)), 6 x 6.
    p_ref: Matrix6<f64>,
    /// Start of the interval \[s\].
    t_ref: f64,
}

impl DrIncrementNoise {
    /// Start an interval at `t` with the DR covariance `p_dr` (n x n, n >= 6); None
    /// when the shape does not fit.
    pub fn new(p_dr: &DMatrix<f64>, t: f64) -> Option<Self> {
        let n = p_dr.nrows();
        if n < 6 || p_dr.ncols() != n {
            return None;
        }
        Some(DrIncrementNoise {
            c: p_dr.columns(0, 6).into_owned(),
            p_ref: Matrix6::from_fn(|i, j| p_dr[(i, j)]),
            t_ref: t,
        })
    }

    /// Start the next interval.
    pub fn restart(&mut self, p_dr: &DMatrix<f64>, t: f64) {
        if let Some(d) = Self::new(p_dr, t) {
            *self = d;
        }
    }

    /// C <- Phi_DR C after the DR filter's covariance step (shape mismatch: ignored).
    pub fn after_dr_predict(&mut self, phi_dr: &DMatrix<f64>) {
        if phi_dr.ncols() == self.c.nrows() && phi_dr.nrows() == self.c.nrows() {
            self.c = phi_dr * &self.c;
        }
    }

    /// C <- (I - K H) C after a DR measurement update with gain `k` (n x m) and
    /// Jacobian `h` (m x n) (shape mismatch: ignored).
    pub fn after_dr_update(&mut self, k: &DMatrix<f64>, h: &DMatrix<f64>) {
        let n = self.c.nrows();
        if k.nrows() == n && h.ncols() == n && k.ncols() == h.nrows() {
            let hc = h * &self.c;
            self.c -= k * hc;
        }
    }

    /// Covariance of the DR increment error e_2 - Phi e_1 from t_ref to now
    /// (interval `dt_s`), with the DR covariance now `p_dr`; projected onto the
    /// positive semi-definite matrices (rounding). Zero when the shape does not fit.
    pub fn noise(&self, p_dr: &DMatrix<f64>, dt_s: f64) -> Matrix6<f64> {
        if p_dr.nrows() != self.c.nrows() || p_dr.ncols() != self.c.nrows() {
            return Matrix6::zeros();
        }
        let mut phi = Matrix6::identity();
        phi.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(Matrix3::identity() * dt_s));
        let p2 = Matrix6::from_fn(|i, j| p_dr[(i, j)]);
        let c21 = Matrix6::from_fn(|i, j| self.c[(i, j)]);
        let q =
            p2 + phi * self.p_ref * phi.transpose() - c21 * phi.transpose() - phi * c21.transpose();
        let q = 0.5 * (q + q.transpose());
        if !q.iter().all(|x| x.is_finite()) {
            return Matrix6::zeros();
        }
        let mut eig = q.symmetric_eigen();
        eig.eigenvalues.apply(|l| *l = l.max(0.0));
        eig.recompose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::earth::lla_diff_ned;
    use nalgebra::UnitQuaternion;

    const LLA0: Vector3<f64> = Vector3::new(0.367, 1.847, 15.0);

    fn dr_at(t: f64, lla: Vector3<f64>, v: Vector3<f64>) -> NavState {
        NavState {
            t,
            lla,
            v_n: v,
            q_bn: UnitQuaternion::identity(),
        }
    }

    fn p0(pos_std_m: f64, vel_std_mps: f64) -> Matrix6<f64> {
        Matrix6::from_diagonal(&Vector6::new(
            pos_std_m.powi(2),
            pos_std_m.powi(2),
            pos_std_m.powi(2),
            vel_std_mps.powi(2),
            vel_std_mps.powi(2),
            vel_std_mps.powi(2),
        ))
    }

    fn fix_at(t: f64, lla: Vector3<f64>, v: Option<Vector3<f64>>) -> ImuFix {
        ImuFix {
            t,
            lla,
            pos_std_ned_m: Vector3::new(1.5, 1.5, 3.0),
            vel_ned_mps: v,
            vel_std_ned_mps: v.map(|_| Vector3::repeat(0.05)),
        }
    }

    /// Deterministic standard normal numbers (xorshift + Box-Muller).
    struct Gauss(u64);
    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn next(&mut self) -> f64 {
            let (u1, u2) = (self.uniform(), self.uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
        fn vec3(&mut self, s: &Vector3<f64>) -> Vector3<f64> {
            Vector3::new(self.next() * s.x, self.next() * s.y, self.next() * s.z)
        }
    }

    fn one() -> NonZeroU32 {
        NonZeroU32::new(1).unwrap()
    }

    /// Static DR standing still 30 m off, noisy fixes at the truth.
    /// `with_velocity`: position + velocity fixes (6 dof); otherwise position only
    /// with a known zero velocity (P_vv = 0), which is plain averaging.
    fn static_run(with_velocity: bool, n: usize) -> (SixState, Vector3<f64>, f64) {
        let truth = LLA0;
        let dr_lla = lla_add_ned(&truth, &Vector3::new(30.0, -20.0, 5.0));
        let dr = dr_at(0.0, dr_lla, Vector3::zeros());
        let vel_std = if with_velocity { 1.0 } else { 0.0 };
        let mut f = SixState::new(&dr, p0(50.0, vel_std), one()).unwrap();
        let mut g = Gauss(0x2545_f491_4f6c_dd1d);
        let mut nis_sum = 0.0;
        for k in 1..=n {
            let t = k as f64;
            f.follow_dr(&dr_at(t, dr_lla, Vector3::zeros()));
            f.predict_covariance(1.0, &Matrix6::zeros());
            let lla = lla_add_ned(&truth, &g.vec3(&Vector3::new(1.5, 1.5, 3.0)));
            let v = with_velocity.then(|| g.vec3(&Vector3::repeat(0.05)));
            match f.update(&fix_at(t, lla, v), None) {
                SixStateOutcome::Applied { nis, dof } => {
                    assert_eq!(dof, if with_velocity { 6 } else { 3 });
                    if k > 1 {
                        nis_sum += nis;
                    }
                }
                o => panic!("epoch {k}: {o:?}"),
            }
        }
        let err = lla_diff_ned(&f.lla(), &truth);
        (f, err, nis_sum / (n - 1) as f64)
    }

    /// Static convergence: position-only fixes average like 1 / (1/P0 + n/sigma^2);
    /// with velocity the estimate converges within 4 sigma of the truth; in both
    /// runs the normalised innovations average their dof (consistent covariance).
    #[test]
    fn static_convergence_and_consistent_covariance() {
        let n = 400;
        let (f, err, mean_nis) = static_run(false, n);
        let s = f.std();
        let expect = |sigma: f64| (1.0 / (1.0 / 50.0f64.powi(2) + n as f64 / sigma.powi(2))).sqrt();
        assert!(
            (s[0] - expect(1.5)).abs() < 1e-9,
            "std N {} vs {}",
            s[0],
            expect(1.5)
        );
        assert!(
            (s[2] - expect(3.0)).abs() < 1e-9,
            "std D {} vs {}",
            s[2],
            expect(3.0)
        );
        for i in 0..3 {
            assert!(
                err[i].abs() < 4.0 * s[i],
                "axis {i}: error {} std {}",
                err[i],
                s[i]
            );
        }
        // chi-square(3) mean over 399 epochs: 3 +- 0.12 (1 sigma).
        assert!((mean_nis - 3.0).abs() < 0.5, "mean NIS {mean_nis}");

        let (f, err, mean_nis) = static_run(true, n);
        let s = f.std();
        for i in 0..3 {
            assert!(s[i] < 0.3, "axis {i}: std {}", s[i]);
            assert!(
                err[i].abs() < 4.0 * s[i],
                "axis {i}: error {} std {}",
                err[i],
                s[i]
            );
        }
        assert!(
            f.v_ned_mps().norm() < 4.0 * s[3].hypot(s[4]).hypot(s[5]),
            "v {:?}",
            f.v_ned_mps()
        );
        // chi-square(6) mean over 399 epochs: 6 +- 0.17 (1 sigma).
        assert!((mean_nis - 6.0).abs() < 0.7, "mean NIS {mean_nis}");
    }

    /// The prediction follows the DR's increments exactly (same velocity: no offset
    /// term), and a velocity offset integrates into the position (r_dot = v).
    #[test]
    fn prediction_follows_dr_increments_and_integrates_velocity_offset() {
        let v_dr = Vector3::new(10.0, 0.0, 0.0);
        let dr0 = dr_at(0.0, LLA0, v_dr);
        let mut f = SixState::new(&dr0, p0(1.0, 0.1), one()).unwrap();
        // The DR moves 100 m north in 10 s.
        let lla1 = lla_add_ned(&LLA0, &Vector3::new(100.0, 0.0, 0.0));
        f.follow_dr(&dr_at(10.0, lla1, v_dr));
        assert!(lla_diff_ned(&f.lla(), &lla1).norm() < 1e-6);
        // A +0.5 m/s east offset of the filter velocity: 5 m east after 10 s more.
        let mut g = f.clone();
        g.v_ned_mps += Vector3::new(0.0, 0.5, 0.0);
        let lla2 = lla_add_ned(&lla1, &Vector3::new(100.0, 0.0, 0.0));
        g.follow_dr(&dr_at(20.0, lla2, v_dr));
        let d = lla_diff_ned(&g.lla(), &lla2);
        assert!((d - Vector3::new(0.0, 5.0, 0.0)).norm() < 1e-6, "{d:?}");
        assert!((g.v_ned_mps() - Vector3::new(10.0, 0.5, 0.0)).norm() < 1e-12);
        // Phi: the velocity variance flows into the position.
        let mut h = SixState::new(&dr0, p0(0.0, 0.1), one()).unwrap();
        h.predict_covariance(10.0, &Matrix6::zeros());
        assert!((h.std()[0] - 1.0).abs() < 1e-12, "{:?}", h.std());
    }

    /// every = 3: epochs 1, 4, 7, ... are fused, the others skipped.
    #[test]
    fn every_n_uses_every_nth_epoch() {
        let dr = dr_at(0.0, LLA0, Vector3::zeros());
        let mut f = SixState::new(&dr, p0(5.0, 0.5), NonZeroU32::new(3).unwrap()).unwrap();
        let used: Vec<bool> = (0..9)
            .map(|k| {
                let fx = fix_at(k as f64, LLA0, None);
                matches!(f.update(&fx, None), SixStateOutcome::Applied { dof: 3, .. })
            })
            .collect();
        assert_eq!(
            used,
            [true, false, false, true, false, false, true, false, false]
        );
    }

    /// The gate rejects a 100 m outlier and leaves the state alone; the innovation
    /// exposed for the integrity monitor matches it.
    #[test]
    fn gate_and_innovation() {
        let dr = dr_at(0.0, LLA0, Vector3::zeros());
        let mut f = SixState::new(&dr, p0(1.0, 0.1), one()).unwrap();
        let far = lla_add_ned(&LLA0, &Vector3::new(0.0, 100.0, 0.0));
        let fx = fix_at(0.0, far, None);
        let (y, s) = f.innovation(&fx).unwrap();
        assert!((y - DVector::from_column_slice(&[0.0, 100.0, 0.0])).norm() < 1e-6);
        assert!((s[(1, 1)] - (1.0 + 2.25)).abs() < 1e-12);
        let gate = crate::chi2::chi2_threshold(3, 1e-4);
        match f.update(&fx, Some(gate)) {
            SixStateOutcome::Rejected { nis, threshold } => {
                assert!((nis - 100.0f64.powi(2) / 3.25).abs() < 1e-6 && threshold == gate)
            }
            o => panic!("{o:?}"),
        }
        assert_eq!(f.lla(), LLA0);
    }

    /// Bad input never panics: non-finite starts are errors, bad fixes are Invalid.
    #[test]
    fn bad_input_is_reported() {
        let mut dr = dr_at(0.0, LLA0, Vector3::zeros());
        let mut f = SixState::new(&dr, p0(1.0, 0.1), one()).unwrap();
        let mut fx = fix_at(0.0, LLA0, None);
        fx.pos_std_ned_m.x = 0.0;
        assert_eq!(f.update(&fx, None), SixStateOutcome::Invalid);
        fx.pos_std_ned_m.x = 1.0;
        fx.lla.x = f64::NAN;
        assert_eq!(f.update(&fx, None), SixStateOutcome::Invalid);
        assert!(SixState::new(&dr, p0(f64::NAN, 0.1), one()).is_err());
        dr.lla.z = f64::INFINITY;
        assert!(SixState::new(&dr, p0(1.0, 0.1), one()).is_err());
        f.follow_dr(&dr);
        assert_eq!(f.lla(), LLA0);
    }

    /// The process noise is the DR increment error: zero for a DR whose transition
    /// matches Phi; g dt phi_E for a tilt error (f^n x phi); P - P+ across a DR
    /// update (its correction is an increment the six-state filter did not expect).
    #[test]
    fn dr_increment_noise_from_the_dr_error_model() {
        let n = 9;
        let dt = 0.2;
        let mut phi = DMatrix::<f64>::identity(n, n);
        for i in 0..3 {
            phi[(i, 3 + i)] = dt;
        }
        let p = DMatrix::<f64>::identity(n, n);
        let mut d = DrIncrementNoise::new(&p, 0.0).unwrap();
        d.after_dr_predict(&phi);
        let p2 = &phi * &p * phi.transpose();
        assert!(d.noise(&p2, dt).norm() < 1e-12);
        // dv_N = g phi_E dt (f^n = (0, 0, -g): (f^n x) has g at (N, E)).
        let g = 9.8;
        phi[(3, 7)] = g * dt;
        let mut p = DMatrix::<f64>::zeros(n, n);
        p[(7, 7)] = 1e-6;
        let mut d = DrIncrementNoise::new(&p, 0.0).unwrap();
        d.after_dr_predict(&phi);
        let q = d.noise(&(&phi * &p * phi.transpose()), dt);
        assert!((q[(3, 3)] - (g * dt).powi(2) * 1e-6).abs() < 1e-15, "{q}");
        assert!(q[(0, 0)].abs() < 1e-15);
        // A DR update of the north position (zero interval): Q = P - P+.
        let p = DMatrix::<f64>::identity(n, n) * 4.0;
        let mut d = DrIncrementNoise::new(&p, 0.0).unwrap();
        let mut h = DMatrix::<f64>::zeros(1, n);
        h[(0, 0)] = 1.0;
        let r = DMatrix::<f64>::from_element(1, 1, 1.0);
        let k = &p * h.transpose() / 5.0;
        let ikh = DMatrix::<f64>::identity(n, n) - &k * &h;
        let p_plus = &ikh * &p * ikh.transpose() + &k * &r * k.transpose();
        d.after_dr_update(&k, &h);
        let q = d.noise(&p_plus, 0.0);
        assert!((q[(0, 0)] - (4.0 - 0.8)).abs() < 1e-12, "{q}");
        assert!(q[(1, 1)].abs() < 1e-12);
        // Shapes that do not fit give nothing, not a panic.
        assert!(DrIncrementNoise::new(&DMatrix::identity(3, 3), 0.0).is_none());
        assert_eq!(d.noise(&DMatrix::identity(3, 3), 0.0), Matrix6::zeros());
    }
}
