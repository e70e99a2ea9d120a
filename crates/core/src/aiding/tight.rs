//! Tightly coupled GNSS (REFERENCES \[SYS\] §3b; seed 000): one receiver epoch of
//! per-satellite pseudoranges with Doppler or time-differenced carrier phase, the
//! receiver clock bias and drift as filter states (models in pseudorange.rs,
//! doppler.rs, tdcp.rs).
//!
//! Policy: the clock bias is (re)set from the pseudoranges when needed; range rates
//! are fused before the pseudoranges (TDCP compares the carrier with the INS
//! displacement since the previous epoch, which must still match the state); each
//! kind is tested jointly per satellite (data snooping). Pseudoranges and Doppler
//! are then fused as scalar updates, each re-linearised at the state the previous
//! left; the TDCP rows of an epoch as one joint update, linearised together before
//! any of them (`Aiding::epoch_fixed`, `Fuser::fuse_epoch`: their prediction holds
//! the INS displacement of the interval, which a feedback does not move). A
//! satellite without a TDCP row applied (no carrier, a restart, a slip, the
//! carriers disagreeing with the INS) gives its Doppler instead. The carriers are
//! tested against the INS every epoch (jointly): most of them disagreeing at once is
//! the INS velocity off, not slips, and Doppler stands in until they agree again.
//! After `gate_timeout_s` without a pseudorange used, the single point fix pulls the
//! solution back first and the carrier differencing restarts.
//!
//! Several systems (`\[gnss\] systems`): the clock bias b is on GPS time, and each
//! other system enabled has an inter-system bias state ISB_sys (a random walk in the
//! source's own block, pseudorange.rs `isb_block`), set from the median of that
//! system's pseudorange residuals less b when the system is first seen or back after
//! `ISB_REINIT_GAP_S`. With no GPS satellite before any ISB is set, the first enabled
//! system present stands in for GPS: b takes its clock and its ISB starts at 0 with
//! `isb_init_sigma_m` (b and that ISB are then not separable until GPS comes; the
//! prior keeps them apart). Doppler and TDCP see one drift for every system (a
//! difference of drifts between the systems' time scales, ~1e-13, is ignored).

use super::gnss_integrity::GnssGuard;
use super::pseudorange::isb_block;
use super::source::{chi2_gate, stack_rows, AidingSource, EpochUpdate, Fuser, Handled};
use super::tdcp::{Interval, TdcpPrevious};
use super::{Aiding, Linearized, ReceiverClock};
use crate::config::{NavConfig, RangeRate, TightOptions};
use crate::earth::c_ne;
use crate::events::{Event, RunSummary};
use crate::integrity::IntegrityState;
use crate::nav::ins_filter::{BlockProcess, BlockSpec, Fused};
use crate::sat::{SatId, System};
use crate::state::{Block, POS, VEL};
use crate::types::{GnssFix, GnssRawEpoch, ImuSample, Measurement, SatMeasurement};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// A system unseen for this long \[s\] has its inter-system bias set again from its
/// pseudoranges when it comes back (the random walk alone would cover a drift of
/// `isb_psd_sqrt` sqrt(gap), which a receiver restart or firmware change can exceed).
const ISB_REINIT_GAP_S: f64 = 600.0;

/// Tight coupling as an aiding source (`\[gnss\] coupling = "tight"`).
pub struct TightGnss {
    opt: TightOptions,
    lever_arm_b: Vector3<f64>,
    gate_timeout_s: f64,
    guard: Option<GnssGuard>,
    clock_set: bool,
    /// The systems used (`GnssOptions::systems`); the others' measurements are ignored.
    systems: Vec<System>,
    /// Previous epoch's carrier per satellite.
    prev: BTreeMap<SatId, TdcpPrevious>,
    /// Per system with an inter-system bias state: the last epoch with one of its
    /// pseudoranges since the bias was set (absent: not set yet).
    isb_seen_t: BTreeMap<System, f64>,
    /// Time of the previous raw epoch.
    prev_t: Option<f64>,
    /// C_n^e C_b^n l^b at the previous epoch \[m\].
    prev_lever_ecef_m: Vector3<f64>,
    /// Time of the last epoch with a pseudorange fused (None: none yet).
    last_pr_used_t: Option<f64>,
    /// Since when the carriers disagree with the INS (most of them at once, tested
    /// every epoch): TDCP is paused, Doppler stands in (None: they agree).
    carriers_distrusted_since: Option<f64>,
}

/// What data snooping leaves: the rows kept with their linearisation, and those
/// dropped with their (w, blunder).
type Snooped<'a> = (Vec<(Aiding<'a>, Linearized)>, Vec<(Aiding<'a>, f64, f64)>);

/// Median of the values (reordered), None when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    })
}

impl TightGnss {
    /// None unless tight coupling is on.
    pub fn from_config(cfg: &NavConfig) -> Option<Self> {
        cfg.tight.enabled.then(|| TightGnss {
            opt: cfg.tight.clone(),
            lever_arm_b: cfg.gnss.lever_arm_b,
            gate_timeout_s: cfg.gnss.gate_timeout_s,
            guard: GnssGuard::from_config(cfg),
            clock_set: false,
            systems: cfg.gnss.systems.clone(),
            prev: BTreeMap::new(),
            isb_seen_t: BTreeMap::new(),
            prev_t: None,
            prev_lever_ecef_m: Vector3::zeros(),
            last_pr_used_t: None,
            carriers_distrusted_since: None,
        })
    }

    fn clock(f: &Fuser) -> ReceiverClock {
        let mut c = ReceiverClock {
            bias_m: f.extra(Block::ClockBias)[0],
            drift_mps: f.extra(Block::ClockDrift)[0],
            ..ReceiverClock::default()
        };
        for s in System::ALL {
            if let Some(&v) = isb_block(s).and_then(|b| f.extra(b).first()) {
                c.isb_m[s.index()] = v;
            }
        }
        c
    }

    /// The systems with an inter-system bias state (enabled, not on GPS time).
    fn isb_systems(&self) -> impl Iterator<Item = (System, Block)> + '_ {
        self.systems
            .iter()
            .filter_map(|&s| isb_block(s).map(|b| (s, b)))
    }

    /// Fuse with the current clock and remember the correction for the monitor.
    fn fuse(&mut self, f: &mut Fuser, a: Aiding, gate: Option<f64>) -> Fused {
        let r = f.fuse_with_clock(a, gate, Self::clock(f));
        self.note(&r);
        r
    }

    /// Remember a correction for the monitor.
    fn note(&mut self, r: &Fused) {
        if let Some(g) = self.guard.as_mut() {
            g.note(r);
        }
    }

    fn update(&mut self, f: &mut Fuser, epoch: &GnssRawEpoch) {
        let opt = &self.opt;
        let gate = chi2_gate(1, opt.gate_probability);
        // Elapsed times along the run (a backward run goes down in time).
        let dir = f.direction();
        // Sigmas: scaled, then floored (the TDCP floor is per interval of dt, shared
        // by the two epochs' carriers).
        let dt = self.prev_t.map_or(1.0, |t0| dir.elapsed(t0, epoch.t));
        let carrier_floor = opt.range_rate_sigma_floor_mps * dt / std::f64::consts::SQRT_2;
        let sats: Vec<SatMeasurement> = epoch
            .sats
            .iter()
            .filter(|s| self.systems.contains(&s.sat.system))
            .map(|s| SatMeasurement {
                pseudorange_std_m: (s.pseudorange_std_m
                    * opt.pseudorange_sigma_scale
                    * opt.sigma_scale.get(s.sat.system))
                .max(opt.pseudorange_sigma_floor_m),
                range_rate_std_mps: (s.range_rate_std_mps * opt.range_rate_sigma_scale)
                    .max(opt.range_rate_sigma_floor_mps),
                carrier_std_m: (s.carrier_std_m * opt.range_rate_sigma_scale).max(carrier_floor),
                ..*s
            })
            .collect();
        let ignored = epoch.sats.len() - sats.len();
        f.record().gnss_sats_ignored += ignored;
        self.check_clock(f, epoch.t, &sats);
        if let Some(guard) = self.guard.as_mut() {
            // The epoch as a whole, through its single point fix when it has one: the
            // fix (and its Doppler velocity) against the prediction, as in loose
            // coupling, with the fix's own covariance (the joint pseudorange NIS is
            // inflated by per-satellite biases the filter does not model). With 1-3
            // satellites, no fix: all pseudoranges jointly (chi-square only).
            let fix_pos = epoch.fix.as_ref().map(Aiding::GnssPosition);
            let prs: Vec<Aiding> = match epoch.fix.as_ref() {
                Some(f) if f.vel_ned.is_some() => {
                    vec![Aiding::GnssPosition(f), Aiding::GnssVelocity(f)]
                }
                Some(f) => vec![Aiding::GnssPosition(f)],
                None => sats
                    .iter()
                    .filter(|s| s.pseudorange_m.is_some())
                    .map(Aiding::Pseudorange)
                    .collect(),
            };
            // The single point fix is noisier than a receiver's filtered fix: the
            // distance threshold is at least its 3-sigma.
            let floor = epoch.fix.as_ref().map_or(0.0, |f| 3.0 * f.std_ned.norm());
            let clock = Self::clock(f);
            if !guard.check(f, epoch.t, &prs, fix_pos, floor, clock) {
                // Nothing of this epoch is used; carrier differencing restarts.
                self.prev_t = None;
                f.record().gnss_rejected += 1;
                return;
            }
        }
        // No pseudorange fused for gate_timeout_s (an outage, a long rejection streak,
        // or dead reckoning while the monitor held GNSS out): the solution may have
        // drifted beyond the pseudorange gates, and the clock reset would absorb part of
        // the offset, so the single point fix pulls it back first (as the loose gate
        // timeout does with a fix) and the clock is set again from there.
        if let (Some(fix), Some(t0), true) = (
            epoch.fix.as_ref(),
            self.last_pr_used_t,
            self.opt.use_pseudorange,
        ) {
            let gap_s = dir.elapsed(t0, epoch.t);
            if gap_s >= self.gate_timeout_s {
                self.return_from_gap(f, epoch.t, gap_s, fix);
                self.check_clock(f, epoch.t, &sats);
            }
        }
        let mut used = false;
        // Each kind is tested jointly against the prior (data snooping), so a faulty
        // satellite is found whatever its place in the list; the rest are fused.
        let w_max = gate.map(f64::sqrt);
        let beyond_gate = |_: &Aiding, w: f64, _: f64| w_max.is_some_and(|m| w.abs() > m);
        let doppler: Vec<Aiding> = sats
            .iter()
            .filter(|s| s.range_rate_mps.is_some())
            .map(Aiding::Doppler)
            .collect();
        match self.opt.range_rate {
            RangeRate::None => {}
            RangeRate::Doppler => used |= self.fuse_snooped(f, &doppler, beyond_gate, |_, _, _| {}),
            RangeRate::Tdcp => {
                let carried = self.fuse_tdcp(f, epoch.t, &sats);
                used |= !carried.is_empty();
                // Each satellite without a carrier row applied (no carrier, none at
                // the previous epoch, a slip, the carriers paused): its Doppler.
                let rest: Vec<Aiding> = doppler
                    .into_iter()
                    .filter(|a| matches!(a, Aiding::Doppler(s) if !carried.contains(&s.sat)))
                    .collect();
                used |= self.fuse_snooped(f, &rest, beyond_gate, |_, _, _| {});
            }
        }
        if self.opt.use_pseudorange {
            let rows: Vec<Aiding> = sats
                .iter()
                .filter(|s| s.pseudorange_m.is_some())
                .map(Aiding::Pseudorange)
                .collect();
            // Fewer than 4 pseudoranges do not fix the position: an epoch with them
            // does not end a gap (after a blockage the single point fix brings the
            // solution back as after an outage).
            let full = rows.len() >= 4;
            if self.fuse_snooped(f, &rows, beyond_gate, |_, _, _| {}) {
                used = true;
                if full {
                    self.last_pr_used_t = Some(epoch.t);
                }
            }
        }
        // The next TDCP interval starts from the attitude after all of this epoch's
        // updates.
        let nav = f.nav();
        let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
        self.prev_lever_ecef_m = c_ne(nav.lla.x, nav.lla.y) * c_bn * self.lever_arm_b;
        if used {
            f.record().gnss_used += 1;
            f.shared().last_gnss_used_t = epoch.t;
            f.shared().note_gnss_fused(epoch.t);
        } else {
            f.record().gnss_rejected += 1;
        }
    }

    /// Back after `gap_s` without a pseudorange used (an outage, a rejection streak,
    /// dead reckoning under the monitor): the solution may have drifted beyond the
    /// pseudorange gates and its covariance no longer covers that. The position and
    /// velocity variances grow by the single point fix's disagreement on the axes
    /// where the covariance cannot explain it (so the fix and the pseudoranges pass
    /// their gates, and an attitude the fix cannot correct is not pulled by an
    /// overconfident correlation), the fix is then fused through the gate (only when
    /// something was widened: otherwise the pseudoranges carry the same), the clock
    /// is set again, and carrier differencing restarts with Doppler standing in for
    /// TDCP meanwhile.
    fn return_from_gap(&mut self, f: &mut Fuser, t: f64, gap_s: f64, fix: &GnssFix) {
        f.flush_covariance();
        let (pos, vel) = {
            let ctx = f.context(Self::clock(f));
            (
                Aiding::GnssPosition(fix).linearize(&ctx),
                Aiding::GnssVelocity(fix).linearize(&ctx),
            )
        };
        // Widen only the axes whose disagreement the covariance cannot explain (beyond
        // 3 sigma of the prediction and the fix): an INS that is still better than
        // the single point fix keeps its weight.
        let mut widened = false;
        let mut offset_m = 0.0;
        for (lin, block) in [(&pos, POS), (&vel, VEL)] {
            let Some(l) = lin else { continue };
            let hph = &l.h * f.covariance() * l.h.transpose();
            for k in 0..3 {
                let (y2, s2) = (l.y[k].powi(2), hph[(k, k)] + l.r[(k, k)]);
                if y2 > 9.0 * s2 {
                    f.add_variance(block + k, y2);
                    widened = true;
                }
            }
            if block == POS {
                offset_m = l.y.norm();
            }
        }
        if widened {
            let gate = chi2_gate(3, Some(1e-4));
            self.fuse(f, Aiding::GnssPosition(fix), gate);
            if fix.vel_ned.is_some() {
                self.fuse(f, Aiding::GnssVelocity(fix), gate);
            }
        }
        f.push_event(Event::TightReturn {
            t,
            gap_s,
            offset_m,
            widened,
        });
        self.clock_set = false;
        self.prev_t = None;
    }

    /// Set the clock bias (and drift) states from the measurements at the first
    /// epoch, and again when the common pseudorange residual jumps by more than
    /// `clock_reset_m` (receivers that steer their clock in millisecond steps); then
    /// the inter-system biases not set yet (`check_isb`). The common residual is
    /// that of the satellites on GPS time and of the systems whose ISB is set (less
    /// it); before the clock is set with none of them, the first enabled system
    /// present stands in for GPS (its ISB set to 0).
    fn check_clock(&mut self, f: &mut Fuser, t: f64, sats: &[SatMeasurement]) {
        // Pseudorange residuals without any clock, with their system.
        let mut residuals: Vec<(System, f64)> = Vec::new();
        let mut drift: Vec<f64> = Vec::new();
        {
            let ctx = f.context(ReceiverClock::default());
            let (r_ant, c_ne, _) = super::pseudorange::antenna_ecef(&ctx);
            let v_ant = c_ne * super::gnss_velocity::antenna_velocity(&ctx);
            for s in sats {
                let d = s.sat_pos_ecef_m - r_ant;
                if let Some(p) = s.pseudorange_m {
                    residuals.push((s.sat.system, p - d.norm()));
                }
                if let Some(rr) = s.range_rate_mps {
                    drift.push(rr - d.normalize().dot(&(s.sat_vel_ecef_mps - v_ant)));
                }
            }
        }
        let isb = Self::clock(f).isb_m;
        let mut bias: Vec<f64> = residuals
            .iter()
            .filter(|(s, _)| isb_block(*s).is_none() || self.isb_current(f, *s, t))
            .map(|(s, r)| r - isb[s.index()])
            .collect();
        if bias.is_empty() && !self.clock_set {
            let stand_in = self
                .isb_systems()
                .find(|(s, _)| residuals.iter().any(|(x, _)| x == s));
            if let Some((system, block)) = stand_in {
                bias = residuals
                    .iter()
                    .filter(|(x, _)| *x == system)
                    .map(|(_, r)| *r)
                    .collect();
                self.set_isb(f, t, system, block, 0.0, bias.len());
            }
        }
        if let Some(b) = median(&mut bias) {
            let jump = b - Self::clock(f).bias_m;
            if !self.clock_set || jump.abs() > self.opt.clock_reset_m {
                self.reset_clock(f, t, b, jump, &mut drift);
            }
        }
        self.check_isb(f, t, &residuals);
    }

    /// Whether the inter-system bias of `system` is set and its system was seen
    /// within `ISB_REINIT_GAP_S`.
    fn isb_current(&self, f: &Fuser, system: System, t: f64) -> bool {
        self.isb_seen_t
            .get(&system)
            .is_some_and(|&t0| f.direction().elapsed(t0, t) <= ISB_REINIT_GAP_S)
    }

    /// Once the clock is set: the inter-system bias of each enabled system present
    /// and not current, from the median of its pseudorange residuals less the
    /// clock bias, with `isb_init_sigma_m`.
    fn check_isb(&mut self, f: &mut Fuser, t: f64, residuals: &[(System, f64)]) {
        if !self.clock_set {
            return;
        }
        let b = Self::clock(f).bias_m;
        let systems: Vec<(System, Block)> = self.isb_systems().collect();
        for (system, block) in systems {
            let mut r: Vec<f64> = residuals
                .iter()
                .filter(|(s, _)| *s == system)
                .map(|(_, r)| r - b)
                .collect();
            let n = r.len();
            let Some(m) = median(&mut r) else {
                continue;
            };
            if !self.isb_current(f, system, t) {
                self.set_isb(f, t, system, block, m, n);
            }
            self.isb_seen_t.insert(system, t);
        }
    }

    /// Set the inter-system bias of `system` to `isb_m` (from `sats` satellites).
    fn set_isb(
        &mut self,
        f: &mut Fuser,
        t: f64,
        system: System,
        block: Block,
        isb_m: f64,
        sats: usize,
    ) {
        let i = f.layout().index(block).expect("tight layout");
        f.flush_covariance();
        f.reset_state(i, self.opt.isb_init_sigma_m.powi(2));
        f.extra_mut(block)[0] = isb_m;
        self.isb_seen_t.insert(system, t);
        f.push_event(Event::IsbSet {
            t,
            system,
            isb_m,
            sats,
        });
    }

    /// Set the clock bias to `b` (a jump of `jump` from the state), and the drift
    /// from the median of `drift` at the first epoch.
    fn reset_clock(&mut self, f: &mut Fuser, t: f64, b: f64, jump: f64, drift: &mut [f64]) {
        let i = f.layout().index(Block::ClockBias).expect("tight layout");
        f.flush_covariance();
        // The bias absorbs the antenna position error: its sigma is the position's.
        let pos_var: f64 = (0..3).map(|k| f.covariance()[(POS + k, POS + k)]).sum();
        f.reset_state(i, pos_var + 10.0f64.powi(2));
        f.extra_mut(Block::ClockBias)[0] = b;
        if !self.clock_set {
            if let Some(d) = median(drift) {
                let vel_var: f64 = (0..3).map(|k| f.covariance()[(VEL + k, VEL + k)]).sum();
                f.reset_state(i + 1, vel_var + 1.0);
                f.extra_mut(Block::ClockDrift)[0] = d;
            }
        }
        self.clock_set = true;
        f.push_event(Event::ClockReset { t, jump_m: jump });
    }

    /// TDCP of the carriers continuous since the previous epoch, with the slip test,
    /// fused as one joint update; returns the satellites whose row was applied (none
    /// when the carriers of most satellites disagree with the INS at once: paused
    /// until an epoch where they agree). The epoch's carriers are remembered either
    /// way.
    fn fuse_tdcp(&mut self, f: &mut Fuser, t: f64, sats: &[SatMeasurement]) -> Vec<SatId> {
        let (slip_sigma, slip_min_m) = (self.opt.slip_sigma, self.opt.slip_min_m);
        let nav = *f.nav();
        let c_bn = nav.q_bn.to_rotation_matrix().into_inner();
        let lever_ecef = c_ne(nav.lla.x, nav.lla.y) * c_bn * self.lever_arm_b;
        // Backward the previous epoch is the later one: D and dt are both from it to
        // this epoch (signed), and the TDCP model holds as it is (tdcp.rs).
        let interval = self.prev_t.map(|t0| Interval {
            antenna_displacement_ecef_m: f.displacement_ecef_m() + lever_ecef
                - self.prev_lever_ecef_m,
            dt_s: t - t0,
        });
        let mut rows = Vec::new();
        if let Some(iv) = interval.filter(|iv| iv.dt_s.abs() <= self.opt.tdcp_max_gap_s) {
            for s in sats
                .iter()
                .filter(|s| !s.lost_lock && s.carrier_m.is_some())
            {
                if let Some(&prev) = self.prev.get(&s.sat) {
                    rows.push(Aiding::Tdcp(s, prev, iv));
                }
            }
        }
        // Cycle-slip test against the INS prediction, all satellites jointly: a slip is
        // a carrier jump beyond slip_sigma (w-test) and beyond slip_min_m.
        let slipped = |a: &Aiding, w: f64, blunder: f64| match a {
            Aiding::Tdcp(_, _, iv) => {
                w.abs() > slip_sigma && (blunder * iv.dt_s).abs() > slip_min_m
            }
            _ => false,
        };
        // Slips are rare and per satellite: the data snooping removes them one at a
        // time (the worst first, then the rest tested again). Most carriers removed
        // is the INS velocity being off (after an outage, or a covariance that does
        // not cover its error), not slips: no TDCP this epoch; the carriers are tested
        // again at the next (one large slip alone flags the others too in the first
        // joint test, so the count is of the rows removed, not of those flagged).
        let mut carried = Vec::new();
        if !rows.is_empty() {
            let (keep, dropped) = Self::snoop(f, &rows, slipped);
            let storm = dropped.len() >= 3 && 2 * dropped.len() > rows.len();
            if storm {
                if self.carriers_distrusted_since.is_none() {
                    self.carriers_distrusted_since = Some(t);
                    f.push_event(Event::CarriersDistrusted {
                        t,
                        flagged: dropped.len(),
                        of: rows.len(),
                    });
                }
            } else {
                if let Some(since) = self.carriers_distrusted_since.take() {
                    f.push_event(Event::CarriersTrusted {
                        t,
                        after_s: f.direction().elapsed(since, t),
                    });
                }
                for (a, w, blunder) in &dropped {
                    if let Aiding::Tdcp(s, _, iv) = a {
                        f.push_event(Event::CycleSlip {
                            t,
                            sat: s.sat,
                            jump_m: blunder * iv.dt_s,
                            w: *w,
                        });
                    }
                    f.count_rejected(a.name());
                }
                // The rows left are fused together (all or none).
                let sats: Vec<SatId> = keep
                    .iter()
                    .filter_map(|(a, _)| match a {
                        Aiding::Tdcp(s, ..) => Some(s.sat),
                        _ => None,
                    })
                    .collect();
                if self.fuse_kept(f, keep) {
                    carried = sats;
                }
            }
        }
        // Remember this epoch (after the updates: the displacement restarts here).
        self.prev.clear();
        for s in sats {
            if let Some(c) = s.carrier_m {
                self.prev.insert(
                    s.sat,
                    TdcpPrevious {
                        t,
                        sat_pos_ecef_m: s.sat_pos_ecef_m,
                        carrier_m: c,
                        carrier_std_m: s.carrier_std_m,
                    },
                );
            }
        }
        self.prev_t = Some(t);
        f.restart_displacement();
        carried
    }

    /// Fuse one-row measurements after data snooping ([`TightGnss::snoop`]; each row
    /// dropped is reported through `rejected` and counted as rejected), then the rest
    /// ([`TightGnss::fuse_kept`]). True if any was applied.
    fn fuse_snooped(
        &mut self,
        f: &mut Fuser,
        rows: &[Aiding],
        is_blunder: impl Fn(&Aiding, f64, f64) -> bool,
        mut rejected: impl FnMut(&Aiding, f64, f64),
    ) -> bool {
        let (keep, dropped) = Self::snoop(f, rows, is_blunder);
        for (a, w, b) in &dropped {
            rejected(a, *w, *b);
            f.count_rejected(a.name());
        }
        self.fuse_kept(f, keep)
    }

    /// Data snooping: test the rows jointly against the prior (Baarda's w-test,
    /// [`crate::filter::Eskf::blunder_test`]) and drop the worst while
    /// `is_blunder(row, w, blunder)` holds for it, testing the rest again. Returns the
    /// rows kept with their linearisation at the current state, and those dropped
    /// with (w, blunder), in the order dropped.
    fn snoop<'a>(
        f: &mut Fuser,
        rows: &[Aiding<'a>],
        is_blunder: impl Fn(&Aiding, f64, f64) -> bool,
    ) -> Snooped<'a> {
        f.flush_covariance();
        let mut keep: Vec<(Aiding, Linearized)> = {
            let ctx = f.context(Self::clock(f));
            rows.iter()
                .filter_map(|a| a.linearize(&ctx).map(|lin| (*a, lin)))
                .collect()
        };
        let mut dropped = Vec::new();
        while !keep.is_empty() {
            let lins: Vec<&Linearized> = keep.iter().map(|(_, lin)| lin).collect();
            let Some(mut stacked) = stack_rows(&lins, f.layout().len()) else {
                break;
            };
            // Under adaptive noise, each row with its source's current scale.
            for (i, (a, _)) in keep.iter().enumerate() {
                let s = f.noise_scale(a.name());
                if s != 1.0 {
                    stacked.r[(i, i)] *= s;
                }
            }
            let Some(tests) = f.blunder_test(&stacked) else {
                break;
            };
            let worst = tests
                .iter()
                .enumerate()
                .filter(|(i, (w, b))| is_blunder(&keep[*i].0, *w, *b))
                .max_by(|a, b| a.1 .0.abs().total_cmp(&b.1 .0.abs()));
            let Some((i, &(w, b))) = worst else {
                break;
            };
            let (a, _) = keep.remove(i);
            dropped.push((a, w, b));
        }
        (keep, dropped)
    }

    /// Fuse the rows kept by [`TightGnss::snoop`] (nothing fused since): those whose
    /// prediction is fixed at the epoch's start (`Aiding::epoch_fixed`, TDCP) together
    /// in one update with the linearisation just tested, then the others one at a
    /// time, each re-linearised at the state the previous left. True if any was
    /// applied.
    fn fuse_kept(&mut self, f: &mut Fuser, keep: Vec<(Aiding, Linearized)>) -> bool {
        let (joint, single): (Vec<_>, Vec<_>) =
            keep.into_iter().partition(|(a, _)| a.epoch_fixed());
        let mut used = false;
        if !joint.is_empty() {
            let rows: Vec<(&'static str, &Linearized)> =
                joint.iter().map(|(a, lin)| (a.name(), lin)).collect();
            let r = f.fuse_epoch(&rows, EpochUpdate::OneShot { gate: None });
            self.note(&r);
            used |= r.applied();
        }
        for (a, _) in single {
            used |= self.fuse(f, a, None).applied();
        }
        used
    }
}

impl AidingSource for TightGnss {
    fn name(&self) -> &'static str {
        "gnss_tight"
    }

    fn blocks(&self) -> Vec<BlockSpec> {
        // The clock states are set from the first epoch's measurements (check_clock),
        // the inter-system biases from the first of each system's (check_isb).
        let isb = self.isb_systems().map(|(_, block)| BlockSpec {
            block,
            initial_variance: vec![self.opt.isb_init_sigma_m.powi(2)],
            process: BlockProcess::RandomWalk(self.opt.isb_psd_sqrt.powi(2)),
        });
        let mut v = vec![
            BlockSpec {
                block: Block::ClockBias,
                initial_variance: vec![1.0],
                process: BlockProcess::RandomWalk(self.opt.clock_bias_psd_sqrt.powi(2)),
            },
            BlockSpec {
                block: Block::ClockDrift,
                initial_variance: vec![self.opt.clock_drift_std0_mps.powi(2)],
                process: BlockProcess::RandomWalk(self.opt.clock_drift_psd_sqrt.powi(2)),
            },
        ];
        v.extend(isb);
        v
    }

    fn tracks_displacement(&self) -> bool {
        self.opt.range_rate == RangeRate::Tdcp
    }

    fn on_measurement(&mut self, m: &Measurement, f: &mut Fuser) -> Handled {
        let Measurement::GnssRaw(epoch) = m else {
            return Handled::No;
        };
        self.update(f, epoch);
        Handled::Yes
    }

    /// The clock bias follows its drift (backward the piece is time-reversed, dt < 0:
    /// b(t - |dt|) = b(t) - drift |dt|).
    fn on_propagate(&mut self, s: &ImuSample, f: &mut Fuser) {
        let drift = f.extra(Block::ClockDrift)[0];
        f.extra_mut(Block::ClockBias)[0] += drift * s.dt;
    }

    fn integrity_state(&self) -> Option<IntegrityState> {
        self.guard.as_ref().map(|g| g.state())
    }

    fn finish(&self, f: &Fuser, summary: &mut RunSummary) {
        let c = Self::clock(f);
        summary.receiver_clock = Some((c.bias_m, c.drift_mps));
    }
}
