//! What the filter assumes about the errors of loosely coupled GNSS fixes, and how it
//! treats fixes that disagree with it (docs/ALGORITHMS.md "GNSS fix errors").
//!
//! - Time-correlated part: a first-order Gauss-Markov position error per NED axis,
//!   b_dot = -b / tau + w, PSD 2 sigma_b² / tau, appended as the `GnssBias` block
//!   (the shaping-filter, or state-augmentation, method: Gelb 1974 §4.5; Brown & Hwang
//!   2012 §8.2). A fix is r_GNSS = r_ant + b + v with v white, so y = r_ant,INS +
//!   b_est - r_GNSS ~ dr + db + ... and R = (1 - rho) std². sigma_b² = rho std² follows the
//!   fix's reported std (a better solution type bounds the correlated error anew).
//! - Robust innovation scale (`InnovationScale`): the median of NIS / dof over recent
//!   fixes against the chi-square median, at least 1; the tests divide the NIS by it
//!   (the variance factor estimated from residuals, as a robust M-estimator scales its
//!   residuals by their median before weighting them: Huber 1981 §5; Yang et al. 2002).
//! - Robust down-weighting: IGG-III (Yang, Song & Xu 2002) on t = sqrt(NIS / dof):
//!   full weight up to k0, weight k0/t ((k1 - t)/(k1 - k0))² up to k1 (the gate).
//!   Beyond the gate a fix is rejected when its innovation also exceeds the drift an
//!   INS can plausibly have since the last fix used (3 std + a dt²/2); inside that
//!   floor it is taken with weight (k1/t)² (a MEMS INS in a hard manoeuvre is often
//!   further off than its covariance says, and rejecting it starts a cascade).
//! - Re-admission after a rejection streak: only when the rejected fixes agree with
//!   each other (consecutive innovations change by less than their 3-sigma) for
//!   `readmit_s`, so a short burst of bad fixes, however consistent, stays out.

use crate::chi2::chi2_threshold;
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

/// Robust scale of the innovations: the median of NIS / dof over the last `window`
/// tested measurements against the median of chi-square(dof) / dof, at least 1. The
/// gate and the down-weighting test NIS / scale, so they judge a fix against the
/// spread the filter really shows (a MEMS INS under vibration is often 2-3x less
/// certain than its noise model says) while the update keeps the reported variance.
/// A median, so a burst of outliers shorter than half the window does not move it.
#[derive(Clone, Debug)]
pub struct InnovationScale {
    window: usize,
    ratios: VecDeque<f64>,
}

impl InnovationScale {
    /// Largest scale applied.
    pub const MAX: f64 = 100.0;

    pub fn new(window: usize) -> Self {
        InnovationScale {
            window,
            ratios: VecDeque::new(),
        }
    }

    /// Record one tested measurement of `dof` rows with normalised innovation squared
    /// `nis` (computed with the reported variance).
    pub fn observe(&mut self, nis: f64, dof: usize) {
        if self.window == 0 || !nis.is_finite() || dof == 0 {
            return;
        }
        self.ratios.push_back(nis / chi2_median(dof));
        while self.ratios.len() > self.window {
            self.ratios.pop_front();
        }
    }

    /// The factor on the innovation covariance for the tests: 1 until a quarter of
    /// the window is seen, then the median ratio within \[1, MAX\].
    pub fn scale(&self) -> f64 {
        if self.window == 0 || self.ratios.len() < self.window.div_ceil(4).max(5).min(self.window) {
            return 1.0;
        }
        let mut v: Vec<f64> = self.ratios.iter().copied().collect();
        let mid = v.len() / 2;
        let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
        m.clamp(1.0, Self::MAX)
    }
}

/// Median of chi-square with `dof` degrees of freedom.
pub fn chi2_median(dof: usize) -> f64 {
    chi2_threshold(dof, 0.5)
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

    /// The next rejected fix: innovation and std NED \[m\]; `vel_std_mps`: the INS
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

    /// Innovation of the latest rejected fix, NED \[m\].
    pub fn last_innovation(&self) -> Vector3<f64> {
        self.last.1
    }

    /// Time of the latest rejected fix \[s\].
    pub fn last_t(&self) -> f64 {
        self.last.0
    }

    /// The rejected fixes have agreed with each other over at least `readmit_s`
    /// (measured between rejected fixes, not up to now: an outage is no agreement;
    /// either way in time, for a backward run).
    pub fn agreed_for(&self, readmit_s: f64) -> bool {
        (self.last.0 - self.agree_since).abs() >= readmit_s
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
    fn innovation_scale_is_the_robust_spread() {
        let mut a = InnovationScale::new(40);
        // NIS of 3 dof at 9x their expected spread, and a burst of 10 outliers.
        let mut k = 0u64;
        for i in 0..200 {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (k >> 11) as f64 / (1u64 << 53) as f64;
            // Exponential-ish spread around the chi-square median, scaled by 9.
            let nis = 9.0 * chi2_median(3) * (0.5 + u);
            a.observe(if (100..110).contains(&i) { 1e6 } else { nis }, 3);
        }
        assert!((a.scale() - 9.0).abs() < 1.0, "{}", a.scale());
        // Consistent innovations give 1.
        let mut b = InnovationScale::new(40);
        for _ in 0..100 {
            b.observe(0.5 * chi2_median(1), 1);
        }
        assert_eq!(b.scale(), 1.0);
        assert!((chi2_median(3) / 2.366 - 1.0).abs() < 1e-3);
        assert!((chi2_median(1) / 0.4549 - 1.0).abs() < 1e-3);
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
        assert!(s.agreed_for(30.0));
        s.push(41.0, Vector3::new(1000.0, 0.0, 0.0), std, v);
        assert!(!s.agreed_for(30.0) && s.agree_since == 41.0);
        // One rejected fix and then nothing for a minute is no agreement.
        let lone = RejectStreak::new(0.0, Vector3::new(50.0, 0.0, 0.0), std);
        assert!(!lone.agreed_for(30.0));
    }
}
