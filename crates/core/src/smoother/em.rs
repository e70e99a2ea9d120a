//! What noise identification learns from a smoothed run (docs/ALGORITHMS.md "Noise
//! identification"): the expectation step of expectation-maximisation over the RTS
//! smoother (REFERENCES \[SS82\], \[GH96\]; \[SARKKA\] ch. 12).
//!
//! The forward filter logs every applied update ([`FusedUpdate`]: innovation y, its
//! rows of H, the diagonal of R, and H times the corrections already fed back at its
//! record). The backward pass then gives, per update, the smoothed residual and its
//! variance
//!
//!   e_j  = s_k^- - dx_before,j                (error relative to the nominal the
//!                                              update saw, record k)
//!   r_s  = y - H e_j,   var_s = diag(H P_k|N H^T)
//!
//! so that E[v v^T | all data] = r_s r_s^T + H P_k|N H^T is the expected square of the
//! measurement noise (its mean over a source is the M-step for that source's R), and
//! per transition k -> k+1 of the process model alone (`RtsRecord::propagated_only`)
//! the expected square of the process noise w = x_{k+1}^- - Phi x_k^+ per state i:
//!
//!   E\[w_i²\] = m_i² + P_{k+1|N,ii} - 2 (P_{k+1|N} (Phi C_k)^T)_ii + (Phi P_k|N Phi^T)_ii,
//!   m = s_{k+1}^- - Phi s_k^+,   P_{k+1,k|N} = P_{k+1|N} C_k^T
//!
//! whose ratio to Q_ii is the M-step of a scale on that state's process noise.

use nalgebra::{DMatrix, DVector};

/// One applied update as the noise identification needs it (logged by the forward
/// filter while it records for the smoother).
#[derive(Clone, Debug, PartialEq)]
pub struct FusedUpdate {
    /// GNSS time of the update \[s\].
    pub t: f64,
    /// The smoother record it belongs to.
    pub record: u64,
    /// The source's update name (`Aiding::name`, e.g. "gnss_position").
    pub source: &'static str,
    /// Innovation h(x_est) - z.
    pub y: Vec<f64>,
    /// Rows of H, as (state index, value) entries that are not zero.
    pub h: Vec<Vec<(usize, f64)>>,
    /// Diagonal of the R the update used.
    pub r: Vec<f64>,
    /// H times the corrections fed back earlier at the same record.
    pub h_dx_before: Vec<f64>,
    /// The source inflated R for this update (robust down-weighting of an outlier):
    /// not a sample of its noise.
    pub down_weighted: bool,
    /// With the fix-error states (`Block::GnssBias`): their nominal values at the
    /// update and the corrections fed back before it at its record (NED \[m\]).
    pub gnss_bias: Option<([f64; 3], [f64; 3])>,
}

/// An update after smoothing.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothedResidual {
    pub t: f64,
    pub source: &'static str,
    /// Smoothed residual y - H e per row.
    pub r_s: Vec<f64>,
    /// Its variance diag(H P|N H^T) per row.
    pub var_s: Vec<f64>,
    /// The R the update used (diagonal).
    pub r: Vec<f64>,
    pub down_weighted: bool,
    /// The smoothed fix-error states (nominal less smoothed error), NED \[m\].
    pub gnss_bias: Option<[f64; 3]>,
}

/// Per state: the expected squared process noise against the model's Q.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProcessNoiseStats {
    /// Sum over transitions of E\[w_i²\] / Q_ii.
    pub ratio_sum: Vec<f64>,
    /// Sum of the squares of those ratios (their spread).
    pub ratio_sq_sum: Vec<f64>,
    /// Transitions counted.
    pub count: Vec<u64>,
    /// With `block_s` > 0: the same sums per block of `block_s` seconds of the run
    /// (block b covers [t_ref + b block_s, t_ref + (b + 1) block_s)), for batch-means
    /// standard errors (the terms are correlated in time).
    pub block_s: f64,
    pub t_ref: f64,
    /// Per block: (ratio sum, count) per state.
    pub blocks: Vec<Vec<(f64, u64)>>,
}

impl ProcessNoiseStats {
    /// Statistics with batch means over blocks of `block_s` seconds from `t_ref`.
    pub fn with_blocks(t_ref: f64, block_s: f64) -> Self {
        ProcessNoiseStats {
            block_s,
            t_ref,
            ..Self::default()
        }
    }

    fn ensure(&mut self, n: usize) {
        if self.ratio_sum.len() < n {
            self.ratio_sum.resize(n, 0.0);
            self.ratio_sq_sum.resize(n, 0.0);
            self.count.resize(n, 0);
        }
    }

    fn add(&mut self, t: f64, i: usize, ratio: f64, n: usize) {
        self.ratio_sum[i] += ratio;
        self.ratio_sq_sum[i] += ratio * ratio;
        self.count[i] += 1;
        if self.block_s > 0.0 {
            let b = ((t - self.t_ref) / self.block_s).floor().max(0.0) as usize;
            if self.blocks.len() <= b {
                self.blocks.resize(b + 1, Vec::new());
            }
            let blk = &mut self.blocks[b];
            if blk.len() < n {
                blk.resize(n, (0.0, 0));
            }
            blk[i].0 += ratio;
            blk[i].1 += 1;
        }
    }

    /// The group's mean ratio in each block that has terms (batch means).
    pub fn block_means(&self, states: &[usize]) -> Vec<f64> {
        self.blocks
            .iter()
            .filter_map(|blk| {
                let (s, c) = states
                    .iter()
                    .filter_map(|&i| blk.get(i))
                    .fold((0.0, 0u64), |(s, c), (bs, bc)| (s + bs, c + bc));
                (c > 0).then(|| s / c as f64)
            })
            .collect()
    }

    /// Mean E\[w_i²\] / Q_ii over the transitions (None without any).
    pub fn mean_ratio(&self, i: usize) -> Option<f64> {
        let c = *self.count.get(i)?;
        (c > 0).then(|| self.ratio_sum[i] / c as f64)
    }

    /// Mean ratio over several states, with the standard deviation of the terms and
    /// their count.
    pub fn group(&self, states: &[usize]) -> Option<(f64, f64, u64)> {
        let (mut s, mut s2, mut c) = (0.0, 0.0, 0u64);
        for &i in states {
            if i < self.count.len() {
                s += self.ratio_sum[i];
                s2 += self.ratio_sq_sum[i];
                c += self.count[i];
            }
        }
        if c == 0 {
            return None;
        }
        let mean = s / c as f64;
        let var = (s2 / c as f64 - mean * mean).max(0.0);
        Some((mean, var.sqrt(), c))
    }
}

/// The smoothed residuals of the updates at record k: `updates` are the record's,
/// `s_prior` its smoothed error before feedback, `p` its smoothed covariance.
pub(crate) fn residuals(
    updates: &[FusedUpdate],
    s_prior: &DVector<f64>,
    p: &DMatrix<f64>,
    gnss_bias_index: Option<usize>,
    out: &mut Vec<SmoothedResidual>,
) {
    for u in updates {
        let mut r_s = Vec::with_capacity(u.y.len());
        let mut var_s = Vec::with_capacity(u.y.len());
        for (k, row) in u.h.iter().enumerate() {
            // H e with e = s_prior - dx_before: H s_prior - H dx_before.
            let hs: f64 = row.iter().map(|&(i, v)| v * s_prior[i]).sum();
            r_s.push(u.y[k] - hs + u.h_dx_before[k]);
            let mut hph = 0.0;
            for &(i, vi) in row {
                for &(j, vj) in row {
                    hph += vi * p[(i, j)] * vj;
                }
            }
            var_s.push(hph.max(0.0));
        }
        let gnss_bias = match (u.gnss_bias, gnss_bias_index) {
            (Some((nominal, dx_before)), Some(b)) => Some([0, 1, 2].map(|k| {
                // True bias = estimate - error; error relative to this nominal.
                nominal[k] - (s_prior[b + k] - dx_before[k])
            })),
            _ => None,
        };
        out.push(SmoothedResidual {
            t: u.t,
            source: u.source,
            r_s,
            var_s,
            r: u.r.clone(),
            down_weighted: u.down_weighted,
            gnss_bias,
        });
    }
}

/// Phi as its entries off the identity (row, column, value).
pub(crate) type PhiEntries = [(usize, usize, f64)];

/// Accumulate E\[w_i²\] / Q_ii for the transition from record k at time `t` (smoothed
/// `s_post`, covariance `p`) to record k+1 (smoothed `s_prior_next`, `p_next`), with the
/// gain `c` = C_k, the transition Phi = I + `phi` and its noise `q`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn accumulate_process_noise(
    stats: &mut ProcessNoiseStats,
    t: f64,
    s_post: &DVector<f64>,
    p: &DMatrix<f64>,
    s_prior_next: &DVector<f64>,
    p_next: &DMatrix<f64>,
    c: &DMatrix<f64>,
    phi: &PhiEntries,
    q: &DMatrix<f64>,
) {
    let n = p.nrows();
    stats.ensure(n);
    // m = s_{k+1}^- - Phi s_k^+.
    let mut m = s_prior_next - s_post;
    for &(i, j, v) in phi {
        m[i] -= v * s_post[j];
    }
    // A = Phi P (rows of Phi: I + E), then diag(A Phi^T).
    let mut a = p.clone();
    for &(i, j, v) in phi {
        for col in 0..n {
            a[(i, col)] += v * p[(j, col)];
        }
    }
    let mut diag_phi_p_phi: Vec<f64> = (0..n).map(|i| a[(i, i)]).collect();
    for &(i, j, v) in phi {
        diag_phi_p_phi[i] += v * a[(i, j)];
    }
    // B = Phi C; diag(P_{k+1|N} B^T)_i = sum_j P_next[i, j] B[i, j].
    let mut b = c.clone();
    for &(i, j, v) in phi {
        for col in 0..n {
            b[(i, col)] += v * c[(j, col)];
        }
    }
    for i in 0..n {
        let qi = q[(i, i)];
        if qi.is_nan() || qi <= 0.0 {
            continue;
        }
        let cross: f64 = (0..n).map(|j| p_next[(i, j)] * b[(i, j)]).sum();
        let e_w2 = m[i] * m[i] + p_next[(i, i)] - 2.0 * cross + diag_phi_p_phi[i];
        let ratio = e_w2.max(0.0) / qi;
        if ratio.is_finite() {
            stats.add(t, i, ratio, n);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::smoother::{RtsBackward, RtsRecord};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A closed-loop scalar filter (error = estimate - truth) over a random walk with
    /// two measurements per epoch (so that the second sees the first's feedback):
    /// its records and logged updates.
    fn forward(
        truth: &[f64],
        z: &[[f64; 2]],
        q: f64,
        r: f64,
    ) -> (Vec<RtsRecord>, Vec<FusedUpdate>) {
        let (mut x, mut p) = (0.0, 100.0);
        let mut recs = Vec::new();
        let mut ups = Vec::new();
        for (k, zk) in z.iter().enumerate().take(truth.len()) {
            if k > 0 {
                p += q;
            }
            let mut dx_sum = 0.0;
            for &zi in zk {
                let y = x - zi;
                ups.push(FusedUpdate {
                    t: k as f64,
                    record: k as u64,
                    source: "test",
                    y: vec![y],
                    h: vec![vec![(0, 1.0)]],
                    r: vec![r],
                    h_dx_before: vec![dx_sum],
                    down_weighted: false,
                    gnss_bias: None,
                });
                let kg = p / (p + r);
                let dx = kg * y;
                x -= dx;
                dx_sum += dx;
                p *= 1.0 - kg;
            }
            recs.push(RtsRecord {
                t: k as f64,
                phi: (k > 0).then(|| DMatrix::identity(1, 1)),
                q: (k > 0).then(|| DMatrix::from_element(1, 1, q)),
                p_post: DMatrix::from_element(1, 1, p),
                dx: DVector::from_element(1, dx_sum),
                propagated_only: true,
            });
        }
        (recs, ups)
    }

    /// Expectation-maximisation on a random walk observed twice per epoch finds the
    /// true process and measurement noise from a start 100x off either way.
    #[test]
    fn em_finds_random_walk_noise() {
        let (q_true, r_true): (f64, f64) = (0.04, 1.0);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(30);
        let w = Normal::new(0.0, q_true.sqrt()).unwrap();
        let v = Normal::new(0.0, r_true.sqrt()).unwrap();
        let n = 20_000;
        let mut truth = vec![0.0; n];
        for k in 1..n {
            truth[k] = truth[k - 1] + w.sample(&mut rng);
        }
        let z: Vec<[f64; 2]> = truth
            .iter()
            .map(|x| [x + v.sample(&mut rng), x + v.sample(&mut rng)])
            .collect();
        for (mut q, mut r) in [(4.0, 0.01), (0.0004, 100.0)] {
            for _ in 0..60 {
                let (recs, ups) = forward(&truth, &z, q, r);
                let mut back = RtsBackward::new();
                let mut stats = ProcessNoiseStats::default();
                let mut res = Vec::new();
                for rec in recs.into_iter().rev() {
                    // Two updates per record, in record order.
                    let k = rec.t as usize;
                    let mine = &ups[2 * k..2 * k + 2];
                    back.step_em(rec, mine, None, &mut stats, &mut res).unwrap();
                }
                let ratio = stats.mean_ratio(0).unwrap();
                q *= ratio;
                r = res
                    .iter()
                    .map(|s| s.r_s[0] * s.r_s[0] + s.var_s[0])
                    .sum::<f64>()
                    / res.len() as f64;
            }
            assert!((q / q_true - 1.0).abs() < 0.1, "q {q}");
            assert!((r / r_true - 1.0).abs() < 0.05, "r {r}");
        }
    }
}
