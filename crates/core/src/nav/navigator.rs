//! The navigator: the INS with its error-state filter (ins_filter.rs) and the aiding
//! sources of the registry. One IMU step (`Navigator::step`) reads like the
//! algorithm: cut the interval at each measurement due in it, propagate up to it,
//! hand the measurement to the sources; then the cadence-driven sources; then the
//! finiteness check.
//!
//! Time handling: a measurement that falls inside an IMU interval splits it (the
//! increments are shared in proportion to time), so the update happens exactly at
//! its epoch (REFERENCES \[SYS\] §1, seed 000 eq. 31-32; timeline.rs).

use super::ins_filter::InsFilter;
use super::timeline::{Due, Inbox, IntervalRest, ReverseInbox, ReverseRest, TimeDirection};
use crate::aiding::registry;
use crate::aiding::source::{AidingSource, Fuser, Shared};
use crate::aiding::VehicleEstimate;
use crate::attitude::{euler_from_c_bn, euler_from_q_bn};
use crate::config::NavConfig;
use crate::events::{AidStatus, Event, InnovationRow, RunSummary, SolutionState};
use crate::integrity::IntegrityState;
use crate::smoother::em::FusedUpdate;
use crate::smoother::{Nominal, RtsRecord};
use crate::state::{Block, StateLayout, ATT, N_INS, POS, VEL};
use crate::types::{ImuErrors, ImuSample, Measurement, NavState};
use nalgebra::{DMatrix, Vector3};

/// Correlation time of the unknown manoeuvres over an IMU gap \[s\]: the velocity
/// random walk's PSD is gap_accel² x this.
const GAP_MANOEUVRE_S: f64 = 1.0;

/// IMU intervals longer than this (and than 5 nominal intervals) are gaps \[s\].
const GAP_MIN_S: f64 = 0.1;

/// Why a run could not start or had to stop (no initial pose, numerical failure).
#[derive(Clone, Debug, PartialEq)]
pub struct NavError(pub String);

impl std::fmt::Display for NavError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for NavError {}

/// INS + filter + aiding sources.
pub struct Navigator {
    ins: InsFilter,
    sources: Vec<Box<dyn AidingSource>>,
    /// The uniform status of each source (same order).
    status: Vec<AidStatus>,
    shared: Shared,
    summary: RunSummary,
    /// Shortest IMU interval over the first 100 samples (IMU gap detection) \[s\].
    nominal_dt: f64,
}

impl Navigator {
    /// Initialise at time `t0` with position `lla` (IMU centre) and attitude `rpy`
    /// \[rad\]; velocity, IMU errors and uncertainties from `cfg.initial`.
    pub fn new(cfg: &NavConfig, t0: f64, lla: Vector3<f64>, rpy: Vector3<f64>) -> Self {
        Self::with_velocity(cfg, t0, lla, rpy, cfg.initial.v_n)
    }

    /// As [`Navigator::new`] with an initial NED velocity \[m/s\].
    pub fn with_velocity(
        cfg: &NavConfig,
        t0: f64,
        lla: Vector3<f64>,
        rpy: Vector3<f64>,
        v_n: Vector3<f64>,
    ) -> Self {
        Self::with_sources(cfg, t0, lla, rpy, v_n, registry::sources(cfg, t0))
    }

    /// As [`Navigator::with_velocity`] with these aiding sources (the registry's,
    /// `registry::sources`, plus any of your own).
    pub fn with_sources(
        cfg: &NavConfig,
        t0: f64,
        lla: Vector3<f64>,
        rpy: Vector3<f64>,
        v_n: Vector3<f64>,
        sources: Vec<Box<dyn AidingSource>>,
    ) -> Self {
        let blocks: Vec<_> = sources.iter().flat_map(|s| s.blocks()).collect();
        let track = sources.iter().any(|s| s.tracks_displacement());
        let ins = InsFilter::new(cfg, t0, lla, rpy, v_n, &blocks, track);
        Navigator {
            status: sources
                .iter()
                .map(|s| AidStatus {
                    name: s.name(),
                    ..Default::default()
                })
                .collect(),
            sources,
            ins,
            shared: Shared {
                last_gnss_used_t: t0,
                is_static: false,
                gnss_fused_t: None,
                gnss_interval_s: None,
                vehicle_fused_t: None,
            },
            summary: RunSummary {
                first_t: t0,
                last_t: t0,
                ..Default::default()
            },
            nominal_dt: f64::INFINITY,
        }
    }

    /// The solution: the navigation state, or with `GnssFusion::SixState` the
    /// six-state filter's position and velocity with the dead reckoning's attitude.
    pub fn nav(&self) -> &NavState {
        if self.ins.six_state.is_some() {
            &self.ins.six_state_out
        } else {
            &self.ins.nav
        }
    }

    /// The error-state filter's own navigation state (with `GnssFusion::SixState`
    /// the dead reckoning without GNSS; otherwise the same as [`Navigator::nav`]).
    pub fn dr_nav(&self) -> &NavState {
        &self.ins.nav
    }

    pub fn imu_errors(&self) -> &ImuErrors {
        &self.ins.imu_errors
    }

    pub fn layout(&self) -> &StateLayout {
        &self.ins.layout
    }

    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.ins.filter.p
    }

    /// Current installation estimates (mounting C_b^m, odometer scale).
    pub fn vehicle(&self) -> &VehicleEstimate {
        &self.ins.vehicle
    }

    /// True while the static detector sees the vehicle at rest.
    pub fn is_static(&self) -> bool {
        self.shared.is_static
    }

    /// Current GNSS-IMU time offset estimate \[s\] (0 when not estimated): a GNSS
    /// epoch tagged t is applied at IMU time t + offset.
    pub fn time_offset(&self) -> f64 {
        self.ins.time_offset_s
    }

    /// Current GNSS-IMU time offset rate \[s/s\].
    pub fn time_offset_rate(&self) -> f64 {
        self.ins.time_offset_rate
    }

    /// Time of the current state on the GNSS (GPS) time scale: the IMU time tag
    /// minus the estimated GNSS-IMU offset. Solutions are written with this time.
    pub fn time_gnss(&self) -> f64 {
        self.ins.time_gnss()
    }

    /// 1-sigma of the 21 INS states in SI units (pos N E D, vel N E D, att r p y,
    /// gyro bias, accel bias, gyro scale, accel scale), as of the last covariance
    /// propagation or update.
    pub fn std21(&self) -> [f64; N_INS] {
        self.ins.std21()
    }

    /// Sums of the raw IMU increments integrated so far: (dt \[s\], dtheta \[rad\],
    /// dvel \[m/s\]), body frame (negative in a backward run, which integrates them
    /// time-reversed).
    pub fn integrated(&self) -> (f64, Vector3<f64>, Vector3<f64>) {
        self.ins.integrated
    }

    /// Which way the run goes in time (backward: nav/backward.rs).
    pub fn direction(&self) -> TimeDirection {
        self.ins.direction
    }

    /// Make this navigator run backward in time (before its first step).
    pub(crate) fn reverse_time(&mut self) {
        self.ins.direction = TimeDirection::Backward;
    }

    pub fn summary(&self) -> &RunSummary {
        &self.summary
    }

    /// The uniform status of each aiding source, in registry order.
    pub fn aid_status(&self) -> &[AidStatus] {
        &self.status
    }

    /// Roll, pitch, yaw \[rad\] of the current attitude.
    pub fn rpy(&self) -> Vector3<f64> {
        euler_from_q_bn(&self.ins.nav.q_bn)
    }

    /// Integrity state of the GNSS (trusted when no monitor runs).
    pub fn integrity_state(&self) -> IntegrityState {
        self.sources
            .iter()
            .find_map(|s| s.integrity_state())
            .unwrap_or(IntegrityState::Trusted)
    }

    /// What aided the solution lately ([`SolutionState`]): GNSS counts when a GNSS
    /// epoch was fused within 1.5 of its intervals + 0.5 s (1 s until two are
    /// seen), odometer / NHC within 1 s.
    pub fn solution_state(&self) -> SolutionState {
        if matches!(
            self.integrity_state(),
            IntegrityState::Spoofed | IntegrityState::Recovering
        ) {
            return SolutionState::GnssExcluded;
        }
        if self.shared.is_static {
            return SolutionState::Static;
        }
        let now = self.time_gnss();
        let recent = |t: Option<f64>, window: f64| t.is_some_and(|t| (now - t).abs() <= window);
        let gnss_window = 1.5 * self.shared.gnss_interval_s.unwrap_or(1.0) + 0.5;
        if recent(self.shared.gnss_fused_t, gnss_window) {
            SolutionState::Gnss
        } else if recent(self.shared.vehicle_fused_t, 1.0) {
            SolutionState::DeadReckoning
        } else {
            SolutionState::Inertial
        }
    }

    /// Log every update tried from now on ([`InnovationRow`]), taken with
    /// [`Navigator::take_innovations`].
    pub fn log_innovations(&mut self) {
        self.ins.innovations = Some(Vec::new());
    }

    /// The updates tried since the last call (empty when not logging).
    pub fn take_innovations(&mut self) -> Vec<InnovationRow> {
        self.ins
            .innovations
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// True while position, velocity and attitude are finite numbers.
    pub fn nav_is_finite(&self) -> bool {
        self.ins.nav_is_finite()
    }

    /// Record what the RTS smoother needs from now on (crate::smoother): one
    /// record per covariance epoch, taken with [`Navigator::take_smoother_records`].
    pub fn record_for_smoothing(&mut self) {
        self.ins.start_recording();
    }

    /// While recording for the smoother: log every applied update for noise
    /// identification (smoother/em.rs), taken with [`Navigator::take_updates`].
    pub fn log_updates(&mut self) {
        self.ins.update_log = Some(Vec::new());
    }

    /// The updates applied since the last call (empty when not logging).
    pub fn take_updates(&mut self) -> Vec<FusedUpdate> {
        self.ins
            .update_log
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Index of the smoother record the current epoch belongs to (the last one
    /// started); None when not recording.
    pub fn smoother_record_index(&self) -> Option<u64> {
        self.ins.recorder.as_ref().map(|r| r.current_index())
    }

    /// The smoother records closed since the last call (after
    /// [`Navigator::finish`], the last one too).
    pub fn take_smoother_records(&mut self) -> Vec<RtsRecord> {
        match self.ins.recorder.as_mut() {
            Some(r) => r.drain().collect(),
            None => Vec::new(),
        }
    }

    /// Everything of the filter's state but the covariance (the error-state
    /// filter's own, also with `GnssFusion::SixState`).
    pub fn nominal(&self) -> Nominal {
        self.ins.nominal()
    }

    /// Six-state fusion runs (its filter could be started).
    pub(crate) fn has_six_state(&self) -> bool {
        self.ins.six_state.is_some()
    }

    pub(crate) fn push_event(&mut self, e: Event) {
        self.summary.events.push(e);
    }

    pub(crate) fn summary_mut(&mut self) -> &mut RunSummary {
        &mut self.summary
    }

    /// Call `f` on every source with its fuser, in registry order.
    fn each_source(&mut self, mut f: impl FnMut(&mut dyn AidingSource, &mut Fuser)) {
        for (src, status) in self.sources.iter_mut().zip(self.status.iter_mut()) {
            let mut fuser = Fuser {
                ins: &mut self.ins,
                record: &mut self.summary,
                shared: &mut self.shared,
                status,
            };
            f(src.as_mut(), &mut fuser);
        }
    }

    /// Advance over one raw IMU interval (or a piece of one).
    pub fn propagate(&mut self, raw: &ImuSample) {
        let s = self.ins.propagate(raw);
        self.each_source(|src, f| src.on_propagate(&s, f));
    }

    /// [`Navigator::propagate`]; over a piece of an IMU gap the velocity and attitude
    /// variances first grow by the plausible motion the bridged increments do not see:
    /// random walks of PSD (a T²/2)²/T, a² T and w² T for position, velocity and
    /// attitude (`filter.gap_accel_mps2`, `gap_rate`; T = [`GAP_MANOEUVRE_S`]), linear
    /// in dt so the total does not depend on where measurements cut the gap.
    fn propagate_bridged(&mut self, raw: &ImuSample, gap: bool) {
        // Backward the piece is time-reversed (dt < 0): the same growth over |dt|.
        if gap && raw.dt != 0.0 {
            let f = &self.ins.cfg.filter;
            let (a, w, t, dt) = (f.gap_accel_mps2, f.gap_rate, GAP_MANOEUVRE_S, raw.dt.abs());
            self.ins
                .widen(POS, Vector3::repeat(0.25 * a * a * t.powi(3) * dt));
            self.ins.widen(VEL, Vector3::repeat(a * a * t * dt));
            self.ins.widen(ATT, Vector3::repeat(w * w * t * dt));
        }
        self.propagate(raw);
    }

    /// Hand one time-tagged input (already reached in time) to the sources.
    pub fn apply(&mut self, m: &Measurement) {
        self.each_source(|src, f| {
            src.on_measurement(m, f);
        });
    }

    /// The cadence-driven sources after the IMU sample that ended at the current
    /// time (static detection with ZUPT/ZARU, then the NHC while moving).
    pub fn apply_constraints(&mut self) {
        self.each_source(|src, f| src.after_imu(f));
    }

    /// One IMU step: the interval (imu.t - imu.dt, imu.t] with every measurement
    /// of `inbox` due in it (timeline.rs), then the cadence-driven sources, then the
    /// finiteness check.
    pub fn step(&mut self, imu: &ImuSample, inbox: &mut Inbox) -> Result<(), NavError> {
        let s = *imu;
        let gap = self.begin_step(&s);
        // Each measurement due in (t_k - dt, t_k]: integrate up to its time, apply it.
        let mut rest = IntervalRest::new(s);
        while let Some(due) = inbox.next_due_in(s.t - s.dt, s.t, self.time_offset()) {
            match due {
                Due::Withheld(m) => self.count_withheld(m),
                Due::Apply { m, t_eff } => {
                    if let Some(piece) = rest.cut_until(t_eff) {
                        self.propagate_bridged(&piece, gap);
                    }
                    self.apply(m);
                }
            }
        }
        if let Some(piece) = rest.take_rest() {
            self.propagate_bridged(&piece, gap);
        }
        self.end_step(s.t)
    }

    /// One IMU step of a backward run (nav/backward.rs): the interval (imu.t - imu.dt,
    /// imu.t] integrated from imu.t down to imu.t - imu.dt, cut at every measurement of
    /// `inbox` due in it (from the latest), then the cadence-driven sources, then the
    /// finiteness check.
    pub(crate) fn step_backward(
        &mut self,
        imu: &ImuSample,
        inbox: &mut ReverseInbox,
    ) -> Result<(), NavError> {
        let s = *imu;
        let gap = self.begin_step(&s);
        let mut rest = ReverseRest::new(s);
        while let Some(due) = inbox.next_due_in(s.t - s.dt, s.t, self.time_offset()) {
            match due {
                Due::Withheld(m) => self.count_withheld(m),
                Due::Apply { m, t_eff } => {
                    if let Some(piece) = rest.cut_until(t_eff) {
                        self.propagate_bridged(&piece, gap);
                    }
                    self.apply(m);
                }
            }
        }
        if let Some(piece) = rest.take_rest() {
            self.propagate_bridged(&piece, gap);
        }
        self.end_step(rest.t_reached())
    }

    /// Before the interval of `s`: IMU gap detection. True when it is a gap.
    fn begin_step(&mut self, s: &ImuSample) -> bool {
        // A gap the reader bridged: the INS knows nothing of the motion over it.
        if self.summary.imu_samples < 100 && s.dt > 0.0 {
            self.nominal_dt = self.nominal_dt.min(s.dt);
        }
        let gap = s.dt > GAP_MIN_S.max(5.0 * self.nominal_dt);
        if gap {
            self.push_event(Event::ImuGap {
                t: s.t - s.dt,
                dt: s.dt,
            });
            for src in &mut self.sources {
                src.on_imu_gap();
            }
        }
        gap
    }

    fn count_withheld(&mut self, m: &Measurement) {
        if matches!(m, Measurement::Gnss(_) | Measurement::GnssRaw(_)) {
            self.summary.gnss_in_outage += 1;
        }
    }

    /// After the interval, at time `t`: the cadence-driven sources, the counters and
    /// the finiteness check.
    fn end_step(&mut self, t: f64) -> Result<(), NavError> {
        self.apply_constraints();
        self.summary.imu_samples += 1;
        self.summary.last_t = t;
        if !self.ins.nav_is_finite()
            || (self.summary.imu_samples.is_multiple_of(256) && !self.ins.covariance_is_finite())
        {
            return Err(NavError(format!(
                "the navigation state stopped being finite at t = {t:.3} (check the IMU units and axes, the initial attitude and the noise settings); the output before this epoch was written"
            )));
        }
        Ok(())
    }

    /// The end-of-run summary with the final estimates.
    pub fn finish(&mut self) -> RunSummary {
        if let Some(r) = self.ins.recorder.as_mut() {
            r.finish(&self.ins.filter.p);
        }
        let ins = &self.ins;
        let s = &mut self.summary;
        if let Some(i) = ins.layout.index(Block::TimeOffset) {
            s.time_offset = Some((ins.time_offset_s, ins.filter.std(i)));
        }
        if let Some(i) = ins.layout.index(Block::TimeOffsetRate) {
            s.time_offset_rate = Some((ins.time_offset_rate, ins.filter.std(i)));
        }
        if let Some(i) = ins.layout.index(Block::OdometerScale) {
            s.odometer_scale = Some((ins.vehicle.odometer_scale, ins.filter.std(i)));
        }
        if let Some(a) = &ins.adaptive {
            s.adaptive_noise = a.posteriors().to_vec();
        }
        let mut summary = self.summary.clone();
        summary.source_states = self.ins.source_states();
        for (src, status) in self.sources.iter().zip(self.status.iter_mut()) {
            let fuser = Fuser {
                ins: &mut self.ins,
                record: &mut self.summary,
                shared: &mut self.shared,
                status,
            };
            src.finish(&fuser, &mut summary);
        }
        let ins = &self.ins;
        if let Some(i) = ins.layout.index(Block::Mounting) {
            summary.mounting = Some((
                euler_from_c_bn(&ins.vehicle.c_bm),
                [ins.filter.std(i), ins.filter.std(i + 1)],
            ));
        }
        summary.aid_status = self.status.clone();
        self.summary = summary.clone();
        summary
    }
}
