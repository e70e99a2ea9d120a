//! The random processes of the error budget: a smooth Gauss-Markov process (so
//! Doppler stays consistent with the range) and the elevation mappings.

use super::{EARTH_RADIUS_M, IONO_SHELL_M};
use crate::random::Stream;

/// A smooth (differentiable) Gauss-Markov process: a first-order GM x with time
/// constant tau, low-passed once more, y' = (x - y) / tau. Stationary: var(x) = 2
/// sigma², cov(x, y) = var(y) = sigma². The rate y' exists, so Doppler is consistent.
/// Exact discretisation: Phi = e^{-dt/tau} [[1, 0], [dt/tau, 1]], Q = P - Phi P Phi^T.
#[derive(Clone, Debug)]
pub(crate) struct SmoothGm {
    tau: f64,
    sigma: f64,
    x: f64,
    y: f64,
}

impl SmoothGm {
    pub fn new(sigma: f64, tau: f64, rng: &mut Stream) -> Self {
        // Draw (x, y) from the stationary covariance [[2s², s²], [s², s²]].
        let (a, b) = (rng.normal(), rng.normal());
        let y = sigma * a;
        let x = y + sigma * b;
        SmoothGm { tau, sigma, x, y }
    }

    pub fn step(&mut self, dt: f64, rng: &mut Stream) {
        if self.sigma == 0.0 {
            return;
        }
        let e = (-dt / self.tau).exp();
        let r = dt / self.tau;
        let s2 = self.sigma * self.sigma;
        // P = s² [[2, 1], [1, 1]]; Phi = e [[1, 0], [r, 1]].
        let (p11, p12, p22) = (2.0 * s2, s2, s2);
        let (f11, f21, f22) = (e, e * r, e);
        let q11 = p11 - f11 * f11 * p11;
        let q12 = p12 - f11 * (f21 * p11 + f22 * p12);
        let q22 = p22 - (f21 * f21 * p11 + 2.0 * f21 * f22 * p12 + f22 * f22 * p22);
        let l11 = q11.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { q12 / l11 } else { 0.0 };
        let l22 = (q22 - l21 * l21).max(0.0).sqrt();
        let (w1, w2) = (rng.normal(), rng.normal());
        let (x, y) = (self.x, self.y);
        self.x = f11 * x + l11 * w1;
        self.y = f21 * x + f22 * y + l21 * w1 + l22 * w2;
    }

    pub fn value(&self) -> f64 {
        self.y
    }

    pub fn rate(&self) -> f64 {
        if self.sigma == 0.0 {
            0.0
        } else {
            (self.x - self.y) / self.tau
        }
    }
}

/// Noise/multipath scaling with elevation, 1 at zenith.
pub fn elevation_scale(el_rad: f64) -> f64 {
    let s = el_rad.sin().max(0.05);
    ((1.0 + 1.0 / (s * s)) / 2.0).sqrt()
}

/// Single-layer ionosphere obliquity factor.
pub fn iono_obliquity(el_rad: f64) -> f64 {
    let k = EARTH_RADIUS_M * el_rad.cos() / (EARTH_RADIUS_M + IONO_SHELL_M);
    1.0 / (1.0 - k * k).sqrt()
}
