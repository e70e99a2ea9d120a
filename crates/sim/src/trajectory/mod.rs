//! Truth trajectories from a list of segments, and the perfect IMU increments that
//! go with them.
//!
//! The truth is the solution of the same WGS-84 rotating-Earth kinematics the
//! navigator mechanizes (SYSTEM.md §1): normal gravity [`gravity_normal`](navfuse_core::earth::gravity_normal), earth rate
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

use self::profile::{s_curve, simpson, Profile};
use nalgebra::Vector3;

mod profile;
#[cfg(test)]
mod tests;
mod truth;

pub use truth::{Rig, TruthGenerator, TruthSample};

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
    /// Latitude, longitude \[rad\], ellipsoidal height \[m\] of the IMU.
    pub lla: Vector3<f64>,
    /// Initial heading \[rad\].
    pub heading_rad: f64,
    /// Initial speed along the body x axis [m/s].
    pub speed_mps: f64,
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

    /// GPS time of the start \[s\].
    pub fn t_start(&self) -> f64 {
        self.start.t0
    }

    /// GPS time of the end \[s\].
    pub fn t_end(&self) -> f64 {
        let c = self.segs.last().expect("validated non-empty");
        c.t_start + c.duration
    }

    /// Total duration \[s\].
    pub fn duration(&self) -> f64 {
        self.t_end() - self.t_start()
    }

    fn seg_at(&self, t: f64) -> &Compiled {
        let k = self.segs.partition_point(|c| c.t_start <= t);
        &self.segs[k.saturating_sub(1)]
    }
}
