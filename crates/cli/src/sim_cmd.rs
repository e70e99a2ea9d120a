//! `navfuse sim SCENARIO --out DIR`: run the simulator.

use std::path::Path;

use anyhow::Context;
use navfuse_sim::generate::generate;
use navfuse_sim::scenario::Scenario;

pub fn main(scenario: &Path, out: &Path, seed: Option<u64>, quiet: bool) -> anyhow::Result<()> {
    let mut sc = Scenario::load(scenario)?;
    if let Some(s) = seed {
        sc.file.seed = s;
    }
    let summary = generate(&sc, out)?;
    let json = serde_json::to_string_pretty(&summary).context("summary to JSON")?;
    let p = out.join("sim_summary.json");
    std::fs::write(&p, json + "\n").with_context(|| format!("{}: cannot write", p.display()))?;
    if !quiet {
        println!(
            "navfuse sim: {:.1} s, {} IMU samples ({}), {} GNSS epochs ({}-{} satellites), {} fixes, {:.0} m travelled; {:.2} s -> {}",
            summary.t_end - summary.t_start,
            summary.imu_samples,
            summary.imu_grade,
            summary.gnss_epochs,
            summary.satellites_min,
            summary.satellites_max,
            summary.gnss_fixes,
            summary.distance_m,
            summary.elapsed_s,
            out.display()
        );
    }
    Ok(())
}
