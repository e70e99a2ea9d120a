//! `navfuse reproduce SEED`: the papers' experiments on the simulator (SYSTEM.md §7).
//!
//! For each random seed: simulate the experiment's scenario (scenarios/*.toml, built
//! into the binary) into the work directory, run every variant of the navigator on
//! the same data with `navfuse_app::run` into memory ([`crate::navigate`]), score its
//! records against the simulated truth, and print the mean and spread over seeds
//! beside the paper's figures. Improvements follow seed 002 eq. 18:
//! (RMSE_base - RMSE_variant) / RMSE_base.
//!
//! On disk: the simulated inputs and truth (a temporary directory, removed at the
//! end; the navigator reads its inputs from files). The solutions are files only with
//! `--keep DIR`.
mod metrics;
mod papers;
mod report;
pub(crate) mod setup;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use navfuse_core::eval::{evaluate, EvalOptions, TrajPoint};
use navfuse_io::config::RunConfig;
use navfuse_io::input::{GnssFormat, GnssSource};
use navfuse_sim::generate::generate;
use navfuse_sim::gnss_sim::EventSpec;
use navfuse_sim::scenario::Scenario;

use crate::navigate::navigate;
use crate::track::load_nav;
use crate::work::WorkDir;

use metrics::{closed_loop_metrics, metrics_of, table4_metrics, Metrics};
use papers::{experiment, GNSS_ONLY};
pub(crate) use report::{spread, variant_list, MAX_WIDTH};
use report::{to_json, to_text};

/// One navigator configuration of an experiment.
pub(crate) struct Variant {
    pub name: &'static str,
    /// What it adds, for the table.
    pub label: &'static str,
    pub apply: fn(&mut RunConfig, &Scenario),
}

/// A figure the paper reports, for the side-by-side table.
pub(crate) struct PaperFigure {
    pub(crate) metric: &'static str,
    pub(crate) variant: &'static str,
    pub(crate) value: f64,
}

pub(crate) struct Experiment {
    pub(crate) id: &'static str,
    pub(crate) title: &'static str,
    pub(crate) scenario_name: &'static str,
    pub(crate) scenario_text: &'static str,
    /// Another scenario (name, text) whose GNSS outages are added to this one's.
    pub(crate) outages_from: Option<(&'static str, &'static str)>,
    pub(crate) variants: Vec<Variant>,
    pub(crate) paper: Vec<PaperFigure>,
    /// Improvement checks: (metric, base variant, variant, claimed fraction).
    pub(crate) claims: Vec<(&'static str, &'static str, &'static str, f64)>,
    /// What the improvement `(base - variant) / base` means for this experiment's
    /// figures, and where the paper states it (the table's footer).
    pub(crate) improvement: &'static str,
    /// Metrics shown (METRICS, CLOSED_LOOP_METRICS).
    pub(crate) metrics: &'static [&'static str],
}

/// The single point fixes of the configuration's RINEX input, as a track.
pub(crate) fn gnss_only_track(cfg: &RunConfig) -> Result<Vec<TrajPoint>> {
    let Some(
        src @ GnssSource {
            format: GnssFormat::Rinex(r),
            ..
        },
    ) = &cfg.gnss
    else {
        bail!("the GNSS-only variant needs a RINEX input");
    };
    let g = navfuse_app::gnss_input::load_rinex(src, r, &cfg.nav.gnss.systems)?;
    Ok(navfuse_io::trajectory::points_of_fixes(&g.fixes))
}

/// The experiment's scenario text, with the `[[gnss.event]]` outages of
/// `outages_from` appended (so the copy the simulator writes has them).
pub(crate) fn scenario_text(ex: &Experiment) -> Result<String> {
    let mut text = ex.scenario_text.to_string();
    let Some((name, other)) = ex.outages_from else {
        return Ok(text);
    };
    let src = Scenario::from_text(Path::new(name), other.to_string())?;
    let events = src.file.gnss.as_ref().map_or(&[][..], |g| &g.events[..]);
    text.push_str(&format!("\n# GNSS outages of {name}\n"));
    let mut n = 0;
    for ev in events {
        if let EventSpec::Outage { start_s, end_s } = ev {
            text.push_str(&format!(
                "\n[[gnss.event]]\ntype = \"outage\"\nstart_s = {start_s:?}\nend_s = {end_s:?}\n"
            ));
            n += 1;
        }
    }
    if n == 0 {
        bail!("{}: {name} has no GNSS outage to add", ex.id);
    }
    Ok(text)
}

/// Per variant, per seed: the metrics.
pub(crate) struct Results {
    pub(crate) seeds: Vec<u64>,
    pub(crate) per_variant: Vec<(&'static str, Vec<Metrics>)>,
}

pub(crate) fn run_experiment(
    ex: &Experiment,
    seeds: &[u64],
    work: &WorkDir,
    quiet: bool,
) -> Result<Results> {
    let mut per_variant: Vec<(&'static str, Vec<Metrics>)> =
        ex.variants.iter().map(|v| (v.name, Vec::new())).collect();
    let text = scenario_text(ex)?;
    for &seed in seeds {
        let mut sc = Scenario::from_text(Path::new(ex.scenario_name), text.clone())?;
        sc.file.seed = seed;
        let dir = work.path().join(format!("{}_seed{seed}", ex.id));
        let sim = generate(&sc, &dir)?;
        let truth = load_nav(&dir.join("truth.nav"))?;
        for (k, v) in ex.variants.iter().enumerate() {
            let mut cfg = navfuse_io::config::load(&dir.join("run.toml"))?;
            (v.apply)(&mut cfg, &sc);
            let out = dir.join(v.name);
            let t_run = std::time::Instant::now();
            let sol = if v.name == GNSS_ONLY {
                gnss_only_track(&cfg)?
            } else {
                navigate(cfg, work.kept(&out))
                    .with_context(|| format!("{} seed {seed}: variant {}", ex.id, v.name))?
                    .track()
                    .points
            };
            let wall = t_run.elapsed();
            let rep = evaluate(&sol, &truth.points, &EvalOptions::default());
            let mut m = metrics_of(&rep);
            closed_loop_metrics(&mut m, &sol, &truth.points, sim.distance_m);
            table4_metrics(&mut m, &sol, &truth.points);
            if !quiet {
                eprintln!(
                    "  {} seed {seed} {:<16} 3D RMSE {:8.3} m  mean {:8.3} m  yaw {:6.3} deg  ({:.1} s sim, {:.2} s run)",
                    ex.id,
                    v.name,
                    m.get("rmse_3d_m").unwrap_or(f64::NAN),
                    m.get("mean_3d_m").unwrap_or(f64::NAN),
                    m.get("rmse_yaw_deg").unwrap_or(f64::NAN),
                    sim.t_end - sim.t_start,
                    wall.as_secs_f64()
                );
            }
            per_variant[k].1.push(m);
        }
    }
    Ok(Results {
        seeds: seeds.to_vec(),
        per_variant,
    })
}

pub fn main(
    id: &str,
    seeds: u64,
    first_seed: u64,
    json_out: bool,
    keep: Option<PathBuf>,
    quiet: bool,
) -> Result<()> {
    let ex = experiment(id)?;
    if seeds == 0 {
        bail!("--seeds must be at least 1");
    }
    let seed_list: Vec<u64> = (first_seed..first_seed + seeds).collect();
    let work = WorkDir::new(keep, &format!("reproduce-{id}"))?;
    let r = run_experiment(&ex, &seed_list, &work, quiet)?;
    if json_out {
        println!("{}", serde_json::to_string_pretty(&to_json(&ex, &r))?);
    } else {
        print!("{}", to_text(&ex, &r));
    }
    Ok(())
}
