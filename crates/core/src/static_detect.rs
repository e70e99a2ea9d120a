//! Static (standstill) detection over a sliding window of IMU samples, for the
//! zero-velocity updates and to suspend the non-holonomic constraint.
//!
//! Static when, over the last `window_s`: the standard deviation of the specific-force
//! vector (RMS deviation from its window mean) is below a threshold (no vibration, no
//! change of acceleration), and the standard deviation of the angular rate (RMS deviation of the rate vector
//! from its window mean) is below a threshold. Standard deviations rather than means,
//! so that an unknown gyro turn-on bias (degrees per second on MEMS parts) does not
//! hide a standstill; the odometer, when present, vetoes steady motion.

use crate::nav::timeline::TimeDirection;
use nalgebra::Vector3;
use std::collections::VecDeque;

#[derive(Clone, Debug)]
pub struct StaticDetector {
    window_s: f64,
    /// (t, dt, f \[m/s²\], w \[rad/s\]) of the samples in the window.
    samples: VecDeque<(f64, f64, Vector3<f64>, Vector3<f64>)>,
    sum_f: Vector3<f64>,
    sum_f2: f64,
    sum_w: Vector3<f64>,
    sum_w2: f64,
    sum_w_dt: Vector3<f64>,
    sum_dt: f64,
}

impl StaticDetector {
    pub fn new(window_s: f64) -> Self {
        StaticDetector {
            window_s,
            samples: VecDeque::new(),
            sum_f: Vector3::zeros(),
            sum_f2: 0.0,
            sum_w: Vector3::zeros(),
            sum_w2: 0.0,
            sum_w_dt: Vector3::zeros(),
            sum_dt: 0.0,
        }
    }

    /// Add one compensated IMU interval ending at `t`: specific force and rate \[SI\].
    /// In a backward run the interval is time-reversed: `dt` < 0, it starts at
    /// t - dt > t (the window then reaches from the latest sample's upper end down).
    pub fn push(&mut self, t: f64, dt: f64, f_b: &Vector3<f64>, w_b: &Vector3<f64>) {
        if dt == 0.0 {
            return;
        }
        self.samples.push_back((t, dt, *f_b, *w_b));
        self.sum_f += f_b;
        self.sum_f2 += f_b.norm_squared();
        self.sum_w += w_b;
        self.sum_w2 += w_b.norm_squared();
        self.sum_w_dt += w_b * dt;
        self.sum_dt += dt;
        while let Some(&(t0, dt0, f0, w0)) = self.samples.front() {
            // Span from where the oldest sample starts to now, along the run.
            let span = t - (t0 - dt0);
            let span = if dt0 < 0.0 { -span } else { span };
            if span <= self.window_s + 1e-9 {
                break;
            }
            self.samples.pop_front();
            self.sum_f -= f0;
            self.sum_f2 -= f0.norm_squared();
            self.sum_w -= w0;
            self.sum_w2 -= w0.norm_squared();
            self.sum_w_dt -= w0 * dt0;
            self.sum_dt -= dt0;
        }
    }

    /// Forget the window (after a gap in the data).
    pub fn clear(&mut self) {
        *self = StaticDetector::new(self.window_s);
    }

    /// Vector standard deviations of the specific force and the rate and their means
    /// over the window (None: fewer than 3 samples).
    pub fn moments(&self) -> Option<(f64, f64, Vector3<f64>, Vector3<f64>)> {
        let n = self.samples.len();
        if n < 3 {
            return None;
        }
        let k = n as f64;
        let mean_f = self.sum_f / k;
        let var_f = ((self.sum_f2 - k * mean_f.norm_squared()) / (k - 1.0)).max(0.0);
        let mean_w = self.sum_w / k;
        let var_w = ((self.sum_w2 - k * mean_w.norm_squared()) / (k - 1.0)).max(0.0);
        Some((var_f.sqrt(), var_w.sqrt(), mean_f, mean_w))
    }

    /// The window's mean angular rate \[rad/s\] when it is full and static:
    /// std(f) < `accel_std_max` \[m/s²\] and std(w) < `gyro_std_max` \[rad/s\] (vector
    /// standard deviations: sqrt(mean |x|² - |mean x|²)).
    pub fn static_mean_rate(&self, accel_std_max: f64, gyro_std_max: f64) -> Option<Vector3<f64>> {
        let n = self.samples.len();
        if n < 3 || self.sum_dt.abs() < 0.9 * self.window_s {
            return None;
        }
        let k = n as f64;
        let mean_f = self.sum_f / k;
        let var_f = ((self.sum_f2 - k * mean_f.norm_squared()) / (k - 1.0)).max(0.0);
        let mean_w = self.sum_w / k;
        let var_w = ((self.sum_w2 - k * mean_w.norm_squared()) / (k - 1.0)).max(0.0);
        (var_f.sqrt() < accel_std_max && var_w.sqrt() < gyro_std_max)
            .then_some(self.sum_w_dt / self.sum_dt)
    }
}

/// Vibration statistics of one sub-window of IMU samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubWindow {
    /// Vector standard deviations of the specific force \[m/s²\] and the angular rate
    /// \[rad/s\] (as [`StaticDetector`] computes them).
    pub accel_std: f64,
    pub gyro_std: f64,
    /// Means of the specific force and the angular rate.
    pub mean_f: Vector3<f64>,
    pub mean_w: Vector3<f64>,
    pub samples: usize,
}

/// Sub-window statistics of compensated samples cut every `len_s` (the last, shorter
/// than half of it, is merged into the one before).
pub fn sub_windows(samples: &[crate::types::ImuSample], len_s: f64) -> Vec<SubWindow> {
    let mut out = Vec::new();
    let Some(first) = samples.first() else {
        return out;
    };
    let t_start = first.t - first.dt;
    let t_end = samples[samples.len() - 1].t;
    let n = (((t_end - t_start) / len_s).floor() as usize).max(1);
    let edge = |k: usize| t_start + len_s * k as f64;
    let mut i = 0;
    for k in 0..n {
        let hi = if k + 1 == n {
            f64::INFINITY
        } else {
            edge(k + 1)
        };
        let mut det = StaticDetector::new(f64::INFINITY);
        let mut count = 0;
        while i < samples.len() && samples[i].t <= hi + 1e-9 {
            let s = &samples[i];
            if s.dt > 0.0 {
                det.push(s.t, s.dt, &(s.dvel / s.dt), &(s.dtheta / s.dt));
                count += 1;
            }
            i += 1;
        }
        if let Some((accel_std, gyro_std, mean_f, mean_w)) = det.moments() {
            out.push(SubWindow {
                accel_std,
                gyro_std,
                mean_f,
                mean_w,
                samples: count,
            });
        }
    }
    out
}

/// How many times its quietest sub-window's vibration a sub-window may show and still
/// count as static: engine idle is steady, a passenger or a closing door raises it for
/// a second (2.7x on the real car drive_0708).
pub const VIBRATION_FACTOR: f64 = 3.0;
/// A static window's sub-window means of the specific force may differ from each
/// other by this \[m/s²\] (0.6 deg of tilt; driving off changes them by 0.5-3 m/s²)
/// plus four times the noise of the difference (std / sqrt(n) of each).
pub const STILL_MEAN_ACCEL_MPS2: f64 = 0.1;
/// The same for the angular rate \[rad/s\] (a car turns at 5-30 deg/s).
pub const STILL_MEAN_RATE: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Whether a window of compensated IMU samples looks static from the IMU alone,
/// calibrated to the data's own vibration: every sub-window's vibration within
/// [`VIBRATION_FACTOR`] times the quietest one's (or within the configured
/// `accel_std_min` / `gyro_std_min`), and the sub-window means of specific force and
/// rate steady (a vehicle that accelerates or turns changes them; vibration averages
/// out). Constant-velocity straight motion passes: the caller asks the GNSS.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuStillness {
    pub is_static: bool,
    /// Quietest and median sub-window standard deviations \[m/s², rad/s\].
    pub accel_floor: f64,
    pub gyro_floor: f64,
    pub accel_median: f64,
    pub gyro_median: f64,
    /// Thresholds used: max(configured, factor x floor).
    pub accel_threshold: f64,
    pub gyro_threshold: f64,
    /// Largest sub-window values, and the largest differences between two
    /// sub-windows' means.
    pub accel_max: f64,
    pub gyro_max: f64,
    pub mean_f_change: f64,
    pub mean_w_change: f64,
    /// The sub-window means are steady (alone: what the GNSS at rest needs).
    pub means_steady: bool,
    /// Per-axis median of the sub-window mean rates \[rad/s\]: the rate at rest,
    /// robust to a knock or a hand that turns the IMU for a second.
    pub rate_median: Vector3<f64>,
    /// Standard deviation of the sub-window mean rates per axis \[rad/s\] (how well
    /// the window's mean rate is known: this over sqrt(sub-windows)).
    pub sub_mean_w_std: Vector3<f64>,
    /// What failed (empty when static).
    pub why_not: String,
}

pub fn imu_stillness(
    subs: &[SubWindow],
    accel_std_min: f64,
    gyro_std_min: f64,
) -> Option<ImuStillness> {
    if subs.is_empty() {
        return None;
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let a: Vec<f64> = subs.iter().map(|s| s.accel_std).collect();
    let g: Vec<f64> = subs.iter().map(|s| s.gyro_std).collect();
    let fold_min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let fold_max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let (accel_floor, gyro_floor) = (fold_min(&a), fold_min(&g));
    let accel_threshold = accel_std_min.max(VIBRATION_FACTOR * accel_floor);
    let gyro_threshold = gyro_std_min.max(VIBRATION_FACTOR * gyro_floor);
    let med3 = |f: &dyn Fn(&SubWindow) -> Vector3<f64>| {
        Vector3::from_fn(|i, _| median(subs.iter().map(|s| f(s)[i]).collect()))
    };
    let mw = med3(&|s| s.mean_w);
    // Every pair of sub-windows: their means within the tolerance plus 4 times the
    // noise of their difference (a change mid-window, not only a drift from the median).
    let mut mean_f_change: f64 = 0.0;
    let mut mean_w_change: f64 = 0.0;
    let mut means_steady = true;
    for (i, a) in subs.iter().enumerate() {
        for b in &subs[i + 1..] {
            let (na, nb) = (a.samples.max(1) as f64, b.samples.max(1) as f64);
            let noise_f = (a.accel_std.powi(2) / na + b.accel_std.powi(2) / nb).sqrt();
            let noise_w = (a.gyro_std.powi(2) / na + b.gyro_std.powi(2) / nb).sqrt();
            let df = (a.mean_f - b.mean_f).norm();
            let dw = (a.mean_w - b.mean_w).norm();
            mean_f_change = mean_f_change.max(df);
            mean_w_change = mean_w_change.max(dw);
            means_steady &= df <= STILL_MEAN_ACCEL_MPS2 + 4.0 * noise_f
                && dw <= STILL_MEAN_RATE + 4.0 * noise_w;
        }
    }
    let (accel_max, gyro_max) = (fold_max(&a), fold_max(&g));
    let k = subs.len() as f64;
    let mean_w = subs.iter().map(|s| s.mean_w).sum::<Vector3<f64>>() / k;
    let sub_mean_w_std = if subs.len() > 1 {
        (subs
            .iter()
            .map(|s| (s.mean_w - mean_w).map(|x| x * x))
            .sum::<Vector3<f64>>()
            / (k - 1.0))
            .map(f64::sqrt)
    } else {
        Vector3::repeat(f64::INFINITY)
    };
    let mut why_not = Vec::new();
    if accel_max > accel_threshold {
        why_not.push(format!(
            "accel std up to {accel_max:.3} m/s² > {accel_threshold:.3} (calibrated: {VIBRATION_FACTOR} x the quietest second's {accel_floor:.3})"
        ));
    }
    if gyro_max > gyro_threshold {
        why_not.push(format!(
            "gyro std up to {:.2} deg/s > {:.2} (calibrated: {VIBRATION_FACTOR} x the quietest second's {:.2})",
            gyro_max.to_degrees(),
            gyro_threshold.to_degrees(),
            gyro_floor.to_degrees()
        ));
    }
    if !means_steady {
        why_not.push(format!(
            "the mean specific force changed by {mean_f_change:.2} m/s² and the mean rate by {:.2} deg/s within the window",
            mean_w_change.to_degrees()
        ));
    }
    Some(ImuStillness {
        is_static: why_not.is_empty(),
        accel_floor,
        gyro_floor,
        accel_median: median(a.clone()),
        gyro_median: median(g.clone()),
        accel_threshold,
        gyro_threshold,
        accel_max,
        gyro_max,
        mean_f_change,
        mean_w_change,
        means_steady,
        rate_median: mw,
        sub_mean_w_std,
        why_not: why_not.join(", "),
    })
}

/// Time-stamped values over a sliding window, for the standstill vetoes: the mean
/// odometer speed, and the INS's mean acceleration from the running sum of its
/// mechanization velocity increments.
#[derive(Clone, Debug)]
pub struct Window<T> {
    window_s: f64,
    items: VecDeque<(f64, T)>,
    /// Which way time goes (a backward run pushes decreasing times).
    dir: TimeDirection,
}

impl<T: Copy> Window<T> {
    pub fn new(window_s: f64) -> Self {
        Window {
            window_s,
            items: VecDeque::new(),
            dir: TimeDirection::Forward,
        }
    }

    /// Set which way time goes (before the first push).
    pub fn set_direction(&mut self, dir: TimeDirection) {
        self.dir = dir;
    }

    /// Add a value at `t`; values older than the window (but the newest) are dropped.
    pub fn push(&mut self, t: f64, v: T) {
        self.items.push_back((t, v));
        let (dir, w) = (self.dir, self.window_s);
        let old = |t0: f64| match dir {
            TimeDirection::Forward => t0 < t - w - 1e-9,
            TimeDirection::Backward => t0 > t + w + 1e-9,
        };
        while self.items.len() > 1 && old(self.items[0].0) {
            self.items.pop_front();
        }
    }

    /// The values no older than the window as seen from `t_now`.
    pub fn recent(&self, t_now: f64) -> impl Iterator<Item = &(f64, T)> {
        let dir = self.dir;
        let since = match dir {
            TimeDirection::Forward => t_now - self.window_s - 1e-9,
            TimeDirection::Backward => t_now + self.window_s + 1e-9,
        };
        self.items.iter().filter(move |(t, _)| match dir {
            TimeDirection::Forward => *t >= since,
            TimeDirection::Backward => *t <= since,
        })
    }

    /// Oldest and newest entry.
    #[allow(clippy::type_complexity)]
    pub fn ends(&self) -> Option<(&(f64, T), &(f64, T))> {
        Some((self.items.front()?, self.items.back()?))
    }
}

/// Mean of the speeds \[m/s\] in the window ending at `t_now` (None: no reading).
pub fn mean_speed(w: &Window<f64>, t_now: f64) -> Option<f64> {
    let (n, sum) = w
        .recent(t_now)
        .fold((0usize, 0.0), |(n, s), (_, v)| (n + 1, s + v));
    (n > 0).then(|| sum / n as f64)
}

/// Mean horizontal acceleration \[m/s²\] from a running sum of velocity increments
/// (NED \[m/s\]) sampled in the window; None until it spans half the window.
pub fn mean_horizontal_accel(w: &Window<Vector3<f64>>, window_s: f64) -> Option<f64> {
    let ((t0, v0), (t1, v1)) = w.ends()?;
    let span = w.dir.elapsed(*t0, *t1);
    (span >= 0.5 * window_s).then(|| (v1 - v0).xy().norm() / span)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_average_what_they_hold() {
        let mut odo = Window::new(1.0);
        let mut dv = Window::new(1.0);
        for k in 0..=30 {
            let t = k as f64 * 0.1;
            odo.push(t, if k % 2 == 0 { 0.1 } else { -0.1 });
            dv.push(t, Vector3::new(-2.0 * t, 0.0, 0.3 * t));
        }
        assert!(mean_speed(&odo, 3.0).unwrap().abs() < 0.02);
        assert!(mean_speed(&odo, 10.0).is_none());
        let a = mean_horizontal_accel(&dv, 1.0).unwrap();
        assert!((a - 2.0).abs() < 1e-9, "{a}");
    }

    /// Sub-windows of an engine's vibration (0.15 m/s², 2.6 deg/s at 27 and 41 Hz, far
    /// above the 0.05 m/s² / 0.5 deg/s floor) are static, a passenger's bump of 2.5x for
    /// a second too; driving off at 0.3 m/s² or turning at 3 deg/s is not, nor (without
    /// GNSS) vibration at 4x its floor.
    #[test]
    fn stillness_is_calibrated_to_the_vibration() {
        use crate::types::ImuSample;
        let g = Vector3::new(0.0, 0.0, -9.8);
        let make = |accel: &dyn Fn(f64) -> Vector3<f64>,
                    rate: &dyn Fn(f64) -> Vector3<f64>,
                    amp: &dyn Fn(f64) -> f64| {
            (1..=1000)
                .map(|k| {
                    let t = k as f64 * 0.01;
                    let v = amp(t);
                    let vib = |p: f64| {
                        (2.0 * std::f64::consts::PI * 27.0 * t + p).sin()
                            + (2.0 * std::f64::consts::PI * 41.0 * t + 2.0 * p).sin()
                    };
                    let f = accel(t) + Vector3::new(vib(0.1), vib(1.3), vib(2.2)) * 0.0866 * v;
                    let w = rate(t) + Vector3::new(vib(0.7), vib(1.9), vib(2.9)) * 0.0262 * v;
                    ImuSample {
                        t,
                        dt: 0.01,
                        dtheta: w * 0.01,
                        dvel: f * 0.01,
                    }
                })
                .collect::<Vec<_>>()
        };
        let still = |s: &[ImuSample]| {
            imu_stillness(&sub_windows(s, 1.0), 0.05, 0.5f64.to_radians()).unwrap()
        };
        let idle = still(&make(&|_| g, &|_| Vector3::zeros(), &|_| 1.0));
        assert!(idle.is_static && idle.means_steady, "{idle:?}");
        assert!(
            idle.accel_median > 0.12 && idle.gyro_median > 2f64.to_radians(),
            "{idle:?}"
        );
        let bump = still(&make(&|_| g, &|_| Vector3::zeros(), &|t| {
            if (4.0..5.0).contains(&t) {
                2.5
            } else {
                1.0
            }
        }));
        assert!(bump.is_static, "{bump:?}");
        let drive = still(&make(
            &|t| g + Vector3::new(0.3 * (t - 5.0).clamp(0.0, 1.0), 0.0, 0.0),
            &|_| Vector3::zeros(),
            &|_| 1.0,
        ));
        assert!(!drive.means_steady, "{drive:?}");
        let turn = still(&make(
            &|_| g,
            &|t| Vector3::new(0.0, 0.0, if t > 5.0 { 3f64.to_radians() } else { 0.0 }),
            &|_| 1.0,
        ));
        assert!(!turn.means_steady, "{turn:?}");
        let rough = still(&make(&|_| g, &|_| Vector3::zeros(), &|t| {
            if t > 5.0 {
                4.0
            } else {
                1.0
            }
        }));
        assert!(rough.means_steady && !rough.is_static, "{rough:?}");
    }

    #[test]
    fn detects_rest_and_motion() {
        let mut d = StaticDetector::new(1.0);
        let g = Vector3::new(0.0, 0.0, -9.8);
        let mut noise = 0.0_f64;
        for k in 1..=100 {
            noise = (noise * 7.3 + 0.31).fract();
            let f = g + Vector3::new(0.0, 0.0, 0.02 * (noise - 0.5));
            d.push(k as f64 * 0.01, 0.01, &f, &Vector3::new(1e-4, 0.0, 0.0));
            if k < 90 {
                assert!(
                    d.static_mean_rate(0.05, 0.01).is_none(),
                    "window not full at {k}"
                );
            }
        }
        assert!(d.static_mean_rate(0.05, 0.01).is_some());
        // Starting to accelerate forward: |f| barely changes, the vector does.
        let mut e = d.clone();
        for k in 101..=150 {
            let a = 0.02 * (k - 100) as f64;
            e.push(
                k as f64 * 0.01,
                0.01,
                &(g + Vector3::new(a, 0.0, 0.0)),
                &Vector3::zeros(),
            );
        }
        assert!(e.static_mean_rate(0.05, 0.01).is_none());
        // Vibration: the magnitude swings by 0.5 m/s².
        for k in 101..=200 {
            let f = g * (1.0 + 0.05 * ((k % 2) as f64 - 0.5));
            d.push(k as f64 * 0.01, 0.01, &f, &Vector3::zeros());
        }
        assert!(d.static_mean_rate(0.05, 0.01).is_none());
        // A large constant gyro bias does not hide rest; a changing rate is motion.
        d.clear();
        for k in 1..=200 {
            d.push(k as f64 * 0.01, 0.01, &g, &Vector3::new(0.0, 0.0, 0.05));
        }
        let w = d
            .static_mean_rate(0.05, 0.01)
            .expect("static with a 3 deg/s bias");
        assert!((w.z - 0.05).abs() < 1e-12);
        for k in 201..=300 {
            let w = Vector3::new(0.0, 0.0, 0.05 + 0.002 * (k - 200) as f64);
            d.push(k as f64 * 0.01, 0.01, &g, &w);
        }
        assert!(d.static_mean_rate(0.05, 0.01).is_none());
    }
}
