//! Truth trajectories from a list of segments, and the perfect IMU increments that
//! go with them.
//!
//! The truth is the solution of the same WGS-84 rotating-Earth kinematics the
//! navigator mechanizes (SYSTEM.md §1): normal gravity [`gravity_normal`], earth rate
//! and transport rate. Each segment gives the rates of speed and of the Euler angles
//! (or, for a body-frame profile, the specific force and Euler rates); one ODE
//! integrates position, velocity, attitude **and the IMU increments**
//! `dtheta = ∫ omega_ib^b dt`, `dvel = ∫ f^b dt` with classical RK4 on sub-steps of at
//! most 5 ms, split at every point where a rate is discontinuous. The increments are
//! therefore integrals over each interval, not point samples.
//!
//! Vehicle model ("speed mode"): the body x axis points along the velocity,
//! `v^n = s [cos(theta) cos(psi), cos(theta) sin(psi), -sin(theta)]` (no sideslip, no
//! angle of attack), roll is the bank angle. Body-profile mode (seed 000): constant
//! specific force in the body frame and constant Euler-angle rates, velocity from
//! `v_dot = C_b^n f^b + g^n - (2 omega_ie^n + omega_en^n) x v^n`.

use std::f64::consts::PI;

use nalgebra::{Matrix3, SVector, Vector3};
use navfuse_core::attitude::c_bn_from_euler;
use navfuse_core::earth::{gravity_normal, omega_en_n, omega_ie_n, radii};
use navfuse_core::types::ImuSample;

/// Gravity used only to size coordinated-turn bank angles [m/s²].
const G_BANK: f64 = 9.806_65;
/// Largest RK4 sub-step [s].
const MAX_SUBSTEP_S: f64 = 0.005;

/// One manoeuvre. Angles in degrees and rates in deg/s, as in the scenario file.
#[derive(Clone, Debug, PartialEq)]
pub enum Segment {
    /// Standing still (speed must be zero when it starts).
    Static { duration_s: f64 },
    /// Straight line at constant speed.
    Hold { duration_s: f64 },
    /// Constant acceleration (negative = braking) until `to_speed_mps`, or for
    /// `duration_s`; `ramp_s` > 0 ramps the acceleration in and out (jerk-limited).
    Accelerate {
        accel_mps2: f64,
        to_speed_mps: Option<f64>,
        duration_s: Option<f64>,
        ramp_s: f64,
    },
    /// Flat turn at constant speed (a car): yaw rate `rate_dps` (positive = right)
    /// through `angle_deg`, rate ramped in and out over `ramp_s`.
    Turn {
        rate_dps: f64,
        angle_deg: f64,
        ramp_s: f64,
    },
    /// Coordinated (banked) turn at constant speed (aircraft): bank
    /// phi = atan(s * rate / g) rolled in and out over `roll_s` each (triangular roll
    /// rate); yaw rate g tan(phi) / s.
    CoordinatedTurn {
        rate_dps: f64,
        angle_deg: f64,
        roll_s: f64,
    },
    /// Climb (positive) or descent (negative) at vertical speed `vertical_speed_mps`
    /// until the height has changed by `height_m`; pitch (= flight-path angle)
    /// rotated in and out over `transition_s` each (triangular pitch rate).
    Climb {
        vertical_speed_mps: f64,
        height_m: f64,
        transition_s: f64,
    },
    /// Lane change of about `width_m` (positive = to the right) over `duration_s`:
    /// heading offset (A/2)(1 - cos(2 pi t / T)), so the yaw rate starts and ends at 0.
    LaneChange { width_m: f64, duration_s: f64 },
    /// Seed 000: constant kinematic acceleration [m/s²] in the body frame
    /// (dv^n/dt = C_b^n a^b) and constant Euler-angle rates (roll, pitch, yaw) [deg/s].
    BodyProfile {
        duration_s: f64,
        accel_body_mps2: [f64; 3],
        euler_rates_dps: [f64; 3],
    },
}

/// Where and how the trajectory starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Start {
    /// GPS time of the start [s of week].
    pub t0: f64,
    /// Latitude, longitude [rad], ellipsoidal height [m] of the IMU.
    pub lla: Vector3<f64>,
    /// Initial heading [rad].
    pub heading_rad: f64,
    /// Initial speed along the body x axis [m/s].
    pub speed_mps: f64,
}

/// A piecewise-linear or sinusoidal rate, in local segment time tau.
#[derive(Clone, Debug, PartialEq)]
enum Profile {
    /// Pieces (duration, rate at start, rate at end), linear in between.
    Linear(Vec<(f64, f64, f64)>),
    /// amp * sin(2 pi tau / period).
    Sine { amp: f64, period: f64 },
}

impl Profile {
    fn zero() -> Self {
        Profile::Linear(Vec::new())
    }

    fn constant(duration: f64, rate: f64) -> Self {
        Profile::Linear(vec![(duration, rate, rate)])
    }

    /// Trapezoid: ramp 0 -> peak over `ramp`, hold, ramp back to 0.
    fn trapezoid(peak: f64, ramp: f64, hold: f64) -> Self {
        let mut v = Vec::new();
        if ramp > 0.0 {
            v.push((ramp, 0.0, peak));
        }
        if hold > 0.0 {
            v.push((hold, peak, peak));
        }
        if ramp > 0.0 {
            v.push((ramp, peak, 0.0));
        }
        Profile::Linear(v)
    }

    /// Rate at local time `tau`, using the piece that contains `tau_sel` (so an
    /// integration step that ends on a knot keeps its own piece's formula).
    fn rate(&self, tau: f64, tau_sel: f64) -> f64 {
        match self {
            Profile::Linear(pieces) => {
                let mut t0 = 0.0;
                for (k, &(d, r0, r1)) in pieces.iter().enumerate() {
                    // The last piece also answers at (and just past) its end.
                    if tau_sel < t0 + d || k + 1 == pieces.len() {
                        return r0 + (r1 - r0) * (tau - t0) / d;
                    }
                    t0 += d;
                }
                0.0
            }
            Profile::Sine { amp, period } => amp * (2.0 * PI * tau / period).sin(),
        }
    }

    /// Local times where the rate or its slope changes.
    fn knots(&self, out: &mut Vec<f64>) {
        if let Profile::Linear(pieces) = self {
            let mut t = 0.0;
            for &(d, _, _) in pieces {
                t += d;
                out.push(t);
            }
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Mode {
    /// Velocity from speed and heading/pitch.
    Speed,
    /// Velocity integrated from a constant body-frame kinematic acceleration [m/s²].
    Force(Vector3<f64>),
}

/// A segment turned into rate profiles on absolute time.
#[derive(Clone, Debug, PartialEq)]
struct Compiled {
    t_start: f64,
    duration: f64,
    mode: Mode,
    accel: Profile,
    roll_rate: Profile,
    pitch_rate: Profile,
    /// Yaw rate; `None` = coordinated (g tan(roll) / speed).
    yaw_rate: Option<Profile>,
}

/// A trajectory: start conditions plus compiled segments.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    start: Start,
    segs: Vec<Compiled>,
    /// Absolute times of all rate discontinuities (sorted).
    breaks: Vec<f64>,
}

/// A problem with the segment list: index (0-based) and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SegmentError {
    pub index: usize,
    pub message: String,
}

impl std::fmt::Display for SegmentError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "segment {}: {}", self.index + 1, self.message)
    }
}

fn positive(index: usize, name: &str, x: f64) -> Result<f64, SegmentError> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(SegmentError {
            index,
            message: format!("{name} must be a finite number > 0, got {x}"),
        })
    }
}

fn non_negative(index: usize, name: &str, x: f64) -> Result<f64, SegmentError> {
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(SegmentError {
            index,
            message: format!("{name} must be a finite number >= 0, got {x}"),
        })
    }
}

/// Angle reached at local time `tau` when going 0 -> `total` over `dur` with a
/// triangular rate (peak 2 total / dur at dur / 2).
fn s_curve(total: f64, dur: f64, tau: f64) -> f64 {
    let u = (tau / dur).clamp(0.0, 1.0);
    if u <= 0.5 {
        2.0 * total * u * u
    } else {
        total - 2.0 * total * (1.0 - u) * (1.0 - u)
    }
}

/// ∫_0^T f by composite Simpson, 2000 intervals (smooth integrands; error < 1e-12).
fn simpson(f: impl Fn(f64) -> f64, t: f64) -> f64 {
    let n = 2000;
    let h = t / n as f64;
    let mut acc = f(0.0) + f(t);
    for k in 1..n {
        acc += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    acc * h / 3.0
}

fn err<T>(index: usize, message: String) -> Result<T, SegmentError> {
    Err(SegmentError { index, message })
}

impl Trajectory {
    /// Compile the segments. The speed, roll and pitch carried between segments are
    /// tracked here so each segment can be sized (a turn needs speed, a static
    /// segment needs zero speed).
    pub fn new(start: Start, segments: &[Segment]) -> Result<Self, SegmentError> {
        let mut segs = Vec::new();
        let mut t = start.t0;
        let mut speed = start.speed_mps;
        let mut force_mode_seen = false;
        if !(speed.is_finite() && speed >= 0.0) {
            return err(0, format!("start speed must be >= 0, got {speed}"));
        }
        if segments.is_empty() {
            return err(0, "the trajectory has no segments".into());
        }
        for (i, seg) in segments.iter().enumerate() {
            if force_mode_seen && !matches!(seg, Segment::BodyProfile { .. }) {
                return err(
                    i,
                    "a vehicle segment cannot follow a body_profile segment (its velocity \
                     is not along the body axis)"
                        .into(),
                );
            }
            let speed_needed = |what: &str| -> Result<(), SegmentError> {
                if speed < 0.5 {
                    err(
                        i,
                        format!(
                            "{what} needs the vehicle moving (>= 0.5 m/s), speed is {speed:.3} m/s"
                        ),
                    )
                } else {
                    Ok(())
                }
            };
            let mut c = Compiled {
                t_start: t,
                duration: 0.0,
                mode: Mode::Speed,
                accel: Profile::zero(),
                roll_rate: Profile::zero(),
                pitch_rate: Profile::zero(),
                yaw_rate: Some(Profile::zero()),
            };
            match *seg {
                Segment::Static { duration_s } => {
                    c.duration = positive(i, "duration_s", duration_s)?;
                    if speed > 1e-9 {
                        return err(
                            i,
                            format!(
                                "static segment but the speed is {speed} m/s (decelerate first)"
                            ),
                        );
                    }
                }
                Segment::Hold { duration_s } => {
                    c.duration = positive(i, "duration_s", duration_s)?;
                }
                Segment::Accelerate {
                    accel_mps2,
                    to_speed_mps,
                    duration_s,
                    ramp_s,
                } => {
                    let ramp = non_negative(i, "ramp_s", ramp_s)?;
                    if !(accel_mps2.is_finite() && accel_mps2 != 0.0) {
                        return err(
                            i,
                            format!("accel_mps2 must be finite and non-zero, got {accel_mps2}"),
                        );
                    }
                    let dv = match (to_speed_mps, duration_s) {
                        (Some(v), None) => {
                            if !(v.is_finite() && v >= 0.0) {
                                return err(i, format!("to_speed_mps must be >= 0, got {v}"));
                            }
                            v - speed
                        }
                        (None, Some(d)) => {
                            let d = positive(i, "duration_s", d)?;
                            // Hold time so that the whole segment lasts d.
                            accel_mps2 * (d - ramp)
                        }
                        _ => {
                            return err(i, "give exactly one of to_speed_mps and duration_s".into())
                        }
                    };
                    if dv * accel_mps2 <= 0.0 {
                        return err(
                            i,
                            format!("accel_mps2 = {accel_mps2} cannot change the speed from {speed} by {dv} m/s"),
                        );
                    }
                    // Trapezoid in acceleration: dv = a (ramp + hold).
                    let hold = dv / accel_mps2 - ramp;
                    if hold < -1e-9 {
                        return err(
                            i,
                            format!("ramp_s = {ramp} is too long for a speed change of {dv} m/s"),
                        );
                    }
                    let hold = hold.max(0.0);
                    c.duration = 2.0 * ramp + hold;
                    c.accel = Profile::trapezoid(accel_mps2, ramp, hold);
                    speed += dv;
                    if speed.abs() < 1e-9 {
                        speed = 0.0;
                    }
                }
                Segment::Turn {
                    rate_dps,
                    angle_deg,
                    ramp_s,
                } => {
                    speed_needed("a turn")?;
                    let ramp = non_negative(i, "ramp_s", ramp_s)?;
                    let (rate, angle) = (rate_dps.to_radians(), angle_deg.to_radians());
                    if !(rate.is_finite() && rate != 0.0 && angle.is_finite() && angle * rate > 0.0)
                    {
                        return err(
                            i,
                            "rate_dps and angle_deg must be non-zero with the same sign".into(),
                        );
                    }
                    let hold = angle / rate - ramp;
                    if hold < -1e-9 {
                        return err(
                            i,
                            format!("ramp_s = {ramp} is too long for a {angle_deg} deg turn"),
                        );
                    }
                    let hold = hold.max(0.0);
                    c.duration = 2.0 * ramp + hold;
                    c.yaw_rate = Some(Profile::trapezoid(rate, ramp, hold));
                }
                Segment::CoordinatedTurn {
                    rate_dps,
                    angle_deg,
                    roll_s,
                } => {
                    speed_needed("a coordinated turn")?;
                    let roll_t = positive(i, "roll_s", roll_s)?;
                    let (rate, angle) = (rate_dps.to_radians(), angle_deg.to_radians());
                    if !(rate.is_finite() && rate != 0.0 && angle.is_finite() && angle * rate > 0.0)
                    {
                        return err(
                            i,
                            "rate_dps and angle_deg must be non-zero with the same sign".into(),
                        );
                    }
                    let bank = (speed * rate / G_BANK).atan();
                    if bank.abs() > 60f64.to_radians() {
                        return err(
                            i,
                            format!(
                                "bank angle {:.1} deg > 60 deg: lower the rate",
                                bank.to_degrees()
                            ),
                        );
                    }
                    // Roll in (and out) with a triangular roll rate, so the angular rate
                    // is continuous; heading change while rolling in, ∫ g tan(phi)/s.
                    let d_roll = simpson(
                        |tau| G_BANK * s_curve(bank, roll_t, tau).tan() / speed,
                        roll_t,
                    );
                    let hold = (angle - 2.0 * d_roll) / rate;
                    if hold < -1e-9 {
                        return err(
                            i,
                            format!("roll_s = {roll_t} is too long for a {angle_deg} deg turn"),
                        );
                    }
                    let hold = hold.max(0.0);
                    c.duration = 2.0 * roll_t + hold;
                    let peak = 2.0 * bank / roll_t;
                    let mut pieces = vec![(0.5 * roll_t, 0.0, peak), (0.5 * roll_t, peak, 0.0)];
                    if hold > 0.0 {
                        pieces.push((hold, 0.0, 0.0));
                    }
                    pieces.push((0.5 * roll_t, 0.0, -peak));
                    pieces.push((0.5 * roll_t, -peak, 0.0));
                    c.roll_rate = Profile::Linear(pieces);
                    c.yaw_rate = None;
                }
                Segment::Climb {
                    vertical_speed_mps,
                    height_m,
                    transition_s,
                } => {
                    speed_needed("a climb")?;
                    let tr = positive(i, "transition_s", transition_s)?;
                    if !(vertical_speed_mps.is_finite()
                        && height_m.is_finite()
                        && vertical_speed_mps * height_m > 0.0)
                    {
                        return err(
                            i,
                            "vertical_speed_mps and height_m must be non-zero with the same sign"
                                .into(),
                        );
                    }
                    if vertical_speed_mps.abs() >= 0.9 * speed {
                        return err(i, format!("vertical speed {vertical_speed_mps} m/s needs a speed above {:.1} m/s", vertical_speed_mps.abs() / 0.9));
                    }
                    // Flight-path angle gamma, entered and left with a triangular pitch
                    // rate (continuous angular rate); heights gained meanwhile by quadrature.
                    let gamma = (vertical_speed_mps / speed).asin();
                    let dh_in = simpson(|tau| speed * s_curve(gamma, tr, tau).sin(), tr);
                    let dh_out = simpson(|tau| speed * (gamma - s_curve(gamma, tr, tau)).sin(), tr);
                    let hold = (height_m - dh_in - dh_out) / (speed * gamma.sin());
                    if hold < -1e-9 {
                        return err(
                            i,
                            format!("transition_s = {tr} is too long for {height_m} m"),
                        );
                    }
                    let hold = hold.max(0.0);
                    c.duration = 2.0 * tr + hold;
                    let peak = 2.0 * gamma / tr;
                    let mut pieces = vec![(0.5 * tr, 0.0, peak), (0.5 * tr, peak, 0.0)];
                    if hold > 0.0 {
                        pieces.push((hold, 0.0, 0.0));
                    }
                    pieces.push((0.5 * tr, 0.0, -peak));
                    pieces.push((0.5 * tr, -peak, 0.0));
                    c.pitch_rate = Profile::Linear(pieces);
                }
                Segment::LaneChange {
                    width_m,
                    duration_s,
                } => {
                    speed_needed("a lane change")?;
                    let d = positive(i, "duration_s", duration_s)?;
                    if !(width_m.is_finite() && width_m != 0.0) {
                        return err(
                            i,
                            format!("width_m must be finite and non-zero, got {width_m}"),
                        );
                    }
                    // Lateral offset s ∫ sin((A/2)(1 - cos(2 pi t/T))) dt = width; solve for A
                    // by Newton on a 64-point quadrature (converges in a few steps).
                    let offset = |a: f64| -> (f64, f64) {
                        let n = 64;
                        let (mut f, mut df) = (0.0, 0.0);
                        for k in 0..n {
                            let tau = (k as f64 + 0.5) / n as f64 * d;
                            let w = 0.5 * (1.0 - (2.0 * PI * tau / d).cos());
                            f += (a * w).sin() * speed * d / n as f64;
                            df += w * (a * w).cos() * speed * d / n as f64;
                        }
                        (f, df)
                    };
                    let mut a = width_m / (0.5 * speed * d);
                    for _ in 0..20 {
                        let (f, df) = offset(a);
                        a -= (f - width_m) / df;
                    }
                    if !a.is_finite() || a.abs() > 45f64.to_radians() {
                        return err(i, format!("a {width_m} m lane change in {d} s at {speed:.1} m/s needs an impossible heading change"));
                    }
                    c.duration = d;
                    c.yaw_rate = Some(Profile::Sine {
                        amp: a * PI / d,
                        period: d,
                    });
                }
                Segment::BodyProfile {
                    duration_s,
                    accel_body_mps2,
                    euler_rates_dps,
                } => {
                    c.duration = positive(i, "duration_s", duration_s)?;
                    let f = Vector3::from(accel_body_mps2);
                    let r = Vector3::from(euler_rates_dps).map(f64::to_radians);
                    if !(f.iter().all(|x| x.is_finite()) && r.iter().all(|x| x.is_finite())) {
                        return err(
                            i,
                            "specific_force_mps2 and euler_rates_dps must be finite".into(),
                        );
                    }
                    c.mode = Mode::Force(f);
                    c.roll_rate = Profile::constant(c.duration, r.x);
                    c.pitch_rate = Profile::constant(c.duration, r.y);
                    c.yaw_rate = Some(Profile::constant(c.duration, r.z));
                    force_mode_seen = true;
                }
            }
            t += c.duration;
            segs.push(c);
        }
        let mut breaks = Vec::new();
        for c in &segs {
            let mut local = vec![0.0, c.duration];
            c.accel.knots(&mut local);
            c.roll_rate.knots(&mut local);
            c.pitch_rate.knots(&mut local);
            if let Some(y) = &c.yaw_rate {
                y.knots(&mut local);
            }
            breaks.extend(local.into_iter().map(|x| c.t_start + x));
        }
        breaks.sort_by(f64::total_cmp);
        breaks.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        Ok(Trajectory {
            start,
            segs,
            breaks,
        })
    }

    /// GPS time of the start [s].
    pub fn t_start(&self) -> f64 {
        self.start.t0
    }

    /// GPS time of the end [s].
    pub fn t_end(&self) -> f64 {
        let c = self.segs.last().expect("validated non-empty");
        c.t_start + c.duration
    }

    /// Total duration [s].
    pub fn duration(&self) -> f64 {
        self.t_end() - self.t_start()
    }

    fn seg_at(&self, t: f64) -> &Compiled {
        let k = self.segs.partition_point(|c| c.t_start <= t);
        &self.segs[k.saturating_sub(1)]
    }
}

/// How the IMU sits in the vehicle. The trajectory moves the vehicle frame m (x along
/// the velocity of the vehicle reference point, e.g. the rear-axle centre, where the
/// non-holonomic constraint holds); the IMU frame b is rotated from m by the mounting
/// angles and sits at `-lever_b` from the reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rig {
    /// C_b^m: IMU frame to vehicle frame (SYSTEM.md §4b: C_b^m = I - (dalpha x)).
    pub c_bm: Matrix3<f64>,
    /// Lever arm from the IMU to the vehicle reference point, IMU frame [m]
    /// (SYSTEM.md §4b l^b).
    pub lever_b: Vector3<f64>,
}

impl Default for Rig {
    fn default() -> Self {
        Rig {
            c_bm: Matrix3::identity(),
            lever_b: Vector3::zeros(),
        }
    }
}

impl Rig {
    /// From mounting angles (roll, pitch, yaw of the IMU frame relative to the vehicle
    /// frame, ZYX) [rad] and the lever arm [m].
    pub fn new(mount_rpy_rad: &Vector3<f64>, lever_b: Vector3<f64>) -> Self {
        Rig {
            c_bm: c_bn_from_euler(mount_rpy_rad),
            lever_b,
        }
    }
}

/// The integrated state: IMU position, IMU velocity (body-profile mode), Euler angles
/// of the vehicle frame, speed, and the running IMU integrals over the current span.
type Y = SVector<f64, 16>;
const LAT: usize = 0;
const VEL: usize = 3;
const EUL: usize = 6;
const SPD: usize = 9;
const DTH: usize = 10;
const DV: usize = 13;

/// Truth at one instant. Position, velocity and attitude are those of the IMU
/// (body frame b = IMU frame); `c_mn`, `speed` describe the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSample {
    /// GPS time [s of week].
    pub t: f64,
    /// IMU latitude, longitude [rad], ellipsoidal height [m].
    pub lla: Vector3<f64>,
    /// IMU NED velocity [m/s].
    pub v_n: Vector3<f64>,
    /// C_b^n of the IMU.
    pub c_bn: Matrix3<f64>,
    /// C_m^n of the vehicle frame.
    pub c_mn: Matrix3<f64>,
    /// Angular rate of the body w.r.t. inertial space, IMU frame [rad/s].
    pub w_ib_b: Vector3<f64>,
    /// Angular rate of the body w.r.t. the Earth, IMU frame [rad/s].
    pub w_eb_b: Vector3<f64>,
    /// Forward speed of the vehicle reference point (speed mode); |v| of the IMU in
    /// body-profile mode [m/s].
    pub speed: f64,
}

impl TruthSample {
    /// Velocity [m/s] (NED) of a point at `lever_b` [m] (IMU frame) from the IMU.
    pub fn velocity_at(&self, lever_b: &Vector3<f64>) -> Vector3<f64> {
        self.v_n + self.c_bn * self.w_eb_b.cross(lever_b)
    }

    /// Roll, pitch, yaw of the IMU [rad] (yaw in (-pi, pi]).
    pub fn euler(&self) -> Vector3<f64> {
        navfuse_core::attitude::euler_from_c_bn(&self.c_bn)
    }
}

/// Rates at time t for state y in segment c.
struct Eval {
    dy: Y,
    sample: TruthSample,
    /// C_n^b v^n: the boundary term of the velocity-increment integral.
    v_b: Vector3<f64>,
}

/// `t_sel`: a time strictly inside the smooth span being integrated (selects the
/// profile pieces).
fn evaluate(c: &Compiled, rig: &Rig, t: f64, t_sel: f64, y: &Y) -> Eval {
    let tau = t - c.t_start;
    let tau_sel = t_sel - c.t_start;
    let lla = Vector3::new(y[LAT], y[LAT + 1], y[LAT + 2]);
    let (roll, pitch, yaw) = (y[EUL], y[EUL + 1], y[EUL + 2]);
    let speed = y[SPD];
    let accel = c.accel.rate(tau, tau_sel);
    let roll_rate = c.roll_rate.rate(tau, tau_sel);
    let pitch_rate = c.pitch_rate.rate(tau, tau_sel);
    let yaw_rate = match &c.yaw_rate {
        Some(p) => p.rate(tau, tau_sel),
        None => G_BANK * roll.tan() / speed,
    };
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    let c_mn = c_bn_from_euler(&Vector3::new(roll, pitch, yaw));
    let c_bn = c_mn * rig.c_bm;
    let c_nb = c_bn.transpose();
    let g_n = Vector3::new(0.0, 0.0, gravity_normal(lla.x, lla.z));
    let w_ie = omega_ie_n(lla.x);
    // Vehicle rate w.r.t. n from Euler-angle rates (ZYX), vehicle frame.
    let w_nm_m = Vector3::new(
        roll_rate - yaw_rate * sp,
        pitch_rate * cr + yaw_rate * sr * cp,
        -pitch_rate * sr + yaw_rate * cr * cp,
    );
    let w_nb_b = rig.c_bm.transpose() * w_nm_m;

    let mut dy = Y::zeros();
    let (v_n, speed_out) = match &c.mode {
        Mode::Speed => {
            // Reference point along the vehicle x axis; the IMU at -lever from it:
            // v_imu = v_ref - C_b^n (w_eb^b x l^b).
            let v_ref = Vector3::new(cp * cy, cp * sy, -sp) * speed;
            let w_eb_ref = w_nb_b + c_nb * omega_en_n(lla.x, lla.z, &v_ref);
            (v_ref - c_bn * w_eb_ref.cross(&rig.lever_b), speed)
        }
        Mode::Force(a_b) => {
            let v = Vector3::new(y[VEL], y[VEL + 1], y[VEL + 2]);
            dy.fixed_rows_mut::<3>(VEL).copy_from(&(c_bn * a_b));
            (v, v.norm())
        }
    };
    let w_en = omega_en_n(lla.x, lla.z, &v_n);
    let w_ib_b = w_nb_b + c_nb * (w_ie + w_en);
    let w_eb_b = w_nb_b + c_nb * w_en;
    let v_b = c_nb * v_n;
    // Integrand of the velocity increment. Force mode: f^b itself. Speed mode, by parts
    // so no acceleration is needed: ∫ C_n^b a dt = [C_n^b v] + ∫ w_nb^b x (C_n^b v) dt,
    // hence f^b -> w_nb^b x v^b + C_n^b (-g + (2 w_ie + w_en) x v); the boundary term is
    // added per span in `TruthGenerator::step`.
    let dv_integrand = match &c.mode {
        // f^b = a^b - C_n^b (g - (2 w_ie + w_en) x v)  (SYSTEM.md §1, rearranged)
        Mode::Force(a_b) => a_b + c_nb * (-g_n + (2.0 * w_ie + w_en).cross(&v_n)),
        Mode::Speed => w_nb_b.cross(&v_b) + c_nb * (-g_n + (2.0 * w_ie + w_en).cross(&v_n)),
    };

    let (m, n) = radii(lla.x);
    dy[LAT] = v_n.x / (m + lla.z);
    dy[LAT + 1] = v_n.y / ((n + lla.z) * lla.x.cos());
    dy[LAT + 2] = -v_n.z;
    dy[EUL] = roll_rate;
    dy[EUL + 1] = pitch_rate;
    dy[EUL + 2] = yaw_rate;
    dy[SPD] = accel;
    dy.fixed_rows_mut::<3>(DTH).copy_from(&w_ib_b);
    dy.fixed_rows_mut::<3>(DV).copy_from(&dv_integrand);
    Eval {
        dy,
        v_b,
        sample: TruthSample {
            t,
            lla,
            v_n,
            c_bn,
            c_mn,
            w_ib_b,
            w_eb_b,
            speed: speed_out,
        },
    }
}

/// Steps a [`Trajectory`] at a fixed IMU interval, producing the truth at each
/// sample time and the exact increments over each interval.
pub struct TruthGenerator<'a> {
    traj: &'a Trajectory,
    rig: Rig,
    dt: f64,
    /// Index of the next sample (sample k is at t0 + k dt).
    k: u64,
    y: Y,
    next_break: usize,
    /// C_n^b v^n of the IMU at the end of the last integrated span.
    v_b_last: Vector3<f64>,
}

impl<'a> TruthGenerator<'a> {
    /// `rate_hz`: IMU output rate.
    pub fn new(traj: &'a Trajectory, rig: Rig, rate_hz: f64) -> Self {
        let s = &traj.start;
        let mut y = Y::zeros();
        y[LAT] = s.lla.x;
        y[LAT + 1] = s.lla.y;
        y[LAT + 2] = s.lla.z;
        y[EUL + 2] = s.heading_rad;
        y[SPD] = s.speed_mps;
        let mut g = TruthGenerator {
            traj,
            rig,
            dt: 1.0 / rate_hz,
            k: 0,
            y,
            next_break: 0,
            v_b_last: Vector3::zeros(),
        };
        // Body-profile mode integrates the IMU velocity: start it from the truth.
        let s0 = g.current();
        g.y.fixed_rows_mut::<3>(VEL).copy_from(&s0.v_n);
        g.v_b_last = s0.c_bn.transpose() * s0.v_n;
        g
    }

    /// IMU interval [s].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    fn time(&self, k: u64) -> f64 {
        self.traj.start.t0 + k as f64 * self.dt
    }

    /// Truth at the current sample time.
    pub fn current(&self) -> TruthSample {
        let t = self.time(self.k);
        let t_sel = t.min(self.traj.t_end() - 1e-9);
        evaluate(self.traj.seg_at(t_sel), &self.rig, t, t_sel, &self.y).sample
    }

    /// Advance one IMU interval. Returns the increments over it (IMU frame) and the
    /// truth at its end, or None once the next sample would pass the end of the
    /// trajectory (the run ends at the last whole IMU interval).
    pub fn step(&mut self) -> Option<(ImuSample, TruthSample)> {
        let t_a = self.time(self.k);
        let t_b = self.time(self.k + 1);
        if t_b > self.traj.t_end() + 1e-9 {
            return None;
        }
        for i in DTH..DTH + 6 {
            self.y[i] = 0.0;
        }
        let breaks = &self.traj.breaks;
        while self.next_break < breaks.len() && breaks[self.next_break] <= t_a + 1e-9 {
            self.next_break += 1;
        }
        let rig = self.rig;
        let mut t = t_a;
        while t < t_b - 1e-12 {
            let mut t_next = t_b;
            if self.next_break < breaks.len() && breaks[self.next_break] < t_b - 1e-9 {
                t_next = breaks[self.next_break];
            }
            // RK4 sub-steps over [t, t_next], no discontinuity inside; the segment and
            // profile pieces are fixed for the span (chosen at its middle).
            let span = t_next - t;
            let n = (span / MAX_SUBSTEP_S).ceil().max(1.0) as usize;
            let h = span / n as f64;
            let t_sel = t + 0.5 * span;
            let seg = self.traj.seg_at(t_sel);
            for j in 0..n {
                let ts = t + j as f64 * h;
                let k1 = evaluate(seg, &rig, ts, t_sel, &self.y).dy;
                let k2 = evaluate(seg, &rig, ts + 0.5 * h, t_sel, &(self.y + k1 * (0.5 * h))).dy;
                let k3 = evaluate(seg, &rig, ts + 0.5 * h, t_sel, &(self.y + k2 * (0.5 * h))).dy;
                let k4 = evaluate(seg, &rig, ts + h, t_sel, &(self.y + k3 * h)).dy;
                self.y += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
            }
            let end = evaluate(seg, &rig, t_next, t_sel, &self.y);
            if seg.mode == Mode::Speed {
                // Boundary term against the previous span's end, so a velocity step of
                // the IMU (a step in angular rate times the lever arm) is an impulse in
                // this interval's velocity increment.
                let dv = end.v_b - self.v_b_last;
                for i in 0..3 {
                    self.y[DV + i] += dv[i];
                }
                // Keep the integrated velocity current for a later body profile.
                self.y.fixed_rows_mut::<3>(VEL).copy_from(&end.sample.v_n);
            }
            self.v_b_last = end.v_b;
            t = t_next;
            if t_next < t_b {
                self.next_break += 1;
            }
        }
        self.k += 1;
        let imu = ImuSample {
            t: t_b,
            dt: t_b - t_a,
            dtheta: Vector3::new(self.y[DTH], self.y[DTH + 1], self.y[DTH + 2]),
            dvel: Vector3::new(self.y[DV], self.y[DV + 1], self.y[DV + 2]),
        };
        Some((imu, self.current()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use navfuse_core::earth::lla_diff_ned;

    fn start(speed: f64) -> Start {
        Start {
            t0: 100_000.0,
            lla: Vector3::new(30f64.to_radians(), 114f64.to_radians(), 20.0),
            heading_rad: 0.3,
            speed_mps: speed,
        }
    }

    fn run(traj: &Trajectory, rate: f64) -> Vec<TruthSample> {
        let mut g = TruthGenerator::new(traj, Rig::default(), rate);
        let mut out = vec![g.current()];
        while let Some((_, s)) = g.step() {
            out.push(s);
        }
        out
    }

    #[test]
    fn static_imu_senses_gravity_and_earth_rate() {
        let traj = Trajectory::new(start(0.0), &[Segment::Static { duration_s: 1.0 }]).unwrap();
        let mut g = TruthGenerator::new(&traj, Rig::default(), 100.0);
        let (imu, s) = g.step().unwrap();
        let gn = gravity_normal(30f64.to_radians(), 20.0);
        // Level, heading 0.3: f^b = (0, 0, -g); |w_ib| = earth rate.
        assert!((imu.dvel.z / imu.dt + gn).abs() < 1e-12);
        assert!(imu.dvel.xy().norm() < 1e-14);
        assert!((imu.dtheta.norm() / imu.dt - navfuse_core::earth::OMEGA_IE).abs() < 1e-15);
        assert!(lla_diff_ned(&s.lla, &traj.start.lla).norm() < 1e-9);
    }

    #[test]
    fn accelerate_reaches_speed_and_distance() {
        let segs = [
            Segment::Accelerate {
                accel_mps2: 2.0,
                to_speed_mps: Some(20.0),
                duration_s: None,
                ramp_s: 1.0,
            },
            Segment::Hold { duration_s: 10.0 },
        ];
        let traj = Trajectory::new(start(0.0), &segs).unwrap();
        // 20 m/s at 2 m/s² with 1 s ramps: 1 + 9 + 1 s; distance = 20*11/2 = 110 m + 200 m.
        assert!((traj.duration() - 21.0).abs() < 1e-12);
        let out = run(&traj, 200.0);
        let last = out.last().unwrap();
        assert!((last.speed - 20.0).abs() < 1e-9);
        let d = lla_diff_ned(&last.lla, &traj.start.lla).norm();
        assert!((d - 310.0).abs() < 1e-3, "{d}");
    }

    #[test]
    fn turn_changes_heading_by_angle() {
        let segs = [Segment::Turn {
            rate_dps: 10.0,
            angle_deg: 90.0,
            ramp_s: 2.0,
        }];
        let traj = Trajectory::new(start(10.0), &segs).unwrap();
        assert!((traj.duration() - 11.0).abs() < 1e-12);
        let out = run(&traj, 100.0);
        let d = out.last().unwrap().euler().z - 0.3;
        assert!((d - PI / 2.0).abs() < 1e-9, "{d}");
    }

    #[test]
    fn coordinated_turn_and_climb_end_where_configured() {
        let segs = [
            Segment::CoordinatedTurn {
                rate_dps: 3.0,
                angle_deg: 180.0,
                roll_s: 4.0,
            },
            Segment::Climb {
                vertical_speed_mps: 3.0,
                height_m: 100.0,
                transition_s: 5.0,
            },
            // The run ends at the last whole IMU interval: hold so the climb completes.
            Segment::Hold { duration_s: 1.0 },
        ];
        let traj = Trajectory::new(start(30.0), &segs).unwrap();
        let out = run(&traj, 100.0);
        let last = out.last().unwrap();
        let dyaw = navfuse_core::attitude::wrap_pi(last.euler().z - 0.3 - PI);
        assert!(dyaw.abs() < 1e-6, "{dyaw}");
        assert!(last.euler().x.abs() < 1e-9 && last.euler().y.abs() < 1e-9);
        assert!((last.lla.z - 120.0).abs() < 1e-3, "{}", last.lla.z);
    }

    #[test]
    fn lane_change_offsets_sideways() {
        let segs = [Segment::LaneChange {
            width_m: 3.5,
            duration_s: 5.0,
        }];
        let mut st = start(20.0);
        st.heading_rad = 0.0;
        let traj = Trajectory::new(st, &segs).unwrap();
        let out = run(&traj, 200.0);
        let last = out.last().unwrap();
        let d = lla_diff_ned(&last.lla, &st.lla);
        assert!((d.y - 3.5).abs() < 1e-3, "{d}");
        assert!(last.euler().z.abs() < 1e-9);
    }

    #[test]
    fn bad_segments_are_rejected() {
        let e = Trajectory::new(
            start(0.0),
            &[Segment::Turn {
                rate_dps: 5.0,
                angle_deg: 90.0,
                ramp_s: 0.0,
            }],
        );
        assert!(e.unwrap_err().message.contains("moving"));
        let e = Trajectory::new(start(5.0), &[Segment::Static { duration_s: 1.0 }]);
        assert!(e.is_err());
    }
}
