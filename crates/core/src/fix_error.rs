//! What the filter assumes about the errors of loosely coupled GNSS fixes, and how it
//! treats fixes that disagree with it (docs/ALGORITHMS.md "GNSS fix errors").
//!
//! - Time-correlated part: a first-order Gauss-Markov position error per NED axis,
//!   b_dot = -b / tau + w, PSD 2 sigma_b² / tau, appended as the `GnssBias` block
//!   (the shaping-filter, or state-augmentation, method: Gelb 1974 §4.5; Brown & Hwang
//!   2012 §8.2). A fix is r_GNSS = r_ant + b + v with v white, so y = r_ant,INS + b_est
//!   - r_GNSS ~ dr + db + ... and R = (1 - rho) std². sigma_b² = rho std² follows the
//!   fix's reported std (a better solution type bounds the correlated error anew).
//! - Adaptive variance scale (innovation-based, Mohamed & Schwarz 1999 eq. 24): the
//!   window mean of (y_i² - (H P H^T)_ii) / R_ii over accepted fixes, at least 1, scales
//!   R when the receiver's reported std is optimistic.
//! - Robust down-weighting: IGG-III (Yang, Song & Xu 2002) on t = sqrt(NIS / dof):
//!   full weight up to k0, weight k0/t ((k1 - t)/(k1 - k0))² up to k1 (the gate),
//!   rejected beyond.
//! - Re-admission after a rejection streak: only when the rejected fixes agree with
//!   each other (consecutive innovations change by less than their 3-sigma) for
//!   `readmit_s`, so a short burst of bad fixes, however consistent, stays out.

use nalgebra::Vector3;
use std::collections::VecDeque;

/// IGG-III weight factor for the test statistic `t` (k0 < k1; 1 below k0, 0 above k1).
pub fn igg3_factor(t: f64, k0: f64, k1: f64) -> f64 {
    if t <= k0 {
        1.0
    } else if t < k1 {
        k0 / t * ((k1 - t) / (k1 - k0)).powi(2)
    } else {
        0.0
    }
}

/// The Gauss-Markov fix error: nominal estimate and current steady-state sigma.
#[derive(Clone, Copy, Debug, Default)]
pub struct FixBias {
    /// Estimated correlated error of the fixes, NED [m].
    pub bias_ned_m: Vector3<f64>,
    /// Steady-state 1-sigma per axis of the process, from the latest fix [m].
    pub sigma_ned_m: Vector3<f64>,
}

impl FixBias {
    /// The nominal estimate decays as the process does over `dt`.
    pub fn propagate(&mut self, dt: f64, corr_time_s: f64) {
        self.bias_ned_m *= (-dt / corr_time_s).exp();
    }
}

/// Window mean of the excess innovation variance ratio; 1 until the window has
/// `min_samples`.
#[derive(Clone, Debug)]
pub struct AdaptiveScale {
    window: usize,
    ratios: VecDeque<f64>,
    sum: f64,
}

impl AdaptiveScale {
    /// Largest scale applied (R at most 100x the reported variance).
    pub const MAX: f64 = 100.0;

    pub fn new(window: usize) -> Self {
        AdaptiveScale {
            window,
            ratios: VecDeque::new(),
            sum: 0.0,
        }
    }

    /// Record one accepted measurement: innovation `y`, diag(H P H^T) and diag(R)
    /// with R already scaled by the current factor (the ratio is taken back to the
    /// reported variance).
    pub fn observe(&mut self, y: &[f64], hph_diag: &[f64], r_diag: &[f64]) {
        if self.window == 0 {
            return;
        }
        let s = self.scale();
        let n = y.len().max(1) as f64;
        let ratio: f64 = y
            .iter()
            .zip(hph_diag)
            .zip(r_diag)
            .map(|((y, hph), r)| {
                // One sample's excess, clipped at 25 (5 sigma) so one outlier that
                // passed the gate cannot inflate the window.
                ((y * y - hph) / (r / s)).clamp(0.0, 25.0 * s)
            })
            .sum::<f64>()
            / n;
        self.ratios.push_back(ratio);
        self.sum += ratio;
        while self.ratios.len() > self.window {
            self.sum -= self.ratios.pop_front().unwrap_or(0.0);
        }
    }

    /// The factor on R: at least 1, at most [`Self::MAX`], 1 until half the window.
    pub fn scale(&self) -> f64 {
        if self.window == 0 || self.ratios.len() < self.window.div_ceil(2) {
            return 1.0;
        }
        (self.sum / self.ratios.len() as f64).clamp(1.0, Self::MAX)
    }
}

/// A run of gate-rejected fixes and whether they agree with each other.
#[derive(Clone, Copy, Debug)]
pub struct RejectStreak {
    pub since: f64,
    /// Time from which consecutive rejected fixes have agreed.
    pub agree_since: f64,
    last: (f64, Vector3<f64>, Vector3<f64>),
}

impl RejectStreak {
    pub fn new(t: f64, y_ned_m: Vector3<f64>, std_ned_m: Vector3<f64>) -> Self {
        RejectStreak {
            since: t,
            agree_since: t,
            last: (t, y_ned_m, std_ned_m),
        }
    }

    /// The next rejected fix: innovation and std NED [m]; `vel_std_mps`: the INS
    /// velocity 1-sigma per axis (how far the innovation may move between fixes).
    pub fn push(&mut self, t: f64, y: Vector3<f64>, std: Vector3<f64>, vel_std_mps: Vector3<f64>) {
        let (t0, y0, s0) = self.last;
        let dt = t - t0;
        let agree = (0..3).all(|i| {
            let tol = (std[i].powi(2) + s0[i].powi(2) + (vel_std_mps[i] * dt).powi(2)).sqrt();
            (y[i] - y0[i]).abs() <= 3.0 * tol
        });
        if !agree {
            self.agree_since = t;
        }
        self.last = (t, y, std);
    }

    /// Innovation of the latest rejected fix, NED [m].
    pub fn last_innovation(&self) -> Vector3<f64> {
        self.last.1
    }

    /// Rejected and mutually consistent for at least `readmit_s` at `t`.
    pub fn agreed_for(&self, t: f64, readmit_s: f64) -> bool {
        t - self.agree_since >= readmit_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn igg3_is_continuous_and_monotone() {
        let (k0, k1) = (1.5, 3.0);
        assert_eq!(igg3_factor(1.0, k0, k1), 1.0);
        assert!((igg3_factor(k0 + 1e-9, k0, k1) - 1.0).abs() < 1e-6);
        assert!(igg3_factor(k1 - 1e-9, k0, k1) < 1e-12);
        assert_eq!(igg3_factor(5.0, k0, k1), 0.0);
        let mut prev = 1.0;
        for i in 0..100 {
            let w = igg3_factor(k0 + i as f64 * 0.015, k0, k1);
            assert!(w <= prev);
            prev = w;
        }
    }

    #[test]
    fn adaptive_scale_finds_an_optimistic_std() {
        let mut a = AdaptiveScale::new(40);
        // Innovations 3x their reported sigma (R = 1, H P H^T = 0.1).
        let mut k = 0u64;
        for _ in 0..200 {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (k >> 11) as f64 / (1u64 << 53) as f64;
            let sign = if u < 0.5 { -1.0 } else { 1.0 };
            let y = sign * 3.0 * 1.05f64.sqrt();
            let s = a.scale();
            a.observe(&[y], &[0.1], &[s]);
        }
        assert!((a.scale() - 9.35).abs() < 0.3, "{}", a.scale());
        // Consistent innovations leave R alone.
        let mut b = AdaptiveScale::new(40);
        for _ in 0..100 {
            b.observe(&[1.0], &[0.5], &[1.0]);
        }
        assert_eq!(b.scale(), 1.0);
    }

    #[test]
    fn streak_agreement_restarts_on_a_jump() {
        let std = Vector3::repeat(1.0);
        let v = Vector3::repeat(0.1);
        let mut s = RejectStreak::new(0.0, Vector3::new(50.0, 0.0, 0.0), std);
        for k in 1..=40 {
            s.push(
                k as f64,
                Vector3::new(50.0 + 0.1 * k as f64, 0.0, 0.0),
                std,
                v,
            );
        }
        assert!(s.agreed_for(40.0, 30.0));
        s.push(41.0, Vector3::new(1000.0, 0.0, 0.0), std, v);
        assert!(!s.agreed_for(41.0, 30.0) && s.agree_since == 41.0);
    }
}
