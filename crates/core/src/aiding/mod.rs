//! Aiding sources. `source.rs` is the seam (the `AidingSource` trait and the
//! `Fuser` handed to it), `registry.rs` THE list of sources. Each source's file holds
//! its measurement model, its policy and its state: `gnss_loose`, `gnss_six_state`,
//! `tight`, `zupt`, `nhc`, `odometer`, `heading`; `gnss_integrity` is the spoofing
//! monitor the GNSS sources share. The pure models the GNSS sources use are
//! `gnss_position`, `gnss_velocity`, `pseudorange`, `doppler`, `tdcp`;
//! `vehicle_frame` is shared kinematics (the vehicle reference point's velocity) for
//! the NHC and the odometer. [`Aiding`] names the built-in models; a source of your
//! own linearises itself and fuses with `Fuser::fuse_rows`.

pub mod adaptive;
pub mod baro;
pub mod doppler;
#[cfg(test)]
mod epoch_tests;
pub mod gnss_integrity;
pub mod gnss_loose;
pub mod gnss_position;
pub mod gnss_six_state;
pub mod gnss_velocity;
pub mod heading;
pub mod nhc;
pub mod odometer;
pub mod pseudorange;
pub mod registry;
pub mod source;
pub mod tdcp;
pub mod tight;
#[cfg(test)]
mod tight_tests;
pub mod vehicle_frame;
pub mod zupt;

use crate::state::StateLayout;
use crate::types::{GnssFix, HeadingObs, NavState, SatMeasurement};
use heading::HeadingAxis;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Current estimates of the vehicle installation (SYSTEM.md §4b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleEstimate {
    /// C_b^m: IMU frame to vehicle frame (nominal mounting corrected by the filter).
    pub c_bm: Matrix3<f64>,
    /// Lever arm IMU centre -> vehicle reference point, IMU frame \[m\].
    pub lever_arm_b: Vector3<f64>,
    /// Odometer scale estimate k (true = (1 + k) measured).
    pub odometer_scale: f64,
}

/// Receiver clock estimates (tight coupling; zero otherwise).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReceiverClock {
    /// c dt_r \[m\] (GPS time).
    pub bias_m: f64,
    /// c dt_r' \[m/s\].
    pub drift_mps: f64,
    /// Inter-system biases c (dt_sys - dt_GPS) \[m\] by `System::index` (zero for
    /// GPS, QZSS, SBAS and the systems not estimated; pseudorange.rs).
    pub isb_m: [f64; crate::sat::System::ALL.len()],
}

impl ReceiverClock {
    /// The clock bias a pseudorange of `system` sees, b + ISB_sys \[m\].
    pub fn bias_for(&self, system: crate::sat::System) -> f64 {
        self.bias_m + self.isb_m[system.index()]
    }
}

/// What the aiding models may read about the current INS solution.
pub struct AidingContext<'a> {
    pub nav: &'a NavState,
    pub layout: &'a StateLayout,
    /// Compensated angular rate w_ib^b over the last IMU interval \[rad/s\].
    pub w_ib_b: Vector3<f64>,
    /// Acceleration d(v^n)/dt over the last IMU interval \[m/s²\].
    pub a_n: Vector3<f64>,
    /// Antenna lever arm in the body frame \[m\].
    pub lever_arm_b: Vector3<f64>,
    pub vehicle: VehicleEstimate,
    pub clock: ReceiverClock,
    /// Estimated time-correlated error of the GNSS fixes, NED \[m\] (zero without the
    /// `GnssBias` block).
    pub gnss_bias_ned_m: Vector3<f64>,
}

/// A linearised measurement: innovation y = h(x_est) - z ~ H dx + v, v ~ N(0, R).
#[derive(Clone, Debug)]
pub struct Linearized {
    pub y: DVector<f64>,
    pub h: DMatrix<f64>,
    pub r: DMatrix<f64>,
}

/// Every measurement the navigator can fuse.
#[derive(Clone, Copy, Debug)]
pub enum Aiding<'a> {
    GnssPosition(&'a GnssFix),
    GnssVelocity(&'a GnssFix),
    /// Dual-antenna heading or course over ground.
    Heading(&'a HeadingObs, HeadingAxis),
    /// Non-holonomic constraint with lateral/vertical std \[m/s\].
    Nhc([f64; 2]),
    /// Measured odometer speed \[m/s\], its error model (odometer.rs: the std and the
    /// calibration threshold apply to the speed predicted from the state), optional
    /// NHC rows (seed 004's 3-row form).
    Odometer {
        speed_mps: f64,
        noise: odometer::OdometerNoise,
        nhc_std: Option<[f64; 2]>,
    },
    /// Zero velocity, std \[m/s\].
    Zupt(f64),
    /// Zero angular rate: window-mean compensated rate \[rad/s\], std \[rad/s\].
    Zaru(Vector3<f64>, f64),
    /// Tight coupling, one satellite: pseudorange.
    Pseudorange(&'a SatMeasurement),
    /// Tight coupling, one satellite: Doppler range rate.
    Doppler(&'a SatMeasurement),
    /// Tight coupling, one satellite: carrier phase differenced with the previous epoch.
    Tdcp(&'a SatMeasurement, tdcp::TdcpPrevious, tdcp::Interval),
}

impl Aiding<'_> {
    /// Short name used in logs and summaries.
    pub fn name(&self) -> &'static str {
        match self {
            Aiding::GnssPosition(_) => "gnss_position",
            Aiding::GnssVelocity(_) => "gnss_velocity",
            Aiding::Heading(_, HeadingAxis::Body(_)) => "dual_antenna_heading",
            Aiding::Heading(_, HeadingAxis::VehicleForward) => "course_over_ground",
            Aiding::Nhc(_) => "nhc",
            Aiding::Odometer { .. } => "odometer",
            Aiding::Zupt(_) => "zupt",
            Aiding::Zaru(..) => "zaru",
            Aiding::Pseudorange(_) => "pseudorange",
            Aiding::Doppler(_) => "doppler",
            Aiding::Tdcp(..) => "tdcp",
        }
    }

    /// Whether a rejection by the gate is also logged as an event (the external
    /// measurements and the standstill updates; not the constraints and the
    /// per-satellite rows, which are many).
    pub fn logs_rejections(&self) -> bool {
        matches!(
            self,
            Aiding::GnssPosition(_)
                | Aiding::GnssVelocity(_)
                | Aiding::Heading(..)
                | Aiding::Zupt(_)
                | Aiding::Zaru(..)
        )
    }

    /// Whether the prediction holds more than the state: a quantity fixed at the
    /// start of the epoch (TDCP: the INS displacement since the previous epoch, and
    /// the lever arm at the epoch's attitude), which a feedback does not move. Such
    /// rows, fused one after another and each re-linearised, would apply the same
    /// correction again (issue 30: the INS velocity corrected once per satellite);
    /// they are fused together, linearised at the state before any of them
    /// ([`source::Fuser::fuse_epoch`]). Pseudorange and Doppler predict from the
    /// state alone (position, velocity, attitude, clock), so their rows may be fused
    /// one at a time, each re-linearised at the state the previous left.
    pub fn epoch_fixed(&self) -> bool {
        matches!(self, Aiding::Tdcp(..))
    }

    /// The measurement model; None when the measurement has nothing to offer
    /// (e.g. a fix without velocity).
    pub fn linearize(&self, ctx: &AidingContext) -> Option<Linearized> {
        match self {
            Aiding::GnssPosition(fix) => Some(gnss_position::linearize(ctx, fix)),
            Aiding::GnssVelocity(fix) => gnss_velocity::linearize(ctx, fix),
            Aiding::Heading(obs, axis) => heading::linearize(ctx, obs, *axis),
            Aiding::Nhc(std) => Some(nhc::linearize(ctx, *std)),
            Aiding::Odometer {
                speed_mps,
                noise,
                nhc_std,
            } => Some(odometer::linearize(ctx, *speed_mps, noise, *nhc_std)),
            Aiding::Zupt(std) => Some(zupt::linearize_zupt(ctx, *std)),
            Aiding::Zaru(w, std) => Some(zupt::linearize_zaru(ctx, w, *std)),
            Aiding::Pseudorange(sat) => pseudorange::linearize(ctx, sat),
            Aiding::Doppler(sat) => doppler::linearize(ctx, sat),
            Aiding::Tdcp(sat, prev, iv) => tdcp::linearize(ctx, sat, prev, iv),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    //! Finite-difference checks of the aiding Jacobians: perturb the true state by a
    //! small error dx with the conventions of state.rs and compare h(x + dx) - h(x)
    //! with H dx.
    use super::*;
    use crate::attitude::{q_bn_from_euler, quat_from_rotvec};
    use crate::earth::lla_add_ned;
    use crate::state::{Block, StateLayout, ATT, BG, POS, SG, VEL};
    use crate::types::HeadingObs;

    pub struct Fixture {
        pub nav: NavState,
        pub layout: StateLayout,
        pub w_ib_b: Vector3<f64>,
        pub vehicle: VehicleEstimate,
    }

    pub fn context_fixture(vehicle_states: bool) -> Fixture {
        let mut layout = StateLayout::ins21();
        if vehicle_states {
            layout.push(Block::OdometerScale);
            layout.push(Block::Mounting);
            layout.push(Block::ClockBias);
            layout.push(Block::ClockDrift);
        }
        Fixture {
            nav: NavState {
                t: 0.0,
                lla: Vector3::new(0.7, 1.9, 120.0),
                v_n: Vector3::new(8.0, -5.0, 0.3),
                q_bn: q_bn_from_euler(&Vector3::new(0.03, -0.05, 2.4)),
            },
            layout,
            w_ib_b: Vector3::new(0.02, -0.01, 0.15),
            vehicle: VehicleEstimate {
                c_bm: crate::attitude::c_bn_from_euler(&Vector3::new(0.01, 0.02, -0.03)),
                lever_arm_b: Vector3::new(-0.8, 0.3, 0.4),
                odometer_scale: 0.003,
            },
        }
    }

    fn ctx<'a>(
        f: &'a Fixture,
        nav: &'a NavState,
        w: Vector3<f64>,
        v: (VehicleEstimate, ReceiverClock),
    ) -> AidingContext<'a> {
        AidingContext {
            nav,
            layout: &f.layout,
            w_ib_b: w,
            a_n: Vector3::zeros(),
            lever_arm_b: Vector3::new(0.5, 0.1, -1.0),
            vehicle: v.0,
            clock: v.1,
            gnss_bias_ned_m: Vector3::zeros(),
        }
    }

    const FIXTURE_CLOCK: ReceiverClock = ReceiverClock {
        bias_m: 1234.5,
        drift_mps: -3.2,
        isb_m: [0.0, -4.0, 7.0, 11.0, 0.0, 0.0, 2.0],
    };

    /// Apply an error dx to the true state (state.rs conventions; the IMU error states
    /// are true - estimate, so the compensated rate is w + db_g + diag(w) ds_g).
    fn inject(
        f: &Fixture,
        dx: &DVector<f64>,
    ) -> (NavState, Vector3<f64>, (VehicleEstimate, ReceiverClock)) {
        let v3 = |i: usize| Vector3::new(dx[i], dx[i + 1], dx[i + 2]);
        let mut nav = f.nav;
        nav.lla = lla_add_ned(&f.nav.lla, &v3(POS));
        nav.v_n += v3(VEL);
        nav.q_bn = quat_from_rotvec(&(-v3(ATT))) * f.nav.q_bn;
        let w = f.w_ib_b + v3(BG) + f.w_ib_b.component_mul(&v3(SG));
        let mut veh = f.vehicle;
        if let Some(i) = f.layout.index(Block::OdometerScale) {
            veh.odometer_scale += dx[i];
        }
        if let Some(i) = f.layout.index(Block::Mounting) {
            let da = Vector3::new(0.0, dx[i], dx[i + 1]);
            veh.c_bm = quat_from_rotvec(&(-da)).to_rotation_matrix().into_inner() * veh.c_bm;
        }
        let mut clock = FIXTURE_CLOCK;
        if let Some(i) = f.layout.index(Block::ClockBias) {
            clock.bias_m += dx[i];
        }
        if let Some(i) = f.layout.index(Block::ClockDrift) {
            clock.drift_mps += dx[i];
        }
        for s in crate::sat::System::ALL {
            if let Some(i) = pseudorange::isb_block(s).and_then(|b| f.layout.index(b)) {
                clock.isb_m[s.index()] += dx[i];
            }
        }
        (nav, w, (veh, clock))
    }

    /// Check column by column that `model`'s Jacobian matches finite differences.
    pub fn numeric_jacobian_check(
        f: &Fixture,
        model: impl Fn(&AidingContext) -> (Vector3<f64>, DMatrix<f64>),
        eps: f64,
    ) {
        let (h0, jac) = model(&ctx(f, &f.nav, f.w_ib_b, (f.vehicle, FIXTURE_CLOCK)));
        let n = f.layout.len();
        for j in 0..n {
            let mut dx = DVector::zeros(n);
            dx[j] = eps;
            let (nav, w, veh) = inject(f, &dx);
            let (h1, _) = model(&ctx(f, &nav, w, veh));
            let num = (h1 - h0) / eps;
            for i in 0..3 {
                let tol = 1e-4 * (1.0 + jac[(i, j)].abs());
                assert!(
                    (num[i] - jac[(i, j)]).abs() < tol,
                    "row {i} col {j}: numeric {} analytic {}",
                    num[i],
                    jac[(i, j)]
                );
            }
        }
    }

    /// Linearized models checked the same way; `make` builds the measurement from the
    /// (perturbed) compensated rate, for ZARU whose input is that rate.
    fn check_linearized<'a>(f: &Fixture, eps: f64, make: impl Fn(Vector3<f64>) -> Aiding<'a>) {
        let c0 = ctx(f, &f.nav, f.w_ib_b, (f.vehicle, FIXTURE_CLOCK));
        let aiding = make(f.w_ib_b);
        let l0 = aiding.linearize(&c0).unwrap();
        let n = f.layout.len();
        for j in 0..n {
            let mut dx = DVector::zeros(n);
            dx[j] = eps;
            let (nav, w, veh) = inject(f, &dx);
            let l1 = make(w).linearize(&ctx(f, &nav, w, veh)).unwrap();
            for i in 0..l0.y.len() {
                let num = (l1.y[i] - l0.y[i]) / eps;
                let tol = 1e-4 * (1.0 + l0.h[(i, j)].abs());
                assert!(
                    (num - l0.h[(i, j)]).abs() < tol,
                    "{} row {i} col {j}: numeric {num} analytic {}",
                    aiding.name(),
                    l0.h[(i, j)]
                );
            }
        }
    }

    #[test]
    fn aiding_jacobians_match_finite_differences() {
        let f = context_fixture(true);
        let fix = GnssFix {
            t: 0.0,
            lla: f.nav.lla,
            std_ned: Vector3::repeat(1.0),
            vel_ned: Some(f.nav.v_n),
            vel_std_ned: Some(Vector3::repeat(0.1)),
        };
        let hd = HeadingObs {
            t: 0.0,
            heading_rad: 2.0,
            std_rad: 0.01,
        };
        let sat = fixture_satellite(&f);
        for a in [
            Aiding::GnssPosition(&fix),
            Aiding::GnssVelocity(&fix),
            Aiding::Heading(&hd, HeadingAxis::Body(Vector3::new(1.2, 0.3, 0.1))),
            Aiding::Heading(&hd, HeadingAxis::VehicleForward),
            Aiding::Nhc([0.1, 0.1]),
            Aiding::Odometer {
                speed_mps: 9.0,
                noise: ODOMETER_NOISE,
                nhc_std: Some([0.1, 0.1]),
            },
            Aiding::Zupt(0.01),
        ] {
            check_linearized(&f, 1e-6, |_| a);
        }
        check_linearized(&f, 1e-6, |w| Aiding::Zaru(w, 1e-4));
        // Ranges of 2e7 m: a larger step keeps the rounding below the tolerance.
        for a in [Aiding::Pseudorange(&sat), Aiding::Doppler(&sat)] {
            check_linearized(&f, 1e-4, |_| a);
        }
    }

    const ODOMETER_NOISE: odometer::OdometerNoise = odometer::OdometerNoise {
        std_mps: 0.05,
        std_speed_fraction: 0.01,
        calibration_min_speed_mps: 1.0,
    };

    /// The odometer model s_od = v^m_x / (1 + k) over random states (speed, heading,
    /// attitude, mounting, lever arm, scale up to +-20 %), with and without the NHC
    /// rows: H matches finite differences, and neither H nor R depends on the measured
    /// speed (the noise of the record must not enter them; y moves by exactly the
    /// change of the measurement). Below the calibration speed the scale and mounting
    /// columns are zero.
    #[test]
    fn odometer_jacobian_over_random_states_without_the_measurement_in_h() {
        use crate::attitude::c_bn_from_euler;
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(30);
        let scale = context_fixture(true)
            .layout
            .index(Block::OdometerScale)
            .unwrap();
        let mount = context_fixture(true).layout.index(Block::Mounting).unwrap();
        for trial in 0..200 {
            let mut f = context_fixture(true);
            let mut u = |a: f64, b: f64| rng.random_range(a..b);
            let speed = if trial % 10 == 0 {
                u(0.0, 0.9)
            } else {
                u(1.5, 40.0)
            };
            let course = u(-3.1, 3.1);
            f.nav.q_bn = q_bn_from_euler(&Vector3::new(u(-0.1, 0.1), u(-0.1, 0.1), course));
            f.nav.v_n = Vector3::new(speed * course.cos(), speed * course.sin(), u(-0.3, 0.3));
            f.w_ib_b = Vector3::new(u(-0.1, 0.1), u(-0.1, 0.1), u(-0.5, 0.5));
            f.vehicle.c_bm = c_bn_from_euler(&Vector3::new(
                u(-0.05, 0.05),
                u(-0.05, 0.05),
                u(-0.05, 0.05),
            ));
            // Within 1 m: the vehicle_frame Jacobian leaves out the Earth rate's share
            // of the lever-arm term (|l| x 7.3e-5 against a tolerance of 1e-4).
            f.vehicle.lever_arm_b = Vector3::new(u(-0.6, 0.6), u(-0.6, 0.6), u(-0.6, 0.6));
            f.vehicle.odometer_scale = u(-0.2, 0.2);
            let measured = speed + u(-0.5, 0.5);
            for nhc_std in [None, Some([0.1, 0.1])] {
                let a = |s: f64| Aiding::Odometer {
                    speed_mps: s,
                    noise: ODOMETER_NOISE,
                    nhc_std,
                };
                let c0 = ctx(&f, &f.nav, f.w_ib_b, (f.vehicle, FIXTURE_CLOCK));
                let l1 = a(measured).linearize(&c0).unwrap();
                let l2 = a(measured + 0.37).linearize(&c0).unwrap();
                assert_eq!(l1.h, l2.h, "trial {trial}: H depends on the measured speed");
                assert_eq!(l1.r, l2.r, "trial {trial}: R depends on the measured speed");
                assert!((l1.y[0] - l2.y[0] - 0.37).abs() < 1e-12);
                let s_pred = odometer::predicted_speed(&c0);
                let calibrating = l1.h[(0, scale)] != 0.0;
                assert_eq!(calibrating, s_pred.abs() >= 1.0 && f.nav.v_n.norm() >= 1.0);
                if calibrating {
                    check_linearized(&f, 1e-6, |_| a(measured));
                } else {
                    let rows = if nhc_std.is_some() { 3 } else { 1 };
                    assert!(
                        (0..rows).all(|i| l1.h[(i, mount)] == 0.0 && l1.h[(i, mount + 1)] == 0.0)
                    );
                }
                assert!((l1.r[(0, 0)] - 0.05f64.hypot(0.01 * s_pred).powi(2)).abs() < 1e-15);
            }
        }
    }

    /// A Galileo pseudorange: the inter-system bias column (and the clock's) besides
    /// the geometry, with the GPS-only layout and with an ISB state for another system.
    #[test]
    fn pseudorange_jacobian_with_inter_system_bias() {
        use crate::sat::{SatId, System};
        let mut f = context_fixture(true);
        f.layout
            .push(pseudorange::isb_block(System::BeiDou).unwrap());
        f.layout
            .push(pseudorange::isb_block(System::Galileo).unwrap());
        let sat = SatMeasurement {
            sat: SatId::new(System::Galileo, 5),
            ..fixture_satellite(&f)
        };
        check_linearized(&f, 1e-4, |_| Aiding::Pseudorange(&sat));
        let c0 = ctx(&f, &f.nav, f.w_ib_b, (f.vehicle, FIXTURE_CLOCK));
        let l = Aiding::Pseudorange(&sat).linearize(&c0).unwrap();
        let col = |s| f.layout.index(pseudorange::isb_block(s).unwrap()).unwrap();
        assert_eq!(l.h[(0, col(System::Galileo))], 1.0);
        assert_eq!(l.h[(0, col(System::BeiDou))], 0.0);
        // QZSS and SBAS share the GPS clock: no ISB of their own.
        assert!(pseudorange::isb_block(System::Qzss).is_none());
        assert!(pseudorange::isb_block(System::Gps).is_none());
        // The prediction carries b + ISB_E: 7 m more than the GPS satellite's.
        let gps = Aiding::Pseudorange(&fixture_satellite(&f))
            .linearize(&c0)
            .unwrap()
            .y[0];
        assert!((l.y[0] - gps - 7.0).abs() < 1e-6);
    }

    /// A satellite 20,000 km up, north-east of the fixture, moving at 3 km/s.
    pub fn fixture_satellite(f: &Fixture) -> SatMeasurement {
        let r = crate::earth::lla_to_ecef(&f.nav.lla);
        let c = crate::earth::c_ne(f.nav.lla.x, f.nav.lla.y);
        let pos = r + c * Vector3::new(9e6, 7e6, -1.6e7);
        SatMeasurement {
            sat: crate::sat::SatId::gps(7),
            sat_pos_ecef_m: pos,
            sat_vel_ecef_mps: c * Vector3::new(-1500.0, 2500.0, 600.0),
            elevation_rad: 0.9,
            pseudorange_m: Some((pos - r).norm() + 1000.0),
            pseudorange_std_m: 3.0,
            range_rate_mps: Some(-400.0),
            range_rate_std_mps: 0.1,
            carrier_m: Some(123.0),
            carrier_std_m: 0.003,
            lost_lock: false,
            dgps: false,
        }
    }

    /// TDCP: the position columns are the exact derivative of the model (the previous
    /// antenna position is the current one minus a fixed displacement); the velocity
    /// column is -u_{k-1} through the antenna velocity Jacobian (d D = d v dt), checked
    /// against the Doppler row, whose line of sight is nearly the same.
    #[test]
    fn tdcp_jacobian() {
        let f = context_fixture(true);
        let sat = fixture_satellite(&f);
        let prev = tdcp::TdcpPrevious {
            t: -1.0,
            sat_pos_ecef_m: sat.sat_pos_ecef_m - sat.sat_vel_ecef_mps,
            carrier_m: 100.0,
            carrier_std_m: 0.003,
        };
        let iv = tdcp::Interval {
            antenna_displacement_ecef_m: crate::earth::c_ne(f.nav.lla.x, f.nav.lla.y) * f.nav.v_n,
            dt_s: 1.0,
        };
        let a = Aiding::Tdcp(&sat, prev, iv);
        let c0 = ctx(&f, &f.nav, f.w_ib_b, (f.vehicle, FIXTURE_CLOCK));
        let l0 = a.linearize(&c0).unwrap();
        let dop = Aiding::Doppler(&sat).linearize(&c0).unwrap();
        let eps = 1.0;
        let n = f.layout.len();
        for j in 0..n {
            let is_pos = (POS..POS + 3).contains(&j);
            let is_clock = f.layout.index(Block::ClockDrift) == Some(j);
            if is_pos || is_clock || (ATT..ATT + 3).contains(&j) {
                let mut dx = DVector::zeros(n);
                dx[j] = eps;
                let (nav, w, veh) = inject(&f, &dx);
                let l1 = a.linearize(&ctx(&f, &nav, w, veh)).unwrap();
                let num = (l1.y[0] - l0.y[0]) / eps;
                // The attitude enters through the lever arm of both epochs' positions
                // (cancels) and through the antenna velocity (not in this model).
                if !(ATT..ATT + 3).contains(&j) {
                    let h = l0.h[(0, j)];
                    assert!(
                        (num - h).abs() < 1e-4 * (1e-3 + h.abs()),
                        "col {j}: {num} vs {h}"
                    );
                }
            }
        }
        for k in 0..3 {
            let (a, b) = (l0.h[(0, VEL + k)], dop.h[(0, VEL + k)]);
            assert!(
                (a - b).abs() < 1e-3 * (1.0 + b.abs()),
                "vel {k}: {a} vs {b}"
            );
        }
        assert!((l0.r[(0, 0)] - 2.0 * 0.003f64.powi(2)).abs() < 1e-12);
    }
}
