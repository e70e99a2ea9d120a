//! `navfuse bench`: speed and memory of the navigator on the KF-GINS stand-in.
//!
//! 1. Full run as KF-GINS does it (read text inputs, write .nav, IMU_ERR and STD at
//!    the IMU rate): wall time, best of `repeat`.
//! 2. Peak resident memory of that run over a quarter and over all of the data
//!    (reset between runs through /proc/self/clear_refs): it must not grow with length.
//! 3. The core filter loop alone on samples already in memory: IMU samples per second.

pub mod report;
pub mod smooth;
pub mod tdcp_sweep;
pub mod tight;

use anyhow::{Context, Result};
use navfuse_app::run_job;
use navfuse_io::config::load_kfgins_yaml;
use navfuse_io::gnss::read_gnss;
use navfuse_io::imu::open_imu;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

const DEFAULT_YAML: &str = "../shared/data/kf-gins/synthetic/kf-gins.yaml";

/// Peak resident set size [KiB] since the last reset (Linux), if readable.
fn peak_rss_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

pub fn main(kf_gins: Option<PathBuf>, repeat: usize, json_out: bool) -> Result<()> {
    let yaml = kf_gins.unwrap_or_else(|| PathBuf::from(DEFAULT_YAML));
    if !yaml.exists() {
        anyhow::bail!(
            "{}: not found. The benchmark runs on the KF-GINS stand-in in ../shared/data/kf-gins/synthetic (or pass --kf-gins FILE.yaml)",
            yaml.display()
        );
    }
    let cfg = load_kfgins_yaml(&yaml)?;
    let tmp = std::env::temp_dir().join(format!("navfuse-bench-{}", std::process::id()));
    let repeat = repeat.max(1);

    // 1 + 2: full runs with file I/O.
    let mut best_full = f64::INFINITY;
    let mut samples_full = 0usize;
    let mut peak_full = None;
    for _ in 0..repeat {
        let can_reset = reset_peak_rss();
        let job = run_job(cfg.clone(), &tmp, false)?;
        best_full = best_full.min(job.wall.as_secs_f64());
        samples_full = job.summary.imu_samples;
        if can_reset {
            peak_full = peak_rss_kib();
        }
    }
    let mut quarter = cfg.clone();
    let span_end = {
        let g = cfg
            .gnss
            .as_ref()
            .context("the benchmark config needs a GNSS file")?;
        let fixes = read_gnss(g)?.fixes;
        let (a, b) = (cfg.nav.start_time.max(fixes[0].t), fixes[fixes.len() - 1].t);
        a + 0.25 * (b - a)
    };
    quarter.nav.end_time = Some(span_end);
    let can_reset = reset_peak_rss();
    let job_q = run_job(quarter, &tmp, false)?;
    let peak_quarter = if can_reset { peak_rss_kib() } else { None };
    let _ = std::fs::remove_dir_all(&tmp);

    // 3: the core loop on in-memory samples, no output.
    let imu: Vec<_> = open_imu(&cfg.imu)?.collect::<Result<_, _>>()?;
    let fixes = match &cfg.gnss {
        Some(g) => read_gnss(g)?.fixes,
        None => Vec::new(),
    };
    let mut best_core = f64::INFINITY;
    let mut samples_core = 0usize;
    for _ in 0..repeat {
        let t = Instant::now();
        let s = navfuse_core::run::<anyhow::Error>(
            &cfg.nav,
            imu.iter().map(|s| Ok(*s)),
            &navfuse_core::merge_measurements(&fixes, &[], &[]),
            None,
            |_| Ok(()),
            |_| {},
        )?;
        best_core = best_core.min(t.elapsed().as_secs_f64());
        samples_core = s.imu_samples;
    }
    let rate = samples_core as f64 / best_core;
    if json_out {
        let v = json!({
            "config": yaml.display().to_string(),
            "full_run": { "imu_samples": samples_full, "wall_s": best_full, "peak_rss_kib": peak_full },
            "quarter_run": { "imu_samples": job_q.summary.imu_samples, "peak_rss_kib": peak_quarter },
            "core_loop": { "imu_samples": samples_core, "wall_s": best_core, "samples_per_s": rate },
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("config: {}", yaml.display());
        println!(
            "full run (read text, write .nav + IMU_ERR + STD at IMU rate): {} samples in {:.3} s (best of {repeat}); KF-GINS: 10.3 s on this machine kind",
            samples_full, best_full
        );
        let kib = |p: Option<u64>| {
            p.map_or("n/a".to_string(), |k| {
                format!("{:.1} MiB", k as f64 / 1024.0)
            })
        };
        println!(
            "peak resident memory: {} for {} samples, {} for {} samples",
            kib(peak_quarter),
            job_q.summary.imu_samples,
            kib(peak_full),
            samples_full
        );
        println!(
            "core filter loop (no I/O): {} samples in {:.3} s = {:.2} M samples/s (best of {repeat})",
            samples_core, best_core, rate / 1e6
        );
    }
    Ok(())
}
