//! Engine-like vibration (`[vibration]`, docs/SIMULATOR.md "Vibration"): a zero-mean
//! specific force and angular rate added to the true IMU increments, as an idling or
//! running engine shakes a car's IMU. Sinusoids at the engine's firing frequency and
//! its harmonics plus band-limited broadband vibration (a sum of many sinusoids of
//! random frequency in a band), every axis with its own random phases; no rectified
//! mean (gyro and accelerometer phases are independent, so no sculling error).
//!
//! Each increment is the exact integral of the vibration over its interval (what an
//! integrating IMU outputs), so a component at a multiple of the IMU rate integrates
//! to zero instead of aliasing into a bias; components above the Nyquist frequency
//! appear attenuated by sin(pi f dt) / (pi f dt) and folded, as in a real sensor
//! without an anti-alias filter. The configured RMS is that of the continuous
//! vibration; the increments' own scatter is lower by that attenuation.

use nalgebra::Vector3;
use serde::Deserialize;
use std::f64::consts::PI;

use crate::random::Stream;

/// When the vibration is on.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum VibrationWhen {
    /// The whole run (the engine runs throughout).
    #[default]
    Always,
    /// Only while the vehicle stands (speed below 1 cm/s): an idling engine.
    Static,
}

fn default_harmonics() -> Vec<f64> {
    // A four-cylinder four-stroke engine idling at 800 rpm fires at 26.7 Hz.
    vec![26.7, 53.3]
}
fn default_band() -> [f64; 2] {
    [10.0, 80.0]
}
fn default_share() -> f64 {
    0.3
}

/// The `[vibration]` table of a scenario.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VibrationSpec {
    /// RMS of the specific-force vibration vector \[m/s²\] (the vector standard
    /// deviation the static detector reads).
    pub accel_mps2: f64,
    /// RMS of the angular-rate vibration vector \[deg/s\].
    pub gyro_dps: f64,
    /// Frequencies of the sinusoids \[Hz\] (the engine's firing frequency and
    /// harmonics), sharing 1 - `broadband_share` of the variance equally.
    #[serde(default = "default_harmonics")]
    pub harmonics_hz: Vec<f64>,
    /// Share of the variance in broadband vibration, in \[0, 1\].
    #[serde(default = "default_share")]
    pub broadband_share: f64,
    /// Band of the broadband vibration \[Hz\].
    #[serde(default = "default_band")]
    pub broadband_hz: [f64; 2],
    #[serde(default)]
    pub when: VibrationWhen,
}

impl VibrationSpec {
    /// Checks the values; Err names the key.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        if !(self.accel_mps2.is_finite() && self.accel_mps2 >= 0.0) {
            return bad(
                "accel_mps2",
                format!("expected a number >= 0, got {}", self.accel_mps2),
            );
        }
        if !(self.gyro_dps.is_finite() && self.gyro_dps >= 0.0) {
            return bad(
                "gyro_dps",
                format!("expected a number >= 0, got {}", self.gyro_dps),
            );
        }
        if let Some(f) = self
            .harmonics_hz
            .iter()
            .find(|f| !(f.is_finite() && **f > 0.0))
        {
            return bad(
                "harmonics_hz",
                format!("expected frequencies > 0 Hz, got {f}"),
            );
        }
        if !(0.0..=1.0).contains(&self.broadband_share) {
            return bad(
                "broadband_share",
                format!("expected a share in [0, 1], got {}", self.broadband_share),
            );
        }
        if self.harmonics_hz.is_empty() && self.broadband_share < 1.0 {
            return bad(
                "harmonics_hz",
                "is empty: set broadband_share = 1 for broadband vibration alone".into(),
            );
        }
        let [lo, hi] = self.broadband_hz;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
            return bad(
                "broadband_hz",
                format!("expected [low, high] with 0 < low < high Hz, got [{lo}, {hi}]"),
            );
        }
        Ok(())
    }
}

/// Sinusoids making up the broadband vibration on each axis.
const BROADBAND_TONES: usize = 24;

/// One sinusoid a sin(w t + p).
#[derive(Clone, Copy, Debug)]
struct Tone {
    amp: f64,
    w: f64,
    phase: f64,
}

/// The vibration of one run: tones per axis of the accelerometers and the gyros.
#[derive(Clone, Debug)]
pub struct Vibration {
    accel: [Vec<Tone>; 3],
    gyro: [Vec<Tone>; 3],
    pub when: VibrationWhen,
}

impl Vibration {
    /// Draws phases and broadband frequencies from the stream `imu.vibration` of
    /// `seed` (no other stream changes).
    pub fn new(spec: &VibrationSpec, seed: u64) -> Self {
        let mut rng = Stream::new(seed, "imu.vibration");
        let mut axes = |rms_vector: f64| -> [Vec<Tone>; 3] {
            // Per-axis variance of a vector RMS, split between the parts.
            let var_axis = rms_vector * rms_vector / 3.0;
            let n_h = spec.harmonics_hz.len().max(1) as f64;
            let var_h = var_axis * (1.0 - spec.broadband_share) / n_h;
            let var_b = var_axis * spec.broadband_share / BROADBAND_TONES as f64;
            std::array::from_fn(|_| {
                let mut tones: Vec<Tone> = spec
                    .harmonics_hz
                    .iter()
                    .map(|f| Tone {
                        amp: (2.0 * var_h).sqrt(),
                        w: 2.0 * PI * f,
                        phase: rng.uniform_range(0.0, 2.0 * PI),
                    })
                    .collect();
                let [lo, hi] = spec.broadband_hz;
                for _ in 0..BROADBAND_TONES {
                    tones.push(Tone {
                        amp: (2.0 * var_b).sqrt(),
                        w: 2.0 * PI * rng.uniform_range(lo, hi),
                        phase: rng.uniform_range(0.0, 2.0 * PI),
                    });
                }
                tones.retain(|t| t.amp > 0.0);
                tones
            })
        };
        let accel = axes(spec.accel_mps2);
        let gyro = axes(spec.gyro_dps.to_radians());
        Vibration {
            accel,
            gyro,
            when: spec.when,
        }
    }

    /// Exact integrals over [a, b] (seconds from the start) of the vibration's
    /// angular rate \[rad\] and specific force \[m/s\].
    pub fn increments(&self, a: f64, b: f64) -> (Vector3<f64>, Vector3<f64>) {
        // Integral of a sin(w t + p) over [a, b] = a (cos(w a + p) - cos(w b + p)) / w.
        let int = |tones: &[Tone]| -> f64 {
            tones
                .iter()
                .map(|t| t.amp * ((t.w * a + t.phase).cos() - (t.w * b + t.phase).cos()) / t.w)
                .sum()
        };
        (
            Vector3::new(int(&self.gyro[0]), int(&self.gyro[1]), int(&self.gyro[2])),
            Vector3::new(
                int(&self.accel[0]),
                int(&self.accel[1]),
                int(&self.accel[2]),
            ),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> VibrationSpec {
        toml::from_str("accel_mps2 = 0.15\ngyro_dps = 2.5").unwrap()
    }

    /// Sampled finely, the vibration has the configured vector RMS and no mean; at
    /// the IMU rate a tone at the rate itself integrates to zero (no aliased bias).
    #[test]
    fn rms_mean_and_no_aliased_bias() {
        let v = Vibration::new(&spec(), 3);
        let dt = 1e-4;
        let n = 200_000;
        let (mut sum_a, mut sum_a2, mut sum_g2) = (Vector3::zeros(), 0.0, 0.0);
        for k in 0..n {
            let (g, a) = v.increments(k as f64 * dt, (k + 1) as f64 * dt);
            let (g, a) = (g / dt, a / dt);
            sum_a += a;
            sum_a2 += a.norm_squared();
            sum_g2 += g.norm_squared();
        }
        let nn = n as f64;
        let rms_a = (sum_a2 / nn).sqrt();
        let rms_g = (sum_g2 / nn).sqrt().to_degrees();
        assert!((rms_a - 0.15).abs() < 0.015, "{rms_a}");
        assert!((rms_g - 2.5).abs() < 0.25, "{rms_g}");
        assert!((sum_a / nn).norm() < 0.01, "{}", (sum_a / nn).norm());
        let tone: VibrationSpec = toml::from_str(
            "accel_mps2 = 1.0\ngyro_dps = 0\nharmonics_hz = [100.0]\nbroadband_share = 0",
        )
        .unwrap();
        let v = Vibration::new(&tone, 1);
        let mut s = Vector3::zeros();
        for k in 0..1000 {
            s += v.increments(k as f64 * 0.01, (k + 1) as f64 * 0.01).1;
        }
        assert!(s.norm() < 1e-9, "{s}");
    }

    #[test]
    fn bad_values_name_their_key() {
        let mut s = spec();
        s.broadband_share = 1.5;
        assert_eq!(s.validate().unwrap_err().0, "broadband_share");
        let mut s = spec();
        s.harmonics_hz = vec![25.0, -1.0];
        assert_eq!(s.validate().unwrap_err().0, "harmonics_hz");
        let mut s = spec();
        s.broadband_hz = [80.0, 10.0];
        assert_eq!(s.validate().unwrap_err().0, "broadband_hz");
        let mut s = spec();
        s.accel_mps2 = f64::NAN;
        assert_eq!(s.validate().unwrap_err().0, "accel_mps2");
    }
}
