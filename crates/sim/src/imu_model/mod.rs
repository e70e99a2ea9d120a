//! IMU error models: grades (presets and custom) applied to perfect increments.
//!
//! Per triad, per interval `[t_k, t_k + dt]` (docs/SIM_IMU.md):
//! `measured = (I + S + M) true + (b_on + b_gm(t_k) + b_rrw(t_k)) dt + N sqrt(dt) w`,
//! then quantised to the increment LSB with the residual carried to the next sample.
//! `S` = diagonal scale-factor errors, `M` = small off-diagonal non-orthogonality
//! terms, `b_on` = turn-on bias (constant for the run), `b_gm` = first-order
//! Gauss-Markov bias instability, `b_rrw` = rate random walk, `N` = white noise
//! density (ARW/VRW). The bias of an interval is the value at its start (rectangle
//! rule; the difference from the exact integral is O(dt/T)), and the processes are
//! stepped to the interval's end afterwards, so [`ImuErrorModel::current_errors`]
//! returns the bias the next interval will use.
//!
//! Bias instability `B` follows the IEEE Std 952-1997 convention (Allan floor
//! `0.664 B`); the GM sigma is `0.664 B / 0.617364` so its Allan maximum (at
//! `tau = 1.89 T`) reaches that floor ([`navfuse_core::allan`]).

use std::f64::consts::PI;

use serde::Deserialize;

use navfuse_core::allan::gm_sigma_for_bias_instability;

mod error_model;
#[cfg(test)]
mod tests;

pub use error_model::{ImuErrorModel, TrueImuErrors};

/// Standard gravity for mg / µg conversions [m/s²] (CGPM 1901).
pub const G0_MPS2: f64 = 9.806_65;
const DEG: f64 = PI / 180.0;
/// deg/h -> rad/s.
const DEGPH: f64 = DEG / 3600.0;
/// 1/sqrt(h) -> 1/sqrt(s).
const PER_SQRTH: f64 = 1.0 / 60.0;
/// mg -> m/s².
const MG: f64 = G0_MPS2 * 1e-3;
/// 1 ft = 0.3048 m.
const FT: f64 = 0.3048;

/// Error figures of one sensor triad, SI units: rad-based for gyros, m-based for
/// accelerometers (unit pairs given as gyro | accel). All standard deviations are
/// 1-sigma and apply independently to each axis.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorErrors {
    /// Turn-on bias sigma, constant over a run [rad/s | m/s²].
    pub turn_on_bias_sigma: f64,
    /// Bias instability `B`, IEEE 952 convention (Allan floor 0.664 B) [rad/s | m/s²].
    pub bias_instability: f64,
    /// Correlation time of the bias-instability Gauss-Markov process \[s\].
    pub bias_corr_time_s: f64,
    /// White noise density: ARW [rad/sqrt(s)] | VRW [m/s/sqrt(s)].
    pub white_noise_density: f64,
    /// Rate random walk `K` [rad/s/sqrt(s) | m/s²/sqrt(s)].
    pub rate_random_walk: f64,
    /// Scale-factor error sigma [-] (1e-6 = 1 ppm).
    pub scale_sigma: f64,
    /// Axis misalignment (non-orthogonality) sigma per off-diagonal term \[rad\].
    pub misalignment_sigma_rad: f64,
    /// Quantisation step of the increment output [rad | m/s]; 0 = none.
    pub quantization: f64,
}

impl SensorErrors {
    /// No errors at all (correlation time 100 s, unused).
    pub fn zero() -> Self {
        Self {
            turn_on_bias_sigma: 0.0,
            bias_instability: 0.0,
            bias_corr_time_s: 100.0,
            white_noise_density: 0.0,
            rate_random_walk: 0.0,
            scale_sigma: 0.0,
            misalignment_sigma_rad: 0.0,
            quantization: 0.0,
        }
    }

    /// Sigma of the bias-instability Gauss-Markov process.
    pub fn gm_sigma(&self) -> f64 {
        gm_sigma_for_bias_instability(self.bias_instability)
    }
}

/// An IMU grade: a name and the error figures of both triads.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuGrade {
    pub name: String,
    pub gyro: SensorErrors,
    pub accel: SensorErrors,
}

/// Names accepted by [`preset`] (and by `grade` in `[imu]`).
pub const PRESET_NAMES: [&str; 6] = [
    "perfect",
    "hg1700",
    "adis16405",
    "imu500",
    "consumer",
    "custom",
];

/// A preset grade by name (sources in docs/SIM_IMU.md), `None` for an unknown name.
pub fn preset(name: &str) -> Option<ImuGrade> {
    let mut g = SensorErrors::zero();
    let mut a = SensorErrors::zero();
    match name {
        "perfect" | "custom" => {}
        "hg1700" => {
            // Honeywell HG1700 (AG58) spec-sheet values as quoted by NavToolkit's
            // hg1700_model: gyro bias 1 deg/h, ARW 0.125 deg/sqrt(h); accel bias 1 mg,
            // VRW 0.065 ft/s/sqrt(h). One "bias" figure only: modelled as turn-on bias,
            // no bias instability. Seed 000 uses 2.424068e-6 rad/s (0.5 deg/h) +
            // rand(+-0.5 deg/h) and 0.0249 + rand(+-0.00637) m/s²; its reproduction
            // sets those itself.
            g.turn_on_bias_sigma = 1.0 * DEGPH;
            g.white_noise_density = 0.125 * DEG * PER_SQRTH;
            g.bias_corr_time_s = 3600.0;
            a.turn_on_bias_sigma = 1.0 * MG;
            a.white_noise_density = 0.065 * FT * PER_SQRTH;
            a.bias_corr_time_s = 3600.0;
        }
        "adis16405" => {
            // Analog Devices ADIS16405 datasheet: gyro initial bias error +-3 deg/s,
            // in-run bias stability 0.007 deg/s, ARW 2.0 deg/sqrt(h), axis-to-axis
            // misalignment 0.05 deg; accel initial bias +-50 mg, in-run bias
            // stability 0.2 mg, VRW 0.2 m/s/sqrt(h), misalignment 0.2 deg.
            // Correlation time 100 s as gnss-ins-sim's grades (not on the datasheet).
            g.turn_on_bias_sigma = 3.0 * DEG;
            g.bias_instability = 0.007 * DEG;
            g.bias_corr_time_s = 100.0;
            g.white_noise_density = 2.0 * DEG * PER_SQRTH;
            g.misalignment_sigma_rad = 0.05 * DEG;
            a.turn_on_bias_sigma = 50.0 * MG;
            a.bias_instability = 0.2 * MG;
            a.bias_corr_time_s = 100.0;
            a.white_noise_density = 0.2 * PER_SQRTH;
            a.misalignment_sigma_rad = 0.2 * DEG;
        }
        "imu500" => {
            // Seed 004: gyro drift 0.1 deg/h, noise 0.007 deg/sqrt(h); accel bias
            // 0.5 mg, noise 20 ug (read as 20 ug/sqrt(Hz) = 1.96e-4 m/s/sqrt(s)).
            // "drift"/"bias" used both as turn-on sigma and as bias instability B.
            g.turn_on_bias_sigma = 0.1 * DEGPH;
            g.bias_instability = 0.1 * DEGPH;
            g.bias_corr_time_s = 100.0;
            g.white_noise_density = 0.007 * DEG * PER_SQRTH;
            a.turn_on_bias_sigma = 0.5 * MG;
            a.bias_instability = 0.5 * MG;
            a.bias_corr_time_s = 100.0;
            a.white_noise_density = 20e-6 * G0_MPS2;
        }
        "consumer" => {
            // Bosch BMI160-class phone MEMS (BMI160 datasheet BST-BMI160-DS000-07):
            // gyro zero-rate offset +-3 deg/s, noise density 0.007 deg/s/sqrt(Hz)
            // (= 0.42 deg/sqrt(h)), sensitivity tolerance 1 %; accel zero-g offset
            // +-40 mg, noise density 180 ug/sqrt(Hz), sensitivity 1 %; cross-axis 1 %.
            // Bias instability (not on the datasheet) from gnss-ins-sim's "low" grade:
            // 10 deg/h, 2e-4 m/s², correlation time 100 s.
            g.turn_on_bias_sigma = 3.0 * DEG;
            g.bias_instability = 10.0 * DEGPH;
            g.bias_corr_time_s = 100.0;
            g.white_noise_density = 0.007 * DEG;
            g.scale_sigma = 0.01;
            g.misalignment_sigma_rad = 0.01;
            a.turn_on_bias_sigma = 40.0 * MG;
            a.bias_instability = 2e-4;
            a.bias_corr_time_s = 100.0;
            a.white_noise_density = 180e-6 * G0_MPS2;
            a.scale_sigma = 0.01;
            a.misalignment_sigma_rad = 0.01;
        }
        _ => return None,
    }
    Some(ImuGrade {
        name: name.to_string(),
        gyro: g,
        accel: a,
    })
}

/// What the simulator writes: increments per interval or mean rates.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ImuOutput {
    /// Angle and velocity increments [rad, m/s] (navfuse's native input).
    #[default]
    Increments,
    /// Increments divided by the interval [rad/s, m/s²].
    Rates,
}

fn default_grade() -> String {
    "perfect".to_string()
}
fn default_rate_hz() -> f64 {
    200.0
}

/// The `[imu]` table of a scenario: a grade, then optional overrides in user units.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImuSpec {
    /// One of [`PRESET_NAMES`].
    #[serde(default = "default_grade")]
    pub grade: String,
    /// Output rate \[Hz\].
    #[serde(default = "default_rate_hz")]
    pub rate_hz: f64,
    #[serde(default)]
    pub output: ImuOutput,
    pub gyro_bias_degph: Option<f64>,
    pub gyro_bias_instability_degph: Option<f64>,
    pub gyro_corr_time_s: Option<f64>,
    pub arw_deg_sqrth: Option<f64>,
    /// Gyro rate random walk [deg/h/sqrt(h)].
    pub gyro_rrw_degph_sqrth: Option<f64>,
    pub gyro_scale_ppm: Option<f64>,
    pub gyro_misalignment_mrad: Option<f64>,
    pub gyro_quantization_rad: Option<f64>,
    pub accel_bias_mg: Option<f64>,
    pub accel_bias_instability_mg: Option<f64>,
    pub accel_corr_time_s: Option<f64>,
    pub vrw_mps_sqrth: Option<f64>,
    /// VRW as a noise density [µg/sqrt(Hz)]; exclusive with `vrw_mps_sqrth`.
    pub vrw_ug_sqrthz: Option<f64>,
    /// Accelerometer rate random walk [mg/sqrt(h)].
    pub accel_rrw_mg_sqrth: Option<f64>,
    pub accel_scale_ppm: Option<f64>,
    pub accel_misalignment_mrad: Option<f64>,
    pub accel_quantization_mps: Option<f64>,
}

impl Default for ImuSpec {
    fn default() -> Self {
        Self {
            grade: default_grade(),
            rate_hz: default_rate_hz(),
            output: ImuOutput::default(),
            gyro_bias_degph: None,
            gyro_bias_instability_degph: None,
            gyro_corr_time_s: None,
            arw_deg_sqrth: None,
            gyro_rrw_degph_sqrth: None,
            gyro_scale_ppm: None,
            gyro_misalignment_mrad: None,
            gyro_quantization_rad: None,
            accel_bias_mg: None,
            accel_bias_instability_mg: None,
            accel_corr_time_s: None,
            vrw_mps_sqrth: None,
            vrw_ug_sqrthz: None,
            accel_rrw_mg_sqrth: None,
            accel_scale_ppm: None,
            accel_misalignment_mrad: None,
            accel_quantization_mps: None,
        }
    }
}

/// Checks an optional override: finite and >= 0 (> 0 when `positive`), then scales.
fn set(
    target: &mut f64,
    value: Option<f64>,
    key: &str,
    scale: f64,
    positive: bool,
) -> Result<(), String> {
    let Some(v) = value else { return Ok(()) };
    if v.is_nan() || (v.is_infinite() && !positive) {
        return Err(format!("imu.{key}: expected a finite number, got {v}"));
    }
    if positive && v <= 0.0 {
        return Err(format!(
            "imu.{key}: expected a number > 0 (or inf), got {v}"
        ));
    }
    if !positive && v < 0.0 {
        return Err(format!("imu.{key}: expected a number >= 0, got {v}"));
    }
    *target = v * scale;
    Ok(())
}

impl ImuSpec {
    /// The grade: the preset, then the overrides converted to SI. Errors name the
    /// key and what was expected. Also checks `rate_hz`.
    pub fn to_grade(&self) -> Result<ImuGrade, String> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(format!(
                "imu.rate_hz: expected a finite number > 0, got {}",
                self.rate_hz
            ));
        }
        let mut grade = preset(&self.grade).ok_or_else(|| {
            format!(
                "imu.grade: expected one of {}, got \"{}\"",
                PRESET_NAMES.join(", "),
                self.grade
            )
        })?;
        let g = &mut grade.gyro;
        set(
            &mut g.turn_on_bias_sigma,
            self.gyro_bias_degph,
            "gyro_bias_degph",
            DEGPH,
            false,
        )?;
        set(
            &mut g.bias_instability,
            self.gyro_bias_instability_degph,
            "gyro_bias_instability_degph",
            DEGPH,
            false,
        )?;
        set(
            &mut g.bias_corr_time_s,
            self.gyro_corr_time_s,
            "gyro_corr_time_s",
            1.0,
            true,
        )?;
        set(
            &mut g.white_noise_density,
            self.arw_deg_sqrth,
            "arw_deg_sqrth",
            DEG * PER_SQRTH,
            false,
        )?;
        set(
            &mut g.rate_random_walk,
            self.gyro_rrw_degph_sqrth,
            "gyro_rrw_degph_sqrth",
            DEGPH * PER_SQRTH,
            false,
        )?;
        set(
            &mut g.scale_sigma,
            self.gyro_scale_ppm,
            "gyro_scale_ppm",
            1e-6,
            false,
        )?;
        set(
            &mut g.misalignment_sigma_rad,
            self.gyro_misalignment_mrad,
            "gyro_misalignment_mrad",
            1e-3,
            false,
        )?;
        set(
            &mut g.quantization,
            self.gyro_quantization_rad,
            "gyro_quantization_rad",
            1.0,
            false,
        )?;
        let a = &mut grade.accel;
        set(
            &mut a.turn_on_bias_sigma,
            self.accel_bias_mg,
            "accel_bias_mg",
            MG,
            false,
        )?;
        set(
            &mut a.bias_instability,
            self.accel_bias_instability_mg,
            "accel_bias_instability_mg",
            MG,
            false,
        )?;
        set(
            &mut a.bias_corr_time_s,
            self.accel_corr_time_s,
            "accel_corr_time_s",
            1.0,
            true,
        )?;
        if self.vrw_mps_sqrth.is_some() && self.vrw_ug_sqrthz.is_some() {
            return Err(
                "imu.vrw_ug_sqrthz: expected at most one of vrw_mps_sqrth and vrw_ug_sqrthz"
                    .to_string(),
            );
        }
        set(
            &mut a.white_noise_density,
            self.vrw_mps_sqrth,
            "vrw_mps_sqrth",
            PER_SQRTH,
            false,
        )?;
        set(
            &mut a.white_noise_density,
            self.vrw_ug_sqrthz,
            "vrw_ug_sqrthz",
            1e-6 * G0_MPS2,
            false,
        )?;
        set(
            &mut a.rate_random_walk,
            self.accel_rrw_mg_sqrth,
            "accel_rrw_mg_sqrth",
            MG * PER_SQRTH,
            false,
        )?;
        set(
            &mut a.scale_sigma,
            self.accel_scale_ppm,
            "accel_scale_ppm",
            1e-6,
            false,
        )?;
        set(
            &mut a.misalignment_sigma_rad,
            self.accel_misalignment_mrad,
            "accel_misalignment_mrad",
            1e-3,
            false,
        )?;
        set(
            &mut a.quantization,
            self.accel_quantization_mps,
            "accel_quantization_mps",
            1.0,
            false,
        )?;
        Ok(grade)
    }
}
