//! Zero-velocity (ZUPT) and zero-angular-rate (ZARU) updates while the vehicle is
//! static (static detector: static_detect.rs).
//!
//!   ZUPT: y = v^n_INS - 0 ~ dv,                       R = std² I
//!   ZARU: y = w_ib^b,mean - C_n^b w_ie^n ~ db_g + diag(w) ds_g,   R = std² I
//!         (compensated rate w = w_true + db_g + diag(w) ds_g with the IMU error states
//!         true - estimate; static: w_true = w_ie^b)

use super::{AidingContext, Linearized};
use crate::earth::omega_ie_n;
use crate::state::{BG, SG, VEL};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

pub fn linearize_zupt(ctx: &AidingContext, std_mps: f64) -> Linearized {
    let mut h = DMatrix::zeros(3, ctx.layout.len());
    h.view_mut((0, VEL), (3, 3)).copy_from(&Matrix3::identity());
    Linearized {
        y: DVector::from_column_slice(ctx.nav.v_n.as_slice()),
        h,
        r: DMatrix::from_diagonal_element(3, 3, std_mps.powi(2)),
    }
}

/// `w_ib_b_mean`: compensated angular rate averaged over the static window \[rad/s\].
pub fn linearize_zaru(ctx: &AidingContext, w_ib_b_mean: &Vector3<f64>, std: f64) -> Linearized {
    let c_nb = ctx.nav.q_bn.to_rotation_matrix().into_inner().transpose();
    let y = w_ib_b_mean - c_nb * omega_ie_n(ctx.nav.lla.x);
    let mut h = DMatrix::zeros(3, ctx.layout.len());
    h.view_mut((0, BG), (3, 3)).copy_from(&Matrix3::identity());
    h.view_mut((0, SG), (3, 3))
        .copy_from(&Matrix3::from_diagonal(w_ib_b_mean));
    Linearized {
        y: DVector::from_column_slice(y.as_slice()),
        h,
        r: DMatrix::from_diagonal_element(3, 3, std.powi(2)),
    }
}

// ---------------------------------------------------------------------------------
// Policy: the static detector over `window_s` of IMU data, vetoed when the odometer
// or a recent GNSS fix saw motion, the INS is fast, or its own mechanization
// accelerates (smooth braking looks static); then ZUPT (and ZARU) at `rate_hz`. A
// ZUPT refused by its innovation test ends the static state until the detector
// lets go.

use super::source::{chi2_gate, AidingSource, Fuser, Handled};
use super::Aiding;
use crate::config::{NavConfig, ZuptOptions};
use crate::events::Event;
use crate::static_detect::{mean_horizontal_accel, mean_speed, StaticDetector, Window};
use crate::types::{ImuSample, Measurement};

/// Zero-velocity / zero-angular-rate updates as an aiding source (`\[zupt\]`).
pub struct Zupt {
    opt: ZuptOptions,
    odometer_enabled: bool,
    /// The largest gyro white-noise density \[rad/s/sqrt(s)\] (ZARU std floor).
    arw_max: f64,
    detector: StaticDetector,
    /// The last ZUPT was refused by its innovation test (not static meanwhile).
    refused: bool,
    /// Odometer speeds over the detection window (IMU time).
    odo_speeds: Window<f64>,
    /// The mechanization's own velocity sum, sampled after each IMU sample.
    mech_dv_window: Window<Vector3<f64>>,
    /// Last time a GNSS fix reported a speed above `max_speed_mps` (GNSS time; None:
    /// none yet).
    gnss_moving_t: Option<f64>,
    next_t: f64,
}

impl Zupt {
    /// None when ZUPT is off; `t0`: the start time (IMU time).
    pub fn from_config(cfg: &NavConfig, t0: f64) -> Option<Self> {
        let z = &cfg.zupt;
        z.enabled.then(|| Zupt {
            opt: z.clone(),
            odometer_enabled: cfg.odometer.enabled,
            arw_max: cfg.imu_noise.arw.max(),
            detector: StaticDetector::new(z.window_s),
            refused: false,
            odo_speeds: Window::new(z.window_s),
            mech_dv_window: Window::new(z.window_s),
            gnss_moving_t: None,
            next_t: t0,
        })
    }
}

impl AidingSource for Zupt {
    fn name(&self) -> &'static str {
        "zupt"
    }

    /// Watches the odometer and the GNSS speed for the motion vetoes (fuses nothing).
    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        self.odo_speeds.set_direction(f.direction());
        match m {
            Measurement::Odometer(o) => self.odo_speeds.push(f.nav().t, o.speed_mps),
            Measurement::Gnss(fix)
                if fix
                    .vel_ned
                    .is_some_and(|v| v.norm() > self.opt.max_speed_mps) =>
            {
                self.gnss_moving_t = Some(fix.t);
            }
            _ => {}
        }
        Handled::No
    }

    /// Backward the piece is time-reversed (dt < 0): the detector takes it so.
    fn on_propagate(&mut self, s: &ImuSample, _f: &mut Fuser) {
        if s.dt != 0.0 {
            self.detector
                .push(s.t, s.dt, &(s.dvel / s.dt), &(s.dtheta / s.dt));
        }
    }

    fn on_imu_gap(&mut self) {
        self.detector.clear();
    }

    fn after_imu(&mut self, f: &mut Fuser) {
        let t = f.nav().t;
        let z = &self.opt;
        // Elapsed times and cadence along the run (a backward run goes down in time).
        let dir = f.direction();
        self.odo_speeds.set_direction(dir);
        self.mech_dv_window.set_direction(dir);
        self.mech_dv_window.push(t, f.mech_dv_n());
        let odo_still = !self.odometer_enabled
            || mean_speed(&self.odo_speeds, t).is_none_or(|v| v.abs() <= z.odometer_still_mps);
        let gnss_still = self
            .gnss_moving_t
            .is_none_or(|tm| dir.elapsed(tm, f.time_gnss()) > 2.0);
        let slow = f.nav().v_n.norm() < z.max_speed_mps;
        let steady = mean_horizontal_accel(&self.mech_dv_window, z.window_s)
            .is_none_or(|a| a <= z.max_accel_mps2);
        let mut w = self
            .detector
            .static_mean_rate(z.accel_std_max, z.gyro_max)
            .filter(|_| odo_still && gnss_still && slow && steady);
        match w {
            None => self.refused = false,
            Some(rate) if dir.reached(t, self.next_t, 1e-9) => {
                let dt = 1.0 / z.rate_hz;
                self.next_t = dir.advance(t, dt);
                let gate = chi2_gate(3, z.gate_probability);
                let fused = f.fuse(Aiding::Zupt(z.velocity_std_mps), gate);
                // The INS disagrees with a standstill: not static until it agrees.
                self.refused = !fused.applied();
                if !self.refused {
                    f.record().static_s += dt;
                    if z.angular_rate_std > 0.0 {
                        // The window mean carries the gyro's white noise, ARW/sqrt(T).
                        let std = z.angular_rate_std.max(self.arw_max / z.window_s.sqrt());
                        f.fuse(Aiding::Zaru(rate, std), gate);
                    }
                }
            }
            Some(_) => {}
        }
        if self.refused {
            w = None;
        }
        if w.is_some() != f.shared_ref().is_static {
            f.shared().is_static = w.is_some();
            let t_gnss = f.time_gnss();
            f.push_event(Event::Static {
                t: t_gnss,
                begins: w.is_some(),
            });
        }
    }
}
