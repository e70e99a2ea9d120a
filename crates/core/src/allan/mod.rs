//! Allan deviation (IEEE Std 952-1997, Annex C) and read-outs of the noise terms: what
//! `navfuse allan` computes for an IMU file ([`imu`]) and what the simulator's tests
//! check its IMU error models with.
//!
//! The overlapping Allan variance is computed from the integrated signal (angle or
//! velocity) `x_k`, `x_0 = 0`, `x_{k+1} = x_k + increment_k`:
//! `sigma²(tau) = sum_k (x_{k+2m} - 2 x_{k+m} + x_k)² / (2 tau² (L - 2m))`,
//! `tau = m dt`, `L` points of `x` (IEEE 952 Annex C, with overlapping clusters);
//! O(L) per cluster size.
//!
//! Noise terms on a log-log Allan-deviation plot (IEEE 952 Annex C):
//! white rate noise (ARW/VRW) `N`: `sigma = N / sqrt(tau)`, slope -1/2;
//! flicker (bias instability) `B`: flat floor `sigma = 0.664 B`;
//! rate random walk `K`: `sigma = K sqrt(tau / 3)`, slope +1/2.
//!
//! A first-order Gauss-Markov (GM) process with standard deviation `s` and
//! correlation time `T` has (IEEE 952 Annex C, correlated noise; `x = tau/T`)
//! `sigma²(tau) = s² (2x - 3 + 4e^{-x} - e^{-2x}) / x²`.
//! It has no floor but a maximum: `0.617364 s` at `tau = 1.8926 T` (found numerically;
//! see the test `gm_peak_constants`). The IMU model therefore sets
//! `s = 0.664 B / 0.617364` so that its bump reaches the flicker floor `0.664 B`.

pub mod imu;

/// Flicker floor factor: `sigma_floor = 0.664 B` (IEEE 952 Annex C; sqrt(2 ln 2 / pi)).
pub const FLICKER_FLOOR_FACTOR: f64 = 0.664;
/// Maximum of a first-order GM's Allan deviation in units of its sigma.
pub const GM_ADEV_PEAK: f64 = 0.617_364;
/// Averaging time of that maximum in units of the correlation time.
pub const GM_ADEV_PEAK_TAU_OVER_T: f64 = 1.8926;

/// Analytic Allan deviation of a first-order GM process (module documentation).
pub fn gauss_markov_adev(sigma: f64, corr_time_s: f64, tau_s: f64) -> f64 {
    let x = tau_s / corr_time_s;
    if x < 1e-4 {
        // Series 2x/3 - x²/2: avoids cancellation at tiny x.
        return sigma * (2.0 * x / 3.0 - x * x / 2.0).max(0.0).sqrt();
    }
    let v = (2.0 * x - 3.0 + 4.0 * (-x).exp() - (-2.0 * x).exp()) / (x * x);
    sigma * v.max(0.0).sqrt()
}

/// GM sigma whose Allan-deviation maximum equals the flicker floor `0.664 B`.
pub fn gm_sigma_for_bias_instability(bias_instability: f64) -> f64 {
    FLICKER_FLOOR_FACTOR * bias_instability / GM_ADEV_PEAK
}

/// Cluster sizes `m` from 1 to `(n - 1) / 2`, about `points_per_decade` per decade,
/// strictly increasing. `n` is the number of rate samples.
pub fn log_spaced_clusters(n: usize, points_per_decade: usize) -> Vec<usize> {
    let max_m = n.saturating_sub(1) / 2;
    if max_m == 0 || points_per_decade == 0 {
        return Vec::new();
    }
    let decades = (max_m as f64).log10();
    let count = (decades * points_per_decade as f64).ceil() as usize + 1;
    let mut out: Vec<usize> = Vec::with_capacity(count);
    for i in 0..count {
        let m = 10f64
            .powf(i as f64 / points_per_decade as f64)
            .round()
            .min(max_m as f64) as usize;
        if out.last() != Some(&m) {
            out.push(m);
        }
    }
    if out.last() != Some(&max_m) {
        out.push(max_m);
    }
    out
}

/// Overlapping Allan deviation of rate samples `samples` taken every `dt_s`:
/// `(tau_s, adev)` for each cluster size in `clusters` that fits (`2m <= n`).
/// The mean is removed before integration (it does not change the Allan variance
/// and keeps the integral small).
pub fn allan_deviation(samples: &[f64], dt_s: f64, clusters: &[usize]) -> Vec<(f64, f64)> {
    let n = samples.len();
    if n == 0 {
        return Vec::new();
    }
    let mean = samples.iter().sum::<f64>() / n as f64;
    let mut x = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    x.push(0.0);
    for &s in samples {
        acc += (s - mean) * dt_s;
        x.push(acc);
    }
    allan_deviation_integrated(&x, dt_s, clusters)
}

/// One point of an Allan-deviation curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AllanPoint {
    /// Averaging time `tau = m dt` \[s\].
    pub tau_s: f64,
    /// Allan deviation at `tau`, in the unit of the rate (rad/s, m/s², ...).
    pub adev: f64,
    /// Cluster size `m` (samples per average).
    pub m: usize,
    /// Independent (non-overlapping) clusters in the record, `floor(n / m)`.
    pub clusters: usize,
    /// 1-sigma relative error of `adev`, `1 / sqrt(2 (clusters - 1))` (IEEE 952
    /// Annex C, the usual error bar; conservative for the overlapping estimate):
    /// the error bar is `adev (1 +- rel_error)`. Infinite for one cluster.
    pub rel_error: f64,
}

/// Overlapping Allan deviation from the integrated signal `x` (`x[k]` at `k dt_s`,
/// e.g. the running sum of angle increments), with the error bar of each point.
/// Cluster sizes with `2m >= x.len()` or `m = 0` are skipped.
pub fn allan_points(x: &[f64], dt_s: f64, clusters: &[usize]) -> Vec<AllanPoint> {
    let l = x.len();
    let mut out = Vec::with_capacity(clusters.len());
    for &m in clusters {
        if m == 0 || 2 * m >= l {
            continue;
        }
        let terms = l - 2 * m;
        let mut sum = 0.0;
        for k in 0..terms {
            let d = x[k + 2 * m] - 2.0 * x[k + m] + x[k];
            sum += d * d;
        }
        let tau = m as f64 * dt_s;
        let independent = (l - 1) / m;
        out.push(AllanPoint {
            tau_s: tau,
            adev: (sum / (2.0 * tau * tau * terms as f64)).sqrt(),
            m,
            clusters: independent,
            rel_error: if independent > 1 {
                1.0 / (2.0 * (independent as f64 - 1.0)).sqrt()
            } else {
                f64::INFINITY
            },
        });
    }
    out
}

/// Overlapping Allan deviation from the integrated signal `x` as `(tau_s, adev)`
/// ([`allan_points`] without the error bars).
pub fn allan_deviation_integrated(x: &[f64], dt_s: f64, clusters: &[usize]) -> Vec<(f64, f64)> {
    allan_points(x, dt_s, clusters)
        .iter()
        .map(|p| (p.tau_s, p.adev))
        .collect()
}

/// White-noise coefficient `N` (ARW or VRW, units/sqrt(s)) from the points with
/// `tau_lo_s <= tau <= tau_hi_s`: least squares of `sigma² = N²/tau` with relative
/// weights, i.e. `N² = mean(sigma² tau)`. `None` without points in range.
pub fn white_noise_coefficient(curve: &[(f64, f64)], tau_lo_s: f64, tau_hi_s: f64) -> Option<f64> {
    let pts: Vec<f64> = curve
        .iter()
        .filter(|(t, _)| *t >= tau_lo_s && *t <= tau_hi_s)
        .map(|(t, a)| a * a * t)
        .collect();
    if pts.is_empty() {
        return None;
    }
    Some((pts.iter().sum::<f64>() / pts.len() as f64).sqrt())
}

/// Least-squares slope of log(adev) against log(tau) over `[tau_lo_s, tau_hi_s]`
/// (-1/2 for white rate noise). `None` with fewer than two points.
pub fn log_slope(curve: &[(f64, f64)], tau_lo_s: f64, tau_hi_s: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = curve
        .iter()
        .filter(|(t, a)| *t >= tau_lo_s && *t <= tau_hi_s && *a > 0.0)
        .map(|(t, a)| (t.ln(), a.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Bias instability `B` from the curve's minimum, `B = min / 0.664` (IEEE 952 for a
/// flicker floor, as on datasheets): `(tau_s of the minimum, B)`. For a GM-modelled
/// sensor this underestimates `B` (its curve falls again after the GM bump); use
/// [`bias_instability_gm_floor`] there.
pub fn bias_instability_from_minimum(curve: &[(f64, f64)]) -> Option<(f64, f64)> {
    curve
        .iter()
        .filter(|(_, a)| a.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|&(t, a)| (t, a / FLICKER_FLOOR_FACTOR))
}

/// Bias instability `B` from the top of the bias-instability bump once the white
/// noise `white_n` (from [`white_noise_coefficient`]) is removed:
/// `B = max_tau sqrt(sigma² - N²/tau) / 0.664`, over points where the remainder is at
/// least half the white part (so a 1 % error in `N` cannot dominate). For a GM model
/// this is its peak (set to `0.664 B`); for a flicker floor it is the floor, as long
/// as no rate random walk rises within the curve. Returns `(tau_s of the peak, B)`.
pub fn bias_instability_gm_floor(curve: &[(f64, f64)], white_n: f64) -> Option<(f64, f64)> {
    curve
        .iter()
        .filter_map(|&(t, a)| {
            let white = white_n * white_n / t;
            let rem = a * a - white;
            (rem >= 0.5 * white && rem.is_finite()).then(|| (t, rem.sqrt()))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(t, r)| (t, r / FLICKER_FLOOR_FACTOR))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Standard normal samples (Box-Muller), seeded.
    pub(crate) fn normals(seed: u64, n: usize) -> Vec<f64> {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let u1: f64 = 1.0 - rng.random::<f64>();
                let u2: f64 = rng.random::<f64>();
                (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
            })
            .collect()
    }

    #[test]
    fn gm_peak_constants() {
        // Golden-section search for the maximum of the analytic GM Allan deviation.
        let f = |x: f64| gauss_markov_adev(1.0, 1.0, x);
        let (mut a, mut b) = (0.5f64, 5.0f64);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let c = b - g * (b - a);
            let d = a + g * (b - a);
            if f(c) > f(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let x = 0.5 * (a + b);
        assert!((x - GM_ADEV_PEAK_TAU_OVER_T).abs() < 1e-3, "x {x}");
        assert!((f(x) - GM_ADEV_PEAK).abs() < 1e-6, "peak {}", f(x));
        // Short-tau limit: GM looks like a rate random walk with K² = 2 s²/T.
        let t = 1e-3;
        let k2 = 2.0;
        assert!((gauss_markov_adev(1.0, 1.0, t) / (k2 * t / 3.0).sqrt() - 1.0).abs() < 1e-3);
    }

    #[test]
    fn white_noise_adev_is_n_over_sqrt_tau() {
        // Rate samples of white noise with density N: per-sample std N / sqrt(dt).
        let (n_coef, dt) = (0.3f64, 0.01f64);
        let y: Vec<f64> = normals(11, 400_000)
            .iter()
            .map(|z| n_coef / dt.sqrt() * z)
            .collect();
        let curve = allan_deviation(&y, dt, &log_spaced_clusters(y.len(), 10));
        for &(t, a) in curve.iter().filter(|(t, _)| *t <= 40.0) {
            let expected = n_coef / t.sqrt();
            // EDF >= ~150 at tau = 40 s of 4000 s: < 6 % standard error; 3 sigma.
            assert!(
                (a / expected - 1.0).abs() < 0.18,
                "tau {t}: {a} vs {expected}"
            );
        }
        let est = white_noise_coefficient(&curve, 0.01, 1.0).unwrap();
        assert!((est / n_coef - 1.0).abs() < 0.01, "N {est}");
        let slope = log_slope(&curve, 0.01, 10.0).unwrap();
        assert!((slope + 0.5).abs() < 0.02, "slope {slope}");
    }

    #[test]
    fn rate_and_integrated_forms_agree() {
        let dt = 0.5;
        let y: Vec<f64> = normals(12, 5000).iter().map(|z| 1.0 + z).collect();
        let mut x = vec![0.0];
        for v in &y {
            x.push(x.last().unwrap() + v * dt);
        }
        let clusters = log_spaced_clusters(y.len(), 5);
        let a = allan_deviation(&y, dt, &clusters);
        let b = allan_deviation_integrated(&x, dt, &clusters);
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(&b) {
            assert_eq!(p.0, q.0);
            assert!((p.1 / q.1 - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn clusters_are_increasing_and_bounded() {
        let c = log_spaced_clusters(1001, 10);
        assert_eq!(c[0], 1);
        assert_eq!(*c.last().unwrap(), 500);
        assert!(c.windows(2).all(|w| w[0] < w[1]));
        assert!(log_spaced_clusters(2, 10).is_empty());
        assert!(allan_deviation(&[], 1.0, &[1]).is_empty());
    }
}
