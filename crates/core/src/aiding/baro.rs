//! Barometric altitude with a bias state (REFERENCES \[ISA\] for the pressure-height
//! relation; the bias model as in PX4 EKF2's baro aid source and Groves §16.2).
//!
//! The barometer reads the pressure altitude h_baro of the sensor, which differs
//! from the ellipsoidal height by a slowly varying bias b (geoid, weather,
//! temperature): h_baro = h_sensor + b + v. With the sensor at lever arm l^b from
//! the IMU centre, h_sensor = h - (C_b^n l^b)_D. Errors are x_est - x_true
//! (state.rs): dr_D = D_est - D_true = -(h_est - h_true), d(C_b^n l^b) =
//! \[C_b^n l^b x\] phi, db = b_est - b_true, so
//!
//!   y = (h - (C_b^n l^b)_D + b)_INS - h_baro ~ -dr_D - (\[C_b^n l^b x\] phi)_D + db
//!   R = std²
//!
//! The bias is a random walk (`bias_random_walk`). It is unknown at the start: the
//! first reading sets it to h_baro - h_sensor,INS with the INS height variance plus
//! the reading's.

use super::source::{chi2_gate, AidingSource, Fuser, Handled};
use super::{AidingContext, Linearized, ReceiverClock};
use crate::attitude::skew;
use crate::config::NavConfig;
use crate::nav::ins_filter::{BlockProcess, BlockSpec};
use crate::state::{Block, ATT, POS};
use crate::types::Measurement;
use nalgebra::{DMatrix, DVector, Vector3};

/// The barometer bias block \[m\].
pub const BARO_BIAS: Block = Block::Source {
    name: "baro_bias",
    len: 1,
};

/// ISA troposphere (ICAO Doc 7488): sea-level temperature \[K\], lapse rate \[K/m\],
/// sea-level pressure \[Pa\], and the exponent R L / (g0 M).
const ISA_T0_K: f64 = 288.15;
const ISA_LAPSE_K_PER_M: f64 = 0.0065;
pub const ISA_P0_PA: f64 = 101_325.0;
const ISA_EXPONENT: f64 = 8.314_462_618 * ISA_LAPSE_K_PER_M / (9.806_65 * 0.028_964_4);

/// Pressure altitude \[m\] of pressure `p_pa` against the reference (sea-level)
/// pressure `p_ref_pa`: h = T0/L (1 - (p/p_ref)^(R L / g0 M)).
pub fn pressure_altitude_m(p_pa: f64, p_ref_pa: f64) -> f64 {
    ISA_T0_K / ISA_LAPSE_K_PER_M * (1.0 - (p_pa / p_ref_pa).powf(ISA_EXPONENT))
}

/// The pressure \[Pa\] at pressure altitude `h_m` (inverse of [`pressure_altitude_m`]).
pub fn pressure_at_altitude_pa(h_m: f64, p_ref_pa: f64) -> f64 {
    p_ref_pa * (1.0 - ISA_LAPSE_K_PER_M * h_m / ISA_T0_K).powf(1.0 / ISA_EXPONENT)
}

/// One barometer reading, on the IMU time scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaroSample {
    /// Time of validity \[s\] (the reader has removed the sensor's delay).
    pub t: f64,
    /// Pressure altitude \[m\].
    pub height_m: f64,
}

/// `\[baro\]` settings in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct BaroOptions {
    pub enabled: bool,
    /// Reading noise 1-sigma \[m\].
    pub std_m: f64,
    /// Random walk of the bias \[m/sqrt(s)\].
    pub bias_random_walk: f64,
    /// Innovation gate tail probability (None: ungated).
    pub gate_probability: Option<f64>,
    /// Sensor position from the IMU centre, IMU frame \[m\].
    pub lever_arm_b: Vector3<f64>,
}

impl Default for BaroOptions {
    fn default() -> Self {
        BaroOptions {
            enabled: false,
            std_m: 0.5,
            bias_random_walk: 0.02,
            gate_probability: Some(1e-4),
            lever_arm_b: Vector3::zeros(),
        }
    }
}

/// The measurement model (module doc); `bias_m`: the bias estimate.
pub fn linearize(
    ctx: &AidingContext,
    z: &BaroSample,
    bias_m: f64,
    lever_arm_b: &Vector3<f64>,
    std_m: f64,
) -> Linearized {
    let c_bn = ctx.nav.q_bn.to_rotation_matrix().into_inner();
    let l_n = c_bn * lever_arm_b;
    let mut h = DMatrix::zeros(1, ctx.layout.len());
    h[(0, POS + 2)] = -1.0;
    let s = skew(&l_n);
    for k in 0..3 {
        h[(0, ATT + k)] = -s[(2, k)];
    }
    if let Some(i) = ctx.layout.index(BARO_BIAS) {
        h[(0, i)] = 1.0;
    }
    let predicted = ctx.nav.lla.z - l_n.z + bias_m;
    Linearized {
        y: DVector::from_element(1, predicted - z.height_m),
        h,
        r: DMatrix::from_element(1, 1, std_m * std_m),
    }
}

/// The barometer as an aiding source (`\[baro\]`).
pub struct Barometer {
    opt: BaroOptions,
    bias_set: bool,
}

impl Barometer {
    /// None when no barometer is used.
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        cfg.baro.enabled.then(|| Barometer {
            opt: cfg.baro.clone(),
            bias_set: false,
        })
    }
}

impl AidingSource for Barometer {
    fn name(&self) -> &'static str {
        "baro"
    }

    fn blocks(&self) -> Vec<BlockSpec> {
        vec![BlockSpec {
            block: BARO_BIAS,
            initial_variance: vec![0.0],
            process: BlockProcess::RandomWalk(self.opt.bias_random_walk.powi(2)),
        }]
    }

    /// A bias never set (no reading) is no estimate: left out of the summary.
    fn finish(&self, _f: &Fuser, summary: &mut crate::events::RunSummary) {
        if !self.bias_set {
            summary.source_states.retain(|s| s.name != "baro_bias");
        }
    }

    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        let Measurement::Baro(z) = m else {
            return Handled::No;
        };
        if !z.height_m.is_finite() {
            return Handled::No;
        }
        let o = &self.opt;
        f.flush_covariance();
        if !self.bias_set {
            // The first reading sets the bias (module doc).
            let l = f.context(ReceiverClock::default());
            let lin = linearize(&l, z, 0.0, &o.lever_arm_b, o.std_m);
            let i = f.layout().index(BARO_BIAS).expect("baro layout");
            let var_d = f.covariance()[(POS + 2, POS + 2)];
            f.reset_state(i, var_d + o.std_m.powi(2));
            f.extra_mut(BARO_BIAS)[0] = -lin.y[0];
            self.bias_set = true;
            return Handled::Yes;
        }
        let bias = f.extra(BARO_BIAS)[0];
        let lin = linearize(
            &f.context(ReceiverClock::default()),
            z,
            bias,
            &o.lever_arm_b,
            o.std_m,
        );
        f.fuse_rows("baro", &lin, chi2_gate(1, o.gate_probability), true);
        Handled::Yes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aiding::tests::context_fixture;
    use crate::aiding::VehicleEstimate;
    use crate::attitude::quat_from_rotvec;
    use crate::earth::lla_add_ned;

    #[test]
    fn pressure_altitude_round_trip_and_isa_points() {
        assert!(pressure_altitude_m(ISA_P0_PA, ISA_P0_PA).abs() < 1e-9);
        // ISA: 89 874.6 Pa at 1000 m, 54 019.9 Pa at 5000 m.
        assert!((pressure_altitude_m(89_874.6, ISA_P0_PA) - 1000.0).abs() < 0.5);
        assert!((pressure_altitude_m(54_019.9, ISA_P0_PA) - 5000.0).abs() < 1.0);
        for h in [-300.0, 0.0, 850.0, 4321.0] {
            let p = pressure_at_altitude_pa(h, 100_900.0);
            assert!((pressure_altitude_m(p, 100_900.0) - h).abs() < 1e-6);
        }
    }

    fn ctx_of<'a>(
        nav: &'a crate::types::NavState,
        layout: &'a crate::state::StateLayout,
        vehicle: VehicleEstimate,
    ) -> AidingContext<'a> {
        AidingContext {
            nav,
            layout,
            w_ib_b: Vector3::zeros(),
            a_n: Vector3::zeros(),
            lever_arm_b: Vector3::zeros(),
            vehicle,
            clock: ReceiverClock::default(),
            gnss_bias_ned_m: Vector3::zeros(),
        }
    }

    /// Finite differences: h(x_true) - h(x_est) against H dx.
    #[test]
    fn jacobian_matches_finite_differences() {
        let mut fx = context_fixture(false);
        fx.nav.t = 0.0;
        let bias_i = fx.layout.push(BARO_BIAS);
        let lever = Vector3::new(0.3, -0.2, 0.15);
        let z = BaroSample {
            t: 0.0,
            height_m: 100.0,
        };
        let (bias_est, d_bias) = (2.0, 0.03);
        let est = linearize(
            &ctx_of(&fx.nav, &fx.layout, fx.vehicle),
            &z,
            bias_est,
            &lever,
            0.5,
        );
        let mut dx = DVector::zeros(fx.layout.len());
        dx[POS + 2] = 0.04;
        dx[ATT] = 2e-4;
        dx[ATT + 1] = -3e-4;
        dx[ATT + 2] = 1e-4;
        dx[bias_i] = d_bias;
        // The true state: est - dx (position NED, C_true = (I + phi x) C_est).
        let mut truth = fx.nav;
        truth.lla = lla_add_ned(&fx.nav.lla, &(-Vector3::new(0.0, 0.0, dx[POS + 2])));
        truth.q_bn =
            quat_from_rotvec(&Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2])) * fx.nav.q_bn;
        let tru = linearize(
            &ctx_of(&truth, &fx.layout, fx.vehicle),
            &z,
            bias_est - d_bias,
            &lever,
            0.5,
        );
        let dy = est.y[0] - tru.y[0];
        let hdx = (&est.h * &dx)[0];
        assert!((dy - hdx).abs() < 1e-6, "dy {dy} H dx {hdx}");
    }
}
