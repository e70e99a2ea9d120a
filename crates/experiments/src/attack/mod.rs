//! `navfuse reproduce seed004 --attack | --jump-runs N | --clean-hours H`: seed 004's
//! spoofing experiment (SYSTEM.md §5, §7 seed 004 row; issue 6) on the simulator.
//!
//! - `--attack`: `scenarios/seed004_attack.toml` (built in: two laps of the seed 004
//!   loop, a 300 s drift attack at 2 m/s) simulated once per seed; every variant runs
//!   on the same data (`navfuse_app::run_job`) and is scored against the truth: alarms
//!   before the attack, detection delay and detector, maximum errors during the attack
//!   and in the 60 s after it, 3D RMSE over the run; mean [min, max] over the seeds
//!   beside the paper's statements.
//! - `--jump-runs N`: N jump attacks on the same car (one lap, seed004_loop.toml) and
//!   navigator as the `monitor` variant: random seed, direction uniform on the sphere,
//!   magnitude 20-200 m, start uniform while the car moves; fraction detected within
//!   1 s, delays, early alarms.
//! - `--clean-hours H`: false alarms on clean drives (no attack) with a MEMS IMU
//!   (ADIS16405, 50 Hz) + odometer + NHC and the `[spoofing]` defaults, in 1-hour
//!   drives of repeated loops with a stop each lap; transitions out of trusted and
//!   entries to spoofed per 10 h.
//!
//! Runs go to two worker threads (the machine has two cores); each run's directory
//! is removed once scored unless `--keep DIR`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use anyhow::{anyhow, bail, Context, Result};
use navfuse_core::config::NhcMode;
use navfuse_core::eval::{evaluate, EvalOptions};
use navfuse_core::integrity::{IntegrityOptions, IntegrityReference, IntegrityState, Transition};
use navfuse_core::outage::Window;
use navfuse_core::Event;
use navfuse_io::config::RunConfig;
use navfuse_sim::generate::generate;
use navfuse_sim::gnss_sim::EventSpec;
use navfuse_sim::random::Stream;
use navfuse_sim::scenario::Scenario;
use serde_json::{json, Value};

use crate::reproduce::{seed004_odometer, seed004_start, spread, user_start, Variant};
use crate::track::load_nav;
use navfuse_app::run_job;

const ATTACK_SCENARIO: &str = "scenarios/seed004_attack.toml";
const ATTACK_TEXT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/seed004_attack.toml"
));
const LOOP_SCENARIO: &str = "scenarios/seed004_loop.toml";
const LOOP_TEXT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/seed004_loop.toml"
));
/// Worker threads (the target machine has two cores).
const WORKERS: usize = 2;
/// Window after the attack's end over which the recovery errors are taken [s].
const AFTER_S: f64 = 60.0;

/// What `navfuse reproduce seed004` was asked for beyond the plain experiment.
pub struct AttackRequest {
    /// The variant table on the attack scenario.
    pub attack: bool,
    /// Runs of the jump Monte Carlo (0 = none).
    pub jump_runs: usize,
    /// Hours of clean driving for the false-alarm count (0 = none).
    pub clean_hours: f64,
}

// ---------------------------------------------------------------------------------
// Navigator configurations

/// Seed 004's start (surveyed position, static levelling + gyrocompassing, ZUPT while
/// static) with the GNSS fixes kept.
fn attack_start(cfg: &mut RunConfig, sc: &Scenario) {
    let gnss = cfg.gnss.take();
    seed004_start(cfg, sc);
    cfg.gnss = gnss;
}

/// The INS/odometer reference: seed 004's odometer and the NHC at every epoch.
fn odometer_nhc(cfg: &mut RunConfig, sc: &Scenario) {
    seed004_odometer(cfg, sc);
    cfg.nav.nhc.mode = NhcMode::Always;
}

/// `[spoofing]` with its defaults (the thresholds under test), and the fix error's
/// correlation time, which the simulator sets (`[gnss.fix] corr_time_s = 30`).
fn monitor_defaults(cfg: &mut RunConfig) {
    cfg.nav.integrity = IntegrityOptions {
        enabled: true,
        gnss_corr_time_s: 30.0,
        ..IntegrityOptions::default()
    };
}

/// Seed 004's architecture: the 6-state fusion (every fix) of GNSS with a dead
/// reckoning that GNSS never corrects, and the monitor testing the GNSS against that
/// dead reckoning (r_INS/OD) with its own covariance.
fn seed004_architecture(cfg: &mut RunConfig) {
    six_state_fusion(cfg);
    // With no GNSS to calibrate them, the dead reckoning's biases wander as the
    // grade's in-run Gauss-Markov process (IMU500: 100 s), not the slow 1 h process
    // that a GNSS-aided filter uses to keep what it has learnt.
    cfg.nav.imu_noise.corr_time_s = 100.0;
    cfg.nav.integrity.reference = IntegrityReference::DeadReckoning;
}

/// Seed 004's 6-state fusion of every fix (`[gnss] fusion = "six_state"`).
fn six_state_fusion(cfg: &mut RunConfig) {
    cfg.nav.gnss.fusion = navfuse_core::config::GnssFusion::SixState {
        every: std::num::NonZeroU32::MIN,
    };
}

/// Seed 004's detector alone: distance R = 10 m, the statistical tests off.
/// (Every statistical detector of `IntegrityOptions` must be switched off here.)
fn distance_only(cfg: &mut RunConfig) {
    monitor_defaults(cfg);
    let i = &mut cfg.nav.integrity;
    i.distance_m = Some(10.0);
    i.chi2_probability = None;
    i.window_epochs = 0;
}

/// The per-epoch chi-square test alone (distance and window off).
fn chi2_only(cfg: &mut RunConfig) {
    monitor_defaults(cfg);
    let i = &mut cfg.nav.integrity;
    i.distance_m = None;
    i.window_epochs = 0;
}

/// The attack's window (start, end) from the scenario's spoof event [s from the start].
fn attack_window_rel(sc: &Scenario) -> Option<(f64, f64)> {
    sc.file.gnss.as_ref()?.events.iter().find_map(|e| match e {
        EventSpec::Spoof { start_s, end_s, .. } => Some((*start_s, *end_s)),
        _ => None,
    })
}

fn variants() -> Vec<Variant> {
    vec![
        Variant {
            name: "no_monitor",
            label: "IMU + odometer + NHC (always) + GNSS, no monitor",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
            },
        },
        Variant {
            name: "monitor",
            label:
                "same + [spoofing] defaults (R 10 m, chi-square, window), INS/odometer reference",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                monitor_defaults(c);
            },
        },
        Variant {
            name: "monitor_R",
            label: "same, seed 004's detector alone: distance R = 10 m (chi-square, window off)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                distance_only(c);
            },
        },
        Variant {
            name: "odo_dr_R",
            label: "seed 004's system: 6-state fusion, the free INS/odometer/NHC dead reckoning as the reference, R = 10 m alone",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                distance_only(c);
                seed004_architecture(c);
            },
        },
        Variant {
            name: "ins_only_R",
            label: "same with a free INS-only dead reckoning (no odometer, no NHC), R = 10 m alone",
            apply: |c, sc| {
                attack_start(c, sc);
                distance_only(c);
                seed004_architecture(c);
            },
        },
        Variant {
            name: "ins_only_chi2",
            label: "free INS-only dead reckoning, chi-square with its own covariance alone",
            apply: |c, sc| {
                attack_start(c, sc);
                chi2_only(c);
                seed004_architecture(c);
            },
        },
        Variant {
            name: "dead_reckoning",
            label: "IMU + odometer + NHC, GNSS removed over the attack (INS/odometer drift bound)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                withhold_gnss_over_attack(c, sc);
            },
        },
        // seed 004's 6-state fusion (`[gnss] fusion = "six_state"`, every fix):
        // GNSS fused with the INS/odometer/NHC dead reckoning by X = [r^n, v^n].
        Variant {
            name: "six_state_monitor",
            label: "seed 004's 6-state fusion of GNSS with INS/odometer/NHC + [spoofing] defaults (against its prediction)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                monitor_defaults(c);
                six_state_fusion(c);
            },
        },
        Variant {
            name: "six_state_dead_reckoning",
            label: "the same 6-state fusion, GNSS removed over the attack (its drift bound)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                six_state_fusion(c);
                withhold_gnss_over_attack(c, sc);
            },
        },
    ]
}

/// An outage over the attack: epochs strictly inside are withheld, so the last fix used
/// is the one before the attack (the first spoofed one, at its start, already carries
/// the false velocity) and the next the true one at its end.
fn withhold_gnss_over_attack(c: &mut RunConfig, sc: &Scenario) {
    // Fused as under the monitor (white fixes, no gate), so that the bound is the
    // monitored filter's own.
    c.nav.gnss.gate_probability = None;
    c.nav.gnss.fix_error = navfuse_core::config::FixErrorOptions::white();
    if let Some((a, b)) = attack_window_rel(sc) {
        let t0 = sc.file.start.time_s;
        c.nav.gnss.outages.windows.push(Window {
            start: t0 + a - 0.5,
            end: t0 + b,
        });
    }
}

// ---------------------------------------------------------------------------------
// Scoring

/// The monitor's transitions of a run.
fn transitions(events: &[Event]) -> Vec<Transition> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Integrity(tr) => Some(*tr),
            _ => None,
        })
        .collect()
}

/// How the monitor reacted to an attack over [a, b] (absolute times).
#[derive(Clone, Debug, Default)]
struct Reaction {
    /// Transitions out of trusted, and entries to spoofed, before a.
    alarms_before: usize,
    spoofed_before: usize,
    /// Delay from a to the first transition out of trusted in [a, b), its detector;
    /// 0 with "already <state>" when the monitor was not trusted at a.
    delay_s: Option<f64>,
    detector: Option<String>,
    /// Delay from a to the first entry to spoofed in [a, b).
    spoofed_delay_s: Option<f64>,
    /// Returns to trusted in (a, b): the false track accepted again.
    readmitted_during: usize,
    /// Time from b to the first return to trusted at or after b (None: never, or the
    /// monitor was trusted anyway).
    trusted_after_end_s: Option<f64>,
}

fn reaction(trs: &[Transition], a: f64, b: f64) -> Reaction {
    let mut r = Reaction::default();
    let mut state = IntegrityState::Trusted;
    for tr in trs.iter().filter(|tr| tr.t < a) {
        r.alarms_before += usize::from(tr.from == IntegrityState::Trusted);
        r.spoofed_before += usize::from(tr.to == IntegrityState::Spoofed);
        state = tr.to;
    }
    if state != IntegrityState::Trusted {
        r.delay_s = Some(0.0);
        r.detector = Some(format!("already {}", state.name()));
    } else if let Some(tr) = trs
        .iter()
        .find(|tr| tr.t >= a && tr.t < b && tr.from == IntegrityState::Trusted)
    {
        r.delay_s = Some(tr.t - a);
        r.detector = Some(tr.detector.name().to_string());
    }
    r.spoofed_delay_s = trs
        .iter()
        .find(|tr| tr.t >= a && tr.t < b && tr.to == IntegrityState::Spoofed)
        .map(|tr| tr.t - a);
    r.readmitted_during = trs
        .iter()
        .filter(|tr| tr.t > a && tr.t < b && tr.to == IntegrityState::Trusted)
        .count();
    let state_at_b = trs
        .iter()
        .rfind(|tr| tr.t < b)
        .map_or(IntegrityState::Trusted, |tr| tr.to);
    if state_at_b != IntegrityState::Trusted {
        r.trusted_after_end_s = trs
            .iter()
            .find(|tr| tr.t >= b && tr.to == IntegrityState::Trusted)
            .map(|tr| tr.t - b);
    }
    r
}

/// The rows of the attack table: (key, label, decimals). Counts have 1 decimal (a
/// mean over seeds).
const ROWS: [(&str, &str, usize); 11] = [
    (
        "alarms_before",
        "alarms before the attack (out of trusted)",
        1,
    ),
    ("spoofed_before", "declared spoofed before the attack", 1),
    ("delay_s", "detection delay after the attack start [s]", 1),
    ("spoofed_delay_s", "declared spoofed after [s]", 1),
    ("readmitted_during", "GNSS re-admitted during the attack", 1),
    (
        "trusted_after_end_s",
        "trusted again after the attack end [s]",
        1,
    ),
    ("max_h_attack_m", "max horizontal error, attack [m]", 2),
    ("max_3d_attack_m", "max 3D error, attack [m]", 2),
    ("max_h_after_m", "max horizontal error, 60 s after [m]", 2),
    ("max_3d_after_m", "max 3D error, 60 s after [m]", 2),
    ("rmse_3d_m", "3D RMSE over the run [m]", 2),
];

/// One variant on one seed.
#[derive(Clone, Debug)]
struct VariantRun {
    monitor: bool,
    /// ROWS values; NaN = not applicable / did not happen.
    values: Vec<(&'static str, f64)>,
    detector: Option<String>,
    /// (t from the start, from, to, detector, statistic, threshold).
    transitions: Vec<(f64, String, String, String, f64, f64)>,
}

impl VariantRun {
    fn get(&self, k: &str) -> f64 {
        self.values
            .iter()
            .find(|(n, _)| *n == k)
            .map_or(f64::NAN, |(_, v)| *v)
    }
}

fn nan_or(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

fn transition_rows(trs: &[Transition], t0: f64) -> Vec<(f64, String, String, String, f64, f64)> {
    trs.iter()
        .map(|tr| {
            (
                tr.t - t0,
                tr.from.name().to_string(),
                tr.to.name().to_string(),
                tr.detector.name().to_string(),
                tr.statistic,
                tr.threshold,
            )
        })
        .collect()
}

/// Simulate `text` into `dir`.
fn simulate(
    name: &str,
    text: String,
    seed: u64,
    dir: &Path,
) -> Result<(Scenario, navfuse_sim::generate::SimSummary)> {
    let mut sc = Scenario::from_text(Path::new(name), text).map_err(|e| anyhow!("{e}"))?;
    sc.file.seed = seed;
    let sim = generate(&sc, dir).map_err(|e| anyhow!("{e}"))?;
    Ok((sc, sim))
}

/// Configure from the simulator's run.toml, run into `out`; whether the monitor ran,
/// and its transitions.
fn navigate(
    dir: &Path,
    sc: &Scenario,
    apply: impl Fn(&mut RunConfig, &Scenario),
    out: &Path,
) -> Result<(bool, Vec<Transition>)> {
    let mut cfg = navfuse_io::config::load(&dir.join("run.toml")).map_err(|e| anyhow!("{e}"))?;
    apply(&mut cfg, sc);
    let monitor = cfg.nav.integrity.enabled;
    let job = run_job(cfg, out, false)?;
    Ok((monitor, transitions(&job.summary.events)))
}

/// The simulated truth and a run's solution.
fn load_tracks(
    dir: &Path,
    out: &Path,
) -> Result<(
    Vec<navfuse_core::eval::TrajPoint>,
    Vec<navfuse_core::eval::TrajPoint>,
)> {
    Ok((
        load_nav(&dir.join("truth.nav"))?.points,
        load_nav(&out.join("solution.nav"))?.points,
    ))
}

/// Seed 004's attack scenario with this seed: every variant.
fn attack_seed(seed: u64, work: &Path, keep: bool, quiet: bool) -> Result<Vec<VariantRun>> {
    let dir = work.join(format!("seed004_attack_seed{seed}"));
    let (sc, _sim) = simulate(ATTACK_SCENARIO, ATTACK_TEXT.to_string(), seed, &dir)?;
    let truth = load_nav(&dir.join("truth.nav"))?.points;
    let t0 = sc.file.start.time_s;
    let (a_rel, b_rel) =
        attack_window_rel(&sc).ok_or_else(|| anyhow!("{ATTACK_SCENARIO}: no spoof event"))?;
    let (a, b) = (t0 + a_rel, t0 + b_rel);
    let mut runs = Vec::new();
    for v in variants() {
        let t_run = std::time::Instant::now();
        let out = dir.join(v.name);
        let (monitor, trs) = navigate(&dir, &sc, v.apply, &out)
            .with_context(|| format!("seed004 --attack seed {seed}: variant {}", v.name))?;
        let sol = load_nav(&out.join("solution.nav"))?.points;
        let rep = evaluate(
            &sol,
            &truth,
            &EvalOptions {
                gaps: vec![
                    Window { start: a, end: b },
                    Window {
                        start: b,
                        end: b + AFTER_S,
                    },
                ],
                ..EvalOptions::default()
            },
        );
        let gap = |k: usize| rep.gaps.get(k);
        let r = reaction(&trs, a, b);
        let m = |x: Option<f64>| if monitor { nan_or(x) } else { f64::NAN };
        let c = |x: usize| if monitor { x as f64 } else { f64::NAN };
        let values = vec![
            ("alarms_before", c(r.alarms_before)),
            ("spoofed_before", c(r.spoofed_before)),
            ("delay_s", m(r.delay_s)),
            ("spoofed_delay_s", m(r.spoofed_delay_s)),
            ("readmitted_during", c(r.readmitted_during)),
            ("trusted_after_end_s", m(r.trusted_after_end_s)),
            ("max_h_attack_m", nan_or(gap(0).map(|g| g.max_horizontal))),
            ("max_3d_attack_m", nan_or(gap(0).map(|g| g.max_3d))),
            ("max_h_after_m", nan_or(gap(1).map(|g| g.max_horizontal))),
            ("max_3d_after_m", nan_or(gap(1).map(|g| g.max_3d))),
            ("rmse_3d_m", rep.pos_3d.rms),
        ];
        let run = VariantRun {
            monitor,
            values,
            detector: r.detector.clone(),
            transitions: transition_rows(&trs, t0),
        };
        if !quiet {
            let first_early = trs
                .iter()
                .find(|tr| tr.t < a && tr.from == IntegrityState::Trusted)
                .map(|tr| format!(", first at {:.0} s ({})", tr.t - t0, tr.detector.name()))
                .unwrap_or_default();
            eprintln!(
                "  seed004 --attack seed {seed} {:<17} {}; max H attack {:7.2} m, after {:7.2} m; 3D RMSE {:7.2} m ({:.2} s)",
                v.name,
                if monitor {
                    format!(
                        "alarms before {}{first_early}, detected {}",
                        r.alarms_before,
                        match (&r.delay_s, &r.detector) {
                            (Some(d), Some(det)) => format!("after {d:.0} s by {det}"),
                            _ => "never".into(),
                        }
                    )
                } else {
                    "no monitor".into()
                },
                run.get("max_h_attack_m"),
                run.get("max_h_after_m"),
                run.get("rmse_3d_m"),
                t_run.elapsed().as_secs_f64()
            );
        }
        runs.push(run);
    }
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(runs)
}

/// Per variant, per seed.
struct AttackResults {
    seeds: Vec<u64>,
    attack_rel: (f64, f64),
    per_variant: Vec<(Variant, Vec<VariantRun>)>,
}

impl AttackResults {
    fn runs(&self, name: &str) -> &[VariantRun] {
        self.per_variant
            .iter()
            .find(|(v, _)| v.name == name)
            .map_or(&[], |(_, r)| r.as_slice())
    }

    fn finite(&self, name: &str, key: &str) -> Vec<f64> {
        self.runs(name)
            .iter()
            .map(|r| r.get(key))
            .filter(|x| x.is_finite())
            .collect()
    }
}

/// "mean [min, max]" of the finite values, "(k/n)" when some are missing, "-" when
/// none is finite.
fn cell(xs: &[f64], n: usize, dec: usize) -> String {
    if xs.is_empty() {
        return if n == 0 {
            "-".into()
        } else {
            format!("- (0/{n})")
        };
    }
    let (mean, lo, hi) = spread(xs);
    let mut s = if xs.len() == 1 || lo == hi {
        format!("{mean:.dec$}")
    } else {
        format!("{mean:.dec$} [{lo:.dec$}, {hi:.dec$}]")
    };
    if xs.len() < n {
        s.push_str(&format!(" ({}/{n})", xs.len()));
    }
    s
}

/// The detectors that detected, with counts: "window x3, chi2".
fn detectors(runs: &[VariantRun]) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for d in runs.iter().filter_map(|r| r.detector.clone()) {
        match counts.iter_mut().find(|(n, _)| *n == d) {
            Some((_, k)) => *k += 1,
            None => counts.push((d, 1)),
        }
    }
    if counts.is_empty() {
        return "-".into();
    }
    counts
        .iter()
        .map(|(d, k)| {
            if *k > 1 {
                format!("{d} x{k}")
            } else {
                d.clone()
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The paper's statements (SYSTEM.md §7 seed 004 row; §5) and what we measured.
fn paper_lines(r: &AttackResults) -> Vec<(&'static str, String)> {
    let n = r.seeds.len();
    let c = |v: &str, k: &str, dec: usize| cell(&r.finite(v, k), n, dec);
    let any = |v: &str, k: &str| {
        r.runs(v)
            .iter()
            .filter(|x| x.get(k).is_finite() && x.get(k) > 0.0)
            .count()
    };
    let detected = |v: &str| r.finite(v, "delay_s").len();
    vec![
        (
            "§7: spoofed segment detected with R = 10 m",
            format!(
                "monitor_R: detected in {}/{n} seeds, after {} s ({}); alarms before the attack {}",
                detected("monitor_R"),
                c("monitor_R", "delay_s", 1),
                detectors(r.runs("monitor_R")),
                c("monitor_R", "alarms_before", 1)
            ),
        ),
        (
            "§7: ... and bridged by INS/odometer",
            format!(
                "max horizontal error during the attack: monitor_R {} m, monitor {} m, dead_reckoning {} m, no_monitor {} m",
                c("monitor_R", "max_h_attack_m", 1),
                c("monitor", "max_h_attack_m", 1),
                c("dead_reckoning", "max_h_attack_m", 1),
                c("no_monitor", "max_h_attack_m", 1)
            ),
        ),
        (
            "§7: after 6 min INS/odometer stays 3.1 m from GNSS (INS alone 72 m)",
            format!(
                "dead_reckoning over the {:.0} s attack: max horizontal {} m",
                r.attack_rel.1 - r.attack_rel.0,
                c("dead_reckoning", "max_h_attack_m", 1)
            ),
        ),
        (
            "§5: with INS alone, drift exceeds R before the attack and gives false alarms",
            format!(
                "ins_only_R: alarms before the attack {} (seeds with any: {}/{n}); detected {}/{n}",
                c("ins_only_R", "alarms_before", 1),
                any("ins_only_R", "alarms_before"),
                detected("ins_only_R")
            ),
        ),
        (
            "§5: with the odometer the reference stays tight",
            format!(
                "monitor_R: alarms before the attack {} (seeds with any: {}/{n})",
                c("monitor_R", "alarms_before", 1),
                any("monitor_R", "alarms_before")
            ),
        ),
        (
            "§5: a chi-square test with the filter's covariance generalises R",
            format!(
                "ins_only_chi2: alarms before {} (seeds with any: {}/{n}), detected {}/{n} after {} s; monitor: alarms before {}, detected after {} s ({})",
                c("ins_only_chi2", "alarms_before", 1),
                any("ins_only_chi2", "alarms_before"),
                detected("ins_only_chi2"),
                c("ins_only_chi2", "delay_s", 1),
                c("monitor", "alarms_before", 1),
                c("monitor", "delay_s", 1),
                detectors(r.runs("monitor"))
            ),
        ),
    ]
}

fn attack_text(r: &AttackResults) -> String {
    let n = r.seeds.len();
    let mut s = format!(
        "Seed 004 spoofing: car, IMU500 + odometer + GNSS 1 Hz, two laps of the 3010 m loop; \
drift attack 2 m/s east from {:.0} s to {:.0} s\n",
        r.attack_rel.0, r.attack_rel.1
    );
    s.push_str(&format!(
        "scenario {ATTACK_SCENARIO}, seeds {:?}; mean [min, max] over seeds, (k/n) = seeds where it happened; \
alarm = a transition out of trusted\n\n",
        r.seeds
    ));
    for (v, _) in &r.per_variant {
        s.push_str(&format!("  {:<17} {}\n", v.name, v.label));
    }
    const W: usize = 25;
    s.push_str(&format!("\n{:<44}", ""));
    for (v, _) in &r.per_variant {
        s.push_str(&format!(" {:>W$}", v.name));
    }
    s.push('\n');
    for (key, label, dec) in ROWS {
        s.push_str(&format!("{label:<44}"));
        for (v, runs) in &r.per_variant {
            let monitor = runs.iter().any(|x| x.monitor);
            let txt = if !monitor && ROWS[..6].iter().any(|(k, _, _)| *k == key) {
                "-".to_string()
            } else {
                cell(&r.finite(v.name, key), n, dec)
            };
            s.push_str(&format!(" {txt:>W$}"));
        }
        s.push('\n');
        if key == "delay_s" {
            s.push_str(&format!("{:<44}", "  detector"));
            for (_, runs) in &r.per_variant {
                s.push_str(&format!(" {:>W$}", detectors(runs)));
            }
            s.push('\n');
        }
    }
    s.push_str("\npaper (SYSTEM.md §7 seed 004 row, §5) and ours:\n");
    for (p, ours) in paper_lines(r) {
        s.push_str(&format!("  {p}\n      ours: {ours}\n"));
    }
    s
}

fn attack_json(r: &AttackResults) -> Value {
    let variants: Vec<Value> = r
        .per_variant
        .iter()
        .map(|(v, runs)| {
            let mut metrics = serde_json::Map::new();
            for (key, _, _) in ROWS {
                let per_seed: Vec<Value> = runs
                    .iter()
                    .map(|x| {
                        let y = x.get(key);
                        if y.is_finite() {
                            json!(y)
                        } else {
                            Value::Null
                        }
                    })
                    .collect();
                let xs = r.finite(v.name, key);
                let (mean, min, max) = if xs.is_empty() {
                    (f64::NAN, f64::NAN, f64::NAN)
                } else {
                    spread(&xs)
                };
                let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
                metrics.insert(
                    key.to_string(),
                    json!({"mean": num(mean), "min": num(min), "max": num(max), "per_seed": per_seed}),
                );
            }
            let per_seed_transitions: Vec<Value> = runs
                .iter()
                .map(|x| {
                    Value::Array(
                        x.transitions
                            .iter()
                            .map(|(t, from, to, d, st, th)| {
                                json!({"t_s": t, "from": from, "to": to, "detector": d,
                                       "statistic": st, "threshold": if th.is_finite() { json!(th) } else { Value::Null }})
                            })
                            .collect(),
                    )
                })
                .collect();
            json!({"name": v.name, "label": v.label, "monitor": runs.iter().any(|x| x.monitor),
                   "detector_per_seed": runs.iter().map(|x| x.detector.clone()).collect::<Vec<_>>(),
                   "metrics": metrics, "transitions_per_seed": per_seed_transitions})
        })
        .collect();
    let paper: Vec<Value> = paper_lines(r)
        .into_iter()
        .map(|(p, o)| json!({"paper": p, "ours": o}))
        .collect();
    json!({"scenario": ATTACK_SCENARIO, "seeds": r.seeds,
           "attack": {"mode": "drift", "velocity_mps": [0.0, 2.0, 0.0],
                      "start_s": r.attack_rel.0, "end_s": r.attack_rel.1},
           "variants": variants, "paper": paper})
}

// ---------------------------------------------------------------------------------
// Monte Carlo

/// `f` over `items` on `WORKERS` threads, results in order; stops handing out work at
/// the first error and returns it. Each item runs on a fresh thread: faer's AVX-512
/// matrix kernels (the filter's covariance products) leave the upper vector register
/// state dirty in the thread that navigated, and the simulator's SSE code then runs
/// about 4x slower in that thread (measured: 0.4 s -> 2.1 s per lap simulated).
fn par_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> Result<R> + Sync) -> Result<Vec<R>> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<Result<R>>>> = Mutex::new(items.iter().map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..WORKERS.min(items.len()) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= items.len() {
                    break;
                }
                let r = std::thread::scope(|t| {
                    t.spawn(|| f(&items[i]))
                        .join()
                        .unwrap_or_else(|_| Err(anyhow!("a run panicked")))
                });
                let failed = r.is_err();
                out.lock().expect("no worker panicked")[i] = Some(r);
                if failed {
                    next.store(items.len(), Ordering::SeqCst);
                    break;
                }
            });
        }
    });
    let out = out.into_inner().expect("no worker panicked");
    let mut res = Vec::with_capacity(out.len());
    let mut missing = false;
    for r in out {
        match r {
            Some(Ok(x)) => res.push(x),
            Some(Err(e)) => return Err(e),
            None => missing = true,
        }
    }
    if missing {
        bail!("a run was not done");
    }
    Ok(res)
}

/// A built-in scenario with `events` (`[[gnss.event]]` tables) in place of its one
/// event and `seed` in the file (so that a kept scenario.toml is what was simulated).
fn with_events(base: &str, seed: u64, events: &str) -> String {
    let a = base
        .find("[[gnss.event]]")
        .expect("the scenario has an event");
    let b = a + base[a..]
        .find("\n\n")
        .expect("a blank line after the event");
    let text = format!("{}{events}{}", &base[..a], &base[b..]);
    text.replacen("seed = 1\n", &format!("seed = {seed}\n"), 1)
}

/// One jump attack of the Monte Carlo.
#[derive(Clone, Debug)]
struct JumpCase {
    run: usize,
    seed: u64,
    start_s: f64,
    offset_m: [f64; 3],
}

#[derive(Clone, Debug)]
struct JumpRun {
    case: JumpCase,
    delay_s: Option<f64>,
    detector: Option<String>,
    spoofed_delay_s: Option<f64>,
    /// Alarms before the attack: (t from the start, detector).
    early: Vec<(f64, String)>,
    /// Entries to spoofed before the attack (confirmed false alarms).
    early_spoofed: usize,
}

/// Jumps on seed004_loop.toml (one lap; the car drives from 61 s to about 372 s)
/// start while the car moves: uniform in [70, 330] s, last 30 s; magnitude uniform in
/// [20, 200] m, direction uniform on the sphere.
fn jump_cases(n: usize, first_seed: u64) -> Vec<JumpCase> {
    let mut rng = Stream::new(first_seed, "jump_monte_carlo");
    (0..n)
        .map(|run| {
            let seed = 1000 + rng.next_u64() % 1_000_000;
            let start_s = (rng.uniform_range(70.0, 330.0) * 10.0).round() / 10.0;
            let mag = rng.uniform_range(20.0, 200.0);
            let z = rng.uniform_range(-1.0, 1.0);
            let az = rng.uniform_range(0.0, std::f64::consts::TAU);
            let h = (1.0 - z * z).sqrt();
            let r = |x: f64| (x * 100.0).round() / 100.0;
            JumpCase {
                run,
                seed,
                start_s,
                offset_m: [r(mag * h * az.cos()), r(mag * h * az.sin()), r(mag * z)],
            }
        })
        .collect()
}

fn jump_run(c: &JumpCase, work: &Path, keep: bool, quiet: bool) -> Result<JumpRun> {
    let end_s = c.start_s + 30.0;
    let ev = format!(
        "[[gnss.event]]\ntype = \"spoof\"\nmode = \"jump\"\nstart_s = {}\nend_s = {}\noffset_m = [{}, {}, {}]\n",
        c.start_s, end_s, c.offset_m[0], c.offset_m[1], c.offset_m[2]
    );
    let dir = work.join(format!("jump{:03}_seed{}", c.run, c.seed));
    let t_wall = std::time::Instant::now();
    let (sc, _sim) = simulate(
        LOOP_SCENARIO,
        with_events(LOOP_TEXT, c.seed, &ev),
        c.seed,
        &dir,
    )?;
    let t0 = sc.file.start.time_s;
    // The `monitor` variant, navigating until 2 s after the attack.
    let apply = |cfg: &mut RunConfig, sc: &Scenario| {
        attack_start(cfg, sc);
        odometer_nhc(cfg, sc);
        monitor_defaults(cfg);
        cfg.nav.end_time = Some(t0 + end_s + 2.0);
    };
    let (_, trs) = navigate(&dir, &sc, apply, &dir.join("out"))
        .with_context(|| format!("jump run {} (seed {})", c.run, c.seed))?;
    let (a, b) = (t0 + c.start_s, t0 + end_s);
    let r = reaction(&trs, a, b);
    let early = trs
        .iter()
        .filter(|tr| tr.t < a && tr.from == IntegrityState::Trusted)
        .map(|tr| (tr.t - t0, tr.detector.name().to_string()))
        .collect();
    let run = JumpRun {
        case: c.clone(),
        delay_s: r.delay_s,
        detector: r.detector,
        spoofed_delay_s: r.spoofed_delay_s,
        early,
        early_spoofed: r.spoofed_before,
    };
    if !quiet {
        eprintln!(
            "  jump {:3} seed {:6} at {:5.1} s offset [{:7.1}, {:7.1}, {:7.1}] m: {}{} ({:.2} s)",
            c.run,
            c.seed,
            c.start_s,
            c.offset_m[0],
            c.offset_m[1],
            c.offset_m[2],
            match (&run.delay_s, &run.detector) {
                (Some(d), Some(det)) => format!("detected after {d:.1} s by {det}"),
                _ => "NOT detected".into(),
            },
            if run.early.is_empty() {
                String::new()
            } else {
                format!("; alarms before the attack: {:?}", run.early)
            },
            t_wall.elapsed().as_secs_f64()
        );
    }
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(run)
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let k = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[k.min(sorted.len() - 1)]
}

fn jump_summary(runs: &[JumpRun]) -> Value {
    let n = runs.len();
    let mut delays: Vec<f64> = runs.iter().filter_map(|r| r.delay_s).collect();
    delays.sort_by(f64::total_cmp);
    let within = runs
        .iter()
        .filter(|r| r.delay_s.is_some_and(|d| d <= 1.0))
        .count();
    let early = runs.iter().filter(|r| !r.early.is_empty()).count();
    let bins = [
        ("<= 1 s", 0.0, 1.0),
        ("1-2 s", 1.0, 2.0),
        ("2-5 s", 2.0, 5.0),
        ("> 5 s", 5.0, f64::INFINITY),
    ];
    let hist: Vec<Value> = bins
        .iter()
        .enumerate()
        .map(|(k, (label, lo, hi))| {
            let c = delays
                .iter()
                .filter(|&&d| {
                    if k == 0 {
                        d <= *hi
                    } else {
                        d > *lo && d <= *hi
                    }
                })
                .count();
            json!({"delay": label, "runs": c})
        })
        .collect();
    let mut det: Vec<(String, usize)> = Vec::new();
    for d in runs.iter().filter_map(|r| r.detector.clone()) {
        match det.iter_mut().find(|(n, _)| *n == d) {
            Some((_, k)) => *k += 1,
            None => det.push((d, 1)),
        }
    }
    let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
    json!({
        "runs": n,
        "detected": delays.len(),
        "detected_within_1s": within,
        "fraction_within_1s": if n > 0 { within as f64 / n as f64 } else { f64::NAN },
        "runs_with_alarm_before_attack": early,
        "runs_declared_spoofed_before_attack": runs.iter().filter(|r| r.early_spoofed > 0).count(),
        "delay_s": {"min": num(quantile(&delays, 0.0)), "median": num(quantile(&delays, 0.5)),
                    "p90": num(quantile(&delays, 0.9)), "max": num(quantile(&delays, 1.0)),
                    "histogram": hist},
        "detectors": det.iter().map(|(d, k)| json!({"detector": d, "runs": k})).collect::<Vec<_>>(),
        "per_run": runs.iter().map(|r| json!({
            "run": r.case.run, "seed": r.case.seed, "start_s": r.case.start_s,
            "offset_m": r.case.offset_m,
            "magnitude_m": (r.case.offset_m.iter().map(|x| x * x).sum::<f64>()).sqrt(),
            "delay_s": r.delay_s, "detector": r.detector, "spoofed_delay_s": r.spoofed_delay_s,
            "alarms_before_attack": r.early.iter().map(|(t, d)| json!({"t_s": t, "detector": d})).collect::<Vec<_>>(),
            "spoofed_before_attack": r.early_spoofed,
        })).collect::<Vec<_>>(),
    })
}

fn jump_text(runs: &[JumpRun], v: &Value) -> String {
    let n = runs.len();
    let g = |k: &str| {
        v["delay_s"][k]
            .as_f64()
            .map_or("-".into(), |x| format!("{x:.1}"))
    };
    let mut s = format!(
        "Jump attacks ({LOOP_SCENARIO}, `monitor` variant: [spoofing] defaults): {n} runs, \
random seed, direction uniform on the sphere, 20-200 m, start uniform in [70, 330] s while moving, 30 s long\n"
    );
    s.push_str(&format!(
        "  detected within 1 s of the attack start: {}/{n} ({:.1} %); detected at all: {}/{n}\n",
        v["detected_within_1s"],
        100.0 * v["fraction_within_1s"].as_f64().unwrap_or(f64::NAN),
        v["detected"]
    ));
    s.push_str(&format!(
        "  delay [s]: min {}, median {}, 90 % {}, max {}; ",
        g("min"),
        g("median"),
        g("p90"),
        g("max")
    ));
    let hist: Vec<String> = v["delay_s"]["histogram"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|h| format!("{} {}", h["delay"].as_str().unwrap_or(""), h["runs"]))
        .collect();
    s.push_str(&format!("runs by delay: {}\n", hist.join(", ")));
    let det: Vec<String> = v["detectors"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|d| format!("{} {}", d["detector"].as_str().unwrap_or(""), d["runs"]))
        .collect();
    s.push_str(&format!("  detectors: {}\n", det.join(", ")));
    s.push_str(&format!(
        "  runs with an alarm before the attack: {}\n",
        v["runs_with_alarm_before_attack"]
    ));
    for r in runs
        .iter()
        .filter(|r| !r.early.is_empty() || !r.delay_s.is_some_and(|d| d <= 1.0))
    {
        s.push_str(&format!(
            "    run {} seed {} start {:.1} s offset {:?} m: {}; early alarms {:?}\n",
            r.case.run,
            r.case.seed,
            r.case.start_s,
            r.case.offset_m,
            match (&r.delay_s, &r.detector) {
                (Some(d), Some(det)) => format!("detected after {d:.1} s by {det}"),
                _ => "not detected".into(),
            },
            r.early
        ));
    }
    s
}

// --- false alarms on clean drives ----------------------------------------------------

/// One lap of the seed 004 loop from a stop to a stop, then 20 s standing (a traffic
/// light): about 332 s.
const LAP: &str = r#"
[[segment]]
type = "accelerate"
accel_mps2 = 1.0
to_speed_mps = 10
ramp_s = 1

[[segment]]
type = "hold"
duration_s = 87.1

[[segment]]
type = "turn"
rate_dps = 9
angle_deg = 90
ramp_s = 2

[[segment]]
type = "hold"
duration_s = 33.9

[[segment]]
type = "turn"
rate_dps = 9
angle_deg = 90
ramp_s = 2

[[segment]]
type = "hold"
duration_s = 87.1

[[segment]]
type = "turn"
rate_dps = 9
angle_deg = 90
ramp_s = 2

[[segment]]
type = "hold"
duration_s = 33.9

[[segment]]
type = "turn"
rate_dps = 9
angle_deg = 90
ramp_s = 2

[[segment]]
type = "accelerate"
accel_mps2 = -1.0
to_speed_mps = 0
ramp_s = 1

[[segment]]
type = "static"
duration_s = 20
"#;
const LAP_S: f64 = 332.0;

/// A clean drive of about `hours` (at least one lap): seed 004's car and GNSS with
/// an ADIS16405 at 50 Hz (turn-on biases 180 deg/h and 5 mg, as seed 002's scenario:
/// what is left after the start-up bias null), no attack.
fn clean_text(seed: u64, hours: f64) -> String {
    let laps = (((hours * 3600.0 - 60.0) / LAP_S).ceil() as usize).max(1);
    let mut s = format!(
        r#"# Clean drive for the false-alarm count of `navfuse reproduce seed004 --clean-hours`:
# seed 004's car, odometer and GNSS fixes (scenarios/seed004_attack.toml) with a MEMS IMU
# (ADIS16405, 50 Hz, turn-on biases after the bias null as scenarios/seed002_car.toml),
# {laps} laps of the loop with a 20 s stop after each, no attack.
seed = {seed}
description = "Clean drive, ADIS16405 + odometer + GNSS, {laps} laps"

[start]
gps_week = 2381
time_s = 345600.0
position_deg_m = [21.0285, 105.8542, 15.0]
heading_deg = 0

[vehicle]
imu_mounting_deg = [0.0, 0.5, 0.5]
imu_to_reference_m = [-0.8, 0.0, 0.3]

[imu]
grade = "adis16405"
rate_hz = 50
gyro_bias_degph = 180
accel_bias_mg = 5

[odometer]
rate_hz = 10
meters_per_pulse = 0.00324
pulses_per_rev = 1024
scale_error_ppm = 2000

[gnss]
rate_hz = 1
antenna_lever_arm_m = [0.0, 0.0, -1.0]
raw = false

[gnss.fix]
horizontal_std_m = 1.5
vertical_std_m = 3.0
corr_time_s = 30

[[segment]]
type = "static"
duration_s = 60
"#
    );
    for _ in 0..laps {
        s.push_str(LAP);
    }
    s
}

#[derive(Clone, Debug)]
struct CleanCase {
    run: usize,
    seed: u64,
    hours: f64,
}

#[derive(Clone, Debug)]
struct CleanRun {
    case: CleanCase,
    hours: f64,
    out_of_trusted: usize,
    spoofed: usize,
    rmse_3d_m: f64,
    transitions: Vec<(f64, String, String, String, f64, f64)>,
}

fn clean_cases(hours: f64, first_seed: u64) -> Vec<CleanCase> {
    let n = hours.ceil().max(1.0) as usize;
    (0..n)
        .map(|k| CleanCase {
            run: k,
            seed: first_seed + k as u64,
            hours: (hours - k as f64).clamp(0.0, 1.0),
        })
        .collect()
}

/// The false-alarm navigator: the `monitor` variant's aiding and thresholds, started
/// as a user would with a MEMS IMU (position from the first fix, levelling and the
/// first GNSS course; no gyrocompassing).
fn clean_config(cfg: &mut RunConfig, sc: &Scenario) {
    user_start(cfg, sc);
    odometer_nhc(cfg, sc);
    monitor_defaults(cfg);
}

fn clean_run(c: &CleanCase, work: &Path, keep: bool, quiet: bool) -> Result<CleanRun> {
    let dir = work.join(format!("clean{:02}_seed{}", c.run, c.seed));
    let t_wall = std::time::Instant::now();
    let name = "seed004 clean drive (built from scenarios/seed004_attack.toml)";
    let (sc, sim) = simulate(name, clean_text(c.seed, c.hours), c.seed, &dir)?;
    let t0 = sc.file.start.time_s;
    let out = dir.join("out");
    let (_, trs) = navigate(&dir, &sc, clean_config, &out)
        .with_context(|| format!("clean run {} (seed {})", c.run, c.seed))?;
    let (truth, sol) = load_tracks(&dir, &out)?;
    let rep = evaluate(&sol, &truth, &EvalOptions::default());
    let run = CleanRun {
        case: c.clone(),
        hours: (sim.t_end - sim.t_start) / 3600.0,
        out_of_trusted: trs
            .iter()
            .filter(|t| t.from == IntegrityState::Trusted)
            .count(),
        spoofed: trs
            .iter()
            .filter(|t| t.to == IntegrityState::Spoofed)
            .count(),
        rmse_3d_m: rep.pos_3d.rms,
        transitions: transition_rows(&trs, t0),
    };
    if !quiet {
        eprintln!(
            "  clean {:2} seed {:3} {:.2} h: {} out of trusted, {} spoofed; 3D RMSE {:.2} m{} ({:.1} s)",
            c.run,
            c.seed,
            run.hours,
            run.out_of_trusted,
            run.spoofed,
            run.rmse_3d_m,
            run.transitions
                .iter()
                .filter(|t| t.1 == "trusted")
                .map(|t| format!("; {:.0} s {} -> {} ({} {:.1} > {:.1})", t.0, t.1, t.2, t.3, t.4, t.5))
                .collect::<String>(),
            t_wall.elapsed().as_secs_f64()
        );
    }
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(run)
}

fn clean_summary(runs: &[CleanRun]) -> Value {
    let hours: f64 = runs.iter().map(|r| r.hours).sum();
    let out: usize = runs.iter().map(|r| r.out_of_trusted).sum();
    let sp: usize = runs.iter().map(|r| r.spoofed).sum();
    let per10 = |k: usize| {
        if hours > 0.0 {
            k as f64 * 10.0 / hours
        } else {
            f64::NAN
        }
    };
    let rmse: Vec<f64> = runs.iter().map(|r| r.rmse_3d_m).collect();
    let (m, lo, hi) = spread(&rmse);
    json!({
        "runs": runs.len(),
        "hours": hours,
        "imu": "adis16405 50 Hz",
        "out_of_trusted": out,
        "spoofed": sp,
        "out_of_trusted_per_10h": per10(out),
        "spoofed_per_10h": per10(sp),
        "rmse_3d_m": {"mean": m, "min": lo, "max": hi},
        "per_run": runs.iter().map(|r| json!({
            "run": r.case.run, "seed": r.case.seed, "hours": r.hours,
            "out_of_trusted": r.out_of_trusted, "spoofed": r.spoofed, "rmse_3d_m": r.rmse_3d_m,
            "transitions": r.transitions.iter().map(|(t, f, to, d, st, th)| json!({
                "t_s": t, "from": f, "to": to, "detector": d, "statistic": st,
                "threshold": if th.is_finite() { json!(th) } else { Value::Null }})).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

fn clean_text_report(runs: &[CleanRun], v: &Value) -> String {
    let mut s = format!(
        "False alarms on clean drives (ADIS16405 50 Hz + odometer + NHC + GNSS 1 Hz, [spoofing] defaults): \
{} runs, {:.2} h in total\n",
        runs.len(),
        v["hours"].as_f64().unwrap_or(0.0)
    );
    s.push_str(&format!(
        "  transitions out of trusted: {} ({:.2} per 10 h); entries to spoofed: {} ({:.2} per 10 h); 3D RMSE {:.2} [{:.2}, {:.2}] m\n",
        v["out_of_trusted"],
        v["out_of_trusted_per_10h"].as_f64().unwrap_or(f64::NAN),
        v["spoofed"],
        v["spoofed_per_10h"].as_f64().unwrap_or(f64::NAN),
        v["rmse_3d_m"]["mean"].as_f64().unwrap_or(f64::NAN),
        v["rmse_3d_m"]["min"].as_f64().unwrap_or(f64::NAN),
        v["rmse_3d_m"]["max"].as_f64().unwrap_or(f64::NAN),
    ));
    for r in runs {
        for t in r.transitions.iter().filter(|t| t.1 == "trusted") {
            s.push_str(&format!(
                "    run {} seed {}: {:.0} s {} -> {} by {} ({:.1}, threshold {:.1})\n",
                r.case.run, r.case.seed, t.0, t.1, t.2, t.3, t.4, t.5
            ));
        }
    }
    s
}

// ---------------------------------------------------------------------------------

pub fn main(
    id: &str,
    req: AttackRequest,
    seeds: u64,
    first_seed: u64,
    json_out: bool,
    keep: Option<PathBuf>,
    quiet: bool,
) -> Result<()> {
    if id != "seed004" {
        bail!("--attack, --jump-runs and --clean-hours belong to seed004 (got '{id}')");
    }
    if !(req.clean_hours.is_finite() && req.clean_hours >= 0.0) {
        bail!("--clean-hours must be >= 0");
    }
    if req.attack && seeds == 0 {
        bail!("--seeds must be at least 1");
    }
    let (work, temp) = match keep {
        Some(d) => (d, false),
        None => (
            std::env::temp_dir().join(format!("navfuse-reproduce-attack-{}", std::process::id())),
            true,
        ),
    };
    std::fs::create_dir_all(&work).with_context(|| format!("{}: cannot create", work.display()))?;
    let result = (|| -> Result<(String, Value)> {
        let mut text = String::new();
        let mut out = serde_json::Map::new();
        out.insert("experiment".into(), json!("seed004"));
        if req.attack {
            let seed_list: Vec<u64> = (first_seed..first_seed + seeds).collect();
            let per_seed = par_map(&seed_list, |&s| attack_seed(s, &work, !temp, quiet))?;
            let sc0 = Scenario::from_text(Path::new(ATTACK_SCENARIO), ATTACK_TEXT.to_string())
                .map_err(|e| anyhow!("{e}"))?;
            let attack_rel = attack_window_rel(&sc0).unwrap_or((f64::NAN, f64::NAN));
            let per_variant = variants()
                .into_iter()
                .enumerate()
                .map(|(k, v)| (v, per_seed.iter().map(|runs| runs[k].clone()).collect()))
                .collect();
            let r = AttackResults {
                seeds: seed_list,
                attack_rel,
                per_variant,
            };
            text.push_str(&attack_text(&r));
            out.insert("attack".into(), attack_json(&r));
        }
        if req.jump_runs > 0 {
            let cases = jump_cases(req.jump_runs, first_seed);
            let runs = par_map(&cases, |c| jump_run(c, &work, !temp, quiet))?;
            let v = jump_summary(&runs);
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(&jump_text(&runs, &v));
            out.insert("jump_monte_carlo".into(), v);
        }
        if req.clean_hours > 0.0 {
            let cases = clean_cases(req.clean_hours, first_seed);
            let runs = par_map(&cases, |c| clean_run(c, &work, !temp, quiet))?;
            let v = clean_summary(&runs);
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(&clean_text_report(&runs, &v));
            out.insert("false_alarms".into(), v);
        }
        Ok((text, Value::Object(out)))
    })();
    if temp {
        let _ = std::fs::remove_dir_all(&work);
    }
    let (text, v) = result?;
    if json_out {
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print!("{text}");
    }
    Ok(())
}
