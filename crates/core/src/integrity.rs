//! GNSS integrity monitor against spoofing (SYSTEM.md §5; seed 004 §3).
//!
//! Sits between the GNSS inputs and the filter. The reference is the navigator's own
//! INS/odometer prediction at the GNSS epoch; each epoch is tested before it is used:
//!
//! - distance: |r_GNSS - r_INS| > R (seed 004's fixed threshold, R = 10 m);
//! - chi-square: the normalised innovation y^T S^-1 y with the filter's covariance,
//!   S = H P H^T + R, against the chi-square quantile of its degrees of freedom;
//! - window: the sum of the last N normalised innovations against the chi-square
//!   quantile of N x dof degrees of freedom (a slow drift that each epoch hides).
//!
//! States: trusted (GNSS fused) -> suspect (one failed epoch, GNSS held back) ->
//! spoofed (`confirm_epochs` failed epochs in a row: GNSS excluded, the navigator runs
//! on INS/odometer/NHC) -> recovering (the GNSS agrees with the dead-reckoning solution
//! again) -> trusted after `readmit_s` of continuous agreement. No file I/O here: the
//! engine feeds [`EpochCheck`]s and logs the [`Transition`]s.

use crate::filter::chi2_threshold;
use std::collections::VecDeque;

/// Settings of the monitor (`[spoofing]` in the run configuration).
#[derive(Clone, Debug, PartialEq)]
pub struct IntegrityOptions {
    pub enabled: bool,
    /// Fixed distance threshold R [m] (seed 004: 10 m); None = off.
    pub distance_m: Option<f64>,
    /// Tail probability of the per-epoch chi-square test; None = off.
    pub chi2_probability: Option<f64>,
    /// Epochs in the windowed sum of normalised innovations (0 = off).
    pub window_epochs: usize,
    /// Tail probability of the windowed test.
    pub window_probability: f64,
    /// Failed epochs in a row that turn suspect into spoofed.
    pub confirm_epochs: usize,
    /// Continuous agreement needed before GNSS is used again [s].
    pub readmit_s: f64,
}

impl Default for IntegrityOptions {
    fn default() -> Self {
        IntegrityOptions {
            enabled: false,
            distance_m: Some(10.0),
            chi2_probability: Some(1e-5),
            window_epochs: 5,
            window_probability: 1e-5,
            confirm_epochs: 2,
            readmit_s: 10.0,
        }
    }
}

/// Where the monitor stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegrityState {
    Trusted,
    Suspect,
    Spoofed,
    Recovering,
}

impl IntegrityState {
    pub fn name(self) -> &'static str {
        match self {
            IntegrityState::Trusted => "trusted",
            IntegrityState::Suspect => "suspect",
            IntegrityState::Spoofed => "spoofed",
            IntegrityState::Recovering => "recovering",
        }
    }

    /// Output flag: 0 trusted, 1 suspect, 2 spoofed, 3 recovering.
    pub fn flag(self) -> u8 {
        self as u8
    }
}

/// Which test decided a transition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Detector {
    Distance,
    ChiSquare,
    Window,
    /// Agreement: every enabled test passed.
    Agreement,
}

impl Detector {
    pub fn name(self) -> &'static str {
        match self {
            Detector::Distance => "distance",
            Detector::ChiSquare => "chi2",
            Detector::Window => "window",
            Detector::Agreement => "agreement",
        }
    }
}

/// One GNSS epoch against the reference: the innovation's norm and its NIS.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpochCheck {
    /// GNSS time [s].
    pub t: f64,
    /// |r_GNSS - r_reference| [m]; NaN when the epoch has no position (e.g. tight
    /// coupling with fewer than 4 satellites): the distance test then abstains.
    pub distance_m: f64,
    /// Normalised innovation squared y^T S^-1 y.
    pub nis: f64,
    /// Its degrees of freedom (rows of y).
    pub dof: usize,
}

/// A state change, with the statistic that caused it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    pub t: f64,
    pub from: IntegrityState,
    pub to: IntegrityState,
    pub detector: Detector,
    pub statistic: f64,
    pub threshold: f64,
}

/// The decision for one epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdict {
    /// Fuse this epoch's GNSS.
    pub use_gnss: bool,
    pub transition: Option<Transition>,
}

/// The first failed test of an epoch, if any: (detector, statistic, threshold).
type Failure = Option<(Detector, f64, f64)>;

#[derive(Clone, Debug)]
pub struct IntegrityMonitor {
    opt: IntegrityOptions,
    state: IntegrityState,
    /// (nis, dof) of the last epochs, for the windowed test.
    window: VecDeque<(f64, usize)>,
    failed_in_row: usize,
    agree_since: f64,
    /// Epochs tested and transitions so far.
    pub epochs: usize,
    pub transitions: Vec<Transition>,
}

impl IntegrityMonitor {
    pub fn new(opt: IntegrityOptions) -> Self {
        IntegrityMonitor {
            opt,
            state: IntegrityState::Trusted,
            window: VecDeque::new(),
            failed_in_row: 0,
            agree_since: f64::NAN,
            epochs: 0,
            transitions: Vec::new(),
        }
    }

    pub fn state(&self) -> IntegrityState {
        self.state
    }

    /// Per-epoch tests (distance, then chi-square).
    fn epoch_failure(&self, c: &EpochCheck) -> Failure {
        if let Some(r) = self.opt.distance_m {
            if c.distance_m.is_finite() && c.distance_m > r {
                return Some((Detector::Distance, c.distance_m, r));
            }
        }
        if let Some(p) = self.opt.chi2_probability {
            let th = chi2_threshold(c.dof.max(1), p);
            if !c.nis.is_finite() || c.nis > th {
                return Some((Detector::ChiSquare, c.nis, th));
            }
        }
        None
    }

    /// Windowed test over the last `window_epochs` epochs (only once the window is
    /// full).
    fn window_failure(&self) -> Failure {
        let n = self.opt.window_epochs;
        if n == 0 || self.window.len() < n {
            return None;
        }
        let (sum, dof) = self
            .window
            .iter()
            .fold((0.0, 0), |(s, d), &(nis, k)| (s + nis, d + k));
        let th = chi2_threshold(dof.max(1), self.opt.window_probability);
        (sum > th).then_some((Detector::Window, sum, th))
    }

    /// Test one epoch and decide whether its GNSS may be fused.
    pub fn check(&mut self, c: &EpochCheck) -> Verdict {
        use IntegrityState::*;
        self.epochs += 1;
        let epoch_fail = self.epoch_failure(c);
        // The window watches the epochs that would be fused (trusted and suspect); in
        // the other states the reference drifts and each epoch is tested on its own.
        let fail = match self.state {
            Trusted | Suspect => {
                if self.opt.window_epochs > 0 {
                    self.window.push_back((c.nis.min(1e12), c.dof));
                    while self.window.len() > self.opt.window_epochs {
                        self.window.pop_front();
                    }
                }
                epoch_fail.or_else(|| self.window_failure())
            }
            Spoofed | Recovering => epoch_fail,
        };
        let (next, use_gnss) = match (self.state, fail) {
            (Trusted, None) => (Trusted, true),
            (Trusted, Some(_)) => {
                self.failed_in_row = 1;
                if self.opt.confirm_epochs <= 1 {
                    (Spoofed, false)
                } else {
                    (Suspect, false)
                }
            }
            (Suspect, None) => (Trusted, true),
            (Suspect, Some(_)) => {
                self.failed_in_row += 1;
                if self.failed_in_row >= self.opt.confirm_epochs {
                    (Spoofed, false)
                } else {
                    (Suspect, false)
                }
            }
            (Spoofed, Some(_)) => (Spoofed, false),
            (Spoofed, None) | (Recovering, None) => {
                if self.state == Spoofed {
                    self.agree_since = c.t;
                }
                if c.t - self.agree_since >= self.opt.readmit_s {
                    (Trusted, true)
                } else {
                    (Recovering, false)
                }
            }
            (Recovering, Some(_)) => (Spoofed, false),
        };
        let transition = (next != self.state).then(|| {
            let (detector, statistic, threshold) =
                fail.unwrap_or((Detector::Agreement, c.nis, f64::NAN));
            Transition {
                t: c.t,
                from: self.state,
                to: next,
                detector,
                statistic,
                threshold,
            }
        });
        if next == Trusted && self.state != Trusted && self.state != Suspect {
            // Re-admitted: the window restarts from clean epochs.
            self.window.clear();
        }
        if next == Trusted {
            self.failed_in_row = 0;
        }
        self.state = next;
        if let Some(tr) = transition {
            self.transitions.push(tr);
        }
        Verdict {
            use_gnss,
            transition,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ep(t: f64, d: f64, nis: f64) -> EpochCheck {
        EpochCheck {
            t,
            distance_m: d,
            nis,
            dof: 3,
        }
    }

    fn on() -> IntegrityOptions {
        IntegrityOptions {
            enabled: true,
            ..Default::default()
        }
    }

    #[test]
    fn a_jump_is_suspect_then_spoofed_then_readmitted_after_agreement() {
        let mut m = IntegrityMonitor::new(on());
        assert!(m.check(&ep(0.0, 1.0, 2.0)).use_gnss);
        let v = m.check(&ep(1.0, 25.0, 200.0));
        assert!(!v.use_gnss);
        let tr = v.transition.unwrap();
        assert_eq!(
            (tr.to, tr.detector),
            (IntegrityState::Suspect, Detector::Distance)
        );
        assert_eq!(tr.statistic, 25.0);
        assert_eq!(
            m.check(&ep(2.0, 25.0, 200.0)).transition.unwrap().to,
            IntegrityState::Spoofed
        );
        // Attack over: agreement for readmit_s (10 s) before GNSS is used again.
        let v = m.check(&ep(3.0, 1.0, 2.0));
        assert_eq!(v.transition.unwrap().to, IntegrityState::Recovering);
        for k in 4..13 {
            assert!(!m.check(&ep(k as f64, 1.0, 2.0)).use_gnss, "t {k}");
        }
        let v = m.check(&ep(13.0, 1.0, 2.0));
        assert!(v.use_gnss);
        assert_eq!(v.transition.unwrap().to, IntegrityState::Trusted);
        // A disagreement while recovering sends it back.
        let mut m2 = m.clone();
        m2.check(&ep(14.0, 30.0, 300.0));
        m2.check(&ep(15.0, 30.0, 300.0));
        assert_eq!(m2.state(), IntegrityState::Spoofed);
        m2.check(&ep(16.0, 1.0, 1.0));
        assert_eq!(
            m2.check(&ep(17.0, 12.0, 1.0)).transition.unwrap().to,
            IntegrityState::Spoofed
        );
    }

    #[test]
    fn a_single_outlier_is_only_suspect() {
        let mut m = IntegrityMonitor::new(on());
        m.check(&ep(0.0, 1.0, 1.0));
        m.check(&ep(1.0, 1.0, 100.0));
        let v = m.check(&ep(2.0, 1.0, 1.0));
        assert!(v.use_gnss);
        assert_eq!(v.transition.unwrap().to, IntegrityState::Trusted);
        assert!(m
            .transitions
            .iter()
            .all(|t| t.to != IntegrityState::Spoofed));
    }

    #[test]
    fn the_window_catches_what_each_epoch_passes() {
        // NIS 12 per epoch with 3 dof: below the per-epoch 1e-5 quantile (25.9), but
        // 10 epochs sum to 120 against the 30-dof quantile (about 68).
        let mut m = IntegrityMonitor::new(IntegrityOptions {
            window_epochs: 10,
            ..on()
        });
        let mut first = None;
        for k in 0..12 {
            let v = m.check(&ep(k as f64, 3.0, 12.0));
            if let (None, Some(tr)) = (first, v.transition) {
                first = Some(tr);
            }
        }
        let tr = first.expect("window detection");
        assert_eq!(tr.detector, Detector::Window);
        assert_eq!(tr.t, 9.0);
        assert!(tr.statistic > tr.threshold);
        // Off: no detection.
        let mut m = IntegrityMonitor::new(IntegrityOptions {
            window_epochs: 0,
            ..on()
        });
        assert!((0..12).all(|k| m.check(&ep(k as f64, 3.0, 12.0)).use_gnss));
    }

    #[test]
    fn distance_abstains_without_a_position_and_nan_nis_fails() {
        let mut m = IntegrityMonitor::new(on());
        assert!(m.check(&ep(0.0, f64::NAN, 1.0)).use_gnss);
        assert!(!m.check(&ep(1.0, f64::NAN, f64::NAN)).use_gnss);
    }
}
