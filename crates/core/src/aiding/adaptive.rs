//! Adaptive measurement noise (opt-in, `[filter] adaptive_noise`): per aiding source
//! name (a row kind: `gnss_position`, `pseudorange`, `nhc`, ...) a scale s on the
//! configured R, R = s R_cfg, with an inverse-gamma posterior IG(alpha, beta) updated
//! by the variational-Bayes fixed point of the VB-AKF (REFERENCES \[SN09\],
//! with a scalar s per row kind instead of one per row; docs/ALGORITHMS.md "Adaptive
//! measurement noise"). Pure: the [`crate::aiding::source::Fuser`] holds it and
//! calls it at every update, so every source has it by construction.

use nalgebra::{DMatrix, DVector};

/// Options of the adaptive noise estimate (`[filter] adaptive_noise = true`).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveNoiseOptions {
    /// Memory of the estimate \[s\]: between two updates of a source dt apart the
    /// posterior is flattened by rho = exp(-|dt| / window_s) (\[SN09\], prediction step), so
    /// it weighs the updates of about the last `window_s` seconds whatever the rate.
    pub window_s: f64,
    /// Fixed-point iterations per update (\[SN09\]), >= 1.
    pub iterations: usize,
    /// The source names adapted; None = every source.
    pub sources: Option<Vec<String>>,
    /// Bounds of the scale s (on the variance; the std scales by sqrt(s)).
    pub min_scale: f64,
    pub max_scale: f64,
}

impl Default for AdaptiveNoiseOptions {
    fn default() -> Self {
        AdaptiveNoiseOptions {
            window_s: DEFAULT_ADAPTIVE_WINDOW_S,
            iterations: 3,
            sources: None,
            min_scale: 0.01,
            max_scale: 100.0,
        }
    }
}

/// Default memory of the adaptive noise estimate \[s\].
pub const DEFAULT_ADAPTIVE_WINDOW_S: f64 = 60.0;

/// Shape of the prior and the floor of the flattened posterior: as much as two rows
/// (weak; a run starts from s = 1, the configured R).
const ALPHA_FLOOR: f64 = 1.0;

/// Inverse-gamma posterior of one source's scale s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalePosterior {
    pub alpha: f64,
    pub beta: f64,
    /// Time of the last update that fed it (GNSS time) \[s\].
    pub last_t: Option<f64>,
    /// Updates that fed it.
    pub updates: usize,
}

impl Default for ScalePosterior {
    fn default() -> Self {
        ScalePosterior {
            alpha: ALPHA_FLOOR,
            beta: ALPHA_FLOOR,
            last_t: None,
            updates: 0,
        }
    }
}

impl ScalePosterior {
    /// The scale the filter uses: 1 / E\[1/s\] = beta / alpha (\[SN09\]).
    pub fn scale(&self) -> f64 {
        self.beta / self.alpha
    }

    /// Posterior std of s (inverse gamma: beta / ((alpha - 1) sqrt(alpha - 2))), for
    /// alpha > 2.
    pub fn sd(&self) -> Option<f64> {
        (self.alpha > 2.0).then(|| self.beta / ((self.alpha - 1.0) * (self.alpha - 2.0).sqrt()))
    }

    /// The prior at time `t`: alpha and beta times rho = exp(-|t - last_t| /
    /// window_s) (\[SN09\] prediction step, the mean kept), alpha held at or above the floor.
    fn predicted(&self, t: f64, window_s: f64) -> ScalePosterior {
        let Some(last) = self.last_t else {
            return *self;
        };
        let rho = (-(t - last).abs() / window_s).exp();
        let alpha = (rho * self.alpha).max(ALPHA_FLOOR);
        ScalePosterior {
            alpha,
            beta: self.scale() * alpha,
            ..*self
        }
    }
}

/// What the VB fixed point of one update gives.
#[derive(Clone, Debug, PartialEq)]
pub struct VbUpdate {
    /// NIS with the prior scales (the predictive test statistic, y^T S^-1 y).
    pub nis_prior: f64,
    /// The scale of each group the state update is to use.
    pub scales: Vec<f64>,
    /// The posterior of each group after the update.
    pub posteriors: Vec<ScalePosterior>,
}

/// `r` with each block scaled by its group's scale; `blocks`: (first row, rows,
/// group) of the diagonal blocks (R is zero between blocks).
pub fn scaled_r(
    r: &DMatrix<f64>,
    blocks: &[(usize, usize, usize)],
    scales: &[f64],
) -> DMatrix<f64> {
    let mut out = r.clone();
    for &(k, d, g) in blocks {
        out.view_mut((k, k), (d, d)).scale_mut(scales[g]);
    }
    out
}

/// The VB-AKF fixed point (\[SN09\]) for the rows y ~ H dx + v, v ~ N(0, R),
/// R = blockdiag(s_g R_cfg,b): `a` = H P^- H^T, `r_cfg` the configured R, `priors`
/// the predicted posterior per group. Each iteration takes the Kalman update with
/// the current scales, then per group alpha = alpha^- + d_g / 2 and
///   beta = beta^- + 1/2 sum_b tr(R_cfg,b^-1 [(y - H m)(y - H m)^T + H P H^T]_b),
/// with, for R_b = s R_cfg,b and S = A + R, u = S^-1 y: y - H m = R u and
/// H P H^T = R - R S^-1 R, so the trace is
/// s d_b - s^2 tr((S^-1)_bb R_cfg,b) + s^2 u_b^T R_cfg,b u_b. Scales are clamped to [min, max]. The state update then
/// uses the scales of the last iteration's Kalman step. None when S is singular.
pub fn vb_update(
    a: &DMatrix<f64>,
    r_cfg: &DMatrix<f64>,
    y: &DVector<f64>,
    blocks: &[(usize, usize, usize)],
    priors: &[ScalePosterior],
    opt: &AdaptiveNoiseOptions,
) -> Option<VbUpdate> {
    let groups = priors.len();
    let clamp = |s: f64| s.clamp(opt.min_scale, opt.max_scale);
    let mut alpha: Vec<f64> = priors.iter().map(|p| p.alpha).collect();
    for &(_, d, g) in blocks {
        alpha[g] += 0.5 * d as f64;
    }
    let mut scales: Vec<f64> = priors.iter().map(|p| clamp(p.scale())).collect();
    let mut beta = vec![0.0; groups];
    let mut nis_prior = f64::NAN;
    for it in 0..opt.iterations.max(1) {
        if it > 0 {
            for g in 0..groups {
                scales[g] = clamp(beta[g] / alpha[g]);
            }
        }
        let s_mat = a + scaled_r(r_cfg, blocks, &scales);
        let s_inv = s_mat.cholesky()?.inverse();
        let u = &s_inv * y;
        if it == 0 {
            nis_prior = y.dot(&u);
        }
        beta.iter_mut().zip(priors).for_each(|(b, p)| *b = p.beta);
        for &(k, d, g) in blocks {
            let s = scales[g];
            let r_b = r_cfg.view((k, k), (d, d));
            let u_b = u.rows(k, d);
            let tr = (s_inv.view((k, k), (d, d)) * r_b).trace();
            let quad = (u_b.transpose() * r_b * u_b)[(0, 0)];
            beta[g] += 0.5 * (s * d as f64 - s * s * tr + s * s * quad);
        }
    }
    if !nis_prior.is_finite() || beta.iter().any(|b| !b.is_finite()) {
        return None;
    }
    let posteriors = (0..groups)
        .map(|g| ScalePosterior {
            alpha: alpha[g],
            // The scale bound holds for the posterior too.
            beta: clamp(beta[g] / alpha[g]) * alpha[g],
            last_t: priors[g].last_t,
            updates: priors[g].updates + 1,
        })
        .collect();
    Some(VbUpdate {
        nis_prior,
        scales,
        posteriors,
    })
}

/// The estimator state: one posterior per source name adapted.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveNoise {
    pub opt: AdaptiveNoiseOptions,
    posteriors: Vec<(&'static str, ScalePosterior)>,
}

impl AdaptiveNoise {
    pub fn new(opt: AdaptiveNoiseOptions) -> Self {
        AdaptiveNoise {
            opt,
            posteriors: Vec::new(),
        }
    }

    /// Whether the source `name` is adapted.
    pub fn adapts(&self, name: &str) -> bool {
        self.opt
            .sources
            .as_ref()
            .is_none_or(|list| list.iter().any(|s| s == name))
    }

    fn get(&self, name: &str) -> ScalePosterior {
        self.posteriors
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, p)| *p)
            .unwrap_or_default()
    }

    /// The current scale of `name` (1 before its first update or when not adapted).
    pub fn scale(&self, name: &str) -> f64 {
        if self.adapts(name) {
            self.get(name).scale()
        } else {
            1.0
        }
    }

    /// The prior of `name` for an update at `t` (forgetting applied).
    pub fn predicted(&self, name: &str, t: f64) -> ScalePosterior {
        self.get(name).predicted(t, self.opt.window_s)
    }

    /// Keep the posterior of `name` after an update at `t`.
    pub fn commit(&mut self, name: &'static str, mut post: ScalePosterior, t: f64) {
        post.last_t = Some(t);
        match self.posteriors.iter_mut().find(|(n, _)| *n == name) {
            Some((_, p)) => *p = post,
            None => self.posteriors.push((name, post)),
        }
    }

    /// Every source adapted so far with its posterior, in the order first seen.
    pub fn posteriors(&self) -> &[(&'static str, ScalePosterior)] {
        &self.posteriors
    }
}

#[cfg(test)]
#[path = "adaptive_tests.rs"]
mod tests;
