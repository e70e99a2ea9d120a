//! Rate profiles of a compiled segment (piecewise linear or sinusoidal) and the
//! small quadratures used to size them.

use std::f64::consts::PI;

/// A piecewise-linear or sinusoidal rate, in local segment time tau.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Profile {
    /// Pieces (duration, rate at start, rate at end), linear in between.
    Linear(Vec<(f64, f64, f64)>),
    /// amp * sin(2 pi tau / period).
    Sine { amp: f64, period: f64 },
}

impl Profile {
    pub(super) fn zero() -> Self {
        Profile::Linear(Vec::new())
    }

    pub(super) fn constant(duration: f64, rate: f64) -> Self {
        Profile::Linear(vec![(duration, rate, rate)])
    }

    /// Trapezoid: ramp 0 -> peak over `ramp`, hold, ramp back to 0.
    pub(super) fn trapezoid(peak: f64, ramp: f64, hold: f64) -> Self {
        let mut v = Vec::new();
        if ramp > 0.0 {
            v.push((ramp, 0.0, peak));
        }
        if hold > 0.0 {
            v.push((hold, peak, peak));
        }
        if ramp > 0.0 {
            v.push((ramp, peak, 0.0));
        }
        Profile::Linear(v)
    }

    /// Rate at local time `tau`, using the piece that contains `tau_sel` (so an
    /// integration step that ends on a knot keeps its own piece's formula).
    pub(super) fn rate(&self, tau: f64, tau_sel: f64) -> f64 {
        match self {
            Profile::Linear(pieces) => {
                let mut t0 = 0.0;
                for (k, &(d, r0, r1)) in pieces.iter().enumerate() {
                    // The last piece also answers at (and just past) its end.
                    if tau_sel < t0 + d || k + 1 == pieces.len() {
                        return r0 + (r1 - r0) * (tau - t0) / d;
                    }
                    t0 += d;
                }
                0.0
            }
            Profile::Sine { amp, period } => amp * (2.0 * PI * tau / period).sin(),
        }
    }

    /// Local times where the rate or its slope changes.
    pub(super) fn knots(&self, out: &mut Vec<f64>) {
        if let Profile::Linear(pieces) = self {
            let mut t = 0.0;
            for &(d, _, _) in pieces {
                t += d;
                out.push(t);
            }
        }
    }
}

/// Angle reached at local time `tau` when going 0 -> `total` over `dur` with a
/// triangular rate (peak 2 total / dur at dur / 2).
pub(super) fn s_curve(total: f64, dur: f64, tau: f64) -> f64 {
    let u = (tau / dur).clamp(0.0, 1.0);
    if u <= 0.5 {
        2.0 * total * u * u
    } else {
        total - 2.0 * total * (1.0 - u) * (1.0 - u)
    }
}

/// ∫_0^T f by composite Simpson, 2000 intervals (smooth integrands; error < 1e-12).
pub(super) fn simpson(f: impl Fn(f64) -> f64, t: f64) -> f64 {
    let n = 2000;
    let h = t / n as f64;
    let mut acc = f(0.0) + f(t);
    for k in 1..n {
        acc += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    acc * h / 3.0
}
