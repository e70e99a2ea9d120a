//! The per-run IMU error model: turn-on biases, Gauss-Markov bias instability, rate
//! random walk, scale factor and misalignment, white noise and quantisation.

use nalgebra::{Matrix3, Vector3};
use navfuse_core::types::ImuErrors;

use super::{ImuGrade, SensorErrors, DEGPH};
use crate::random::{GaussMarkov, RandomWalk, Stream};

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
    /// \[mGal\], gyro scale \[ppm\], accel scale \[ppm\].
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
pub(super) struct Triad {
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
pub(crate) fn quantize(v: &Vector3<f64>, lsb: f64, residual: &mut Vector3<f64>) -> Vector3<f64> {
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
