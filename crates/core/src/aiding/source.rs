//! The seam between the navigator and its aiding sources.
//!
//! An aiding source holds its measurement model, its policy (when it is due, gates,
//! timeouts, vetoes, counters, events) and its state, and declares the extra
//! error-state blocks it owns. The navigator hands it each measurement and, after
//! every IMU step, the chance to fuse cadence-driven constraints; the source fuses
//! through a [`Fuser`], which applies the update, feeds the correction back, and
//! keeps the source's uniform [`AidStatus`] (as PX4 EKF2's aid sources do).
//! `registry.rs` lists the sources.

use crate::aiding::adaptive::{scaled_r, vb_update};
use crate::aiding::{Aiding, AidingContext, Linearized, ReceiverClock, VehicleEstimate};
use crate::events::{AidStatus, Event, InnovationRow, RunSummary, UpdateKind};
use crate::filter::UpdateOutcome;
use crate::integrity::IntegrityState;
use crate::nav::ins_filter::{BlockProcess, BlockSpec, Fused, InsFilter};
use crate::nav::timeline::TimeDirection;
use crate::six_state::SixState;
use crate::smoother::em::FusedUpdate;
use crate::state::{Block, StateLayout};
use crate::types::{ImuErrors, ImuSample, Measurement, NavState};
use nalgebra::{DMatrix, DVector, Vector3};

/// Whether a source took a measurement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handled {
    Yes,
    No,
}

/// Facts the sources tell each other.
#[derive(Clone, Debug, PartialEq)]
pub struct Shared {
    /// Time of the last GNSS epoch used (GNSS time) \[s\]: the NHC's outage mode and
    /// the loose drift floor read it (the start time until then; in a backward run
    /// the latest GNSS time used, going down).
    pub last_gnss_used_t: f64,
    /// The static detector sees the vehicle at rest (ZUPT): no NHC meanwhile.
    pub is_static: bool,
    /// Time of the last GNSS epoch fused (any weight; GNSS time) \[s\], and the
    /// latest interval between two such epochs under 30 s \[s\]: the solution
    /// state (`Navigator::solution_state`).
    pub gnss_fused_t: Option<f64>,
    pub gnss_interval_s: Option<f64>,
    /// Time of the last odometer or NHC update applied (GNSS time) \[s\].
    pub vehicle_fused_t: Option<f64>,
}

impl Shared {
    /// A GNSS epoch was fused at `t`.
    pub fn note_gnss_fused(&mut self, t: f64) {
        if let Some(prev) = self.gnss_fused_t {
            let dt = (t - prev).abs();
            if dt > 1e-3 && dt < 30.0 {
                self.gnss_interval_s = Some(dt);
            }
        }
        self.gnss_fused_t = Some(t);
    }
}

/// One aiding source: model, policy and state (see the module doc).
pub trait AidingSource: Send {
    /// Short name for logs and statuses.
    fn name(&self) -> &'static str;

    /// Extra error-state blocks this source owns (appended in registry order).
    fn blocks(&self) -> Vec<BlockSpec> {
        Vec::new()
    }

    /// The source needs the INS displacement between its epochs
    /// ([`Fuser::displacement_ecef_m`]; TDCP).
    fn tracks_displacement(&self) -> bool {
        false
    }

    /// A measurement has come due; fuse it (or not). Every source sees every
    /// measurement: several may react to one (the ZUPT watches the odometer).
    fn on_measurement(&mut self, _m: &Measurement, _f: &mut Fuser) -> Handled {
        Handled::No
    }

    /// A piece of an IMU interval was integrated (`imu`: compensated increments).
    fn on_propagate(&mut self, _imu: &ImuSample, _f: &mut Fuser) {}

    /// The next IMU interval is a gap the reader bridged.
    fn on_imu_gap(&mut self) {}

    /// After each IMU sample: cadence-driven constraints (ZUPT, NHC).
    fn after_imu(&mut self, _f: &mut Fuser) {}

    /// The GNSS integrity state, for a source that monitors it.
    fn integrity_state(&self) -> Option<IntegrityState> {
        None
    }

    /// End of the run: report final estimates into the summary.
    fn finish(&self, _f: &Fuser, _summary: &mut RunSummary) {}
}

/// What a source may do to the filter while it is called.
pub struct Fuser<'a> {
    pub(crate) ins: &'a mut InsFilter,
    pub(crate) record: &'a mut RunSummary,
    pub(crate) shared: &'a mut Shared,
    pub(crate) status: &'a mut AidStatus,
}

impl Fuser<'_> {
    /// The navigation state (the dead reckoning's under six-state fusion).
    pub fn nav(&self) -> &NavState {
        &self.ins.nav
    }

    /// Time of the current state on the GNSS time scale \[s\].
    pub fn time_gnss(&self) -> f64 {
        self.ins.time_gnss()
    }

    /// Which way the run goes in time: a backward run (nav/backward.rs) reaches the
    /// measurements from the last to the first. Elapsed times and cadences go through
    /// it (`TimeDirection::elapsed`, `advance`, `reached`).
    pub fn direction(&self) -> TimeDirection {
        self.ins.direction
    }

    pub fn layout(&self) -> &StateLayout {
        &self.ins.layout
    }

    /// Error covariance (as of the last flush).
    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.ins.filter.p
    }

    /// 1-sigma of state `i` (as of the last flush).
    pub fn std(&self, i: usize) -> f64 {
        self.ins.filter.std(i)
    }

    /// 1-sigma of the velocity, NED \[m/s\].
    pub fn vel_std_ned_mps(&self) -> Vector3<f64> {
        self.ins.vel_std_ned_mps()
    }

    /// Compensated angular rate over the last IMU interval \[rad/s\].
    pub fn w_ib_b(&self) -> Vector3<f64> {
        self.ins.w_ib_b
    }

    pub fn imu_errors(&self) -> &ImuErrors {
        &self.ins.imu_errors
    }

    pub fn vehicle(&self) -> &VehicleEstimate {
        &self.ins.vehicle
    }

    /// Sum of the mechanization's own velocity increments (no feedback), NED \[m/s\].
    pub fn mech_dv_n(&self) -> Vector3<f64> {
        self.ins.mech_dv_n
    }

    /// Number of feedbacks so far (a change means the INS position jumped).
    pub fn corrections(&self) -> u64 {
        self.ins.corrections
    }

    /// The mechanization's own displacement since the last restart (feedback jumps
    /// excluded), ECEF \[m\]; zero unless a source tracks it.
    pub fn displacement_ecef_m(&self) -> Vector3<f64> {
        self.ins.displacement_ecef_m()
    }

    /// Start the displacement anew from the current position.
    pub fn restart_displacement(&mut self) {
        self.ins.restart_displacement();
    }

    pub fn shared(&mut self) -> &mut Shared {
        self.shared
    }

    pub fn shared_ref(&self) -> &Shared {
        self.shared
    }

    /// The run's record: counters and events.
    pub fn record(&mut self) -> &mut RunSummary {
        self.record
    }

    pub fn push_event(&mut self, e: Event) {
        self.record.events.push(e);
    }

    /// What the aiding models see, with receiver clock `clock`.
    pub fn context(&self, clock: ReceiverClock) -> AidingContext<'_> {
        self.ins.context(clock)
    }

    /// Bring the covariance up to the current time.
    pub fn flush_covariance(&mut self) {
        self.ins.flush_covariance();
    }

    /// Add `var` to the variances of the 3-state block starting at index `block`.
    pub fn widen(&mut self, block: usize, var: Vector3<f64>) {
        self.ins.widen(block, var);
    }

    /// Add `var` to the variance of state `i` (covariance flushed by the caller).
    pub fn add_variance(&mut self, i: usize, var: f64) {
        self.ins.add_variance(i, var);
    }

    /// Reset state `i`: uncorrelated, with variance `var`.
    pub fn reset_state(&mut self, i: usize, var: f64) {
        self.ins.reset_state(i, var);
    }

    /// Nominal values of a source block (empty when the layout lacks it).
    pub fn extra(&self, block: Block) -> &[f64] {
        self.ins.extra(block)
    }

    pub fn extra_mut(&mut self, block: Block) -> &mut [f64] {
        self.ins.extra_mut(block)
    }

    /// Change the process model of a source block.
    pub fn set_process(&mut self, block: Block, process: BlockProcess) {
        self.ins.set_process(block, process);
    }

    /// Normalised innovation squared of `lin` against the current covariance.
    pub fn nis(&self, lin: &Linearized) -> Option<f64> {
        self.ins.filter.nis(&lin.y, &lin.h, &lin.r)
    }

    /// The adaptive noise scale of source `name` as of now (aiding/adaptive.rs): the
    /// factor the next update of `name` starts from; 1 when adaptive noise is off or
    /// does not cover `name`.
    pub fn noise_scale(&self, name: &str) -> f64 {
        self.ins.adaptive.as_ref().map_or(1.0, |a| a.scale(name))
    }

    /// [`Fuser::nis`] with R times [`Fuser::noise_scale`] of `name`: the NIS the
    /// update of `name` is tested with.
    pub fn nis_adapted(&self, name: &str, lin: &Linearized) -> Option<f64> {
        let s = self.noise_scale(name);
        if s == 1.0 {
            return self.nis(lin);
        }
        self.ins.filter.nis(&lin.y, &lin.h, &(&lin.r * s))
    }

    /// Baarda's w-test of stacked rows (filter.rs): (w, blunder) per row.
    pub fn blunder_test(&self, lin: &Linearized) -> Option<Vec<(f64, f64)>> {
        self.ins.filter.blunder_test(&lin.y, &lin.h, &lin.r)
    }

    /// Fuse one of the built-in measurements with an optional chi-square gate.
    pub fn fuse(&mut self, aiding: Aiding, gate: Option<f64>) -> Fused {
        self.fuse_with_clock(aiding, gate, ReceiverClock::default())
    }

    /// [`Fuser::fuse`] with the receiver clock the GNSS models need.
    pub fn fuse_with_clock(
        &mut self,
        aiding: Aiding,
        gate: Option<f64>,
        clock: ReceiverClock,
    ) -> Fused {
        self.flush_covariance();
        let Some(lin) = aiding.linearize(&self.context(clock)) else {
            return Fused::NotApplicable;
        };
        self.fuse_linearized(&aiding, &lin, gate, None)
    }

    /// Fuse an already linearised built-in measurement (covariance flushed).
    /// `nis_stat`: the NIS to record for a down-weighted row (that of the reported R).
    pub fn fuse_linearized(
        &mut self,
        aiding: &Aiding,
        lin: &Linearized,
        gate: Option<f64>,
        nis_stat: Option<f64>,
    ) -> Fused {
        let logged = aiding.logs_rejections();
        let out = self.fuse_named(aiding.name(), logged, lin, gate, nis_stat);
        if out.applied() && matches!(aiding, Aiding::Nhc(_) | Aiding::Odometer { .. }) {
            self.shared.vehicle_fused_t = Some(self.time_gnss());
        }
        out
    }

    /// Fuse rows of a source's own model under `name` (a custom source's entry
    /// point); `log_rejections`: a rejection is also an [`Event::Rejected`].
    pub fn fuse_rows(
        &mut self,
        name: &'static str,
        lin: &Linearized,
        gate: Option<f64>,
        log_rejections: bool,
    ) -> Fused {
        self.flush_covariance();
        self.fuse_named(name, log_rejections, lin, gate, None)
    }

    fn fuse_named(
        &mut self,
        name: &'static str,
        logged: bool,
        lin: &Linearized,
        gate: Option<f64>,
        nis_stat: Option<f64>,
    ) -> Fused {
        let t = self.time_gnss();
        let adapted = self.adapt(name, t, lin, gate, nis_stat);
        let (lin, update_gate, nis_stat) = match &adapted {
            Some(a) => (&a.lin, a.gate, a.nis_stat),
            None => (lin, gate, nis_stat),
        };
        let st = &mut *self.status;
        st.innovation.clear();
        st.innovation.extend(lin.y.iter());
        let entry = self.ins.update_entry(t, name, lin);
        let outcome = self.ins.update(lin, update_gate);
        if let (Some(mut e), UpdateOutcome::Applied { nis, .. }) = (entry, &outcome) {
            // A row whose R the source inflated (robust down-weighting) has a NIS
            // below that of its reported R.
            e.down_weighted = match &adapted {
                Some(a) => a.down_weighted,
                None => nis_stat.is_some_and(|n| *nis < n * (1.0 - 1e-9)),
            };
            if let Some(log) = self.ins.update_log.as_mut() {
                log.push(e);
            }
        }
        if let UpdateOutcome::Applied {
            nis,
            s_diag,
            log_det_s,
            ..
        }
        | UpdateOutcome::Rejected {
            nis,
            s_diag,
            log_det_s,
            ..
        } = &outcome
        {
            let stats = self.record.innovation_stats.entry(name).or_default();
            // A down-weighted row counts with the NIS of its reported R.
            let nis = nis_stat.unwrap_or(*nis);
            stats.note(t, lin.y.as_slice(), s_diag, nis, *log_det_s);
        }
        if let Some(log) = self.ins.innovations.as_mut() {
            let mut innovation = [f64::NAN; 3];
            for (v, y) in innovation.iter_mut().zip(lin.y.iter()) {
                *v = *y;
            }
            let (nis, kind) = match &outcome {
                UpdateOutcome::Applied { nis, .. } => {
                    (nis_stat.unwrap_or(*nis), UpdateKind::Applied)
                }
                UpdateOutcome::Rejected { nis, .. } => (*nis, UpdateKind::Rejected),
                UpdateOutcome::Singular => (f64::NAN, UpdateKind::Singular),
            };
            log.push(InnovationRow {
                t,
                source: name,
                rows: lin.y.len(),
                innovation,
                nis,
                gate,
                outcome: kind,
            });
        }
        match outcome {
            UpdateOutcome::Applied { dx, nis, .. } => {
                let nis = nis_stat.unwrap_or(nis);
                let e = self.record.aiding_nis.entry(name).or_default();
                *e = (e.0 + nis, e.1 + lin.y.len());
                *self.record.aiding_used.entry(name).or_default() += 1;
                st.fused += 1;
                st.nis = Some(nis);
                st.test_ratio = gate.map(|g| nis / g);
                st.last_fused = true;
                st.last_fused_t = Some(t);
                Fused::Applied(dx)
            }
            UpdateOutcome::Rejected { nis, threshold, .. } => {
                *self.record.aiding_rejected.entry(name).or_default() += 1;
                st.rejected += 1;
                st.nis = Some(nis);
                st.test_ratio = Some(nis / threshold);
                st.last_fused = false;
                if logged {
                    self.record.events.push(Event::Rejected {
                        t,
                        source: name,
                        nis,
                        threshold,
                    });
                }
                Fused::Rejected
            }
            UpdateOutcome::Singular => {
                *self.record.aiding_rejected.entry(name).or_default() += 1;
                st.rejected += 1;
                st.nis = None;
                st.test_ratio = None;
                st.last_fused = false;
                self.record.events.push(Event::Singular { t, source: name });
                Fused::Singular
            }
        }
    }

    /// Adaptive noise for one update of `name` (aiding/adaptive.rs; None when off or
    /// not covering `name`). The gate and the source's down-weighting test see the
    /// scale before this update (s^-): an outlier cannot widen its own R to pass.
    /// Rejected and down-weighted updates are applied (or not) with s^- and do not
    /// feed the estimate; the others go through the VB fixed point and are applied
    /// with its R (their gate already passed), recorded with the NIS under s^-.
    fn adapt(
        &mut self,
        name: &'static str,
        t: f64,
        lin: &Linearized,
        gate: Option<f64>,
        nis_stat: Option<f64>,
    ) -> Option<Adapted> {
        let ad = self.ins.adaptive.as_ref()?;
        if !ad.adapts(name) {
            return None;
        }
        let prior = ad.predicted(name, t);
        let a = &lin.h * &self.ins.filter.p * lin.h.transpose();
        let blocks = [(0, lin.y.len(), 0)];
        let vb = vb_update(&a, &lin.r, &lin.y, &blocks, &[prior], &ad.opt)?;
        let rejected = gate.is_some_and(|g| vb.nis_prior > g);
        let down_weighted = nis_stat.is_some_and(|n| vb.nis_prior < n * (1.0 - 1e-9));
        let with_scale = |s: f64| Linearized {
            r: &lin.r * s,
            ..lin.clone()
        };
        if rejected || down_weighted {
            let s = prior.scale().clamp(ad.opt.min_scale, ad.opt.max_scale);
            return Some(Adapted {
                lin: with_scale(s),
                gate,
                nis_stat: nis_stat.or(Some(vb.nis_prior)),
                down_weighted,
            });
        }
        let lin = with_scale(vb.scales[0]);
        if let Some(ad) = self.ins.adaptive.as_mut() {
            ad.commit(name, vb.posteriors[0], t);
        }
        Some(Adapted {
            lin,
            gate: None,
            nis_stat: Some(vb.nis_prior),
            down_weighted: false,
        })
    }

    /// Adaptive noise for the stacked rows of one epoch (`names` per row; the rows of
    /// each `rows` entry form a block of R): scaled per name, by the VB fixed point
    /// for a one-shot update that passes its gate under the scales before it (then
    /// applied ungated, the estimates kept), else by those scales (a sequential update
    /// gates row by row: it neither changes nor feeds the estimate). None when off.
    fn adapt_epoch(
        &mut self,
        t: f64,
        rows: &[(&'static str, &Linearized)],
        stacked: &Linearized,
        how: EpochUpdate,
    ) -> Option<(Linearized, EpochUpdate)> {
        let ad = self.ins.adaptive.as_ref()?;
        let mut groups: Vec<&'static str> = Vec::new();
        let mut blocks = Vec::with_capacity(rows.len());
        let mut k = 0;
        for (name, l) in rows {
            let d = l.y.len();
            if ad.adapts(name) {
                let g = match groups.iter().position(|n| n == name) {
                    Some(g) => g,
                    None => {
                        groups.push(name);
                        groups.len() - 1
                    }
                };
                blocks.push((k, d, g));
            }
            k += d;
        }
        if groups.is_empty() {
            return None;
        }
        let priors: Vec<_> = groups.iter().map(|n| ad.predicted(n, t)).collect();
        let prior_scales: Vec<f64> = priors
            .iter()
            .map(|p| p.scale().clamp(ad.opt.min_scale, ad.opt.max_scale))
            .collect();
        let with_scales = |scales: &[f64]| Linearized {
            r: scaled_r(&stacked.r, &blocks, scales),
            ..stacked.clone()
        };
        let EpochUpdate::OneShot { gate } = how else {
            return Some((with_scales(&prior_scales), how));
        };
        let a = &stacked.h * &self.ins.filter.p * stacked.h.transpose();
        let Some(vb) = vb_update(&a, &stacked.r, &stacked.y, &blocks, &priors, &ad.opt) else {
            return Some((with_scales(&prior_scales), how));
        };
        if gate.is_some_and(|g| vb.nis_prior > g) {
            return Some((with_scales(&prior_scales), how));
        }
        let lin = with_scales(&vb.scales);
        if let Some(ad) = self.ins.adaptive.as_mut() {
            for (name, post) in groups.iter().zip(vb.posteriors) {
                ad.commit(name, post, t);
            }
        }
        Some((lin, EpochUpdate::OneShot { gate: None }))
    }

    /// Fuse the measurements of one epoch linearised together at the current state
    /// (none fused in between): `rows` as (name, model), each of one or more rows,
    /// applied as `how` says. Carrier-phase measurements need this: their prediction
    /// holds quantities fixed at the epoch's start (TDCP: the INS displacement since
    /// the previous epoch), so re-linearising them one after another's feedback would
    /// apply the same correction again ([`Aiding::epoch_fixed`]).
    ///
    /// Bookkeeping per scalar row, under its name: an innovations.csv row with its
    /// innovation given the rows before it, e_i, and its share of the NIS, e_i^2 / s_i
    /// (the sequential decomposition, `crate::filter::RowTerms`: the same in both
    /// modes, and the shares sum to the joint NIS), `aiding_used` / `aiding_rejected`
    /// and the NIS statistics per row. Returns the correction fed back (Applied when
    /// any row was applied).
    pub fn fuse_epoch(&mut self, rows: &[(&'static str, &Linearized)], how: EpochUpdate) -> Fused {
        self.flush_covariance();
        let lins: Vec<&Linearized> = rows.iter().map(|(_, l)| *l).collect();
        let Some(mut stacked) = stack_rows(&lins, self.ins.layout.len()) else {
            return Fused::NotApplicable;
        };
        let names: Vec<&'static str> = rows
            .iter()
            .flat_map(|(name, l)| std::iter::repeat_n(*name, l.y.len()))
            .collect();
        let t = self.time_gnss();
        let mut how_applied = how;
        let mut adapted = false;
        if let Some((lin, h)) = self.adapt_epoch(t, rows, &stacked, how) {
            stacked = lin;
            how_applied = h;
            adapted = true;
        }
        // Noise identification's log, taken at the state all rows are linearised at
        // (with the R applied).
        let mut first = 0;
        let entries: Vec<Option<FusedUpdate>> = rows
            .iter()
            .map(|(name, l)| {
                let d = l.y.len();
                first += d;
                if adapted {
                    let r = stacked.r.view((first - d, first - d), (d, d)).into_owned();
                    let scaled = Linearized { r, ..(*l).clone() };
                    self.ins.update_entry(t, name, &scaled)
                } else {
                    self.ins.update_entry(t, name, l)
                }
            })
            .collect();
        // Per row: (e_i, s_i, outcome), and the total correction.
        let (per_row, gate, dx) = match how_applied {
            EpochUpdate::OneShot { gate } => {
                let (out, terms) = self.ins.update_joint(&stacked, gate);
                let kind = match &out {
                    UpdateOutcome::Applied { .. } => UpdateKind::Applied,
                    UpdateOutcome::Rejected { nis, threshold, .. } => {
                        if let Some(name) = rows.first().map(|r| r.0) {
                            self.record.events.push(Event::Rejected {
                                t,
                                source: name,
                                nis: *nis,
                                threshold: *threshold,
                            });
                        }
                        UpdateKind::Rejected
                    }
                    UpdateOutcome::Singular => UpdateKind::Singular,
                };
                let per_row = match terms {
                    Some(r) => (0..names.len())
                        .map(|i| (r.innovation[i], r.variance[i], kind))
                        .collect(),
                    None => vec![(f64::NAN, f64::NAN, kind); names.len()],
                };
                let dx = match out {
                    UpdateOutcome::Applied { dx, .. } => Some(dx),
                    _ => None,
                };
                (per_row, None, dx)
            }
            EpochUpdate::Sequential { row_gate } => {
                match self.ins.update_sequential(&stacked, row_gate) {
                    Some((dx, r)) => {
                        let any = r.iter().any(|x| x.applied);
                        let per_row: Vec<(f64, f64, UpdateKind)> = r
                            .into_iter()
                            .map(|x| {
                                let (e, s) = (x.innovation, x.variance);
                                let kind = if x.applied {
                                    UpdateKind::Applied
                                } else if s > 0.0 && e.is_finite() {
                                    UpdateKind::Rejected
                                } else {
                                    UpdateKind::Singular
                                };
                                (e, s, kind)
                            })
                            .collect();
                        (per_row, row_gate, any.then_some(dx))
                    }
                    // Correlated rows cannot be taken one at a time.
                    None => return self.fuse_epoch(rows, EpochUpdate::OneShot { gate: None }),
                }
            }
        };
        if let Some(log) = self.ins.update_log.as_mut() {
            let mut first = 0;
            for ((_, l), entry) in rows.iter().zip(entries) {
                let n = l.y.len();
                let applied = per_row[first..first + n]
                    .iter()
                    .all(|r| r.2 == UpdateKind::Applied);
                if let (true, Some(e)) = (applied, entry) {
                    log.push(e);
                }
                first += n;
            }
        }
        let st = &mut *self.status;
        st.innovation.clear();
        let mut joint_nis = 0.0;
        for (&name, &(e, s, kind)) in names.iter().zip(&per_row) {
            let nis = e * e / s;
            st.innovation.push(e);
            if kind != UpdateKind::Singular {
                let stats = self.record.innovation_stats.entry(name).or_default();
                stats.note(t, &[e], &[s, f64::NAN, f64::NAN], nis, s.ln());
            }
            if let Some(log) = self.ins.innovations.as_mut() {
                log.push(InnovationRow {
                    t,
                    source: name,
                    rows: 1,
                    innovation: [e, f64::NAN, f64::NAN],
                    nis: if kind == UpdateKind::Singular {
                        f64::NAN
                    } else {
                        nis
                    },
                    gate,
                    outcome: kind,
                });
            }
            match kind {
                UpdateKind::Applied => {
                    let acc = self.record.aiding_nis.entry(name).or_default();
                    *acc = (acc.0 + nis, acc.1 + 1);
                    *self.record.aiding_used.entry(name).or_default() += 1;
                    st.fused += 1;
                    joint_nis += nis;
                }
                UpdateKind::Rejected | UpdateKind::Singular => {
                    *self.record.aiding_rejected.entry(name).or_default() += 1;
                    st.rejected += 1;
                }
            }
        }
        st.test_ratio = None;
        match dx {
            Some(dx) => {
                st.nis = Some(joint_nis);
                st.last_fused = true;
                st.last_fused_t = Some(t);
                Fused::Applied(dx)
            }
            None => {
                st.last_fused = false;
                if per_row.iter().all(|r| r.2 == UpdateKind::Singular) {
                    st.nis = None;
                    if let Some(name) = rows.first().map(|r| r.0) {
                        self.record.events.push(Event::Singular { t, source: name });
                    }
                    Fused::Singular
                } else {
                    Fused::Rejected
                }
            }
        }
    }

    /// A row dropped by a joint test (data snooping) counts as rejected.
    pub fn count_rejected(&mut self, name: &'static str) {
        *self.record.aiding_rejected.entry(name).or_default() += 1;
        self.status.rejected += 1;
    }

    /// `GnssFusion::SixState`: the six-state filter, when it runs.
    pub(crate) fn six_state(&mut self) -> Option<&mut SixState> {
        self.ins.six_state.as_mut()
    }

    /// `GnssFusion::SixState`: move it with the dead reckoning and refresh the output.
    pub(crate) fn six_state_follow_dr(&mut self) {
        self.ins.six_state_follow_dr();
    }

    /// `GnssFusion::SixState`: refresh the output solution after a six-state update.
    pub(crate) fn six_state_refresh(&mut self) {
        if let Some(six) = &self.ins.six_state {
            self.ins.six_state_out = six.solution(&self.ins.nav);
        }
    }
}

/// One update of [`Fuser::fuse_named`] under adaptive noise: the rows with the R to
/// apply, the gate of the update, the NIS to record and whether it was down-weighted.
struct Adapted {
    lin: Linearized,
    gate: Option<f64>,
    nis_stat: Option<f64>,
    down_weighted: bool,
}

/// How [`Fuser::fuse_epoch`] applies the measurements of one epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EpochUpdate {
    /// One stacked update, gated jointly (`gate` on the joint NIS, as many degrees of
    /// freedom as rows; a rejection is an [`Event::Rejected`] under the first name).
    OneShot { gate: Option<f64> },
    /// Row by row (`crate::filter::Eskf::update_sequential`): each row's prediction
    /// includes the corrections of the rows before it (innovation y_i - H_i dx), each
    /// row gated alone (`row_gate`, 1 dof), one feedback at the end. Ungated, the same
    /// state as `OneShot`. Needs uncorrelated rows (diagonal R); correlated ones are
    /// fused one-shot.
    Sequential { row_gate: Option<f64> },
}

/// Chi-square gate for `dof` rows at tail probability `p`.
pub fn chi2_gate(dof: usize, p: Option<f64>) -> Option<f64> {
    p.map(|p| crate::chi2::chi2_threshold(dof, p))
}

/// Measurements stacked into one (rows in order, block-diagonal R); None if empty.
pub fn stack_rows(lins: &[&Linearized], n_states: usize) -> Option<Linearized> {
    let m: usize = lins.iter().map(|l| l.y.len()).sum();
    if m == 0 {
        return None;
    }
    let mut y = DVector::zeros(m);
    let mut h = DMatrix::zeros(m, n_states);
    let mut r = DMatrix::zeros(m, m);
    let mut k = 0;
    for l in lins {
        let d = l.y.len();
        y.rows_mut(k, d).copy_from(&l.y);
        h.rows_mut(k, d).copy_from(&l.h);
        r.view_mut((k, k), (d, d)).copy_from(&l.r);
        k += d;
    }
    Some(Linearized { y, h, r })
}
