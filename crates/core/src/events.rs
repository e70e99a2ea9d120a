//! What a run reports: events with their time, the end-of-run summary and the
//! uniform status each aiding source keeps (innovation, NIS, fused or rejected, time
//! of the last fusion; as PX4's aid sources do).

use crate::integrity::Transition;
use nalgebra::Vector3;
use std::collections::BTreeMap;

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
    /// An IMU interval of `dt` seconds from `t` (a gap the reader bridged): the INS
    /// uncertainty was grown by the plausible motion over it.
    ImuGap { t: f64, dt: f64 },
    /// Fixes had been rejected for `streak_s` seconds; this one was used ungated.
    GateBypassed { t: f64, streak_s: f64 },
    /// Loose coupling: fixes rejected for `streak_s` seconds had agreed with each
    /// other for `gnss.readmit_s`; the filter widened its uncertainty by their
    /// disagreement `offset_m` and took this one.
    GnssReadmitted {
        t: f64,
        streak_s: f64,
        offset_m: f64,
    },
    /// Tight coupling: no pseudorange had been fused for `gap_s` seconds (outage,
    /// rejection streak, or dead reckoning under the integrity monitor); the position
    /// and velocity uncertainty was widened by the single point fix's disagreement
    /// `offset_m` where the covariance could not explain it (`widened`; the fix then
    /// fused through the gate), and the carriers restarted.
    TightReturn {
        t: f64,
        gap_s: f64,
        offset_m: f64,
        widened: bool,
    },
    /// Tight coupling: the carriers of `flagged` of `of` satellites disagreed with the
    /// INS at once (its velocity, not cycle slips): TDCP is not fused until they
    /// agree again (tested every epoch); Doppler stands in when the receiver gives it.
    CarriersDistrusted { t: f64, flagged: usize, of: usize },
    /// Tight coupling: the carriers agree with the INS again (tested every epoch),
    /// `after_s` seconds after they were distrusted; TDCP resumes.
    CarriersTrusted { t: f64, after_s: f64 },
    /// How the initial attitude was found, and why that way (what the data showed;
    /// IMU data before the start not navigated; empty when there is nothing to say).
    Aligned {
        t: f64,
        method: &'static str,
        rpy_deg: [f64; 3],
        reason: String,
        /// IMU data read from the start time on but before the start, not navigated
        /// \[s\] (0: everything read is navigated).
        skipped_s: f64,
    },
    /// The vehicle came to rest / started moving (static detector).
    Static { t: f64, begins: bool },
    /// The receiver clock bias state was (re)set from the pseudoranges: at the first
    /// epoch, or after a clock jump of `jump_m`.
    ClockReset { t: f64, jump_m: f64 },
    /// A carrier-phase cycle slip: the carrier jump `jump_m` over the interval
    /// estimated against the INS and the other satellites, with its w-test statistic
    /// `w`; the satellite's carrier differencing restarts.
    CycleSlip {
        t: f64,
        sat: crate::sat::SatId,
        jump_m: f64,
        w: f64,
    },
    /// Tight coupling: the inter-system bias of `system` was set from the median of
    /// its `sats` satellites' pseudorange residuals (first seen, or back after a long
    /// absence).
    IsbSet {
        t: f64,
        system: crate::sat::System,
        isb_m: f64,
        sats: usize,
    },
    /// The GNSS integrity monitor changed state (spoofing detection).
    Integrity(Transition),
}

impl std::fmt::Display for Event {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Event::Rejected { t, source, nis, threshold } => write!(
                f,
                "{t:.3} {source} rejected: normalised innovation squared {nis:.1} > gate {threshold:.1}"
            ),
            Event::ImuGap { t, dt } => write!(
                f,
                "{t:.3} imu gap of {dt:.3} s bridged: position, velocity and attitude uncertainty grown by the plausible motion ([filter] gap_accel_mps2, gap_rate_dps)"
            ),
            Event::Singular { t, source } => {
                write!(f, "{t:.3} {source} dropped: innovation covariance not positive definite")
            }
            Event::GateBypassed { t, streak_s } => write!(
                f,
                "{t:.3} gnss fix used without the gate: fixes rejected for {streak_s:.1} s (gate timeout)"
            ),
            Event::GnssReadmitted { t, streak_s, offset_m } => write!(
                f,
                "{t:.3} gnss fixes re-admitted: rejected for {streak_s:.1} s but consistent with each other; the INS was {offset_m:.2} m away"
            ),
            Event::TightReturn {
                t,
                gap_s,
                offset_m,
                widened,
            } => write!(
                f,
                "{t:.3} gnss back after {gap_s:.1} s without a pseudorange used: the single point fix is {offset_m:.1} m away{}; carrier differencing restarted",
                if *widened { ", beyond the covariance: uncertainty widened and the fix fused" } else { ", within the covariance" }
            ),
            Event::CarriersDistrusted { t, flagged, of } => write!(
                f,
                "{t:.3} carriers of {flagged} of {of} satellites disagree with the INS at once (its velocity, not slips): TDCP paused, Doppler used"
            ),
            Event::CarriersTrusted { t, after_s } => write!(
                f,
                "{t:.3} carriers agree with the INS again after {after_s:.1} s: TDCP resumed"
            ),
            Event::Aligned {
                t,
                method,
                rpy_deg,
                reason,
                ..
            } => {
                write!(
                    f,
                    "{t:.3} aligned ({method}): roll {:.3} pitch {:.3} yaw {:.3} deg",
                    rpy_deg[0], rpy_deg[1], rpy_deg[2]
                )?;
                if reason.is_empty() {
                    Ok(())
                } else {
                    write!(f, "; {reason}")
                }
            }
            Event::ClockReset { t, jump_m } => write!(
                f,
                "{t:.3} receiver clock bias set from the pseudoranges (step {jump_m:.1} m)"
            ),
            Event::Integrity(tr) => {
                let th = if tr.threshold.is_finite() {
                    format!(" > {:.2}", tr.threshold)
                } else {
                    String::new()
                };
                write!(
                    f,
                    "{:.3} GNSS integrity: {} -> {} ({} {:.2}{th})",
                    tr.t,
                    tr.from.name(),
                    tr.to.name(),
                    tr.detector.name(),
                    tr.statistic
                )
            }
            Event::CycleSlip { t, sat, jump_m, w } => write!(
                f,
                "{t:.3} {sat} cycle slip: carrier jump {jump_m:.3} m against the INS (w-test {w:.1})"
            ),
            Event::IsbSet {
                t,
                system,
                isb_m,
                sats,
            } => write!(
                f,
                "{t:.3} {} inter-system bias set to {isb_m:.3} m from {sats} satellites",
                system.name()
            ),
            Event::Static { t, begins } => {
                if *begins {
                    write!(f, "{t:.3} static: zero-velocity updates start")
                } else {
                    write!(f, "{t:.3} moving: zero-velocity updates stop")
                }
            }
        }
    }
}

/// What aided the solution at an output epoch (`solution.csv` column `state`), in
/// this order of precedence: GNSS excluded by the integrity monitor, static (ZUPT),
/// GNSS fused recently, vehicle constraints (odometer, NHC) fused recently, free
/// inertial.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SolutionState {
    /// A GNSS fix or pseudorange was fused within the last GNSS intervals.
    Gnss,
    /// The static detector sees the vehicle at rest (zero-velocity updates).
    Static,
    /// No GNSS lately; odometer or NHC updates bound the drift.
    DeadReckoning,
    /// No GNSS and no vehicle constraint lately: the INS alone (coasting).
    Inertial,
    /// The integrity monitor holds GNSS out (spoofed, or recovering).
    GnssExcluded,
}

impl SolutionState {
    pub const ALL: [SolutionState; 5] = [
        SolutionState::Gnss,
        SolutionState::Static,
        SolutionState::DeadReckoning,
        SolutionState::Inertial,
        SolutionState::GnssExcluded,
    ];

    /// The name written in solution.csv.
    pub fn name(self) -> &'static str {
        match self {
            SolutionState::Gnss => "gnss",
            SolutionState::Static => "static",
            SolutionState::DeadReckoning => "dead_reckoning",
            SolutionState::Inertial => "inertial",
            SolutionState::GnssExcluded => "gnss_excluded",
        }
    }

    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|v| v.name() == s)
    }
}

/// One update tried by an aiding source (`innovations.csv`): what the gate saw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InnovationRow {
    /// GNSS time scale \[s\].
    pub t: f64,
    /// The measurement's name (`Aiding::name`, or a custom source's).
    pub source: &'static str,
    /// Number of rows stacked.
    pub rows: usize,
    /// The first three innovations h(x) - z, in the measurement's units (NaN past
    /// `rows`).
    pub innovation: [f64; 3],
    /// Normalised innovation squared y^T S^-1 y (NaN when S was singular).
    pub nis: f64,
    /// The chi-square gate on the NIS, when gated.
    pub gate: Option<f64>,
    pub outcome: UpdateKind,
}

/// How an update ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpdateKind {
    Applied,
    Rejected,
    Singular,
}

impl UpdateKind {
    pub fn name(self) -> &'static str {
        match self {
            UpdateKind::Applied => "applied",
            UpdateKind::Rejected => "rejected",
            UpdateKind::Singular => "singular",
        }
    }
}

/// A normalised innovation squared per row above this is "extreme": the filter and the
/// data disagree by more than 10 sigma (`InnovationStats::extreme`).
pub const EXTREME_NIS_PER_ROW: f64 = 100.0;

/// Consecutive updates of a source further apart than this \[s\] do not enter the
/// lag-1 autocorrelation of its innovations (an outage between them).
pub const AUTOCORR_MAX_GAP_S: f64 = 10.0;

/// Per-source statistics of the innovations of every update tried (applied or
/// rejected by its gate), for the consistency checks after a run: how often the NIS is
/// extreme, and the lag-1 autocorrelation of each row's normalised innovation
/// e = y / sqrt(S_ii). For a filter whose model matches the data the innovations are
/// white (REFERENCES \[BS\] §5.4: the innovation sequence of an optimal filter is
/// white with covariance S), so a clear positive autocorrelation says the errors are
/// time-correlated where the model has them white.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InnovationStats {
    /// Updates tried (applied or rejected; not singular ones).
    pub tried: usize,
    /// Of them, those with NIS per row above [`EXTREME_NIS_PER_ROW`].
    pub extreme: usize,
    /// Per row (the first three): sum of e_k e_{k-1}, of e_k², of e_{k-1}² over pairs
    /// of consecutive updates of the same number of rows within
    /// [`AUTOCORR_MAX_GAP_S`], and the number of pairs.
    pub lag_sum: [f64; 3],
    pub sq_sum: [f64; 3],
    pub sq_prev_sum: [f64; 3],
    pub pairs: [usize; 3],
    /// Sum of the intervals between those pairs \[s\].
    pub pair_dt_sum: f64,
    /// Sum over the updates tried of the Gaussian log-likelihood of the innovation,
    /// -(ln det(2 pi S) + NIS) / 2 (the innovation form of the likelihood: REFERENCES
    /// \[SCHWEPPE65\]).
    pub log_likelihood: f64,
    /// The previous update's time, rows and normalised innovations.
    prev: Option<(f64, usize, [f64; 3])>,
}

impl InnovationStats {
    /// Note one update tried at time `t` with innovation `y`, its innovation variances
    /// `s_diag` (first three rows), NIS and ln det S.
    pub fn note(&mut self, t: f64, y: &[f64], s_diag: &[f64; 3], nis: f64, log_det_s: f64) {
        let rows = y.len();
        self.tried += 1;
        self.log_likelihood -=
            0.5 * (log_det_s + rows as f64 * (2.0 * std::f64::consts::PI).ln() + nis);
        if nis > EXTREME_NIS_PER_ROW * rows.max(1) as f64 {
            self.extreme += 1;
        }
        let mut e = [f64::NAN; 3];
        for (k, (v, s)) in y.iter().zip(s_diag).enumerate() {
            e[k] = if *s > 0.0 { v / s.sqrt() } else { f64::NAN };
        }
        if let Some((t0, r0, e0)) = self.prev {
            if r0 == rows && (t - t0).abs() <= AUTOCORR_MAX_GAP_S && t != t0 {
                self.pair_dt_sum += (t - t0).abs();
                for k in 0..rows.min(3) {
                    if e[k].is_finite() && e0[k].is_finite() {
                        self.lag_sum[k] += e[k] * e0[k];
                        self.sq_sum[k] += e[k] * e[k];
                        self.sq_prev_sum[k] += e0[k] * e0[k];
                        self.pairs[k] += 1;
                    }
                }
            }
        }
        self.prev = Some((t, rows, e));
    }

    /// Lag-1 autocorrelation of row `k`'s normalised innovation (None with fewer than
    /// 10 pairs).
    pub fn autocorrelation(&self, k: usize) -> Option<f64> {
        let d = (self.sq_sum[k] * self.sq_prev_sum[k]).sqrt();
        (self.pairs[k] >= 10 && d > 0.0).then(|| self.lag_sum[k] / d)
    }

    /// Mean interval between the updates paired for the autocorrelation \[s\].
    pub fn mean_pair_dt(&self) -> Option<f64> {
        let n = self.pairs.iter().copied().max().unwrap_or(0);
        (n > 0).then(|| self.pair_dt_sum / n as f64)
    }

    /// Share of the updates tried with an extreme NIS.
    pub fn extreme_share(&self) -> f64 {
        self.extreme as f64 / self.tried.max(1) as f64
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
    /// Tight coupling: satellite measurements of systems not in `\[gnss\] systems`,
    /// ignored.
    pub gnss_sats_ignored: usize,
    pub outputs: usize,
    pub events: Vec<Event>,
    /// Per aiding source (Aiding::name): updates applied and rejected by their test.
    pub aiding_used: BTreeMap<&'static str, usize>,
    pub aiding_rejected: BTreeMap<&'static str, usize>,
    /// Per aiding source: sums of the normalised innovation squared of the applied
    /// updates and of their rows (mean NIS per row = 1 for a consistent filter).
    pub aiding_nis: BTreeMap<&'static str, (f64, usize)>,
    /// Per aiding source: how its innovations behaved ([`InnovationStats`]).
    pub innovation_stats: BTreeMap<&'static str, InnovationStats>,
    /// Time spent static according to the detector \[s\].
    pub static_s: f64,
    /// Final GNSS-IMU time offset at `last_t` and its 1-sigma \[s\], when estimated.
    pub time_offset: Option<(f64, f64)>,
    /// Final time-offset rate and its 1-sigma \[s/s\], when estimated.
    pub time_offset_rate: Option<(f64, f64)>,
    /// Final odometer scale k and its 1-sigma, when estimated.
    pub odometer_scale: Option<(f64, f64)>,
    /// Final IMU mounting roll, pitch, yaw \[rad\] and 1-sigma of pitch and yaw, when
    /// estimated.
    pub mounting: Option<(Vector3<f64>, [f64; 2])>,
    /// Final receiver clock bias \[m\] and drift \[m/s\], when estimated.
    pub receiver_clock: Option<(f64, f64)>,
    /// The uniform status of each aiding source at the end, in registry order.
    pub aid_status: Vec<AidStatus>,
    /// Final estimates of the blocks the sources define in their own files
    /// (`Block::Source`): name, values and 1-sigma per state.
    pub source_states: Vec<SourceState>,
    /// Adaptive measurement noise (aiding/adaptive.rs), when on: the final posterior
    /// of each source's scale on its configured R.
    pub adaptive_noise: Vec<(&'static str, crate::aiding::adaptive::ScalePosterior)>,
}

/// The final estimate of a source's own block.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SourceState {
    pub name: &'static str,
    pub value: Vec<f64>,
    pub std: Vec<f64>,
}

/// The uniform status of one aiding source, kept by the [`crate::aiding::source::Fuser`]
/// for every update the source makes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AidStatus {
    /// The source's name (`AidingSource::name`).
    pub name: &'static str,
    /// Updates applied (including down-weighted ones).
    pub fused: usize,
    /// Updates rejected by their test (gate, data snooping) or dropped as singular.
    pub rejected: usize,
    /// Innovation of the last update tried (its rows), h(x_est) - z.
    pub innovation: Vec<f64>,
    /// Normalised innovation squared of the last update tried.
    pub nis: Option<f64>,
    /// NIS / gate of the last gated update tried (> 1: rejected).
    pub test_ratio: Option<f64>,
    /// Whether the last update tried was applied.
    pub last_fused: bool,
    /// Time of the last applied update (GNSS time scale) \[s\].
    pub last_fused_t: Option<f64>,
}
