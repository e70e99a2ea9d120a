//! `navfuse bench --report`: the time and memory of `navfuse report` on one hour at
//! 200 Hz (issue 18). The hour of `navfuse bench --smooth` (scenarios/hour_200hz.toml
//! with a barometer and every vehicle state) is simulated and run with `--smooth`
//! (not timed); then the report is built against the simulated truth (read, thin,
//! score, draw, write the page), best of `repeat`: wall time and peak resident
//! memory.

use super::smooth::{hour_config, Scratch};
use super::{peak_rss_kib, reset_peak_rss};
use crate::track::load_nav;
use anyhow::{Context, Result};
use navfuse_app::run_job;
use navfuse_io::input::SmootherSpec;
use serde_json::json;
use std::time::Instant;

pub fn main(repeat: usize, json_out: bool) -> Result<()> {
    let repeat = repeat.max(1);
    let scratch =
        Scratch(std::env::temp_dir().join(format!("navfuse-bench-report-{}", std::process::id())));
    let mut cfg = hour_config(&scratch)?;
    cfg.output.csv = true;
    cfg.smoother = SmootherSpec {
        enabled: true,
        ..SmootherSpec::default()
    };
    let out = scratch.0.join("out");
    let job = run_job(cfg, &out, false)?;
    let track = load_nav(&scratch.0.join("sim/truth.nav"))?;
    let truth = navfuse_report::Truth {
        path: scratch.0.join("sim/truth.nav"),
        points: track.points,
        lever_arm_b: None,
    };
    let page = out.join("report.html");
    let mut best = (f64::INFINITY, None, 0usize, 0usize);
    for _ in 0..repeat {
        let can_reset = reset_peak_rss();
        let t = Instant::now();
        let report = navfuse_report::build(&out, Some(&truth)).context("building the report")?;
        let html = report.html();
        std::fs::write(&page, &html).with_context(|| format!("writing {}", page.display()))?;
        let wall = t.elapsed().as_secs_f64();
        let peak = if can_reset { peak_rss_kib() } else { None };
        if wall < best.0 {
            best = (wall, peak, report.figures.len(), html.len());
        }
    }
    let (wall, peak, figures, bytes) = best;
    let mib = peak.map(|k| k as f64 / 1024.0);
    if json_out {
        let v = json!({
            "scenario": "scenarios/hour_200hz.toml",
            "epochs": job.summary.outputs,
            "wall_s": wall,
            "peak_rss_kib": peak,
            "figures": figures,
            "html_bytes": bytes,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "report of one hour at 200 Hz ({} epochs, forward + smoothed, truth at 200 Hz): {wall:.2} s, peak memory {} (best of {repeat}); {figures} figures, {:.1} MB of HTML",
            job.summary.outputs,
            mib.map_or("n/a".into(), |m| format!("{m:.0} MiB")),
            bytes as f64 / 1e6
        );
    }
    Ok(())
}
