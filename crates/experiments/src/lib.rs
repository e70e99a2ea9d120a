//! navfuse-experiments: what `navfuse reproduce` and `navfuse bench` do, as a library.
//!
//! - [`reproduce`]: the papers' experiments on the simulator (SYSTEM.md §7): simulate
//!   the experiment's scenario per seed, run every navigator variant on the same data
//!   (`navfuse_app::run`), score it against the simulated truth, print the figures
//!   beside the paper's. seed004 also has the spoofing experiments (`attack`: the
//!   drift attack's variant table, jump attacks, false alarms on clean drives).
//! - [`batch`]: many runs in one process on a pool of threads (`navfuse batch`):
//!   a manifest of configurations or one scenario over many seeds, a folder per case
//!   and one table.
//! - [`bench()`]: speed and memory of the navigator, loose coupling on the KF-GINS
//!   stand-in or tight coupling on a simulated drive.
//!
//! Map: `reproduce` (run, report) -> `reproduce::papers` (the experiments and their
//! figures), `reproduce::setup` (the navigator configurations), `reproduce::metrics`;
//! `attack` -> `attack::{variants, reaction, drift, jumps, clean}`; `bench`,
//! `bench::tight`; [`track`] (trajectories to score).

mod attack;
pub mod batch;
mod bench;
mod navigate;
mod pool;
mod reproduce;
mod scenarios;
pub mod track;
pub mod tuning;
mod work;

use std::path::PathBuf;

pub use anyhow::{Error, Result};

/// What `navfuse reproduce` was asked for.
#[derive(Clone, Debug)]
pub struct ReproduceArgs {
    /// seed000, seed001, seed002 or seed004.
    pub experiment: String,
    /// Number of random seeds.
    pub seeds: u64,
    /// First seed (seeds are consecutive).
    pub first_seed: u64,
    /// Print JSON instead of the text tables.
    pub json: bool,
    /// Keep the simulated data and the solutions in this directory.
    pub keep: Option<PathBuf>,
    /// No per-run progress lines on stderr.
    pub quiet: bool,
    /// seed004: the drift attack's variant table.
    pub attack: bool,
    /// seed004: runs of the jump-attack Monte Carlo (0 = none).
    pub jump_runs: usize,
    /// seed004: hours of clean driving for the false-alarm count (0 = none).
    pub clean_hours: f64,
}

/// `navfuse reproduce`: the plain experiment, or with `attack`, `jump_runs` or
/// `clean_hours` (seed004 only) the spoofing ones. Prints the result on stdout.
pub fn reproduce(a: &ReproduceArgs) -> Result<()> {
    if a.attack || a.jump_runs > 0 || a.clean_hours != 0.0 {
        let req = attack::AttackRequest {
            attack: a.attack,
            jump_runs: a.jump_runs,
            clean_hours: a.clean_hours,
        };
        attack::main(
            &a.experiment,
            req,
            a.seeds,
            a.first_seed,
            a.json,
            a.keep.clone(),
            a.quiet,
        )
    } else {
        reproduce::main(
            &a.experiment,
            a.seeds,
            a.first_seed,
            a.json,
            a.keep.clone(),
            a.quiet,
        )
    }
}

/// What `navfuse bench` was asked for.
#[derive(Clone, Debug)]
pub struct BenchArgs {
    /// KF-GINS YAML for the loose full run (default: the stand-in in ../shared/data).
    pub kf_gins: Option<PathBuf>,
    /// Tight coupling on simulated data instead.
    pub tight: bool,
    /// The smoother on one simulated hour at 200 Hz instead.
    pub smooth: bool,
    /// `navfuse report` on one simulated hour at 200 Hz instead.
    pub report: bool,
    /// The TDCP sweep instead: tight coupling with TDCP against Doppler over random
    /// sites and start times, with and without an outage (issue 30 part A).
    pub tdcp_sweep: bool,
    /// With `tdcp_sweep`: the number of simulated drives.
    pub runs: usize,
    /// With `tdcp_sweep`: the sweep's seed (sites, start times, outages, the
    /// simulator's seeds).
    pub seed: u64,
    /// With `tight`: seconds of data to simulate and navigate.
    pub duration_s: f64,
    /// With `tight`: a scenario file in place of the built-in one.
    pub scenario: Option<PathBuf>,
    /// Repetitions of each measurement (the best is reported).
    pub repeat: usize,
    /// Print JSON.
    pub json: bool,
    /// Noise identification against the hand-tuned runs instead, with this many
    /// seeds per simulated case (0: not this benchmark).
    pub tune_seeds: usize,
    /// With `tune_seeds`: only the simulated cases.
    pub tune_sim_only: bool,
}

/// With `tight`: the default of [`BenchArgs::duration_s`] \[s\].
pub const BENCH_TIGHT_DEFAULT_DURATION_S: f64 = bench::tight::DEFAULT_DURATION_S;
/// With `tdcp_sweep`: the default of [`BenchArgs::runs`].
pub const BENCH_TDCP_SWEEP_DEFAULT_RUNS: usize = bench::tdcp_sweep::DEFAULT_RUNS;

/// `navfuse bench`: loose coupling on the KF-GINS stand-in, or with `tight` tight
/// coupling on a simulated drive (`smooth`, `report`: the smoother, the report;
/// `tdcp_sweep`: TDCP against Doppler over random drives, an error on FAIL). Prints
/// the figures on stdout.
pub fn bench(a: &BenchArgs) -> Result<()> {
    if a.tune_seeds > 0 {
        tuning::main(&tuning::TuneBenchArgs {
            seeds: a.tune_seeds,
            sim_only: a.tune_sim_only,
            json: a.json,
        })
    } else if a.tdcp_sweep {
        bench::tdcp_sweep::main(a.runs, a.seed, a.json, false)
    } else if a.report {
        bench::report::main(a.repeat, a.json)
    } else if a.smooth {
        bench::smooth::main(a.repeat, a.json)
    } else if a.tight {
        bench::tight::main(a.scenario.clone(), a.duration_s, a.repeat, a.json)
    } else {
        bench::main(a.kf_gins.clone(), a.repeat, a.json)
    }
}
