//! Error-state Kalman filter arithmetic: covariance propagation and the Joseph-form
//! update with an innovation (chi-square) gate. SYSTEM.md §2.
//!
//! The filter runs closed loop: the error estimate is fed back into the nominal
//! state right after each update and reset to zero, so only the covariance is kept.

use nalgebra::{DMatrix, DVector};

// The chi-square gate threshold moved to [`crate::chi2`]; re-exported for the engine.

/// Result of one measurement update.
#[derive(Clone, Debug)]
pub enum UpdateOutcome {
    /// Accepted; the error-state estimate to feed back (x_est - x_true), the
    /// normalised innovation squared, the innovation variances S_ii of the first
    /// three rows and ln det S.
    Applied {
        dx: DVector<f64>,
        nis: f64,
        s_diag: [f64; 3],
        log_det_s: f64,
    },
    /// Rejected by the innovation gate: normalised innovation squared, threshold,
    /// S_ii of the first three rows and ln det S.
    Rejected {
        nis: f64,
        threshold: f64,
        s_diag: [f64; 3],
        log_det_s: f64,
    },
    /// Innovation covariance not positive definite (measurement dropped).
    Singular,
}

/// Per-row terms of a joint update (the stacked rows of one epoch): with the
/// Cholesky factor S = H P H^T + R = L L^T and w = L^-1 y, row i's innovation given
/// the rows before it is e_i = L_ii w_i with variance s_i = L_ii^2 (what a
/// sequential update row by row would see, [`Eskf::update_sequential`]), and its
/// share of the joint NIS is nis_i = w_i^2 (they sum to y^T S^-1 y). REFERENCES [BS].
#[derive(Clone, Debug, PartialEq)]
pub struct RowTerms {
    pub innovation: DVector<f64>,
    pub variance: DVector<f64>,
    pub nis: DVector<f64>,
}

impl RowTerms {
    fn of(chol: &nalgebra::Cholesky<f64, nalgebra::Dyn>, y: &DVector<f64>) -> RowTerms {
        let l = chol.l_dirty();
        let w = l
            .solve_lower_triangular(y)
            .unwrap_or_else(|| DVector::from_element(y.len(), f64::NAN));
        let d = l.diagonal();
        RowTerms {
            innovation: d.component_mul(&w),
            variance: d.component_mul(&d),
            nis: w.component_mul(&w),
        }
    }
}

/// One row of [`Eskf::update_sequential`]: its innovation e_i (less the corrections
/// of the rows before it), variance s_i, and whether it was applied (not gated out,
/// s_i > 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequentialRow {
    pub innovation: f64,
    pub variance: f64,
    pub applied: bool,
}

/// Covariance of the error state plus scratch space for propagation.
#[derive(Clone, Debug)]
pub struct Eskf {
    pub p: DMatrix<f64>,
    tmp: DMatrix<f64>,
    tmp2: DMatrix<f64>,
}

impl Eskf {
    pub fn new(p0: DMatrix<f64>) -> Self {
        let n = p0.nrows();
        Eskf {
            p: p0,
            tmp: DMatrix::zeros(n, n),
            tmp2: DMatrix::zeros(n, n),
        }
    }

    pub fn dim(&self) -> usize {
        self.p.nrows()
    }

    /// P = Phi P Phi^T + Qd (SYSTEM.md §2), then symmetrised.
    pub fn predict(&mut self, phi: &DMatrix<f64>, qd: &DMatrix<f64>) {
        matmul(&mut self.tmp, phi, &self.p, false, false);
        self.tmp2.as_mut_slice().copy_from_slice(qd.as_slice());
        matmul(&mut self.tmp2, &self.tmp, phi, true, true);
        std::mem::swap(&mut self.p, &mut self.tmp2);
        self.symmetrize();
    }

    fn symmetrize(&mut self) {
        let n = self.dim();
        let p = self.p.as_mut_slice();
        for i in 0..n {
            for j in (i + 1)..n {
                let a = 0.5 * (p[i * n + j] + p[j * n + i]);
                p[i * n + j] = a;
                p[j * n + i] = a;
            }
        }
    }

    /// Joseph-form update for innovation `y = h(x_est) - z` with Jacobian `h`
    /// (y ~ H dx + noise) and noise covariance `r`. With `gate = Some(t)`, the update
    /// is rejected when y^T S^-1 y > t.
    pub fn update(
        &mut self,
        y: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
        gate: Option<f64>,
    ) -> UpdateOutcome {
        let ph_t = &self.p * h.transpose();
        let s = h * &ph_t + r;
        let Some(chol) = s.clone().cholesky() else {
            return UpdateOutcome::Singular;
        };
        let s_inv_y = chol.solve(y);
        let nis = y.dot(&s_inv_y);
        if !nis.is_finite() {
            return UpdateOutcome::Singular;
        }
        let mut s_diag = [f64::NAN; 3];
        for (k, v) in s_diag.iter_mut().enumerate().take(s.nrows()) {
            *v = s[(k, k)];
        }
        // ln det S = 2 sum ln L_ii (S = L L^T).
        let l = chol.l_dirty();
        let log_det_s = 2.0 * (0..s.nrows()).map(|k| l[(k, k)].ln()).sum::<f64>();
        if let Some(t) = gate {
            if nis > t {
                return UpdateOutcome::Rejected {
                    nis,
                    threshold: t,
                    s_diag,
                    log_det_s,
                };
            }
        }
        let dx = self.apply(&chol, &ph_t, y, h, r);
        UpdateOutcome::Applied {
            dx,
            nis,
            s_diag,
            log_det_s,
        }
    }

    /// The gain and the Joseph-form covariance update of [`Eskf::update`] once S = H P
    /// H^T + R is factored (`chol`, with `ph_t` = P H^T); returns dx = K y.
    fn apply(
        &mut self,
        chol: &nalgebra::Cholesky<f64, nalgebra::Dyn>,
        ph_t: &DMatrix<f64>,
        y: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> DVector<f64> {
        // K = P H^T S^-1, computed as (S^-1 H P)^T since S is symmetric.
        let k = chol.solve(&ph_t.transpose()).transpose();
        let dx = &k * y;
        let n = self.dim();
        // Joseph form: P = (I - K H) P (I - K H)^T + K R K^T.
        let mut i_kh = DMatrix::<f64>::identity(n, n);
        i_kh.gemm(-1.0, &k, h, 1.0);
        matmul(&mut self.tmp, &i_kh, &self.p, false, false);
        let kr = &k * r;
        matmul(&mut self.p, &kr, &k, true, false);
        matmul(&mut self.p, &self.tmp, &i_kh, true, true);
        self.symmetrize();
        dx
    }

    /// [`Eskf::update`] of stacked rows (the measurements of one epoch, linearised
    /// together at the state before any of them), gated jointly, with the per-row
    /// terms of the sequential decomposition of the innovation ([`RowTerms`]).
    pub fn update_joint(
        &mut self,
        y: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
        gate: Option<f64>,
    ) -> (UpdateOutcome, Option<RowTerms>) {
        let ph_t = &self.p * h.transpose();
        let s = h * &ph_t + r;
        let Some(chol) = s.cholesky() else {
            return (UpdateOutcome::Singular, None);
        };
        let rows = RowTerms::of(&chol, y);
        let nis = rows.nis.sum();
        if !nis.is_finite() {
            return (UpdateOutcome::Singular, None);
        }
        let mut s_diag = [f64::NAN; 3];
        let l = chol.l_dirty();
        for (k, v) in s_diag.iter_mut().enumerate().take(l.nrows()) {
            // S_kk = sum_j L_kj^2 (j <= k).
            *v = (0..=k).map(|j| l[(k, j)].powi(2)).sum();
        }
        // ln det S = sum ln s_i (the rows' sequential variances, s_i = L_ii^2).
        let log_det_s = rows.variance.iter().map(|v| v.ln()).sum::<f64>();
        if let Some(t) = gate {
            if nis > t {
                let rejected = UpdateOutcome::Rejected {
                    nis,
                    threshold: t,
                    s_diag,
                    log_det_s,
                };
                return (rejected, Some(rows));
            }
        }
        let dx = self.apply(&chol, &ph_t, y, h, r);
        let applied = UpdateOutcome::Applied {
            dx,
            nis,
            s_diag,
            log_det_s,
        };
        (applied, Some(rows))
    }

    /// The rows of one epoch fused one at a time (diagonal `r`; None otherwise): the
    /// textbook sequential update, row i with innovation y_i - H_i dx (dx: the
    /// corrections of the rows before it), variance s_i = H_i P H_i^T + R_ii over the
    /// covariance they left, gated alone by `row_gate` on e_i^2 / s_i, scalar Joseph
    /// update. Without a gate it equals [`Eskf::update_joint`] (same dx and P, and
    /// `terms` equal to its [`RowTerms`]). Returns the total correction (none fed
    /// back: the caller does it once) and each row's [`SequentialRow`].
    pub fn update_sequential(
        &mut self,
        y: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
        row_gate: Option<f64>,
    ) -> Option<(DVector<f64>, Vec<SequentialRow>)> {
        let (m, n) = h.shape();
        let diagonal = (0..m).all(|i| (0..m).all(|j| i == j || r[(i, j)] == 0.0));
        if !diagonal {
            return None;
        }
        let mut dx = DVector::zeros(n);
        let mut rows = Vec::with_capacity(m);
        for i in 0..m {
            let hi = h.rows(i, 1).into_owned();
            let ri = r.view((i, i), (1, 1)).into_owned();
            let e = y[i] - (&hi * &dx)[0];
            let ph_t = &self.p * hi.transpose();
            let s = (&hi * &ph_t)[(0, 0)] + ri[(0, 0)];
            let row = |applied| SequentialRow {
                innovation: e,
                variance: s,
                applied,
            };
            if !(s > 0.0 && e.is_finite()) || row_gate.is_some_and(|g| e * e / s > g) {
                rows.push(row(false));
                continue;
            }
            let chol = DMatrix::from_element(1, 1, s).cholesky()?;
            dx += self.apply(&chol, &ph_t, &DVector::from_element(1, e), &hi, &ri);
            rows.push(row(true));
        }
        Some((dx, rows))
    }

    /// Kalman gain K = P H^T (H P H^T + R)^-1 of a measurement, without updating
    /// (e.g. to carry a cross-covariance through the update, six_state.rs); None
    /// when S is singular.
    pub fn gain(&self, h: &DMatrix<f64>, r: &DMatrix<f64>) -> Option<DMatrix<f64>> {
        let ph_t = &self.p * h.transpose();
        let chol = (h * &ph_t + r).cholesky()?;
        Some(chol.solve(&ph_t.transpose()).transpose())
    }

    /// Innovation covariance S = H P H^T + R.
    fn innovation_cov(&self, h: &DMatrix<f64>, r: &DMatrix<f64>) -> DMatrix<f64> {
        h * &self.p * h.transpose() + r
    }

    /// Normalised innovation squared y^T S^-1 y with S = H P H^T + R, without
    /// updating; None when S is singular.
    pub fn nis(&self, y: &DVector<f64>, h: &DMatrix<f64>, r: &DMatrix<f64>) -> Option<f64> {
        let v = y.dot(&self.innovation_cov(h, r).cholesky()?.solve(y));
        v.is_finite().then_some(v)
    }

    /// Baarda's w-test of a batch of measurements against the prior, for data
    /// snooping (one blunder at a time): with y ~ H dx + v and S = H P H^T + R,
    /// w_i = (S^-1 y)_i / sqrt((S^-1)_ii) is N(0, 1) when row i has no blunder, and
    /// (S^-1 y)_i / (S^-1)_ii estimates the blunder of row i. Returns (w_i, blunder_i)
    /// per row, or None when S is singular. The rows are tested jointly, so the test
    /// does not depend on their order.
    pub fn blunder_test(
        &self,
        y: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Option<Vec<(f64, f64)>> {
        let s_inv = self.innovation_cov(h, r).cholesky()?.inverse();
        let g = &s_inv * y;
        (0..y.len())
            .map(|i| {
                let d = s_inv[(i, i)];
                (d > 0.0 && g[i].is_finite()).then(|| (g[i] / d.sqrt(), g[i] / d))
            })
            .collect()
    }

    /// 1-sigma of each state.
    pub fn std(&self, i: usize) -> f64 {
        self.p[(i, i)].max(0.0).sqrt()
    }

    /// Forget what is known about state `i`: clear its correlations and give it
    /// variance `var` (e.g. after re-initialising the estimate).
    pub fn reset_state(&mut self, i: usize, var: f64) {
        let n = self.dim();
        for j in 0..n {
            self.p[(i, j)] = 0.0;
            self.p[(j, i)] = 0.0;
        }
        self.p[(i, i)] = var;
    }
}

/// dst (+)= lhs * rhs (or lhs * rhs^T) via faer on zero-copy views of the
/// column-major nalgebra storage (about 7x faster than nalgebra's gemm at 21x21).
pub(crate) fn matmul(
    dst: &mut DMatrix<f64>,
    lhs: &DMatrix<f64>,
    rhs: &DMatrix<f64>,
    rhs_t: bool,
    add: bool,
) {
    use faer::{linalg::matmul::matmul as fm, Accum, MatMut, MatRef, Par};
    let (m, n) = dst.shape();
    let l = MatRef::from_column_major_slice(lhs.as_slice(), lhs.nrows(), lhs.ncols());
    let r = MatRef::from_column_major_slice(rhs.as_slice(), rhs.nrows(), rhs.ncols());
    let r = if rhs_t { r.transpose() } else { r };
    let d = MatMut::from_column_major_slice_mut(dst.as_mut_slice(), m, n);
    let acc = if add { Accum::Add } else { Accum::Replace };
    fm(d, acc, l, r, 1.0, Par::Seq);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalar_update_matches_closed_form() {
        let mut f = Eskf::new(DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 1.0])));
        let h = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let r = DMatrix::from_element(1, 1, 1.0);
        let y = DVector::from_vec(vec![2.0]);
        match f.update(&y, &h, &r, None) {
            UpdateOutcome::Applied { dx, nis, .. } => {
                assert!((dx[0] - 1.6).abs() < 1e-12);
                assert!(dx[1].abs() < 1e-12);
                assert!((nis - 0.8).abs() < 1e-12);
            }
            o => panic!("{o:?}"),
        }
        assert!((f.p[(0, 0)] - 0.8).abs() < 1e-12);
        assert!((f.p[(1, 1)] - 1.0).abs() < 1e-12);
        // A wild innovation is gated.
        let y = DVector::from_vec(vec![100.0]);
        assert!(matches!(
            f.update(&y, &h, &r, Some(10.0)),
            UpdateOutcome::Rejected { .. }
        ));
    }

    /// The joint update of stacked rows and the sequential one (each row's innovation
    /// less the corrections of the rows before it) agree: dx, P and the per-row terms,
    /// to 1e-9 of the prior sigma (or of the correction, when larger), over random
    /// covariances, Jacobians, noises, innovations (drawn from S, one trial in five
    /// 30x larger) and numbers of rows.
    #[test]
    fn joint_and_sequential_updates_agree() {
        use rand::{RngExt, SeedableRng};
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(30);
        let g = |rng: &mut rand_pcg::Pcg64| -> f64 { StandardNormal.sample(rng) };
        let mut worst: f64 = 0.0;
        for trial in 0..500 {
            let n = rng.random_range(2..=30);
            let m = rng.random_range(1..=15);
            let scale = DVector::from_fn(n, |_, _| 10f64.powf(rng.random_range(-4.0..2.0)));
            let b = DMatrix::from_fn(n, n, |_, _| g(&mut rng));
            let bbt = &b * b.transpose();
            let p = DMatrix::from_fn(n, n, |i, j| bbt[(i, j)] * scale[i] * scale[j] / n as f64)
                + DMatrix::from_diagonal(&scale.map(|s| 0.1 * s * s));
            // Rows of O(1) for corrections of O(sigma).
            let h = DMatrix::from_fn(m, n, |_, j| g(&mut rng) / scale[j]);
            let r = DMatrix::from_diagonal(&DVector::from_fn(m, |_, _| {
                10f64.powf(rng.random_range(-6.0..2.0))
            }));
            let s_cov = &h * &p * h.transpose() + &r;
            let k = if trial % 5 == 0 { 30.0 } else { 1.0 };
            let y =
                s_cov.clone().cholesky().unwrap().l() * DVector::from_fn(m, |_, _| k * g(&mut rng));
            let mut a = Eskf::new(p.clone());
            let mut s = Eskf::new(p.clone());
            let (out, terms) = a.update_joint(&y, &h, &r, None);
            let UpdateOutcome::Applied { dx, nis, .. } = out else {
                panic!("trial {trial}: {out:?}")
            };
            let terms = terms.unwrap();
            let (dx_s, rows) = s.update_sequential(&y, &h, &r, None).unwrap();
            let sd = p.diagonal().map(f64::sqrt);
            for i in 0..n {
                let d = (dx[i] - dx_s[i]).abs() / (sd[i] + dx[i].abs());
                worst = worst.max(d);
                assert!(
                    d < 1e-9,
                    "trial {trial} dx[{i}]: {} vs {} (sd {}, cond S {:.1e})",
                    dx[i],
                    dx_s[i],
                    sd[i],
                    {
                        let e = s_cov.symmetric_eigenvalues();
                        e.max() / e.min()
                    }
                );
                for j in 0..n {
                    let d = (a.p[(i, j)] - s.p[(i, j)]).abs() / (sd[i] * sd[j]);
                    assert!(d < 1e-9, "trial {trial} P[{i},{j}]: {d:e}");
                }
            }
            for (k, row) in rows.iter().enumerate() {
                let (e, v) = (row.innovation, row.variance);
                assert!(row.applied);
                let tol = 1e-9 * (v.sqrt() + e.abs());
                assert!(
                    (e - terms.innovation[k]).abs() < tol,
                    "trial {trial} e[{k}]"
                );
                assert!(
                    (v - terms.variance[k]).abs() < 1e-9 * v,
                    "trial {trial} s[{k}]"
                );
                assert!((e * e / v - terms.nis[k]).abs() < 1e-9 * (1.0 + terms.nis[k]));
            }
            let direct = Eskf::new(p).nis(&y, &h, &r).unwrap();
            assert!(
                (nis - direct).abs() < 1e-9 * (1.0 + direct),
                "trial {trial}"
            );
        }
        eprintln!("joint vs sequential: largest relative difference of dx {worst:.1e}");
    }
}
