//! The Allan deviation of an IMU record: the three gyro and three accelerometer axes,
//! each with its curve (tau, deviation, error bar) and the datasheet read-offs (IEEE
//! Std 952-1997 Annex C):
//!
//! - random walk `N` (ARW for gyros, VRW for accelerometers): the -1/2-slope line
//!   fitted to the white-noise part of the curve, read at tau = 1 s
//!   (`sigma(tau) = N / sqrt(tau)`, so `N = sigma(1 s)` on that line). The fitted part:
//!   the longest run of consecutive points, before the curve's minimum, whose local
//!   log-log slope is within [`SLOPE_TOLERANCE`] of -1/2; the line is the least
//!   squares `N² = mean(sigma² tau)` over it ([`white_noise_coefficient`]).
//! - bias instability `B`: the curve's minimum / 0.664 (flicker floor), over the
//!   points with at least [`MIN_CLUSTERS`] independent clusters (error bar <= 24 %).
//!   When that minimum is the last such point the curve is still falling and `B` is
//!   an upper bound ([`BiasInstability::still_falling`]).
//!
//! Everything is in SI (rad/s, m/s²; `N` in rad/sqrt(s), m/s/sqrt(s));
//! [`Sensor::units`] gives the datasheet units for tables and plots (deg/h,
//! deg/sqrt(h), mGal, m/s/sqrt(h)). A plot needs nothing else: per axis the curve with
//! its error bars `adev (1 +- rel_error)`, the -1/2 line `N / sqrt(tau)` over
//! `[tau_lo_s, tau_hi_s]` (or the whole range) and the floor `0.664 B` at `tau_s`.

use super::FLICKER_FLOOR_FACTOR;
use super::{allan_points, log_spaced_clusters, white_noise_coefficient, AllanPoint};

/// Points per decade of tau.
pub const POINTS_PER_DECADE: usize = 10;
/// How far the local slope may be from -1/2 in the white-noise fit.
pub const SLOPE_TOLERANCE: f64 = 0.1;
/// Fewest independent clusters of a point used for the bias instability.
pub const MIN_CLUSTERS: usize = 10;

/// Gyro or accelerometer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sensor {
    Gyro,
    Accel,
}

/// Datasheet units of a sensor's figures: names and factors from SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayUnits {
    /// Unit of the Allan deviation and of the bias instability (deg/h, mGal).
    pub adev: &'static str,
    /// Factor from SI (rad/s, m/s²) to `adev`.
    pub adev_factor: f64,
    /// Unit of the random walk (deg/sqrt(h), m/s/sqrt(h)).
    pub random_walk: &'static str,
    /// Factor from SI (rad/sqrt(s), m/s/sqrt(s)) to `random_walk`.
    pub random_walk_factor: f64,
}

impl Sensor {
    pub fn name(self) -> &'static str {
        match self {
            Sensor::Gyro => "gyro",
            Sensor::Accel => "accel",
        }
    }

    /// Name of the random-walk term: ARW (gyro), VRW (accel).
    pub fn random_walk_name(self) -> &'static str {
        match self {
            Sensor::Gyro => "ARW",
            Sensor::Accel => "VRW",
        }
    }

    /// deg/h and deg/sqrt(h) for gyros; mGal (1e-5 m/s²) and m/s/sqrt(h) for
    /// accelerometers. sqrt(3600 s) = 60 sqrt(s).
    pub fn units(self) -> DisplayUnits {
        match self {
            Sensor::Gyro => DisplayUnits {
                adev: "deg/h",
                adev_factor: 3600.0_f64.to_degrees(),
                random_walk: "deg/sqrt(h)",
                random_walk_factor: 60.0_f64.to_degrees(),
            },
            Sensor::Accel => DisplayUnits {
                adev: "mGal",
                adev_factor: 1e5,
                random_walk: "m/s/sqrt(h)",
                random_walk_factor: 60.0,
            },
        }
    }
}

/// The fitted -1/2 line `sigma = N / sqrt(tau)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RandomWalk {
    /// `N`, the line's value at tau = 1 s [rad/sqrt(s) | m/s/sqrt(s)].
    pub coefficient: f64,
    /// The fitted part of the curve \[s\].
    pub tau_lo_s: f64,
    pub tau_hi_s: f64,
    /// Points fitted.
    pub points: usize,
}

/// The bias instability read at the curve's minimum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasInstability {
    /// `B = min / 0.664` [rad/s | m/s²].
    pub value: f64,
    /// Averaging time of the minimum \[s\].
    pub tau_s: f64,
    /// The minimum is the longest usable tau: the curve may still fall, `B` is an
    /// upper bound (record too short, or no flicker floor).
    pub still_falling: bool,
}

/// One axis: its curve and read-offs.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisAllan {
    pub sensor: Sensor,
    /// 0, 1, 2 = x, y, z (the body frame the IMU reader rotates to).
    pub axis: usize,
    /// In SI: rad/s (gyro), m/s² (accel).
    pub curve: Vec<AllanPoint>,
    pub random_walk: Option<RandomWalk>,
    pub bias_instability: Option<BiasInstability>,
}

impl AxisAllan {
    /// `gyro_x`, ..., `accel_z`.
    pub fn name(&self) -> String {
        format!("{}_{}", self.sensor.name(), ["x", "y", "z"][self.axis])
    }
}

/// The six axes of one record.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuAllan {
    /// Sample interval used \[s\].
    pub dt_s: f64,
    /// Increments analysed.
    pub samples: usize,
    /// gyro x, y, z, accel x, y, z.
    pub axes: Vec<AxisAllan>,
}

impl ImuAllan {
    /// From the increments of each channel (gyro x y z \[rad\], accel x y z [m/s]),
    /// one every `dt_s` seconds. The mean increment is removed before integration
    /// (it does not change the Allan variance, and keeps the integral small: gravity
    /// on a vertical accelerometer).
    pub fn from_increments(channels: &[Vec<f64>; 6], dt_s: f64) -> Self {
        let samples = channels.iter().map(Vec::len).min().unwrap_or(0);
        let clusters = log_spaced_clusters(samples, POINTS_PER_DECADE);
        let axes = channels
            .iter()
            .enumerate()
            .map(|(ch, inc)| {
                let inc = &inc[..samples];
                let mean = inc.iter().sum::<f64>() / samples.max(1) as f64;
                let mut x = Vec::with_capacity(samples + 1);
                let mut acc = 0.0;
                x.push(0.0);
                for d in inc {
                    acc += d - mean;
                    x.push(acc);
                }
                // x is the integrated rate (angle, velocity): the deviation is a rate.
                let curve = allan_points(&x, dt_s, &clusters);
                AxisAllan {
                    sensor: if ch < 3 { Sensor::Gyro } else { Sensor::Accel },
                    axis: ch % 3,
                    random_walk: fit_random_walk(&curve),
                    bias_instability: bias_instability(&curve),
                    curve,
                }
            })
            .collect();
        ImuAllan {
            dt_s,
            samples,
            axes,
        }
    }

    /// Length of the record \[s\].
    pub fn duration_s(&self) -> f64 {
        self.samples as f64 * self.dt_s
    }
}

/// Index of the curve's minimum over the points with enough clusters.
fn usable_minimum(curve: &[AllanPoint]) -> Option<(usize, bool)> {
    let usable: Vec<usize> = (0..curve.len())
        .filter(|&i| curve[i].clusters >= MIN_CLUSTERS && curve[i].adev.is_finite())
        .collect();
    let &last = usable.last()?;
    let i = usable
        .iter()
        .copied()
        .min_by(|&a, &b| curve[a].adev.total_cmp(&curve[b].adev))?;
    Some((i, i == last))
}

/// The -1/2 line (module documentation).
pub fn fit_random_walk(curve: &[AllanPoint]) -> Option<RandomWalk> {
    let (end, _) = usable_minimum(curve)?;
    let slope = |a: &AllanPoint, b: &AllanPoint| {
        (b.adev.ln() - a.adev.ln()) / (b.tau_s.ln() - a.tau_s.ln())
    };
    // Local slope at i: over its neighbours (one-sided at the ends).
    let local = |i: usize| {
        let lo = i.saturating_sub(1);
        let hi = (i + 1).min(curve.len() - 1);
        (hi > lo).then(|| slope(&curve[lo], &curve[hi]))
    };
    let ok: Vec<bool> = (0..=end)
        .map(|i| local(i).is_some_and(|s| (s + 0.5).abs() <= SLOPE_TOLERANCE))
        .collect();
    // Longest run of consecutive ok points (the first at equal length).
    let (mut best, mut start) = (None::<(usize, usize)>, None);
    for i in 0..=ok.len() {
        match (ok.get(i).copied().unwrap_or(false), start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                if best.is_none_or(|(a, b)| i - s > b - a) {
                    best = Some((s, i));
                }
                start = None;
            }
            _ => {}
        }
    }
    let (a, b) = best?;
    let pts: Vec<(f64, f64)> = curve[a..b].iter().map(|p| (p.tau_s, p.adev)).collect();
    let (tau_lo_s, tau_hi_s) = (pts[0].0, pts[pts.len() - 1].0);
    Some(RandomWalk {
        coefficient: white_noise_coefficient(&pts, tau_lo_s, tau_hi_s)?,
        tau_lo_s,
        tau_hi_s,
        points: pts.len(),
    })
}

/// The minimum / 0.664 (module documentation).
pub fn bias_instability(curve: &[AllanPoint]) -> Option<BiasInstability> {
    let (i, still_falling) = usable_minimum(curve)?;
    Some(BiasInstability {
        value: curve[i].adev / FLICKER_FLOOR_FACTOR,
        tau_s: curve[i].tau_s,
        still_falling,
    })
}

#[cfg(test)]
mod tests {
    use super::super::tests::normals;
    use super::*;

    /// White rate noise of density `n` plus a flicker-like floor: a random walk of
    /// the bias would rise; a sum of first-order GM processes over decades of
    /// correlation time gives a flat floor. Here white noise alone, and white noise
    /// plus one GM bump, are enough to test the read-offs.
    fn white(n: f64, dt: f64, len: usize, seed: u64) -> Vec<f64> {
        normals(seed, len)
            .iter()
            .map(|z| n / dt.sqrt() * z * dt)
            .collect()
    }

    #[test]
    fn random_walk_of_white_noise_is_recovered_on_every_axis() {
        let dt = 0.01;
        let n_gyro = 0.2f64.to_radians() / 60.0; // 0.2 deg/sqrt(h)
        let n_acc = 0.05 / 60.0; // 0.05 m/s/sqrt(h)
        let len = 200_000;
        let ch: [Vec<f64>; 6] = std::array::from_fn(|k| {
            let n = if k < 3 { n_gyro } else { n_acc };
            let mut v = white(n, dt, len, 100 + k as u64);
            if k == 5 {
                // Gravity on z: a constant increment, removed with the mean.
                v.iter_mut().for_each(|x| *x -= 9.81 * dt);
            }
            v
        });
        let a = ImuAllan::from_increments(&ch, dt);
        assert_eq!(a.axes.len(), 6);
        for ax in &a.axes {
            let n = if ax.sensor == Sensor::Gyro {
                n_gyro
            } else {
                n_acc
            };
            let rw = ax.random_walk.expect("a white-noise fit");
            assert!(
                (rw.coefficient / n - 1.0).abs() < 0.05,
                "{} {rw:?}",
                ax.name()
            );
            // White noise only: the minimum lies at the long end (2000 s of data: the
            // last usable tau is 200 s; the scatter there may put it one point early).
            let bi = ax.bias_instability.unwrap();
            assert!(bi.tau_s > 50.0, "{} {bi:?}", ax.name());
            // Error bars shrink with more clusters.
            assert!(ax.curve[0].rel_error < ax.curve.last().unwrap().rel_error);
        }
        let u = Sensor::Gyro.units();
        let arw = a.axes[0].random_walk.unwrap().coefficient * u.random_walk_factor;
        assert!((arw / 0.2 - 1.0).abs() < 0.05, "ARW {arw} deg/sqrt(h)");
    }

    #[test]
    fn bias_instability_is_the_minimum_over_0_664() {
        let curve: Vec<AllanPoint> = [(0.1, 3.0), (1.0, 1.0), (10.0, 0.664), (100.0, 2.0)]
            .iter()
            .map(|&(tau_s, adev)| AllanPoint {
                tau_s,
                adev,
                m: 1,
                clusters: 100,
                rel_error: 0.07,
            })
            .collect();
        let b = bias_instability(&curve).unwrap();
        assert!((b.value - 1.0).abs() < 1e-12 && b.tau_s == 10.0 && !b.still_falling);
        // 0.1 -> 1 s: slope -0.477, 1 -> 10 s: -0.18: only the first points fit.
        let rw = fit_random_walk(&curve).unwrap();
        assert_eq!((rw.tau_lo_s, rw.points), (0.1, 1));
        assert!(fit_random_walk(&[]).is_none() && bias_instability(&[]).is_none());
    }

    #[test]
    fn units_convert_si_to_datasheet_figures() {
        let g = Sensor::Gyro.units();
        // 1 deg/h in rad/s -> 1.
        assert!((1f64.to_radians() / 3600.0 * g.adev_factor - 1.0).abs() < 1e-12);
        // 1 deg/sqrt(h) = (pi/180) / 60 rad/sqrt(s).
        assert!((1f64.to_radians() / 60.0 * g.random_walk_factor - 1.0).abs() < 1e-12);
        let a = Sensor::Accel.units();
        assert!((1e-5 * a.adev_factor - 1.0).abs() < 1e-12); // 1 mGal
    }
}
