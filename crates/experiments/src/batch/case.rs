//! One case of a batch: (simulate,) navigate, score. The figures come from the run's
//! records in memory ([`crate::navigate`]), the same whether the run's files are
//! written or not, in whatever thread or process.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use navfuse_app::score::ScoreOptions;
use navfuse_app::{config, RunConfig};
use navfuse_core::eval::EvalReport;
use navfuse_io::trajectory::{read_trajectory, TrajFormat, Trajectory};
use navfuse_sim::generate::generate;

use super::manifest::{Case, Source};
use super::metrics::figures;
use crate::navigate::{navigate, Navigated};
use crate::work::WorkDir;

/// What a case gave: its output epochs and its figures.
pub(crate) struct Outcome {
    /// The run's status ("completed" or "unreliable").
    pub status: &'static str,
    pub epochs: usize,
    pub metrics: Vec<(String, f64)>,
}

/// RTKLIB `.pos` truths: the fixed solutions only (`navfuse eval`'s default).
const POS_QUALITY: [u8; 1] = [1];

/// Run `case`; its files go into `dir` (the case folder) when given.
pub(crate) fn run(case: &Case, dir: Option<&Path>) -> Result<Outcome> {
    match &case.source {
        Source::Config {
            path,
            kf_gins,
            truth,
            lever_arm,
        } => {
            let cfg = if *kf_gins {
                config::load_kfgins_yaml(path)
            } else {
                config::load(path)
            }
            .with_context(|| format!("configuration {}", path.display()))?;
            let nav = navigate_case(case, cfg, dir)?;
            let report = match truth {
                Some(t) => {
                    let truth = read_trajectory(t, None, &POS_QUALITY)
                        .with_context(|| format!("truth {}", t.display()))?;
                    Some(score(case, &nav, truth, *lever_arm, t)?)
                }
                None => None,
            };
            Ok(outcome(&nav, report.as_ref()))
        }
        Source::Sim { scenario } => {
            let mut sc = (**scenario).clone();
            sc.file.seed = case.seed.context("a Monte Carlo case without a seed")?;
            let work = WorkDir::new(dir.map(|d| d.join("sim")), "batch")?;
            let summary = generate(&sc, work.path())
                .with_context(|| format!("simulating {}", sc.path.display()))?;
            let json = serde_json::to_string_pretty(&summary)?;
            std::fs::write(work.path().join("sim_summary.json"), json + "\n")
                .with_context(|| format!("{}: cannot write", work.path().display()))?;
            let run_toml = work.path().join("run.toml");
            let cfg = config::load(&run_toml)?;
            let nav = navigate_case(case, cfg, dir)?;
            let truth_path = work.path().join("truth.nav");
            let truth = read_trajectory(&truth_path, None, &[])?;
            let report = score(case, &nav, truth, None, &truth_path)?;
            Ok(outcome(&nav, Some(&report)))
        }
    }
}

/// The case's outages and smoothing on top of `cfg` (as `navfuse run --outages
/// --smooth`), then the run.
fn navigate_case(case: &Case, mut cfg: RunConfig, dir: Option<&Path>) -> Result<Navigated> {
    if let Some(extra) = &case.outages {
        let o = &mut cfg.nav.gnss.outages;
        o.windows.extend(extra.windows.iter().cloned());
        o.periodic.extend(extra.periodic.iter().cloned());
    }
    if case.smooth {
        cfg.smoother.enabled = true;
    }
    Ok(navigate(cfg, dir)?)
}

/// The solution scored (the smoothed one when the case smooths) against `truth`,
/// as `navfuse eval SOLUTION.nav TRUTH [--gaps] [--lever-arm]` scores the written
/// file.
fn score(
    case: &Case,
    nav: &Navigated,
    truth: Trajectory,
    lever_arm: Option<nalgebra::Vector3<f64>>,
    truth_path: &Path,
) -> Result<EvalReport> {
    let track = if case.smooth {
        nav.smoothed_track()
    } else {
        nav.track()
    };
    let sol = Trajectory {
        format: TrajFormat::Nav,
        week: track.week,
        points: track.points,
        warnings: Vec::new(),
    };
    let opts = ScoreOptions {
        gaps: case.gaps.clone(),
        lever_arm_b: lever_arm,
        lever_arm_name: "lever_arm",
        ..Default::default()
    };
    let name = if case.smooth {
        "the smoothed solution"
    } else {
        "the solution"
    };
    Ok(navfuse_app::score::score(
        &sol,
        name,
        truth,
        &truth_path.display().to_string(),
        &opts,
    )?)
}

fn outcome(nav: &Navigated, report: Option<&EvalReport>) -> Outcome {
    Outcome {
        status: nav.job.status,
        epochs: nav.rows.len(),
        metrics: figures(&nav.job, report),
    }
}

/// The case folder in the batch folder `out`.
pub(crate) fn case_dir(out: Option<&Path>, case: &Case) -> Option<PathBuf> {
    out.map(|o| o.join(&case.name))
}
