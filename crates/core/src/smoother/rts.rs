//! The backward pass of the Rauch-Tung-Striebel smoother over the records of a
//! closed-loop error-state filter (REFERENCES \[RTS65\], \[SARKKA\] ch. 8; the
//! feedback resets as in docs/ALGORITHMS.md "Smoothing").
//!
//! Record k: transition Phi_k from record k-1 and its noise Q_k (so the prior
//! covariance is P_k^- = Phi_k P_{k-1}^+ Phi_k^T + Q_k), updated covariance P_k^+,
//! correction dx_k fed back. Errors are taken relative to the forward nominal
//! after feedback, where the filter's own estimate is zero, so with
//! s_k^- = s_k^+ + dx_k (the same error relative to the nominal before feedback):
//!
//!   C_k     = P_k^+ Phi_{k+1}^T (P_{k+1}^-)^-1
//!   s_k^+   = C_k s_{k+1}^-                       (s_N^+ = 0)
//!   P_k|N   = (I - C_k Phi_{k+1}) P_k^+ (I - C_k Phi_{k+1})^T
//!             + C_k (Q_{k+1} + P_{k+1|N}) C_k^T
//!
//! The covariance line is the Joseph-like form of P_k^+ + C_k (P_{k+1|N} -
//! P_{k+1}^-) C_k^T: a sum of positive semi-definite terms, symmetrised.

use super::em::{self, FusedUpdate, ProcessNoiseStats, SmoothedResidual};
use super::record::RtsRecord;
use crate::filter::matmul;
use nalgebra::{DMatrix, DVector};

/// The smoothed error estimate at one record.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothedRecord {
    /// IMU time of the record \[s\].
    pub t: f64,
    /// Smoothed error relative to the forward nominal after the record's feedback.
    pub s_post: DVector<f64>,
    /// The same relative to the nominal before the feedback (s_post + dx).
    pub s_prior: DVector<f64>,
    /// Smoothed variances (diagonal of P_k|N).
    pub var: DVector<f64>,
}

/// Why the backward pass cannot go on.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothError(pub String);

impl std::fmt::Display for SmoothError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SmoothError {}

/// Phi - I as its entries that are not zero: (row, column, value). Phi is mostly
/// the identity (the INS error dynamics couple few states per step).
fn off_identity(phi: &DMatrix<f64>) -> Vec<(usize, usize, f64)> {
    let n = phi.nrows();
    let mut e = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let v = phi[(i, j)] - if i == j { 1.0 } else { 0.0 };
            if v != 0.0 {
                e.push((i, j, v));
            }
        }
    }
    e
}

/// Phi * a with Phi = I + E.
fn phi_mul(e: &[(usize, usize, f64)], a: &DMatrix<f64>) -> DMatrix<f64> {
    let mut out = a.clone();
    for &(i, j, v) in e {
        for c in 0..a.ncols() {
            out[(i, c)] += v * a[(j, c)];
        }
    }
    out
}

/// a * Phi^T with Phi = I + E.
fn mul_phi_t(a: &DMatrix<f64>, e: &[(usize, usize, f64)]) -> DMatrix<f64> {
    let mut out = a.clone();
    for &(i, j, v) in e {
        for r in 0..a.nrows() {
            out[(r, i)] += v * a[(r, j)];
        }
    }
    out
}

/// a * Phi with Phi = I + E.
fn mul_phi(a: &DMatrix<f64>, e: &[(usize, usize, f64)]) -> DMatrix<f64> {
    let mut out = a.clone();
    for &(i, j, v) in e {
        for r in 0..a.nrows() {
            out[(r, j)] += v * a[(r, i)];
        }
    }
    out
}

/// a * b (or a * b^T) into a new matrix (faer, filter.rs).
fn mul(a: &DMatrix<f64>, b: &DMatrix<f64>, b_t: bool) -> DMatrix<f64> {
    let rows = a.nrows();
    let cols = if b_t { b.nrows() } else { b.ncols() };
    let mut out = DMatrix::zeros(rows, cols);
    matmul(&mut out, a, b, b_t, false);
    out
}

/// What the recursion needs of record k besides its successor's smoothed values: the
/// gain C_k, I - C_k Phi_{k+1}, Q_{k+1}, and the record's own P_k^+ and dx_k. These
/// depend on the forward filter only, so they can be made ahead (another thread)
/// of the recursion that uses them.
pub struct Gain {
    pub t: f64,
    /// C_k and I - C_k Phi; None for the last record (nothing after it).
    c: Option<(DMatrix<f64>, DMatrix<f64>)>,
    q: Option<DMatrix<f64>>,
    p_post: DMatrix<f64>,
    dx: DVector<f64>,
    /// The later record's Phi - I entries, and whether its transition is the process
    /// model alone (noise identification, em.rs).
    phi_next: Vec<(usize, usize, f64)>,
    propagated_next: bool,
}

impl Gain {
    /// The forward variances of the record (diagonal of P_k^+).
    pub fn forward_var(&self) -> DVector<f64> {
        self.p_post.diagonal()
    }

    /// Whether updates were applied at the record.
    pub fn updated(&self) -> bool {
        self.dx.iter().any(|v| *v != 0.0)
    }
}

/// Makes the [`Gain`]s from the records, last to first.
#[derive(Default)]
pub struct GainMaker {
    /// The later record's Phi - I (empty: identity), Q, and whether its transition
    /// is the process model alone.
    #[allow(clippy::type_complexity)]
    later: Option<(Vec<(usize, usize, f64)>, Option<DMatrix<f64>>, bool)>,
    /// Records where P^- had to be inverted by eigen-decomposition (not positive
    /// definite in floating point).
    pub pseudo_inverses: u64,
}

impl GainMaker {
    pub fn new() -> Self {
        Self::default()
    }

    /// The gain of record k, given after record k+1 (or first, the last record).
    pub fn gain(&mut self, rec: RtsRecord) -> Result<Gain, SmoothError> {
        let n = rec.dim();
        let next = (
            rec.phi.as_ref().map(off_identity).unwrap_or_default(),
            rec.q,
            rec.propagated_only,
        );
        let (c, q, phi_next, propagated_next) = match self.later.replace(next) {
            None => (None, None, Vec::new(), false),
            Some((phi, q, propagated)) => {
                if q.as_ref().is_some_and(|q| q.nrows() != n) {
                    return Err(SmoothError(format!(
                        "record at t = {:.3}: {n} states, the later record more or fewer",
                        rec.t
                    )));
                }
                let phi_p = phi_mul(&phi, &rec.p_post);
                // P^- = Phi P^+ Phi^T + Q.
                let mut p_prior = mul_phi_t(&phi_p, &phi);
                if let Some(q) = &q {
                    p_prior += q;
                }
                // C^T = (P^-)^-1 Phi P^+.
                let c = self.solve_spd(&p_prior, &phi_p).transpose();
                let mut i_c_phi = -mul_phi(&c, &phi);
                for i in 0..n {
                    i_c_phi[(i, i)] += 1.0;
                }
                (Some((c, i_c_phi)), q, phi, propagated)
            }
        };
        Ok(Gain {
            t: rec.t,
            c,
            q,
            p_post: rec.p_post,
            dx: rec.dx,
            phi_next,
            propagated_next,
        })
    }

    /// X with P X = B for a symmetric positive semi-definite P: states with zero
    /// variance (not estimated) get zero rows; the rest are solved by Cholesky on
    /// the correlation matrix (scaled to unit diagonal), or by eigen-decomposition
    /// with small eigenvalues dropped when that fails.
    fn solve_spd(&mut self, p: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
        let n = p.nrows();
        let active: Vec<usize> = (0..n).filter(|&i| p[(i, i)] > 0.0).collect();
        let m = active.len();
        let mut out = DMatrix::zeros(n, b.ncols());
        if m == 0 {
            return out;
        }
        let d: Vec<f64> = active.iter().map(|&i| p[(i, i)].sqrt()).collect();
        let r = DMatrix::from_fn(m, m, |a, c| p[(active[a], active[c])] / (d[a] * d[c]));
        let rhs = DMatrix::from_fn(m, b.ncols(), |a, c| b[(active[a], c)] / d[a]);
        let y = match llt_solve(&r, &rhs) {
            Some(y) => y,
            None => {
                self.pseudo_inverses += 1;
                let eig = r.symmetric_eigen();
                let top = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
                let inv = DVector::from_fn(m, |i, _| {
                    let l = eig.eigenvalues[i];
                    if l > 1e-12 * top {
                        1.0 / l
                    } else {
                        0.0
                    }
                });
                let v = &eig.eigenvectors;
                v * DMatrix::from_diagonal(&inv) * v.transpose() * rhs
            }
        };
        for (a, &i) in active.iter().enumerate() {
            for c in 0..b.ncols() {
                out[(i, c)] = y[(a, c)] / d[a];
            }
        }
        out
    }
}

/// The recursion: feed the gains from the last record to the first; each call
/// returns that record's smoothed estimate.
#[derive(Default)]
pub struct RtsBackward {
    gains: GainMaker,
    /// The later record's smoothed s^- and P|N.
    later: Option<(DVector<f64>, DMatrix<f64>)>,
}

impl RtsBackward {
    pub fn new() -> Self {
        Self::default()
    }

    /// Records whose P^- needed an eigen-decomposition (made by [`RtsBackward::step`]).
    pub fn pseudo_inverses(&self) -> u64 {
        self.gains.pseudo_inverses
    }

    /// One step back: record k after record k+1 (or the last record).
    pub fn step(&mut self, rec: RtsRecord) -> Result<SmoothedRecord, SmoothError> {
        let g = self.gains.gain(rec)?;
        self.smooth(g)
    }

    /// [`RtsBackward::step`] with the expectation step of noise identification
    /// ([`RtsBackward::smooth_em`]).
    pub fn step_em(
        &mut self,
        rec: RtsRecord,
        updates: &[FusedUpdate],
        gnss_bias_index: Option<usize>,
        process: &mut ProcessNoiseStats,
        residuals: &mut Vec<SmoothedResidual>,
    ) -> Result<SmoothedRecord, SmoothError> {
        let g = self.gains.gain(rec)?;
        self.smooth_em(g, updates, gnss_bias_index, process, residuals)
    }

    /// One step back with a gain made ahead ([`GainMaker`]).
    pub fn smooth(&mut self, g: Gain) -> Result<SmoothedRecord, SmoothError> {
        self.smooth_inner(g, None)
    }

    /// [`RtsBackward::smooth`] with the noise identification's expectation step
    /// (em.rs): the smoothed residuals of `updates` (the record's applied updates) are
    /// appended to `residuals`, and the transition to the later record, when it is the
    /// process model alone, is added to `process`. `gnss_bias_index`: where the
    /// fix-error states are in the layout.
    pub fn smooth_em(
        &mut self,
        g: Gain,
        updates: &[FusedUpdate],
        gnss_bias_index: Option<usize>,
        process: &mut ProcessNoiseStats,
        residuals: &mut Vec<SmoothedResidual>,
    ) -> Result<SmoothedRecord, SmoothError> {
        self.smooth_inner(
            g,
            Some(EmSinks {
                updates,
                gnss_bias_index,
                process,
                residuals,
            }),
        )
    }

    fn smooth_inner(
        &mut self,
        g: Gain,
        em: Option<EmSinks<'_>>,
    ) -> Result<SmoothedRecord, SmoothError> {
        let n = g.p_post.nrows();
        let (s_post, p_smoothed, later) = match (self.later.take(), g.c) {
            (None, _) | (_, None) => (DVector::zeros(n), g.p_post, None),
            (Some((s_prior_next, p_next)), Some((c, i_c_phi))) => {
                if p_next.nrows() != n {
                    return Err(SmoothError(format!(
                        "record at t = {:.3}: {n} states, the later record {}",
                        g.t,
                        p_next.nrows()
                    )));
                }
                let s_post = &c * &s_prior_next;
                let mut q_plus_ps = p_next.clone();
                if let Some(q) = &g.q {
                    q_plus_ps += q;
                }
                let a = mul(&i_c_phi, &g.p_post, false);
                let mut p = mul(&a, &i_c_phi, true);
                let cq = mul(&c, &q_plus_ps, false);
                matmul(&mut p, &cq, &c, true, true);
                symmetrize(&mut p);
                (s_post, p, Some((s_prior_next, p_next, c)))
            }
        };
        if !s_post.iter().all(|v| v.is_finite()) || !(0..n).all(|i| p_smoothed[(i, i)].is_finite())
        {
            return Err(SmoothError(format!(
                "the smoothed estimate stopped being finite at t = {:.3}",
                g.t
            )));
        }
        let s_prior = &s_post + &g.dx;
        if let Some(em) = em {
            em::residuals(
                em.updates,
                &s_prior,
                &p_smoothed,
                em.gnss_bias_index,
                em.residuals,
            );
            if let (Some((s_next, p_next, c)), Some(q), true) = (&later, &g.q, g.propagated_next) {
                em::accumulate_process_noise(
                    em.process,
                    g.t,
                    &s_post,
                    &p_smoothed,
                    s_next,
                    p_next,
                    c,
                    &g.phi_next,
                    q,
                );
            }
        }
        let out = SmoothedRecord {
            t: g.t,
            s_post,
            s_prior: s_prior.clone(),
            var: DVector::from_fn(n, |i, _| p_smoothed[(i, i)].max(0.0)),
        };
        self.later = Some((s_prior, p_smoothed));
        Ok(out)
    }
}

/// Where [`RtsBackward::smooth_em`] puts what it learns.
struct EmSinks<'a> {
    updates: &'a [FusedUpdate],
    gnss_bias_index: Option<usize>,
    process: &'a mut ProcessNoiseStats,
    residuals: &'a mut Vec<SmoothedResidual>,
}

/// r x = rhs for a symmetric positive definite r (faer's Cholesky); None when r is
/// not positive definite.
fn llt_solve(r: &DMatrix<f64>, rhs: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    use faer::linalg::solvers::SolveCore;
    use faer::{Conj, MatMut, MatRef, Side};
    let m = r.nrows();
    let l = MatRef::from_column_major_slice(r.as_slice(), m, m)
        .llt(Side::Lower)
        .ok()?;
    let mut y = rhs.clone();
    let k = y.ncols();
    l.solve_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(y.as_mut_slice(), m, k),
    );
    Some(y)
}

fn symmetrize(p: &mut DMatrix<f64>) {
    let n = p.nrows();
    for i in 0..n {
        for j in (i + 1)..n {
            let a = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = a;
            p[(j, i)] = a;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scalar random walk observed at both ends: the smoothed mid value and
    /// variance have closed forms.
    #[test]
    fn scalar_random_walk_between_two_fixes() {
        // x0 ~ N(0, 1) observed, then 10 steps of random walk q = 0.1 each, then a
        // measurement with R = 1. Forward: P0+ = 0.5 (after z0 with R = 1).
        let q = 0.1;
        let r = 1.0;
        let mut recs = Vec::new();
        let mut p = 1.0;
        // Record 0: update z0 = 0 at x prior 0 -> dx = 0.
        let p0_post = p * r / (p + r);
        recs.push(RtsRecord {
            t: 0.0,
            phi: None,
            q: None,
            p_post: DMatrix::from_element(1, 1, p0_post),
            dx: DVector::zeros(1),
            propagated_only: true,
        });
        p = p0_post;
        for k in 1..10 {
            p += q;
            recs.push(RtsRecord {
                t: k as f64,
                phi: Some(DMatrix::identity(1, 1)),
                q: Some(DMatrix::from_element(1, 1, q)),
                p_post: DMatrix::from_element(1, 1, p),
                dx: DVector::zeros(1),
                propagated_only: true,
            });
        }
        // Record 10: innovation y = x_est - z = 1 (z = -1), dx = K y.
        p += q;
        let k = p / (p + r);
        let dx = k * 1.0;
        recs.push(RtsRecord {
            t: 10.0,
            phi: Some(DMatrix::identity(1, 1)),
            q: Some(DMatrix::from_element(1, 1, q)),
            p_post: DMatrix::from_element(1, 1, p * (1.0 - k)),
            dx: DVector::from_element(1, dx),
            propagated_only: true,
        });
        let mut b = RtsBackward::new();
        let out: Vec<_> = recs.into_iter().rev().map(|r| b.step(r).unwrap()).collect();
        // Batch solution: the nominal (x_est) is 0 up to t = 10 before feedback;
        // states x_k = x_0 + w; data z0 = 0 (R 1), z10 = -1 (R 1); prior x0 ~ N(0,1)
        // is folded into the first update as in the filter. The smoothed value of x_0
        // is the batch posterior: information form.
        // Unknown x0, x10 = x0 + W (var 1.0): z0 = x0 + v0, z10 = x10 + v10, x0 prior N(0,1).
        // Equivalent: x0 posterior after z0: N(0, 0.5); then z10 = x0 + W + v10 with
        // var(W + v10) = 2.0: x0|all = 0.5 / (0.5 + 2.0) * (-1) = -0.2, var 0.5*2/2.5 = 0.4.
        let s0 = &out[10];
        // s = x_est - x_true estimate: x_est = 0, so x_true estimate = -s.
        assert!((-s0.s_post[0] - (-0.2)).abs() < 1e-12, "{}", s0.s_post[0]);
        assert!((s0.var[0] - 0.4).abs() < 1e-12, "{}", s0.var[0]);
        // The last record's smoothed estimate is the filter's.
        assert!(out[0].s_post[0].abs() < 1e-15);
        // Variances never above the filter's.
        for (o, k) in out.iter().zip((0..=10).rev()) {
            let fwd = if k == 0 {
                p0_post
            } else {
                (p0_post + q * k as f64).min(f64::MAX)
            };
            assert!(o.var[0] <= fwd + 1e-12, "k = {k}: {} > {fwd}", o.var[0]);
        }
    }

    /// Zero-variance states (not estimated) do not break the solve.
    #[test]
    fn zero_variance_state_is_left_alone() {
        let mut p = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.0]));
        let rec0 = RtsRecord {
            t: 0.0,
            phi: None,
            q: None,
            p_post: p.clone(),
            dx: DVector::zeros(2),
            propagated_only: true,
        };
        p[(0, 0)] = 2.0;
        let rec1 = RtsRecord {
            t: 1.0,
            phi: Some(DMatrix::identity(2, 2)),
            q: Some(DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.0]))),
            p_post: DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.0])),
            dx: DVector::from_vec(vec![0.5, 0.0]),
            propagated_only: true,
        };
        let mut b = RtsBackward::new();
        b.step(rec1).unwrap();
        let s = b.step(rec0).unwrap();
        assert!((s.s_post[0] - 0.25).abs() < 1e-12);
        assert_eq!(s.s_post[1], 0.0);
        assert_eq!(b.pseudo_inverses(), 0);
    }
}
