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
//! `tau = 1.89 T`) reaches that floor ([`crate::allan`]).

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};
use navfuse_core::types::ImuErrors;
use serde::Deserialize;

use crate::allan::gm_sigma_for_bias_instability;
use crate::random::{GaussMarkov, RandomWalk, Stream};

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
    /// Correlation time of the bias-instability Gauss-Markov process [s].
    pub bias_corr_time_s: f64,
    /// White noise density: ARW [rad/sqrt(s)] | VRW [m/s/sqrt(s)].
    pub white_noise_density: f64,
    /// Rate random walk `K` [rad/s/sqrt(s) | m/s²/sqrt(s)].
    pub rate_random_walk: f64,
    /// Scale-factor error sigma [-] (1e-6 = 1 ppm).
    pub scale_sigma: f64,
    /// Axis misalignment (non-orthogonality) sigma per off-diagonal term [rad].
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
    /// Output rate [Hz].
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

/// True sensor errors at one instant, SI (rad/s, m/s², -, -), as the navigator
/// estimates them ([`ImuErrors`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrueImuErrors {
    pub gyro_bias_rad_s: Vector3<f64>,
    pub accel_bias_mps2: Vector3<f64>,
    /// Scale-factor error [-] per axis (the diagonal of S).
    pub gyro_scale: Vector3<f64>,
    pub accel_scale: Vector3<f64>,
}

impl TrueImuErrors {
    /// The same in navfuse-core's type.
    pub fn to_core(&self) -> ImuErrors {
        ImuErrors {
            gyro_bias: self.gyro_bias_rad_s,
            accel_bias: self.accel_bias_mps2,
            gyro_scale: self.gyro_scale,
            accel_scale: self.accel_scale,
        }
    }

    /// KF-GINS `IMU_ERR` columns 2-13 (docs/FORMATS.md): gyro bias [deg/h], accel bias
    /// [mGal], gyro scale [ppm], accel scale [ppm].
    pub fn kf_gins_columns(&self) -> [f64; 12] {
        let mut out = [0.0; 12];
        for i in 0..3 {
            out[i] = self.gyro_bias_rad_s[i] / DEGPH;
            out[3 + i] = self.accel_bias_mps2[i] / 1e-5;
            out[6 + i] = self.gyro_scale[i] * 1e6;
            out[9 + i] = self.accel_scale[i] * 1e6;
        }
        out
    }
}

/// Time-varying errors of one triad and their random streams.
#[derive(Clone, Debug)]
struct Triad {
    matrix: Matrix3<f64>,
    scale: Vector3<f64>,
    turn_on: Vector3<f64>,
    gm: [GaussMarkov; 3],
    rrw: [RandomWalk; 3],
    white_density: f64,
    quantization: f64,
    residual: Vector3<f64>,
    gm_rng: Stream,
    rrw_rng: Stream,
    white_rng: Stream,
}

impl Triad {
    fn new(e: &SensorErrors, seed: u64, prefix: &str) -> Self {
        let mut turn_on_rng = Stream::new(seed, &format!("{prefix}.turn_on_bias"));
        let mut scale_rng = Stream::new(seed, &format!("{prefix}.scale"));
        let mut mis_rng = Stream::new(seed, &format!("{prefix}.misalignment"));
        let mut gm_rng = Stream::new(seed, &format!("{prefix}.bias_instability"));
        let turn_on = Vector3::from_fn(|_, _| e.turn_on_bias_sigma * turn_on_rng.normal());
        let scale = Vector3::from_fn(|_, _| e.scale_sigma * scale_rng.normal());
        let mut matrix = Matrix3::identity() + Matrix3::from_diagonal(&scale);
        for (r, c) in [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)] {
            matrix[(r, c)] = e.misalignment_sigma_rad * mis_rng.normal();
        }
        let s = e.gm_sigma();
        let t = e.bias_corr_time_s;
        let gm = [
            GaussMarkov::new(s, t, &mut gm_rng),
            GaussMarkov::new(s, t, &mut gm_rng),
            GaussMarkov::new(s, t, &mut gm_rng),
        ];
        let q = e.rate_random_walk * e.rate_random_walk;
        Self {
            matrix,
            scale,
            turn_on,
            gm,
            rrw: [
                RandomWalk::new(q, 0.0),
                RandomWalk::new(q, 0.0),
                RandomWalk::new(q, 0.0),
            ],
            white_density: e.white_noise_density,
            quantization: e.quantization,
            residual: Vector3::zeros(),
            gm_rng,
            rrw_rng: Stream::new(seed, &format!("{prefix}.rate_random_walk")),
            white_rng: Stream::new(seed, &format!("{prefix}.white_noise")),
        }
    }

    #[inline]
    fn bias(&self) -> Vector3<f64> {
        Vector3::new(
            self.turn_on[0] + self.gm[0].value() + self.rrw[0].value(),
            self.turn_on[1] + self.gm[1].value() + self.rrw[1].value(),
            self.turn_on[2] + self.gm[2].value() + self.rrw[2].value(),
        )
    }

    #[inline]
    fn apply(&mut self, dt_s: f64, truth: &Vector3<f64>) -> Vector3<f64> {
        let mut out = self.matrix * truth + self.bias() * dt_s;
        if self.white_density > 0.0 {
            let s = self.white_density * dt_s.sqrt();
            for i in 0..3 {
                out[i] += s * self.white_rng.normal();
            }
        }
        for i in 0..3 {
            self.gm[i].step(dt_s, &mut self.gm_rng);
            self.rrw[i].step(dt_s, &mut self.rrw_rng);
        }
        if self.quantization > 0.0 {
            out = quantize(&out, self.quantization, &mut self.residual);
        }
        out
    }
}

/// Quantise to multiples of `lsb`, carrying the remainder to the next sample so the
/// running sum of the output never differs from the running sum of the input by
/// more than `lsb / 2` (no bias of the mean).
pub fn quantize(v: &Vector3<f64>, lsb: f64, residual: &mut Vector3<f64>) -> Vector3<f64> {
    let mut out = Vector3::zeros();
    for i in 0..3 {
        let want = v[i] + residual[i];
        out[i] = (want / lsb).round() * lsb;
        residual[i] = want - out[i];
    }
    out
}

/// A grade turned into one random realisation (see the module documentation).
#[derive(Clone, Debug)]
pub struct ImuErrorModel {
    gyro: Triad,
    accel: Triad,
}

impl ImuErrorModel {
    /// Draws turn-on biases, scale factors and misalignments from streams named
    /// `imu.gyro.*` / `imu.accel.*` of scenario seed `rng_seed`.
    pub fn new(grade: &ImuGrade, rng_seed: u64) -> Self {
        Self {
            gyro: Triad::new(&grade.gyro, rng_seed, "imu.gyro"),
            accel: Triad::new(&grade.accel, rng_seed, "imu.accel"),
        }
    }

    /// Measured (angle, velocity) increments of one interval of `dt_s` from the true
    /// ones; advances the time-varying errors by `dt_s`.
    #[inline]
    pub fn apply(
        &mut self,
        dt_s: f64,
        dtheta_true: &Vector3<f64>,
        dvel_true: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        (
            self.gyro.apply(dt_s, dtheta_true),
            self.accel.apply(dt_s, dvel_true),
        )
    }

    /// Biases (for the next interval) and scale-factor errors now.
    pub fn current_errors(&self) -> TrueImuErrors {
        TrueImuErrors {
            gyro_bias_rad_s: self.gyro.bias(),
            accel_bias_mps2: self.accel.bias(),
            gyro_scale: self.gyro.scale,
            accel_scale: self.accel.scale,
        }
    }

    /// `I + S + M` of the gyros (measured = matrix * true + ...).
    pub fn gyro_matrix(&self) -> Matrix3<f64> {
        self.gyro.matrix
    }

    /// `I + S + M` of the accelerometers.
    pub fn accel_matrix(&self) -> Matrix3<f64> {
        self.accel.matrix
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_residual_carry_keeps_the_sum() {
        let lsb = 1e-3;
        let mut res = Vector3::zeros();
        let v = Vector3::new(0.2e-3, -0.37e-3, 1.26e-3);
        let (mut sum_in, mut sum_out) = (Vector3::zeros(), Vector3::zeros());
        for _ in 0..10_000 {
            let q = quantize(&v, lsb, &mut res);
            for i in 0..3 {
                let steps = q[i] / lsb;
                assert!((steps - steps.round()).abs() < 1e-9);
            }
            sum_in += v;
            sum_out += q;
            // |carried residual| <= lsb/2; 1e-9 covers the f64 rounding of the sums.
            assert!(res.amax() <= 0.5 * lsb * (1.0 + 1e-9));
            assert!((sum_in - sum_out).amax() <= 0.5 * lsb + 1e-9);
        }
        // Without the carry, 0.2e-3 would always round to 0: the mean would be lost.
        assert!((sum_out[0] / 10_000.0 - 0.2e-3).abs() < 1e-7);
        assert!((sum_out[1] / 10_000.0 + 0.37e-3).abs() < 1e-7);
    }

    #[test]
    fn quantised_model_output_is_on_the_grid_and_unbiased() {
        let spec = ImuSpec {
            grade: "custom".into(),
            gyro_quantization_rad: Some(1e-6),
            accel_quantization_mps: Some(1e-4),
            ..Default::default()
        };
        let mut m = ImuErrorModel::new(&spec.to_grade().unwrap(), 1);
        let true_dth = Vector3::new(3.3e-7, 0.0, -1.7e-6);
        let true_dv = Vector3::new(0.098, 0.0, -2.5e-5);
        let (mut s_th, mut s_v) = (Vector3::zeros(), Vector3::zeros());
        for _ in 0..1000 {
            let (dth, dv) = m.apply(0.01, &true_dth, &true_dv);
            assert!(dth
                .iter()
                .all(|x| ((x / 1e-6) - (x / 1e-6).round()).abs() < 1e-6));
            assert!(dv
                .iter()
                .all(|x| ((x / 1e-4) - (x / 1e-4).round()).abs() < 1e-6));
            s_th += dth;
            s_v += dv;
        }
        assert!((s_th - true_dth * 1000.0).amax() <= 0.5e-6 + 1e-15);
        assert!((s_v - true_dv * 1000.0).amax() <= 0.5e-4 + 1e-12);
    }

    #[test]
    fn perfect_grade_is_identity() {
        let grade = ImuSpec::default().to_grade().unwrap();
        let mut m = ImuErrorModel::new(&grade, 7);
        let th = Vector3::new(1e-3, -2e-3, 3e-3);
        let v = Vector3::new(0.1, 0.2, -0.098);
        for _ in 0..100 {
            assert_eq!(m.apply(0.005, &th, &v), (th, v));
        }
        assert_eq!(m.current_errors(), TrueImuErrors::default());
    }

    #[test]
    fn deterministic_and_scale_misalignment_applied() {
        let spec = ImuSpec {
            grade: "consumer".into(),
            ..Default::default()
        };
        let grade = spec.to_grade().unwrap();
        let mut a = ImuErrorModel::new(&grade, 42);
        let mut b = ImuErrorModel::new(&grade, 42);
        let c = ImuErrorModel::new(&grade, 43);
        let th = Vector3::new(0.01, 0.0, 0.0);
        let v = Vector3::new(0.0, 0.0, -0.098);
        for _ in 0..100 {
            assert_eq!(a.apply(0.01, &th, &v), b.apply(0.01, &th, &v));
        }
        assert_ne!(a.gyro_matrix(), c.gyro_matrix());
        let m = a.gyro_matrix();
        let e = a.current_errors();
        for i in 0..3 {
            assert!((m[(i, i)] - 1.0 - e.gyro_scale[i]).abs() < 1e-15);
        }
        assert!(m[(0, 1)] != 0.0 && m[(2, 0)] != 0.0);
    }

    #[test]
    fn turn_on_bias_statistics() {
        // Across seeds, the turn-on gyro bias has the configured sigma (HG1700 1 deg/h).
        let grade = preset("hg1700").unwrap();
        let n = 4000;
        let mut s2 = 0.0;
        for seed in 0..n {
            let b = ImuErrorModel::new(&grade, seed)
                .current_errors()
                .gyro_bias_rad_s;
            s2 += b.norm_squared() / 3.0;
        }
        let sigma = (s2 / n as f64).sqrt();
        // 12 000 draws: 0.65 % standard error.
        assert!(
            (sigma / DEGPH - 1.0).abs() < 0.03,
            "sigma {} deg/h",
            sigma / DEGPH
        );
    }

    #[test]
    fn kf_gins_units() {
        let e = TrueImuErrors {
            gyro_bias_rad_s: Vector3::new(DEGPH, 0.0, 0.0),
            accel_bias_mps2: Vector3::new(0.0, 1e-5, 0.0),
            gyro_scale: Vector3::new(0.0, 0.0, 1e-6),
            accel_scale: Vector3::new(2e-6, 0.0, 0.0),
        };
        let c = e.kf_gins_columns();
        assert!((c[0] - 1.0).abs() < 1e-12);
        assert!((c[4] - 1.0).abs() < 1e-9);
        assert!((c[8] - 1.0).abs() < 1e-9);
        assert!((c[9] - 2.0).abs() < 1e-9);
        assert_eq!(e.to_core().gyro_bias, e.gyro_bias_rad_s);
    }

    #[test]
    fn spec_parses_and_converts_units() {
        let spec: ImuSpec = toml::from_str(
            "grade = \"imu500\"\nrate_hz = 100\noutput = \"rates\"\n\
             arw_deg_sqrth = 0.6\nvrw_ug_sqrthz = 50\ngyro_scale_ppm = 300\n\
             accel_bias_mg = 2\ngyro_misalignment_mrad = 0.5\ngyro_corr_time_s = inf",
        )
        .unwrap();
        assert_eq!(spec.output, ImuOutput::Rates);
        let g = spec.to_grade().unwrap();
        assert!((g.gyro.white_noise_density - 0.6 * DEG / 60.0).abs() < 1e-15);
        assert!((g.accel.white_noise_density - 50e-6 * G0_MPS2).abs() < 1e-15);
        assert!((g.gyro.scale_sigma - 300e-6).abs() < 1e-15);
        assert!((g.accel.turn_on_bias_sigma - 2.0 * MG).abs() < 1e-15);
        assert!((g.gyro.misalignment_sigma_rad - 5e-4).abs() < 1e-15);
        assert!(g.gyro.bias_corr_time_s.is_infinite());
        // Untouched preset values stay.
        assert!((g.gyro.bias_instability - 0.1 * DEGPH).abs() < 1e-18);
        let d: ImuSpec = toml::from_str("").unwrap();
        assert_eq!(d, ImuSpec::default());
        assert_eq!(d.rate_hz, 200.0);
        assert_eq!(d.output, ImuOutput::Increments);
    }

    #[test]
    fn spec_errors_name_the_key() {
        let bad = |s: &str| ImuSpec {
            grade: s.to_string(),
            ..Default::default()
        };
        let e = bad("hg1800").to_grade().unwrap_err();
        assert!(e.contains("imu.grade") && e.contains("hg1700"), "{e}");
        let e = ImuSpec {
            arw_deg_sqrth: Some(-0.1),
            ..Default::default()
        }
        .to_grade()
        .unwrap_err();
        assert!(e.contains("imu.arw_deg_sqrth") && e.contains(">= 0"), "{e}");
        let e = ImuSpec {
            accel_bias_mg: Some(f64::NAN),
            ..Default::default()
        }
        .to_grade()
        .unwrap_err();
        assert!(
            e.contains("imu.accel_bias_mg") && e.contains("finite"),
            "{e}"
        );
        let e = ImuSpec {
            accel_bias_instability_mg: Some(f64::INFINITY),
            ..Default::default()
        }
        .to_grade()
        .unwrap_err();
        assert!(e.contains("imu.accel_bias_instability_mg"), "{e}");
        let e = ImuSpec {
            gyro_corr_time_s: Some(0.0),
            ..Default::default()
        }
        .to_grade()
        .unwrap_err();
        assert!(
            e.contains("imu.gyro_corr_time_s") && e.contains("> 0"),
            "{e}"
        );
        let e = ImuSpec {
            rate_hz: 0.0,
            ..Default::default()
        }
        .to_grade()
        .unwrap_err();
        assert!(e.contains("imu.rate_hz"), "{e}");
        let e = ImuSpec {
            vrw_mps_sqrth: Some(0.1),
            vrw_ug_sqrthz: Some(20.0),
            ..Default::default()
        }
        .to_grade()
        .unwrap_err();
        assert!(
            e.contains("vrw_mps_sqrth") && e.contains("vrw_ug_sqrthz"),
            "{e}"
        );
        // Unknown keys are rejected by serde (the loader adds file/line).
        let r: Result<ImuSpec, _> = toml::from_str("grade = \"perfect\"\narw = 1.0");
        assert!(r.unwrap_err().to_string().contains("arw"));
    }

    #[test]
    fn every_preset_converts() {
        for name in PRESET_NAMES {
            let g = ImuSpec {
                grade: name.to_string(),
                ..Default::default()
            }
            .to_grade()
            .unwrap();
            assert_eq!(g.name, name);
        }
    }
}
