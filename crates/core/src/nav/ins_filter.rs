//! The INS and its closed-loop error-state filter: the nominal state, the error
//! covariance, the nominal values of the extra state blocks the aiding sources append,
//! and the three operations of the filter (KF-GINS's shape): propagate, update, feed
//! back.
//!
//! The covariance is propagated every `covariance_period_s` (and always right before
//! an update) with the transition matrix built from the mean specific force and rate
//! over that span (docs/ALGORITHMS.md "Error-state filter"; REFERENCES \[SYS\] §2).

use crate::aiding::adaptive::AdaptiveNoise;
use crate::aiding::{AidingContext, Linearized, ReceiverClock, VehicleEstimate};
use crate::attitude::{c_bn_from_euler, q_bn_from_euler};
use crate::config::{NavConfig, NhcMode};
use crate::earth::lla_to_ecef;
use crate::error_model::{fill_f, fill_qc, Discretizer, MeanMotion};
use crate::events::InnovationRow;
use crate::filter::{Eskf, RowTerms, SequentialRow, UpdateOutcome};
use crate::mechanization::Mechanizer;
use crate::nav::timeline::TimeDirection;
use crate::six_state::SixState;
use crate::smoother::em::FusedUpdate;
use crate::smoother::nominal::{correct, source_ranges, Nominal, NominalMut};
use crate::smoother::record::{Recorder, Transition};
use crate::state::{Block, StateLayout, ATT, BA, BG, N_INS, POS, SA, SG, VEL};
use crate::types::{ImuErrors, ImuSample, NavState};
use nalgebra::{DMatrix, DVector, Vector3};

/// How the error states of a source's block evolve between updates.
#[derive(Clone, Debug, PartialEq)]
pub enum BlockProcess {
    /// Random walk with this PSD per state \[unit²/s\].
    RandomWalk(f64),
    /// First-order Gauss-Markov with correlation time `corr_time_s` and steady-state
    /// sigma per state (the nominal value decays with it too); exact discretisation.
    GaussMarkov { corr_time_s: f64, sigma: Vec<f64> },
}

/// A block of error states a source appends to the filter.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockSpec {
    pub block: Block,
    /// Initial variance of each of its states.
    pub initial_variance: Vec<f64>,
    pub process: BlockProcess,
}

#[derive(Clone, Copy, Debug, Default)]
struct Accum {
    dt: f64,
    dv_f_n: Vector3<f64>,
    dtheta: Vector3<f64>,
    dvel: Vector3<f64>,
}

/// A source-owned block: where it is, how it evolves.
#[derive(Clone, Debug)]
struct SourceBlock {
    block: Block,
    index: usize,
    /// None only for a block already pushed by the INS layout.
    process: Option<BlockProcess>,
}

/// INS + error-state filter + extra states.
pub struct InsFilter {
    pub(crate) cfg: NavConfig,
    pub(crate) layout: StateLayout,
    pub(crate) filter: Eskf,
    disc: Discretizer,
    mech: Mechanizer,
    pub(crate) nav: NavState,
    pub(crate) imu_errors: ImuErrors,
    /// Installation estimates (mounting, odometer scale): filter states the
    /// odometer and the NHC both read.
    pub(crate) vehicle: VehicleEstimate,
    /// GNSS-IMU time offset tau0 + rate (t - t0) \[s\], \[s/s\] (timeline.rs).
    pub(crate) time_offset_s: f64,
    pub(crate) time_offset_rate: f64,
    acc: Accum,
    /// Compensated angular rate over the last IMU interval \[rad/s\].
    pub(crate) w_ib_b: Vector3<f64>,
    /// Acceleration d(v^n)/dt over the last IMU interval \[m/s²\].
    pub(crate) a_n: Vector3<f64>,
    /// Running sum of the mechanization's own velocity increments (no feedback), NED
    /// \[m/s\].
    pub(crate) mech_dv_n: Vector3<f64>,
    /// Sums of the raw IMU increments integrated so far (dt, dtheta, dvel).
    pub(crate) integrated: (f64, Vector3<f64>, Vector3<f64>),
    /// Nominal values of the source-owned blocks, by state index.
    extra: DVector<f64>,
    source_blocks: Vec<SourceBlock>,
    random_walks: Vec<(Block, f64)>,
    /// The INS displacement since `restart_displacement` from the mechanization only
    /// (feedback jumps excluded), ECEF \[m\], and the ECEF position after the last
    /// mechanization step or feedback; tracked when a source asks (TDCP).
    displacement: Option<(Vector3<f64>, Vector3<f64>)>,
    /// Feedbacks applied so far (sources that keep a reference to the INS position
    /// see its jumps by this count).
    pub(crate) corrections: u64,
    /// `GnssFusion::SixState`: the six-state filter that takes the fixes (six_state.rs)
    /// and the output solution built from it; this filter is then a dead reckoning.
    pub(crate) six_state: Option<SixState>,
    pub(crate) six_state_out: NavState,
    /// What the RTS smoother needs, when the run records for it (smoother/record.rs).
    pub(crate) recorder: Option<Recorder>,
    /// Every update tried since the last drain, when the run logs them
    /// (`innovations.csv`).
    pub(crate) innovations: Option<Vec<InnovationRow>>,
    /// Every update applied since the last drain, for noise identification (while
    /// recording for the smoother; smoother/em.rs).
    pub(crate) update_log: Option<Vec<FusedUpdate>>,
    /// Which way the run goes in time (nav/backward.rs: backward, the IMU pieces
    /// come time-reversed, dt < 0).
    pub(crate) direction: TimeDirection,
    /// The adaptive measurement-noise estimate, when on (aiding/adaptive.rs).
    pub(crate) adaptive: Option<AdaptiveNoise>,
}

/// What an update applied.
#[derive(Clone, Debug, PartialEq)]
pub enum Fused {
    /// Applied: the error-state correction dx that was fed back (state.rs
    /// conventions; dx\[0..3\] the position error, NED \[m\]).
    Applied(DVector<f64>),
    Rejected,
    Singular,
    /// The source had nothing to offer (e.g. a fix without velocity).
    NotApplicable,
}

impl Fused {
    pub fn applied(&self) -> bool {
        matches!(self, Fused::Applied(_))
    }

    /// The position correction fed back, NED \[m\] (x_est - x_true convention).
    pub fn position_correction(&self) -> Option<Vector3<f64>> {
        match self {
            Fused::Applied(dx) => Some(Vector3::new(dx[POS], dx[POS + 1], dx[POS + 2])),
            _ => None,
        }
    }
}

/// The INS-level blocks, in layout order: time offset (and rate), odometer scale,
/// mounting. The sources' own blocks follow in registry order.
fn ins_layout(cfg: &NavConfig) -> StateLayout {
    let mut layout = StateLayout::ins21();
    if let Some(to) = cfg.filter.time_offset {
        if to.std_s > 0.0 {
            layout.push(Block::TimeOffset);
            if to.rate_std > 0.0 {
                layout.push(Block::TimeOffsetRate);
            }
        }
    }
    let odo = &cfg.odometer;
    if odo.enabled && odo.scale_std > 0.0 {
        layout.push(Block::OdometerScale);
    }
    if cfg.vehicle.mounting_std > 0.0 && (odo.enabled || cfg.nhc.mode != NhcMode::Off) {
        layout.push(Block::Mounting);
    }
    layout
}

impl InsFilter {
    /// The filter at `t0` with position `lla`, attitude `rpy` \[rad\] and velocity
    /// `v_n`; `blocks`: the sources' blocks with their initial variances per state.
    pub(crate) fn new(
        cfg: &NavConfig,
        t0: f64,
        lla: Vector3<f64>,
        rpy: Vector3<f64>,
        v_n: Vector3<f64>,
        blocks: &[BlockSpec],
        track_displacement: bool,
    ) -> Self {
        let mut layout = ins_layout(cfg);
        let mut source_blocks = Vec::new();
        for spec in blocks {
            if layout.index(spec.block).is_none() {
                let index = layout.push(spec.block);
                source_blocks.push(SourceBlock {
                    block: spec.block,
                    index,
                    process: Some(spec.process.clone()),
                });
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
        let odo = &cfg.odometer;
        if let Some(i) = layout.index(Block::OdometerScale) {
            p0[i] = odo.scale_std.powi(2);
        }
        if let Some(i) = layout.index(Block::Mounting) {
            p0[i] = cfg.vehicle.mounting_std.powi(2);
            p0[i + 1] = cfg.vehicle.mounting_std.powi(2);
        }
        for spec in blocks {
            if let Some(i) = layout.index(spec.block) {
                let var = &spec.initial_variance;
                for (k, v) in var.iter().enumerate().take(spec.block.len()) {
                    p0[i + k] = *v;
                }
            }
        }
        let nav = NavState {
            t: t0,
            lla,
            v_n,
            q_bn: q_bn_from_euler(&rpy),
        };
        let p0 = DMatrix::from_diagonal(&p0);
        InsFilter {
            six_state: crate::aiding::gnss_six_state::new_six_state(cfg, &nav, &p0),
            six_state_out: nav,
            cfg: cfg.clone(),
            filter: Eskf::new(p0),
            disc: Discretizer::new(n),
            layout,
            mech: Mechanizer::new(),
            nav,
            imu_errors: ini.imu_errors,
            vehicle: VehicleEstimate {
                c_bm: c_bn_from_euler(&cfg.vehicle.mounting_rpy),
                lever_arm_b: cfg.vehicle.lever_arm_b,
                odometer_scale: odo.scale_initial,
            },
            time_offset_s,
            time_offset_rate,
            acc: Accum::default(),
            w_ib_b: Vector3::zeros(),
            a_n: Vector3::zeros(),
            mech_dv_n: Vector3::zeros(),
            integrated: (0.0, Vector3::zeros(), Vector3::zeros()),
            extra: DVector::zeros(n),
            source_blocks,
            random_walks: Vec::new(),
            displacement: track_displacement.then(|| (Vector3::zeros(), lla_to_ecef(&lla))),
            corrections: 0,
            recorder: None,
            innovations: None,
            update_log: None,
            direction: TimeDirection::Forward,
            adaptive: cfg.filter.adaptive_noise.clone().map(AdaptiveNoise::new),
        }
    }

    /// Set the process model of a source's block (kept until set again).
    pub(crate) fn set_process(&mut self, block: Block, process: BlockProcess) {
        if let Some(sb) = self.source_blocks.iter_mut().find(|s| s.block == block) {
            sb.process = Some(process);
        }
    }

    /// Nominal values of a source's block (empty when the layout lacks it).
    pub(crate) fn extra(&self, block: Block) -> &[f64] {
        match self.layout.index(block) {
            Some(i) => &self.extra.as_slice()[i..i + block.len()],
            None => &[],
        }
    }

    pub(crate) fn extra_mut(&mut self, block: Block) -> &mut [f64] {
        match self.layout.index(block) {
            Some(i) => &mut self.extra.as_mut_slice()[i..i + block.len()],
            None => &mut [],
        }
    }

    /// Time of the current state on the GNSS time scale \[s\].
    pub(crate) fn time_gnss(&self) -> f64 {
        self.nav.t - self.time_offset_s
    }

    /// Advance over one raw IMU interval; returns the compensated sample. Backward
    /// the interval comes time-reversed (timeline::ReverseRest: dt < 0, increments
    /// negated), and so do the compensated sample, the sums and the accumulated span.
    pub(crate) fn propagate(&mut self, raw: &ImuSample) -> ImuSample {
        let sum = &mut self.integrated;
        *sum = (sum.0 + raw.dt, sum.1 + raw.dtheta, sum.2 + raw.dvel);
        let s = self.imu_errors.compensate(raw);
        // The offset line tau0 + rate (t - t0) follows elapsed time (after an IMU gap
        // the interval's dt is shorter than the time that passed).
        self.time_offset_s += self.time_offset_rate * (raw.t - self.nav.t);
        let v_before = self.nav.v_n;
        let (next, info) = self.mech.step(&self.nav, &s);
        self.mech_dv_n += next.v_n - v_before;
        self.nav = next;
        if let Some((d, last)) = self.displacement.as_mut() {
            let r = lla_to_ecef(&self.nav.lla);
            *d += r - *last;
            *last = r;
        }
        if s.dt != 0.0 {
            self.w_ib_b = s.dtheta / s.dt;
            self.a_n = (self.nav.v_n - v_before) / s.dt;
        }
        self.acc.dt += s.dt;
        self.acc.dv_f_n += info.dv_f_n;
        self.acc.dtheta += s.dtheta;
        self.acc.dvel += s.dvel;
        if self.acc.dt.abs() >= self.cfg.filter.covariance_period_s - 1e-9 {
            self.flush_covariance();
        }
        self.six_state_follow_dr();
        s
    }

    /// `GnssFusion::SixState`: move the six-state filter by the dead reckoning's
    /// increments since the last call and refresh the output solution.
    pub(crate) fn six_state_follow_dr(&mut self) {
        if let Some(six) = self.six_state.as_mut() {
            six.follow_dr(&self.nav);
            self.six_state_out = six.solution(&self.nav);
        }
    }

    /// Add `var` to the variances of the 3-state block starting at `block` (the
    /// covariance brought up to date first): what re-admissions and gaps widen.
    pub(crate) fn widen(&mut self, block: usize, var: Vector3<f64>) {
        self.flush_covariance();
        for k in 0..3 {
            self.record(Transition::AddVariance(block + k, var[k]));
            self.filter.p[(block + k, block + k)] += var[k];
        }
    }

    /// Propagate the covariance over the accumulated span (REFERENCES \[SYS\] §2).
    pub(crate) fn flush_covariance(&mut self) {
        let a = self.acc;
        if a.dt == 0.0 {
            return;
        }
        let mm = MeanMotion {
            f_n: a.dv_f_n / a.dt,
            f_b: a.dvel / a.dt,
            w_b: a.dtheta / a.dt,
        };
        self.random_walks.clear();
        self.random_walks.push((
            Block::TimeOffset,
            self.cfg.filter.time_offset.map_or(0.0, |t| t.random_walk),
        ));
        self.random_walks
            .push((Block::OdometerScale, self.cfg.odometer.scale_random_walk));
        for sb in &self.source_blocks {
            if let Some(BlockProcess::RandomWalk(psd)) = sb.process {
                self.random_walks.push((sb.block, psd));
            }
        }
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
            &self.random_walks,
        );
        for sb in &self.source_blocks {
            if let Some(BlockProcess::GaussMarkov { corr_time_s, sigma }) = &sb.process {
                // First-order Gauss-Markov (fix_error.rs): F = -1/tau, Qc = 2 sigma²/tau;
                // the nominal value decays with it.
                let (i, tau) = (sb.index, *corr_time_s);
                for (k, s) in sigma.iter().enumerate().take(sb.block.len()) {
                    self.disc.f[(i + k, i + k)] = -1.0 / tau;
                    self.disc.qc[(i + k, i + k)] = 2.0 * s.powi(2) / tau;
                }
                let e = (-a.dt.abs() / tau).exp();
                for k in 0..sb.block.len() {
                    self.extra[i + k] *= e;
                }
            }
        }
        self.disc.discretize(a.dt);
        if a.dt < 0.0 {
            // Backward: the IMU errors' Gauss-Markov rows decay with |dt|.
            self.disc.reverse_gauss_markov(BG..SA + 3, a.dt);
        }
        for sb in &self.source_blocks {
            if let Some(BlockProcess::GaussMarkov { corr_time_s, sigma }) = &sb.process {
                // Exact discretisation (a long span, e.g. a bridged IMU gap, must not
                // take Phi below zero).
                let (i, tau) = (sb.index, *corr_time_s);
                let e = (-a.dt.abs() / tau).exp();
                for (k, s) in sigma.iter().enumerate().take(sb.block.len()) {
                    self.disc.phi[(i + k, i + k)] = e;
                    self.disc.qd[(i + k, i + k)] = s.powi(2) * (1.0 - e * e);
                }
            }
        }
        if let Some(r) = self.recorder.as_mut() {
            let tr = Transition::Propagate(&self.disc.phi, &self.disc.qd);
            r.transition(self.nav.t, tr, &self.filter.p);
        }
        self.filter.predict(&self.disc.phi, &self.disc.qd);
        if let Some(six) = self.six_state.as_mut() {
            // The six-state process noise follows the DR errors (six_state.rs).
            six.on_dr_predict(&self.disc.phi);
        }
        self.acc = Accum::default();
    }

    /// What the aiding models see of the current solution, with the receiver clock
    /// `clock` (tight coupling; zero for the other sources). The fix-error estimate is
    /// zero here: the loose source, which owns it, puts it in its own context.
    pub(crate) fn context(&self, clock: ReceiverClock) -> AidingContext<'_> {
        AidingContext {
            nav: &self.nav,
            layout: &self.layout,
            w_ib_b: self.w_ib_b,
            a_n: self.a_n,
            lever_arm_b: self.cfg.gnss.lever_arm_b,
            vehicle: self.vehicle,
            clock,
            gnss_bias_ned_m: Vector3::zeros(),
        }
    }

    /// The filter update with measurement `lin` (covariance flushed by the caller) and
    /// an optional gate; on success the correction is fed back.
    pub(crate) fn update(&mut self, lin: &Linearized, gate: Option<f64>) -> UpdateOutcome {
        // GnssFusion::SixState: the gain carries the DR error correlation through the
        // update (six_state.rs process noise).
        let gain = match self.six_state {
            Some(_) => self.filter.gain(&lin.h, &lin.r),
            None => None,
        };
        let out = self.filter.update(&lin.y, &lin.h, &lin.r, gate);
        if let UpdateOutcome::Applied { dx, .. } = &out {
            if let Some(r) = self.recorder.as_mut() {
                r.applied(dx);
            }
            if let (Some(six), Some(k)) = (self.six_state.as_mut(), gain) {
                six.on_dr_update(&k, &lin.h);
            }
            self.feedback(dx);
        }
        out
    }

    /// [`InsFilter::update`] of the stacked rows of one epoch, linearised together at
    /// the state before any of them: one joint update ([`Eskf::update_joint`]), with
    /// the per-row terms for the bookkeeping.
    pub(crate) fn update_joint(
        &mut self,
        lin: &Linearized,
        gate: Option<f64>,
    ) -> (UpdateOutcome, Option<RowTerms>) {
        let gain = match self.six_state {
            Some(_) => self.filter.gain(&lin.h, &lin.r),
            None => None,
        };
        let (out, rows) = self.filter.update_joint(&lin.y, &lin.h, &lin.r, gate);
        if let UpdateOutcome::Applied { dx, .. } = &out {
            self.applied(dx, gain.as_ref().map(|k| (k, &lin.h)));
        }
        (out, rows)
    }

    /// The same rows one at a time ([`Eskf::update_sequential`]: each innovation less
    /// the corrections of the rows before it, each row gated alone by `row_gate`), the
    /// sum of the corrections fed back once; None when `lin.r` is not diagonal. The
    /// sum, and each row's outcome.
    pub(crate) fn update_sequential(
        &mut self,
        lin: &Linearized,
        row_gate: Option<f64>,
    ) -> Option<(DVector<f64>, Vec<SequentialRow>)> {
        let prior = self.six_state.is_some().then(|| self.filter.clone());
        let (dx, rows) = self
            .filter
            .update_sequential(&lin.y, &lin.h, &lin.r, row_gate)?;
        let kept: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].applied).collect();
        if !kept.is_empty() {
            // GnssFusion::SixState: the gain of the rows applied, over the prior.
            let h = lin.h.select_rows(&kept);
            let gain =
                prior.and_then(|p| p.gain(&h, &lin.r.select_rows(&kept).select_columns(&kept)));
            self.applied(&dx, gain.as_ref().map(|k| (k, &h)));
        }
        Some((dx, rows))
    }

    /// An update's correction `dx` (with its gain and H under six-state fusion) is
    /// recorded and fed back.
    fn applied(&mut self, dx: &DVector<f64>, gain_h: Option<(&DMatrix<f64>, &DMatrix<f64>)>) {
        if let Some(r) = self.recorder.as_mut() {
            r.applied(dx);
        }
        if let (Some(six), Some((k, h))) = (self.six_state.as_mut(), gain_h) {
            six.on_dr_update(k, h);
        }
        self.feedback(dx);
    }

    /// Closed-loop feedback of the error estimate, then implicit reset to zero.
    fn feedback(&mut self, dx: &DVector<f64>) {
        let old_lla = self.nav.lla;
        let st = NominalMut {
            nav: &mut self.nav,
            imu_errors: &mut self.imu_errors,
            time_offset_s: &mut self.time_offset_s,
            time_offset_rate: &mut self.time_offset_rate,
            odometer_scale: &mut self.vehicle.odometer_scale,
            c_bm: &mut self.vehicle.c_bm,
            extra: &mut self.extra,
        };
        correct(&self.layout, dx, st, source_ranges(&self.layout));
        let d_vel = Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]);
        self.mech
            .shift_previous(&(self.nav.lla - old_lla), &(-d_vel));
        self.corrections += 1;
        // The displacement since the previous epoch is the mechanization's only.
        if let Some((_, last)) = self.displacement.as_mut() {
            *last = lla_to_ecef(&self.nav.lla);
        }
        // The dead reckoning's own corrections are part of its increments.
        self.six_state_follow_dr();
    }

    /// Add `var` to the variance of state `i` (covariance flushed by the caller).
    pub(crate) fn add_variance(&mut self, i: usize, var: f64) {
        self.record(Transition::AddVariance(i, var));
        self.filter.p[(i, i)] += var;
    }

    /// Re-initialise state `i`: uncorrelated, with variance `var`.
    pub(crate) fn reset_state(&mut self, i: usize, var: f64) {
        self.record(Transition::Reset(i, var));
        self.filter.reset_state(i, var);
    }

    fn record(&mut self, tr: Transition<'_>) {
        if let Some(r) = self.recorder.as_mut() {
            r.transition(self.nav.t, tr, &self.filter.p);
        }
    }

    /// What noise identification needs of update `lin` of `source` at time `t`,
    /// taken before it is applied (smoother/em.rs); None unless the run logs updates
    /// while recording.
    pub(crate) fn update_entry(
        &self,
        t: f64,
        source: &'static str,
        lin: &Linearized,
    ) -> Option<FusedUpdate> {
        self.update_log.as_ref()?;
        let rec = self.recorder.as_ref()?;
        let dx = rec.open_dx();
        let rows = lin.y.len();
        let h: Vec<Vec<(usize, f64)>> = (0..rows)
            .map(|k| {
                (0..lin.h.ncols())
                    .filter(|&j| lin.h[(k, j)] != 0.0)
                    .map(|j| (j, lin.h[(k, j)]))
                    .collect()
            })
            .collect();
        let h_dx_before = h
            .iter()
            .map(|row| row.iter().map(|&(j, v)| v * dx[j]).sum())
            .collect();
        let gnss_bias = self.layout.index(Block::GnssBias).map(|b| {
            (
                [0, 1, 2].map(|k| self.extra[b + k]),
                [0, 1, 2].map(|k| dx[b + k]),
            )
        });
        Some(FusedUpdate {
            t,
            record: rec.current_index(),
            source,
            y: lin.y.iter().copied().collect(),
            h,
            r: (0..rows).map(|k| lin.r[(k, k)]).collect(),
            h_dx_before,
            down_weighted: false,
            gnss_bias,
        })
    }

    /// Record for the RTS smoother from now on.
    pub(crate) fn start_recording(&mut self) {
        self.recorder = Some(Recorder::new(self.nav.t, self.layout.len()));
    }

    /// Everything of the state but the covariance.
    pub(crate) fn nominal(&self) -> Nominal {
        Nominal {
            nav: self.nav,
            imu_errors: self.imu_errors,
            time_offset_s: self.time_offset_s,
            time_offset_rate: self.time_offset_rate,
            odometer_scale: self.vehicle.odometer_scale,
            c_bm: self.vehicle.c_bm,
            extra: self.extra.clone(),
        }
    }

    /// The mechanization's own displacement since the last restart, ECEF \[m\].
    pub(crate) fn displacement_ecef_m(&self) -> Vector3<f64> {
        self.displacement.map_or(Vector3::zeros(), |(d, _)| d)
    }

    /// Start the displacement anew from the current position.
    pub(crate) fn restart_displacement(&mut self) {
        let r = lla_to_ecef(&self.nav.lla);
        if let Some(d) = self.displacement.as_mut() {
            *d = (Vector3::zeros(), r);
        }
    }

    /// Final estimates of the `Block::Source` blocks.
    pub(crate) fn source_states(&self) -> Vec<crate::events::SourceState> {
        self.source_blocks
            .iter()
            .filter_map(|sb| match sb.block {
                Block::Source { name, len } => Some(crate::events::SourceState {
                    name,
                    value: self.extra.as_slice()[sb.index..sb.index + len].to_vec(),
                    std: (sb.index..sb.index + len)
                        .map(|i| self.filter.std(i))
                        .collect(),
                }),
                _ => None,
            })
            .collect()
    }

    /// 1-sigma of the 21 INS states (six-state position/velocity when it runs).
    pub(crate) fn std21(&self) -> [f64; N_INS] {
        let mut s = [0.0; N_INS];
        for (i, v) in s.iter_mut().enumerate() {
            *v = self.filter.std(i);
        }
        if let Some(six) = &self.six_state {
            let s6 = six.std_now(&self.filter.p);
            s[POS..POS + 3].copy_from_slice(&s6[..3]);
            s[VEL..VEL + 3].copy_from_slice(&s6[3..]);
        }
        s
    }

    /// 1-sigma of the velocity, NED \[m/s\] (as of the last covariance flush).
    pub(crate) fn vel_std_ned_mps(&self) -> Vector3<f64> {
        Vector3::from_fn(|k, _| self.filter.std(VEL + k))
    }

    /// True while position, velocity and attitude are finite numbers.
    pub(crate) fn nav_is_finite(&self) -> bool {
        let n = &self.nav;
        n.lla
            .iter()
            .chain(n.v_n.iter())
            .chain(n.q_bn.coords.iter())
            .all(|x| x.is_finite())
    }

    /// True while the covariance diagonal is finite.
    pub(crate) fn covariance_is_finite(&self) -> bool {
        (0..self.filter.dim()).all(|i| self.filter.p[(i, i)].is_finite())
    }
}
