//! The navigator: nominal INS state, closed-loop error-state filter and the time
//! loop that interleaves IMU intervals with aiding measurements.
//!
//! Time handling: a GNSS epoch that falls inside an IMU interval splits it (the
//! increments are shared in proportion to time), so the update happens exactly at
//! the epoch (SYSTEM.md §1, seed 000 eq. 31-32). The covariance is propagated every
//! `covariance_period_s` (and always right before an update) with the transition
//! matrix built from the mean specific force and rate over that span.

use crate::aiding::{Aiding, AidingContext};
use crate::alignment;
use crate::attitude::{c_bn_from_euler, euler_from_q_bn, q_bn_from_euler, quat_from_rotvec};
use crate::config::{AttitudeInit, NavConfig};
use crate::earth::lla_add_ned;
use crate::error_model::{fill_f, fill_qc, Discretizer, MeanMotion};
use crate::filter::{chi2_threshold, Eskf, UpdateOutcome};
use crate::mechanization::Mechanizer;
use crate::state::{Block, StateLayout, ATT, BA, BG, N_INS, POS, SA, SG, VEL};
use crate::types::{GnssFix, ImuErrors, ImuSample, NavState};
use nalgebra::{DMatrix, DVector, Vector3};

/// Something worth telling the user about, with its time.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A measurement failed the innovation gate.
    Rejected {
        t: f64,
        source: &'static str,
        nis: f64,
        threshold: f64,
    },
    /// A measurement's innovation covariance was singular; dropped.
    Singular { t: f64, source: &'static str },
    /// Fixes had been rejected for `streak_s` seconds; this one was used ungated.
    GateBypassed { t: f64, streak_s: f64 },
}

impl std::fmt::Display for Event {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Event::Rejected { t, source, nis, threshold } => write!(
                f,
                "{t:.3} {source} rejected: normalised innovation squared {nis:.1} > gate {threshold:.1}"
            ),
            Event::Singular { t, source } => {
                write!(f, "{t:.3} {source} dropped: innovation covariance not positive definite")
            }
            Event::GateBypassed { t, streak_s } => write!(
                f,
                "{t:.3} gnss fix used without the gate: fixes rejected for {streak_s:.1} s (gate timeout)"
            ),
        }
    }
}

/// Counts for the end-of-run summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSummary {
    pub first_t: f64,
    pub last_t: f64,
    pub imu_samples: usize,
    pub gnss_used: usize,
    pub gnss_rejected: usize,
    pub gnss_in_outage: usize,
    pub gnss_before_start: usize,
    pub outputs: usize,
    pub events: Vec<Event>,
    /// Final GNSS-IMU time offset at `last_t` and its 1-sigma [s], when estimated.
    pub time_offset: Option<(f64, f64)>,
    /// Final time-offset rate and its 1-sigma [s/s], when estimated.
    pub time_offset_rate: Option<(f64, f64)>,
}

#[derive(Clone, Copy, Debug, Default)]
struct Accum {
    dt: f64,
    dv_f_n: Vector3<f64>,
    dtheta: Vector3<f64>,
    dvel: Vector3<f64>,
}

/// Nominal state + error covariance + mechanization history.
pub struct Navigator {
    cfg: NavConfig,
    layout: StateLayout,
    filter: Eskf,
    disc: Discretizer,
    mech: Mechanizer,
    nav: NavState,
    imu_errors: ImuErrors,
    time_offset_s: f64,
    time_offset_rate: f64,
    acc: Accum,
    w_ib_b: Vector3<f64>,
    /// Acceleration d(v^n)/dt over the last IMU interval [m/s²].
    a_n: Vector3<f64>,
    gate3: Option<f64>,
    /// Time of the first of the current run of gate-rejected fixes.
    reject_streak_since: Option<f64>,
    summary: RunSummary,
}

impl Navigator {
    /// Initialise at time `t0` with position `lla` (IMU centre) and attitude `rpy`
    /// [rad]; the rest (velocity, IMU errors, uncertainties) from `cfg.initial`.
    pub fn new(cfg: &NavConfig, t0: f64, lla: Vector3<f64>, rpy: Vector3<f64>) -> Self {
        let mut layout = StateLayout::ins21();
        if let Some(to) = cfg.filter.time_offset {
            if to.std_s > 0.0 {
                layout.push(Block::TimeOffset);
                if to.rate_std > 0.0 {
                    layout.push(Block::TimeOffsetRate);
                }
            }
        }
        let n = layout.len();
        let ini = &cfg.initial;
        let mut p0 = DVector::zeros(n);
        let e = &ini.imu_errors_std;
        for k in 0..3 {
            p0[POS + k] = ini.pos_std[k].powi(2);
            p0[VEL + k] = ini.vel_std[k].powi(2);
            p0[ATT + k] = ini.att_std[k].powi(2);
            p0[BG + k] = e.gyro_bias[k].powi(2);
            p0[BA + k] = e.accel_bias[k].powi(2);
            p0[SG + k] = e.gyro_scale[k].powi(2);
            p0[SA + k] = e.accel_scale[k].powi(2);
        }
        let (mut time_offset_s, mut time_offset_rate) = (0.0, 0.0);
        if let Some(to) = cfg.filter.time_offset {
            time_offset_s = to.initial_s;
            time_offset_rate = to.initial_rate;
            if let Some(i) = layout.index(Block::TimeOffset) {
                p0[i] = to.std_s.powi(2);
            }
            if let Some(i) = layout.index(Block::TimeOffsetRate) {
                p0[i] = to.rate_std.powi(2);
            }
        }
        let nav = NavState {
            t: t0,
            lla,
            v_n: ini.v_n,
            q_bn: q_bn_from_euler(&rpy),
        };
        let gate3 = cfg.gnss.gate_probability.map(|p| chi2_threshold(3, p));
        Navigator {
            cfg: cfg.clone(),
            filter: Eskf::new(DMatrix::from_diagonal(&p0)),
            disc: Discretizer::new(n),
            layout,
            mech: Mechanizer::new(),
            nav,
            imu_errors: ini.imu_errors,
            time_offset_s,
            time_offset_rate,
            acc: Accum::default(),
            w_ib_b: Vector3::zeros(),
            a_n: Vector3::zeros(),
            gate3,
            reject_streak_since: None,
            summary: RunSummary {
                first_t: t0,
                last_t: t0,
                ..Default::default()
            },
        }
    }

    pub fn nav(&self) -> &NavState {
        &self.nav
    }

    pub fn imu_errors(&self) -> &ImuErrors {
        &self.imu_errors
    }

    pub fn layout(&self) -> &StateLayout {
        &self.layout
    }

    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.filter.p
    }

    /// Current GNSS-IMU time offset estimate [s] (0 when not estimated): a GNSS
    /// epoch tagged t is applied at IMU time t + offset.
    pub fn time_offset(&self) -> f64 {
        self.time_offset_s
    }

    /// Time of the current state on the GNSS (GPS) time scale: the IMU time tag
    /// minus the estimated GNSS-IMU offset. Solutions are written with this time.
    pub fn time_gnss(&self) -> f64 {
        self.nav.t - self.time_offset_s
    }

    /// 1-sigma of the 21 INS states in SI units (pos N E D, vel N E D, att r p y,
    /// gyro bias, accel bias, gyro scale, accel scale), as of the last covariance
    /// propagation or update.
    pub fn std21(&self) -> [f64; N_INS] {
        let mut s = [0.0; N_INS];
        for (i, v) in s.iter_mut().enumerate() {
            *v = self.filter.std(i);
        }
        s
    }

    pub fn summary(&self) -> &RunSummary {
        &self.summary
    }

    /// Advance over one raw IMU interval.
    pub fn propagate(&mut self, raw: &ImuSample) {
        let s = self.imu_errors.compensate(raw);
        // The offset line tau0 + rate (t - t0) follows elapsed time (after an IMU gap
        // the interval's dt is shorter than the time that passed).
        self.time_offset_s += self.time_offset_rate * (raw.t - self.nav.t);
        let v_before = self.nav.v_n;
        let (next, info) = self.mech.step(&self.nav, &s);
        self.nav = next;
        if s.dt > 0.0 {
            self.w_ib_b = s.dtheta / s.dt;
            self.a_n = (self.nav.v_n - v_before) / s.dt;
        }
        self.acc.dt += s.dt;
        self.acc.dv_f_n += info.dv_f_n;
        self.acc.dtheta += s.dtheta;
        self.acc.dvel += s.dvel;
        if self.acc.dt >= self.cfg.filter.covariance_period_s - 1e-9 {
            self.flush_covariance();
        }
    }

    /// Propagate the covariance over the accumulated span (SYSTEM.md §2).
    pub fn flush_covariance(&mut self) {
        let a = self.acc;
        if a.dt <= 0.0 {
            return;
        }
        let mm = MeanMotion {
            f_n: a.dv_f_n / a.dt,
            f_b: a.dvel / a.dt,
            w_b: a.dtheta / a.dt,
        };
        let rw = self.cfg.filter.time_offset.map_or(0.0, |t| t.random_walk);
        fill_f(
            &mut self.disc.f,
            &self.layout,
            &self.nav,
            &mm,
            self.cfg.imu_noise.corr_time_s,
        );
        fill_qc(
            &mut self.disc.qc,
            &self.layout,
            &self.nav,
            &self.cfg.imu_noise,
            rw,
        );
        self.disc.discretize(a.dt);
        self.filter.predict(&self.disc.phi, &self.disc.qd);
        self.acc = Accum::default();
    }

    /// Fuse one aiding measurement; returns true when it was applied.
    pub fn fuse(&mut self, aiding: Aiding, gate: Option<f64>) -> bool {
        self.flush_covariance();
        let ctx = AidingContext {
            nav: &self.nav,
            layout: &self.layout,
            w_ib_b: self.w_ib_b,
            a_n: self.a_n,
            lever_arm_b: self.cfg.gnss.lever_arm_b,
        };
        let Some(lin) = aiding.linearize(&ctx) else {
            return false;
        };
        match self.filter.update(&lin.y, &lin.h, &lin.r, gate) {
            UpdateOutcome::Applied { dx, .. } => {
                self.feedback(&dx);
                true
            }
            UpdateOutcome::Rejected { nis, threshold } => {
                self.summary.events.push(Event::Rejected {
                    t: self.time_gnss(),
                    source: aiding.name(),
                    nis,
                    threshold,
                });
                false
            }
            UpdateOutcome::Singular => {
                self.summary.events.push(Event::Singular {
                    t: self.time_gnss(),
                    source: aiding.name(),
                });
                false
            }
        }
    }

    /// Closed-loop feedback of the error estimate, then implicit reset to zero.
    fn feedback(&mut self, dx: &DVector<f64>) {
        let d_pos = Vector3::new(dx[POS], dx[POS + 1], dx[POS + 2]);
        let d_vel = Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]);
        let phi = Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2]);
        let old_lla = self.nav.lla;
        self.nav.lla = lla_add_ned(&self.nav.lla, &(-d_pos));
        self.nav.v_n -= d_vel;
        // C_true = (I + phi x) C_est.
        self.nav.q_bn = quat_from_rotvec(&phi) * self.nav.q_bn;
        self.mech
            .shift_previous(&(self.nav.lla - old_lla), &(-d_vel));
        let e = &mut self.imu_errors;
        for k in 0..3 {
            e.gyro_bias[k] += dx[BG + k];
            e.accel_bias[k] += dx[BA + k];
            e.gyro_scale[k] += dx[SG + k];
            e.accel_scale[k] += dx[SA + k];
        }
        if let Some(i) = self.layout.index(Block::TimeOffset) {
            self.time_offset_s -= dx[i];
        }
        if let Some(i) = self.layout.index(Block::TimeOffsetRate) {
            self.time_offset_rate -= dx[i];
        }
    }

    /// Current GNSS-IMU time offset rate [s/s].
    pub fn time_offset_rate(&self) -> f64 {
        self.time_offset_rate
    }

    /// Loosely coupled GNSS update: position, then velocity if present and enabled.
    pub fn update_gnss(&mut self, fix: &GnssFix) {
        let mut f = *fix;
        let g = &self.cfg.gnss;
        if let Some(s) = g.position_std_override {
            f.std_ned = s;
        }
        if let (Some(s), true) = (g.velocity_std_override, f.vel_ned.is_some()) {
            f.vel_std_ned = Some(s);
        }
        let use_vel = g.use_velocity;
        let mut gate = self.gate3;
        if let (Some(t0), Some(_)) = (self.reject_streak_since, gate) {
            if fix.t - t0 >= g.gate_timeout_s {
                gate = None;
                self.summary.events.push(Event::GateBypassed {
                    t: fix.t,
                    streak_s: fix.t - t0,
                });
            }
        }
        let n_events = self.summary.events.len();
        let used = self.fuse(Aiding::GnssPosition(&f), gate);
        if used {
            self.summary.gnss_used += 1;
            self.reject_streak_since = None;
        } else {
            self.summary.gnss_rejected += 1;
            let gated = self.summary.events[n_events..]
                .iter()
                .any(|e| matches!(e, Event::Rejected { .. }));
            if gated {
                self.reject_streak_since.get_or_insert(fix.t);
            }
        }
        if use_vel && f.vel_ned.is_some() {
            self.fuse(Aiding::GnssVelocity(&f), gate);
        }
    }

    /// True while position, velocity and attitude are finite numbers.
    pub fn nav_is_finite(&self) -> bool {
        let n = &self.nav;
        n.lla
            .iter()
            .chain(n.v_n.iter())
            .chain(n.q_bn.coords.iter())
            .all(|x| x.is_finite())
    }

    /// True while the covariance diagonal is finite.
    pub fn covariance_is_finite(&self) -> bool {
        (0..self.filter.dim()).all(|i| self.filter.p[(i, i)].is_finite())
    }

    /// Roll, pitch, yaw [rad] of the current attitude.
    pub fn rpy(&self) -> Vector3<f64> {
        euler_from_q_bn(&self.nav.q_bn)
    }
}

/// Why a run could not start or had to stop (no initial pose, numerical failure).
#[derive(Clone, Debug, PartialEq)]
pub struct NavError(pub String);

impl std::fmt::Display for NavError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for NavError {}

/// Initial position and attitude from the configuration, or found from the data
/// (levelling window `window`, GNSS course, first GNSS fix). SYSTEM.md §1.
/// Also returns the time of the GNSS fix used as the initial position, if any (that
/// fix is then not used again as a measurement).
pub fn initial_pose(
    cfg: &NavConfig,
    t0: f64,
    window: &[ImuSample],
    gnss: &[GnssFix],
) -> Result<(Vector3<f64>, Vector3<f64>, Option<f64>), NavError> {
    let rpy = match cfg.initial.attitude {
        AttitudeInit::Given(rpy) => rpy,
        AttitudeInit::LevelAndGnssCourse { min_speed_mps, .. } => {
            let compensated: Vec<ImuSample> = window
                .iter()
                .map(|s| cfg.initial.imu_errors.compensate(s))
                .collect();
            let (f_b, _) = alignment::mean_motion(&compensated).ok_or_else(|| {
                NavError("alignment: no IMU samples in the levelling window".into())
            })?;
            let (roll, pitch) = alignment::level(&f_b);
            let (_, yaw) = alignment::first_course(gnss, t0, min_speed_mps).ok_or_else(|| {
                NavError(format!(
                    "alignment: no GNSS epoch after t = {t0:.3} with a horizontal speed of at least {min_speed_mps} m/s, so the initial yaw is unknown (give initial.attitude_deg)"
                ))
            })?;
            Vector3::new(roll, pitch, yaw)
        }
    };
    let mut fix_used = None;
    let lla = match cfg.initial.lla {
        Some(lla) => lla,
        None => {
            let fix = gnss.iter().find(|f| f.t >= t0 - 0.5).ok_or_else(|| {
                NavError(format!(
                    "no initial position given and no GNSS fix at or after t = {t0:.3}"
                ))
            })?;
            let l_n = c_bn_from_euler(&rpy) * cfg.gnss.lever_arm_b;
            fix_used = Some(fix.t);
            lla_add_ned(&fix.lla, &(-l_n))
        }
    };
    Ok((lla, rpy, fix_used))
}

/// Run the navigator over an IMU stream and a time-sorted list of GNSS fixes.
///
/// `on_output` is called at every IMU epoch (`output_period_s = None`) or at the
/// first epoch at or after each multiple of the period; `on_progress` every 8192
/// samples with the current time. The first IMU sample at or after
/// `cfg.start_time` fixes the initial epoch (its own interval is not integrated).
/// With alignment, the samples of the levelling window are buffered, the initial
/// attitude is computed, and the window is then navigated like any other data.
pub fn run<E: From<NavError>>(
    cfg: &NavConfig,
    imu: impl Iterator<Item = Result<ImuSample, E>>,
    gnss: &[GnssFix],
    output_period_s: Option<f64>,
    mut on_output: impl FnMut(&Navigator) -> Result<(), E>,
    mut on_progress: impl FnMut(f64),
) -> Result<RunSummary, E> {
    let end = cfg.end_time.unwrap_or(f64::INFINITY);
    let mut imu = imu.filter(|r| r.as_ref().map_or(true, |s| s.t >= cfg.start_time));
    // Initial epoch and, for alignment, the levelling window.
    let first = match imu.next() {
        Some(r) => r?,
        None => return Ok(RunSummary::default()),
    };
    let t0 = first.t;
    let mut window = Vec::new();
    if let AttitudeInit::LevelAndGnssCourse { level_window_s, .. } = cfg.initial.attitude {
        for r in imu.by_ref() {
            let s = r?;
            let full = s.t > t0 + level_window_s;
            window.push(s);
            if full {
                break;
            }
        }
    }
    let (lla0, rpy0, fix_used) =
        initial_pose(cfg, t0, &window[..window.len().saturating_sub(1)], gnss)?;
    let mut n = Navigator::new(cfg, t0, lla0, rpy0);
    let mut gi = 0usize;
    // Fixes up to the initial epoch are not used.
    while gi < gnss.len()
        && (gnss[gi].t + n.time_offset() <= t0 || fix_used.is_some_and(|t| gnss[gi].t <= t))
    {
        gi += 1;
    }
    n.summary.gnss_before_start = gi;
    let mut t_prev = t0 - n.time_offset();
    let period = output_period_s.filter(|p| *p > 0.0);
    for item in window.into_iter().map(Ok).chain(imu) {
        let s = item?;
        if s.t > end {
            break;
        }
        let mut rest = s;
        while gi < gnss.len() {
            let fix = &gnss[gi];
            let t_fix = fix.t + n.time_offset();
            if t_fix > s.t {
                break;
            }
            gi += 1;
            if cfg.gnss.outages.contains(fix.t) {
                n.summary.gnss_in_outage += 1;
                continue;
            }
            // Split the interval at the epoch unless it coincides with an end.
            let t_begin = rest.t - rest.dt;
            if t_fix > t_begin + 1e-9 && t_fix < rest.t - 1e-9 {
                let lambda = (t_fix - t_begin) / rest.dt;
                let first = ImuSample {
                    t: t_fix,
                    dt: rest.dt * lambda,
                    dtheta: rest.dtheta * lambda,
                    dvel: rest.dvel * lambda,
                };
                n.propagate(&first);
                rest = ImuSample {
                    t: rest.t,
                    dt: rest.dt - first.dt,
                    dtheta: rest.dtheta - first.dtheta,
                    dvel: rest.dvel - first.dvel,
                };
                n.update_gnss(fix);
            } else if t_fix >= rest.t - 1e-9 {
                n.propagate(&rest);
                rest.dt = 0.0;
                n.update_gnss(fix);
            } else {
                // At or before the start of this interval (e.g. after the time
                // offset estimate moved): apply now.
                n.update_gnss(fix);
            }
        }
        if rest.dt > 0.0 {
            n.propagate(&rest);
        }
        n.summary.imu_samples += 1;
        n.summary.last_t = s.t;
        if !n.nav_is_finite() || (n.summary.imu_samples % 256 == 0 && !n.covariance_is_finite()) {
            return Err(NavError(format!(
                "the navigation state stopped being finite at t = {:.3} (check the IMU units and axes, the initial attitude and the noise settings); the output before this epoch was written",
                s.t
            ))
            .into());
        }
        // Cadence on the time scale the records carry (GNSS time).
        let t_out = n.time_gnss();
        let due = match period {
            None => true,
            Some(p) => ((t_out + 1e-6) / p).floor() > ((t_prev + 1e-6) / p).floor(),
        };
        if due {
            n.summary.outputs += 1;
            on_output(&n)?;
        }
        if n.summary.imu_samples % 8192 == 0 {
            on_progress(s.t);
        }
        t_prev = t_out;
    }
    if let Some(i) = n.layout.index(Block::TimeOffset) {
        n.summary.time_offset = Some((n.time_offset_s, n.filter.std(i)));
    }
    if let Some(i) = n.layout.index(Block::TimeOffsetRate) {
        n.summary.time_offset_rate = Some((n.time_offset_rate, n.filter.std(i)));
    }
    Ok(n.summary.clone())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{
        FilterOptions, GnssOptions, ImuNoise, InitialState, DEFAULT_GATE_TIMEOUT_S,
    };
    use crate::earth::{gravity_normal, omega_ie_n};
    use crate::outage::OutageSchedule;

    fn cfg() -> NavConfig {
        let noise = ImuNoise {
            arw: Vector3::repeat(1e-5),
            vrw: Vector3::repeat(1e-4),
            gyro_bias_std: Vector3::repeat(1e-6),
            accel_bias_std: Vector3::repeat(1e-4),
            gyro_scale_std: Vector3::repeat(1e-4),
            accel_scale_std: Vector3::repeat(1e-4),
            corr_time_s: 3600.0,
        };
        NavConfig {
            initial: InitialState {
                lla: Some(Vector3::new(0.6, 2.0, 50.0)),
                v_n: Vector3::zeros(),
                attitude: AttitudeInit::Given(Vector3::new(0.0, 0.0, 0.3)),
                imu_errors: ImuErrors::default(),
                pos_std: Vector3::repeat(0.1),
                vel_std: Vector3::repeat(0.01),
                att_std: Vector3::repeat(0.001),
                imu_errors_std: ImuErrors {
                    gyro_bias: noise.gyro_bias_std,
                    accel_bias: noise.accel_bias_std,
                    gyro_scale: noise.gyro_scale_std,
                    accel_scale: noise.accel_scale_std,
                },
            },
            imu_noise: noise,
            gnss: GnssOptions {
                lever_arm_b: Vector3::new(0.5, 0.2, -1.0),
                use_velocity: false,
                position_std_override: None,
                velocity_std_override: None,
                gate_probability: None,
                gate_timeout_s: DEFAULT_GATE_TIMEOUT_S,
                outages: OutageSchedule::default(),
            },
            filter: FilterOptions {
                covariance_period_s: 0.0,
                time_offset: None,
            },
            start_time: f64::NEG_INFINITY,
            end_time: None,
        }
    }

    /// Exact increments of a stationary IMU over `dt` (gravity and Earth rate only).
    fn static_sample(c: &NavConfig, t: f64, dt: f64) -> ImuSample {
        let lla = c.initial.lla.unwrap();
        let AttitudeInit::Given(rpy) = c.initial.attitude else {
            unreachable!()
        };
        let c_nb = c_bn_from_euler(&rpy).transpose();
        let f_b = c_nb * Vector3::new(0.0, 0.0, -gravity_normal(lla.x, lla.z));
        let w_b = c_nb * omega_ie_n(lla.x);
        ImuSample {
            t,
            dt,
            dtheta: w_b * dt,
            dvel: f_b * dt,
        }
    }

    fn final_state(c: &NavConfig, imu: &[ImuSample], fixes: &[GnssFix]) -> (NavState, Vec<f64>) {
        let mut last = None;
        let mut times = Vec::new();
        run::<NavError>(
            c,
            imu.iter().map(|s| Ok(*s)),
            fixes,
            None,
            |n| {
                last = Some(*n.nav());
                times.push(n.nav().t);
                Ok(())
            },
            |_| {},
        )
        .unwrap();
        (last.unwrap(), times)
    }

    /// A GNSS epoch inside an IMU interval splits it: the result equals feeding the
    /// two halves as separate samples, and the update moves the state (it was applied).
    #[test]
    fn gnss_epoch_splits_the_imu_interval_exactly() {
        let c = cfg();
        let dt = 0.01;
        let t_fix = 0.5037; // inside (0.50, 0.51]
        let whole: Vec<ImuSample> = (0..=100)
            .map(|k| static_sample(&c, k as f64 * dt, dt))
            .collect();
        let mut split = Vec::new();
        for s in &whole {
            if s.t > t_fix && s.t - s.dt < t_fix {
                let a = t_fix - (s.t - s.dt);
                split.push(static_sample(&c, t_fix, a));
                split.push(static_sample(&c, s.t, s.dt - a));
            } else {
                split.push(*s);
            }
        }
        // The fix is 1 m north of where the antenna really is.
        let lla = c.initial.lla.unwrap();
        let AttitudeInit::Given(rpy) = c.initial.attitude else {
            unreachable!()
        };
        let ant = lla_add_ned(
            &lla,
            &(c_bn_from_euler(&rpy) * c.gnss.lever_arm_b + Vector3::new(1.0, 0.0, 0.0)),
        );
        let fixes = [GnssFix {
            t: t_fix,
            lla: ant,
            std_ned: Vector3::repeat(0.1),
            vel_ned: None,
            vel_std_ned: None,
        }];
        let (a, ta) = final_state(&c, &whole, &fixes);
        let (b, tb) = final_state(&c, &split, &fixes);
        assert!(
            crate::earth::lla_diff_ned(&a.lla, &b.lla).norm() < 1e-9,
            "{:?} {:?}",
            a.lla,
            b.lla
        );
        assert!((a.v_n - b.v_n).norm() < 1e-12);
        assert!(a.q_bn.angle_to(&b.q_bn) < 1e-12);
        // Half of the 1 m offset is taken in (equal position std of state and fix).
        let moved = crate::earth::lla_diff_ned(&a.lla, &lla);
        assert!((moved.x - 0.5).abs() < 0.01, "{moved:?}");
        // Output at every IMU epoch of the input (the split point is not an output).
        assert_eq!(ta.len(), 100);
        assert_eq!(tb.len(), 101);
    }

    /// An IMU stream in the wrong units drives the state to infinity: the run stops with
    /// an error naming the time instead of writing NaN.
    #[test]
    fn non_finite_state_stops_the_run() {
        let c = cfg();
        let imu: Vec<ImuSample> = (0..=2000)
            .map(|k| {
                let mut s = static_sample(&c, k as f64 * 0.01, 0.01);
                s.dvel *= 1e150; // absurd units
                s
            })
            .collect();
        let mut outputs = 0;
        let r = run::<NavError>(
            &c,
            imu.iter().map(|s| Ok(*s)),
            &[],
            None,
            |n| {
                assert!(n.nav_is_finite());
                outputs += 1;
                Ok(())
            },
            |_| {},
        );
        let e = r.expect_err("must stop");
        assert!(e.0.contains("stopped being finite at t = "), "{e}");
        assert!(outputs > 0 && outputs < 2000);
    }

    /// With an output period, one output at the first epoch at or after each multiple.
    #[test]
    fn output_period_picks_one_epoch_per_period() {
        let c = cfg();
        let imu: Vec<ImuSample> = (0..=1000)
            .map(|k| static_sample(&c, 100.0 + k as f64 * 0.005, 0.005))
            .collect();
        let mut times = Vec::new();
        run::<NavError>(
            &c,
            imu.iter().map(|s| Ok(*s)),
            &[],
            Some(0.1),
            |n| {
                times.push(n.nav().t);
                Ok(())
            },
            |_| {},
        )
        .unwrap();
        assert_eq!(times.len(), 50);
        assert!(
            (times[0] - 100.1).abs() < 1e-9 && (times[49] - 105.0).abs() < 1e-9,
            "{times:?}"
        );
    }

    /// Fixes inside an outage window are withheld and counted; those at its ends are used.
    #[test]
    fn outage_windows_withhold_fixes() {
        let mut c = cfg();
        c.gnss.outages = OutageSchedule::parse("1:3").unwrap();
        let imu: Vec<ImuSample> = (0..=500)
            .map(|k| static_sample(&c, k as f64 * 0.01, 0.01))
            .collect();
        let lla = c.initial.lla.unwrap();
        let AttitudeInit::Given(rpy) = c.initial.attitude else {
            unreachable!()
        };
        let ant = lla_add_ned(&lla, &(c_bn_from_euler(&rpy) * c.gnss.lever_arm_b));
        let fixes: Vec<GnssFix> = (1..=4)
            .map(|k| GnssFix {
                t: k as f64,
                lla: ant,
                std_ned: Vector3::repeat(0.1),
                vel_ned: None,
                vel_std_ned: None,
            })
            .collect();
        let s = run::<NavError>(
            &c,
            imu.iter().map(|s| Ok(*s)),
            &fixes,
            None,
            |_| Ok(()),
            |_| {},
        )
        .unwrap();
        assert_eq!((s.gnss_used, s.gnss_in_outage), (3, 1));
    }
}
