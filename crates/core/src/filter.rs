//! Error-state Kalman filter arithmetic: covariance propagation and the Joseph-form
//! update with an innovation (chi-square) gate. SYSTEM.md §2.
//!
//! The filter runs closed loop: the error estimate is fed back into the nominal
//! state right after each update and reset to zero, so only the covariance is kept.

use nalgebra::{DMatrix, DVector};

/// The chi-square gate threshold moved to [`crate::chi2`]; re-exported for the engine.

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
        UpdateOutcome::Applied {
            dx,
            nis,
            s_diag,
            log_det_s,
        }
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
}
