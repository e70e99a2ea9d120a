//! Simulated barometer (scenario `\[baro\]`, docs/SIMULATOR.md): the pressure of the
//! true height plus the errors a MEMS barometer shows,
//!
//!   h_baro = h_true + b0 + w(t) + A sin(2 pi (t - t0) / P) + v,
//!
//! an offset b0 (pressure altitude against ellipsoidal height: geoid and weather), a
//! random-walk drift w (weather), a slow temperature-like error of amplitude A and
//! period P, and white noise v; written as pressure with the ISA relation
//! (navfuse_core::aiding::baro) and tagged `delay_s` after its time of validity.

use crate::random::{RandomWalk, Stream};
use navfuse_core::aiding::baro::{pressure_at_altitude_pa, ISA_P0_PA};
use serde::Deserialize;

fn default_rate() -> f64 {
    10.0
}
fn default_noise() -> f64 {
    0.3
}
fn default_bias() -> f64 {
    5.0
}
fn default_drift() -> f64 {
    1.0
}
fn default_slow_amplitude() -> f64 {
    1.0
}
fn default_slow_period() -> f64 {
    1800.0
}
fn default_p_ref() -> f64 {
    ISA_P0_PA
}

/// `\[baro\]` of a scenario.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaroSpec {
    /// Output rate \[Hz\].
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
    /// White noise 1-sigma \[m\].
    #[serde(default = "default_noise")]
    pub noise_std_m: f64,
    /// Offset b0 at the start \[m\].
    #[serde(default = "default_bias")]
    pub bias_m: f64,
    /// Random-walk drift of the offset \[m/sqrt(h)\].
    #[serde(default = "default_drift")]
    pub bias_drift_m_per_sqrth: f64,
    /// Temperature-like slow error: amplitude \[m\] and period \[s\].
    #[serde(default = "default_slow_amplitude")]
    pub slow_amplitude_m: f64,
    #[serde(default = "default_slow_period")]
    pub slow_period_s: f64,
    /// Reference (sea-level) pressure of the written pressures \[Pa\].
    #[serde(default = "default_p_ref")]
    pub reference_pressure_pa: f64,
    /// The reading is written this long after its time of validity \[s\].
    #[serde(default)]
    pub delay_s: f64,
}

impl Default for BaroSpec {
    /// The defaults of a `[baro]` table with no keys.
    fn default() -> Self {
        BaroSpec {
            rate_hz: default_rate(),
            noise_std_m: default_noise(),
            bias_m: default_bias(),
            bias_drift_m_per_sqrth: default_drift(),
            slow_amplitude_m: default_slow_amplitude(),
            slow_period_s: default_slow_period(),
            reference_pressure_pa: default_p_ref(),
            delay_s: 0.0,
        }
    }
}

/// One simulated reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaroReading {
    /// Time tag \[s\] (time of validity + delay).
    pub t_tag: f64,
    pub pressure_pa: f64,
    /// The error without the white noise: b0 + w(t) + slow(t) \[m\] (what a filter's
    /// bias state should find).
    pub bias_m: f64,
}

/// The barometer's error processes.
pub struct BaroSim {
    spec: BaroSpec,
    rng: Stream,
    walk: RandomWalk,
    t0: f64,
    t_prev: f64,
}

impl BaroSim {
    pub fn new(spec: &BaroSpec, seed: u64, t0: f64) -> Self {
        let q = (spec.bias_drift_m_per_sqrth / 60.0).powi(2);
        BaroSim {
            spec: spec.clone(),
            rng: Stream::new(seed, "baro"),
            walk: RandomWalk::new(q, spec.bias_m),
            t0,
            t_prev: t0,
        }
    }

    /// The reading valid at `t` \[s\] for a sensor at true height `h_m`.
    pub fn sample(&mut self, t: f64, h_m: f64) -> BaroReading {
        let s = &self.spec;
        let walk = self.walk.step(t - self.t_prev, &mut self.rng);
        self.t_prev = t;
        let slow = if s.slow_period_s > 0.0 {
            s.slow_amplitude_m * (std::f64::consts::TAU * (t - self.t0) / s.slow_period_s).sin()
        } else {
            0.0
        };
        let bias_m = walk + slow;
        let h_baro = h_m + bias_m + s.noise_std_m * self.rng.normal();
        BaroReading {
            t_tag: t + s.delay_s,
            pressure_pa: pressure_at_altitude_pa(h_baro, s.reference_pressure_pa),
            bias_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use navfuse_core::aiding::baro::pressure_altitude_m;

    #[test]
    fn readings_carry_the_bias_and_the_noise() {
        let spec = BaroSpec {
            rate_hz: 10.0,
            noise_std_m: 0.3,
            bias_m: 5.0,
            bias_drift_m_per_sqrth: 0.0,
            slow_amplitude_m: 0.0,
            slow_period_s: 1800.0,
            reference_pressure_pa: ISA_P0_PA,
            delay_s: 0.05,
        };
        let mut sim = BaroSim::new(&spec, 7, 0.0);
        let n = 20_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for k in 0..n {
            let t = k as f64 * 0.1;
            let r = sim.sample(t, 250.0);
            assert_eq!(r.t_tag, t + 0.05);
            assert_eq!(r.bias_m, 5.0);
            let e = pressure_altitude_m(r.pressure_pa, ISA_P0_PA) - 255.0;
            sum += e;
            sum2 += e * e;
        }
        let mean = sum / n as f64;
        let std = (sum2 / n as f64 - mean * mean).sqrt();
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((std - 0.3).abs() < 0.01, "std {std}");
    }
}
