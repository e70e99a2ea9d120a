//! `navfuse reproduce seed004 --attack | --jump-runs N | --clean-hours H`: seed 004's
//! spoofing experiment (SYSTEM.md §5, §7 seed 004 row; issue 6) on the simulator.
//!
//! - `--attack`: `scenarios/seed004_attack.toml` (built in: two laps of the seed 004
//!   loop, a 300 s drift attack at 2 m/s) simulated once per seed; every variant runs
//!   on the same data (`navfuse_app::run`, in memory) and is scored against the
//!   truth: alarms before the attack, detection delay and detector, maximum errors
//!   during the attack and in the 60 s after it, 3D RMSE over the run; mean [min,
//!   max] over the seeds beside the paper's statements.
//! - `--jump-runs N`: N jump attacks on the same car (one lap, seed004_loop.toml) and
//!   navigator as the `monitor` variant: random seed, direction uniform on the sphere,
//!   magnitude 20-200 m, start uniform while the car moves; fraction detected within
//!   1 s, delays, early alarms.
//! - `--clean-hours H`: false alarms on clean drives (no attack) with a MEMS IMU
//!   (ADIS16405, 50 Hz) + odometer + NHC and the `[spoofing]` defaults, in 1-hour
//!   drives of repeated loops with a stop each lap; transitions out of trusted and
//!   entries to spoofed per 10 h.
//!
//! Runs go to two worker threads (the machine has two cores). Each run's simulated
//! data are written to its own directory and removed once scored; the navigator's
//! output stays in memory. With `--keep DIR` both stay, the solutions as the files
//! of `navfuse run`.

mod clean;
mod drift;
mod jumps;
mod reaction;
mod variants;

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Result};
use navfuse_core::integrity::Transition;
use navfuse_io::config::RunConfig;
use navfuse_sim::generate::generate;
use navfuse_sim::scenario::Scenario;
use serde_json::{json, Value};

use crate::navigate::Navigated;
use crate::pool::Next;
use crate::scenarios::builtin;
use crate::work::WorkDir;

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

use clean::{clean_cases, clean_run, clean_summary, clean_text_report};
use drift::{attack_json, attack_seed, attack_text, AttackResults};
use jumps::{jump_cases, jump_run, jump_summary, jump_text};
use reaction::transitions;
use variants::{attack_window_rel, variants};

/// Simulate `sc` into `dir`.
fn simulate(sc: &Scenario, dir: &Path) -> Result<navfuse_sim::generate::SimSummary> {
    Ok(generate(sc, dir)?)
}

/// A run on simulated data: whether the monitor ran, its transitions, the run.
struct AttackRun {
    monitor: bool,
    transitions: Vec<Transition>,
    nav: Navigated,
}

/// Configure from the simulator's run.toml in `dir`, then `apply`, and run in memory
/// (with `--keep`, also into `out`).
fn navigate(
    dir: &Path,
    sc: &Scenario,
    apply: impl Fn(&mut RunConfig, &Scenario),
    work: &WorkDir,
    out: &Path,
) -> Result<AttackRun> {
    let mut cfg = navfuse_io::config::load(&dir.join("run.toml"))?;
    apply(&mut cfg, sc);
    let monitor = cfg.nav.integrity.enabled;
    let nav = crate::navigate::navigate(cfg, work.kept(out))?;
    Ok(AttackRun {
        monitor,
        transitions: transitions(&nav.job.summary.events),
        nav,
    })
}

/// `f` over `items` on `WORKERS` threads (each item on a fresh thread,
/// [`crate::pool`]), results in order; stops handing out work at the first error and
/// returns it.
fn par_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> Result<R> + Sync) -> Result<Vec<R>> {
    let out = crate::pool::run_indexed(
        items.len(),
        WORKERS,
        |i| f(&items[i]),
        |_| Err(anyhow!("a run panicked")),
        |_, r| match r {
            Ok(_) => Next::Continue,
            Err(_) => Next::Stop,
        },
    );
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
    let work = WorkDir::new(keep, "reproduce-attack")?;
    let result = (|| -> Result<(String, Value)> {
        let mut text = String::new();
        let mut out = serde_json::Map::new();
        out.insert("experiment".into(), json!("seed004"));
        if req.attack {
            let seed_list: Vec<u64> = (first_seed..first_seed + seeds).collect();
            let per_seed = par_map(&seed_list, |&s| attack_seed(s, &work, quiet))?;
            let sc0 = builtin(ATTACK_SCENARIO, ATTACK_TEXT)?;
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
            let runs = par_map(&cases, |c| jump_run(c, &work, quiet))?;
            let v = jump_summary(&runs);
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(&jump_text(&runs, &v));
            out.insert("jump_monte_carlo".into(), v);
        }
        if req.clean_hours > 0.0 {
            let cases = clean_cases(req.clean_hours, first_seed);
            let runs = par_map(&cases, |c| clean_run(c, &work, quiet))?;
            let v = clean_summary(&runs);
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(&clean_text_report(&runs, &v));
            out.insert("false_alarms".into(), v);
        }
        Ok((text, Value::Object(out)))
    })();
    drop(work);
    let (text, v) = result?;
    if json_out {
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print!("{text}");
    }
    Ok(())
}
