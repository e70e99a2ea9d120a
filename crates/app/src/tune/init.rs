//! Where the noise identification starts when the configuration gives no IMU noise:
//! the white-noise level of each sensor axis read from the data itself.
//!
//! For a sample sequence x_k = s(t_k) + n_k with white noise n of variance sigma² and
//! a signal s smooth at the sample rate, the second difference
//! x_{k+1} - 2 x_k + x_{k-1} has variance 6 sigma² (the signal's part, s'' dt², is
//! negligible at IMU rates), so sigma² = E\[(Delta² x)²\] / 6 with no static segment
//! needed; a robust version takes the median of the squares over 0.4549 (the median
//! of chi-square(1)), so that manoeuvres and shocks do not weigh. The rate noise
//! sigma gives the random walk sigma sqrt(dt) (IEEE Std 952-1997: ARW/VRW is the rate
//! noise density). Vibration on a vehicle counts: it is noise to the filter.
//!
//! The bias instabilities start from ratios typical of each class (the Leador A15:
//! 0.027 deg/h for ARW 0.003 deg/sqrt(h); the ADIS16405: about 25 deg/h for
//! 2 deg/sqrt(h); accelerometers about 500 mGal per m/s/sqrt(h)), for the
//! expectation-maximisation to refine.

use navfuse_core::config::ImuNoise;
use navfuse_core::ImuSample;

/// Median of chi-square with one degree of freedom.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_8;

/// White rate noise \[unit/s/sqrt(s) of the increments: rad or m/s\] per axis of the
/// increments `f` (dtheta or dvel) of `imu`, or None with too few regular samples.
fn white_density(imu: &[ImuSample], f: impl Fn(&ImuSample) -> [f64; 3]) -> Option<[f64; 3]> {
    let dt_med = {
        let mut d: Vec<f64> = imu
            .iter()
            .take(2000)
            .map(|s| s.dt)
            .filter(|d| *d > 0.0)
            .collect();
        if d.len() < 10 {
            return None;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    };
    let mut sq: [Vec<f64>; 3] = Default::default();
    for w in imu.windows(3) {
        // Regular intervals only (no gap, no jitter beyond 20 %).
        if w.iter().any(|s| (s.dt - dt_med).abs() > 0.2 * dt_med) {
            continue;
        }
        let r = |s: &ImuSample| {
            let v = f(s);
            [v[0] / s.dt, v[1] / s.dt, v[2] / s.dt]
        };
        let (a, b, c) = (r(&w[0]), r(&w[1]), r(&w[2]));
        for k in 0..3 {
            let d2 = c[k] - 2.0 * b[k] + a[k];
            if d2.is_finite() {
                sq[k].push(d2 * d2);
            }
        }
    }
    if sq[0].len() < 100 {
        return None;
    }
    let mut out = [0.0; 3];
    for k in 0..3 {
        let v = &mut sq[k];
        let mid = v.len() / 2;
        let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
        // Rate noise sigma, then density sigma sqrt(dt).
        let sigma = (*m / CHI2_1_MEDIAN / 6.0).sqrt();
        out[k] = sigma * dt_med.sqrt();
    }
    Some(out)
}

/// What the data say of the IMU's white noise, and the model started from it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DataNoise {
    /// Angle and velocity random walk per axis \[rad/sqrt(s)\], \[m/s/sqrt(s)\].
    pub arw: [f64; 3],
    pub vrw: [f64; 3],
}

/// The white noise of `imu`'s gyros and accelerometers (None with fewer than a few
/// hundred regular samples).
pub(crate) fn data_noise(imu: &[ImuSample]) -> Option<DataNoise> {
    Some(DataNoise {
        arw: white_density(imu, |s| [s.dtheta.x, s.dtheta.y, s.dtheta.z])?,
        vrw: white_density(imu, |s| [s.dvel.x, s.dvel.y, s.dvel.z])?,
    })
}

/// Set `noise` (the keys listed in `defaulted`) from what the data say: ARW and VRW
/// from the white noise, the bias instabilities from them by the class ratios, the
/// scale factors at 1000 ppm (300 ppm for an IMU of tactical grade or better).
/// Returns the keys set.
pub(crate) fn start_from_data(
    noise: &mut ImuNoise,
    d: &DataNoise,
    defaulted: &[&str],
) -> Vec<&'static str> {
    let mut set = Vec::new();
    let mut when = |key: &'static str, f: &mut dyn FnMut()| {
        if defaulted.contains(&key) {
            f();
            set.push(key);
        }
    };
    let arw_deg_sqrth = |r: f64| r.to_degrees() * 60.0;
    let mean = |a: [f64; 3]| (a[0] + a[1] + a[2]) / 3.0;
    let arw_mean = arw_deg_sqrth(mean(d.arw));
    let vrw_mean = mean(d.vrw) * 60.0;
    when("imu_noise.arw_deg_sqrth", &mut || {
        noise.arw = nalgebra::Vector3::from(d.arw)
    });
    when("imu_noise.vrw_mps_sqrth", &mut || {
        noise.vrw = nalgebra::Vector3::from(d.vrw)
    });
    // deg/h from deg/sqrt(h): 10x; mGal from m/s/sqrt(h): 500x.
    when("imu_noise.gyro_bias_std_degph", &mut || {
        noise.gyro_bias_std = nalgebra::Vector3::repeat((10.0 * arw_mean).to_radians() / 3600.0)
    });
    when("imu_noise.accel_bias_std_mgal", &mut || {
        noise.accel_bias_std = nalgebra::Vector3::repeat(500.0 * vrw_mean * 1e-5)
    });
    let scale = if arw_mean < 0.05 { 300e-6 } else { 1000e-6 };
    when("imu_noise.gyro_scale_std_ppm", &mut || {
        noise.gyro_scale_std = nalgebra::Vector3::repeat(scale)
    });
    when("imu_noise.accel_scale_std_ppm", &mut || {
        noise.accel_scale_std = nalgebra::Vector3::repeat(scale)
    });
    set
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// White noise of known density on a moving signal is found within 3 %.
    #[test]
    fn white_noise_density_is_found_under_motion() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let dt: f64 = 0.01;
        let (arw, vrw) = (2e-3, 5e-3); // rad/sqrt(s), m/s/sqrt(s)
        let ng = Normal::new(0.0, arw / dt.sqrt()).unwrap();
        let na = Normal::new(0.0, vrw / dt.sqrt()).unwrap();
        let imu: Vec<ImuSample> = (0..100_000)
            .map(|k| {
                let t = k as f64 * dt;
                // A turning, accelerating vehicle.
                let w = Vector3::new(0.1 * (0.3 * t).sin(), 0.0, 0.2 * (0.05 * t).cos());
                let f = Vector3::new(2.0 * (0.2 * t).sin(), 0.5, -9.8);
                let noise_g = Vector3::from_fn(|_, _| ng.sample(&mut rng));
                let noise_a = Vector3::from_fn(|_, _| na.sample(&mut rng));
                ImuSample {
                    t,
                    dt,
                    dtheta: (w + noise_g) * dt,
                    dvel: (f + noise_a) * dt,
                }
            })
            .collect();
        let d = data_noise(&imu).unwrap();
        for k in 0..3 {
            assert!((d.arw[k] / arw - 1.0).abs() < 0.03, "{:?}", d.arw);
            assert!((d.vrw[k] / vrw - 1.0).abs() < 0.03, "{:?}", d.vrw);
        }
    }
}
