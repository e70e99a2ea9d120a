//! `navfuse bench --tight`: speed of tight coupling (issue 5: 10 satellites at 1 Hz
//! and a 200 Hz IMU must run at least 500x faster than real time).
//!
//! 1. Simulate the scenario (built in: `scenarios/bench_tight_10sat.toml`), cut to
//!    `--duration-s`, into a temporary directory (not timed), and count the satellites
//!    per epoch in obs.rnx: fewer than 10 on average is an error, not a benchmark.
//! 2. Full run as `navfuse run` does it, in tight mode (pseudoranges + TDCP): read
//!    imu.txt, obs.rnx and nav.rnx, prepare every epoch, navigate, write solution.nav
//!    at the IMU rate. Wall time, best of `repeat`; real-time factor = seconds of data
//!    / wall seconds, PASS at 500x or more.
//! 3. The core loop alone on the IMU samples and prepared GNSS epochs already in
//!    memory, no output; and, apart, the GNSS input stage (read the RINEX files,
//!    satellite positions, single point fixes).
//!
//! The verdict is printed (and in the JSON), not turned into the exit status: timing
//! depends on the machine. The exit status is non-zero only when the benchmark could
//! not run as specified (e.g. too few satellites).

use anyhow::{bail, Context, Result};
use navfuse_app::run_job;
use navfuse_io::config::RunConfig;
use navfuse_io::imu::open_imu;
use navfuse_io::input::{Coupling, GnssFormat};
use navfuse_sim::generate::generate;
use navfuse_sim::scenario::{Scenario, SegmentSpec};

use crate::scenarios::{builtin, changed};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The built-in scenario (editing the file changes the bench after a rebuild).
const SCENARIO_NAME: &str = "scenarios/bench_tight_10sat.toml";
const SCENARIO_TEXT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/bench_tight_10sat.toml"
));
/// The requirement: satellites per epoch and real-time factor.
pub const SATELLITES: f64 = 10.0;
pub const REQUIRED_SPEEDUP: f64 = 500.0;
pub const DEFAULT_DURATION_S: f64 = 600.0;

/// Removes the scratch directory however the bench ends.
struct Scratch(PathBuf);
impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Min / mean / max of per-epoch satellite counts.
#[derive(Clone, Copy, Debug)]
struct Counts {
    epochs: usize,
    min: usize,
    mean: f64,
    max: usize,
}

impl Counts {
    fn of(n: impl Iterator<Item = usize>) -> Counts {
        let (mut epochs, mut sum, mut min, mut max) = (0usize, 0usize, usize::MAX, 0usize);
        for k in n {
            epochs += 1;
            sum += k;
            min = min.min(k);
            max = max.max(k);
        }
        Counts {
            epochs,
            min: if epochs == 0 { 0 } else { min },
            mean: if epochs == 0 {
                0.0
            } else {
                sum as f64 / epochs as f64
            },
            max,
        }
    }
    fn json(&self) -> serde_json::Value {
        json!({ "epochs": self.epochs, "min": self.min, "mean": self.mean, "max": self.max })
    }
}

/// The scenario cut to `duration_s`: trailing segments are dropped and a `hold` (or
/// `static`, when the vehicle stands) fills up to the duration.
fn cut_scenario(full: Scenario, duration_s: f64) -> Result<Scenario> {
    let path = full.path.clone();
    let full_s = full.trajectory.duration();
    if duration_s > full_s + 1e-6 {
        bail!(
            "--duration-s {duration_s}: the scenario {} is only {full_s:.1} s long",
            path.display()
        );
    }
    if (full_s - duration_s).abs() < 1e-6 {
        return Ok(full);
    }
    let with = |segments: &[SegmentSpec], change: &str| {
        let mut file = full.file.clone();
        file.segments = segments.to_vec();
        changed(&full, file, change)
    };
    // The longest prefix of whole segments that fits, then a filler.
    let segments = &full.file.segments;
    let mut keep = 0usize;
    let mut kept_s = 0.0;
    for k in 1..segments.len() {
        let d = with(&segments[..k], "")?.trajectory.duration();
        if d > duration_s + 1e-9 {
            break;
        }
        keep = k;
        kept_s = d;
    }
    let change = format!("navfuse bench: cut to {duration_s} s, the first {keep} segments");
    let rest = duration_s - kept_s;
    if rest < 1e-6 {
        return with(&segments[..keep], &change);
    }
    let mut last_err = None;
    for filler in [
        SegmentSpec::Hold { duration_s: rest },
        SegmentSpec::Static { duration_s: rest },
    ] {
        let mut cut = segments[..keep].to_vec();
        cut.push(filler);
        match with(&cut, &format!("{change} and a {rest} s filler")) {
            Ok(sc) => return Ok(sc),
            Err(e) => last_err = Some(e),
        }
    }
    Err(last_err.unwrap()).context(format!("cannot cut {} to {duration_s} s", path.display()))
}

/// The simulator's run.toml: for a scenario with raw GNSS and no receiver fixes it is
/// tight coupling (pseudoranges + TDCP) on obs.rnx / nav.rnx with the scenario's
/// elevation mask and antenna lever arm.
fn tight_config(dir: &Path) -> Result<RunConfig> {
    let p = dir.join("run.toml");
    let cfg = navfuse_io::config::load(&p)?;
    let tight = matches!(
        cfg.gnss.as_ref().map(|g| &g.format),
        Some(GnssFormat::Rinex(r)) if r.coupling == Coupling::Tight
    );
    if !tight {
        bail!(
            "{}: not a tight-coupling run; the bench scenario needs [gnss] raw = true and no [gnss.fix]",
            p.display()
        );
    }
    Ok(cfg)
}

pub fn main(
    scenario: Option<PathBuf>,
    duration_s: f64,
    repeat: usize,
    json_out: bool,
) -> Result<()> {
    let repeat = repeat.max(1);
    if !(duration_s.is_finite() && duration_s >= 10.0) {
        bail!("--duration-s: expected at least 10 s, got {duration_s}");
    }
    let full = match &scenario {
        Some(p) => Scenario::load(p)?,
        None => builtin(SCENARIO_NAME, SCENARIO_TEXT)?,
    };
    let path = full.path.clone();
    let sc = cut_scenario(full, duration_s)?;
    let gnss_hz = sc.file.gnss.as_ref().map_or(0.0, |g| g.rate_hz);
    let scratch =
        Scratch(std::env::temp_dir().join(format!("navfuse-bench-tight-{}", std::process::id())));
    let sim_dir = scratch.0.join("sim");
    let out_dir = scratch.0.join("out");

    // 1. Simulate (not timed) and count the satellites.
    let t_sim = Instant::now();
    let sim = generate(&sc, &sim_dir)?;
    let sim_s = t_sim.elapsed().as_secs_f64();
    let cfg = tight_config(&sim_dir)?;
    let obs = navfuse_io::rinex_obs::read_rinex_obs(&sim_dir.join("obs.rnx"))?;
    let in_file = Counts::of(obs.iter().map(|e| e.sats.len()));
    drop(obs);
    if in_file.epochs == 0 || in_file.mean < SATELLITES - 1e-9 {
        bail!(
            "{}: obs.rnx has {:.2} satellites per epoch on average (min {}, max {}, {} epochs), fewer than the {SATELLITES} the benchmark is specified for; \
             pick a site, start time, elevation mask or blockage `keep` that leaves {SATELLITES} in view",
            path.display(),
            in_file.mean,
            in_file.min,
            in_file.max,
            in_file.epochs
        );
    }

    // 3a. GNSS input stage alone (also gives the prepared epochs for the core loop).
    let (src, rinex) = match &cfg.gnss {
        Some(
            src @ navfuse_io::input::GnssSource {
                format: GnssFormat::Rinex(r),
                ..
            },
        ) if r.coupling == Coupling::Tight => (src, r),
        _ => bail!("internal: the bench configuration is not tight RINEX"),
    };
    let mut best_gnss = f64::INFINITY;
    let mut raw = Vec::new();
    for _ in 0..repeat {
        let t = Instant::now();
        let g = navfuse_app::gnss_input::load_rinex(src, rinex, &cfg.nav.gnss.systems)?;
        best_gnss = best_gnss.min(t.elapsed().as_secs_f64());
        raw = g.raw;
    }
    let prepared = Counts::of(
        raw.iter()
            .map(|e| e.sats.iter().filter(|s| s.pseudorange_m.is_some()).count()),
    );
    if prepared.mean < SATELLITES - 1e-9 {
        bail!(
            "{}: after the GNSS layer (elevation mask {} deg) the epochs have {:.2} satellites with a pseudorange on average (min {}, max {}), fewer than {SATELLITES}",
            path.display(),
            rinex.elevation_mask_deg,
            prepared.mean,
            prepared.min,
            prepared.max
        );
    }

    // 2. Full runs with file I/O.
    let mut best_full = f64::INFINITY;
    let mut job = None;
    for _ in 0..repeat {
        let j = run_job(cfg.clone(), &out_dir, false).context("tight run")?;
        best_full = best_full.min(j.wall.as_secs_f64());
        job = Some(j);
    }
    let job = job.expect("repeat >= 1");
    let s = &job.summary;
    let span = (s.last_t - s.first_t).max(0.0);
    let pr_used = s.aiding_used.get("pseudorange").copied().unwrap_or(0);
    let pr_rejected = s.aiding_rejected.get("pseudorange").copied().unwrap_or(0);
    let rr_used = ["tdcp", "range_rate", "doppler"]
        .iter()
        .map(|k| s.aiding_used.get(k).copied().unwrap_or(0))
        .sum::<usize>();
    let gnss_epochs = s.gnss_used.max(1);

    // 3b. The core loop on samples and prepared epochs in memory, no output.
    let imu: Vec<_> = open_imu(&cfg.imu)?.collect::<Result<_, _>>()?;
    let measurements = navfuse_core::merge_raw_epochs(Vec::new(), raw);
    let mut best_core = f64::INFINITY;
    let mut core = None;
    for _ in 0..repeat {
        let t = Instant::now();
        let c = navfuse_core::run::<anyhow::Error>(
            &cfg.nav,
            imu.iter().map(|s| Ok(*s)),
            &measurements,
            None,
            |_| Ok(()),
            |_| {},
        )?;
        best_core = best_core.min(t.elapsed().as_secs_f64());
        core = Some(c);
    }
    let core = core.expect("repeat >= 1");
    let span_core = (core.last_t - core.first_t).max(0.0);
    drop(scratch);

    let rtf_full = span / best_full;
    let rtf_core = span_core / best_core;
    let pass = rtf_full >= REQUIRED_SPEEDUP;
    let verdict = if pass { "PASS" } else { "FAIL" };
    if json_out {
        let v = json!({
            "scenario": path.display().to_string(),
            "duration_s": duration_s,
            "simulation": { "wall_s": sim_s, "imu_samples": sim.imu_samples, "imu_rate_hz": sim.imu_rate_hz, "gnss_rate_hz": gnss_hz, "gnss_epochs": sim.gnss_epochs },
            "satellites_per_epoch": { "obs_rnx": in_file.json(), "prepared": prepared.json() },
            "filter_updates_per_epoch": {
                "pseudorange_used": pr_used as f64 / gnss_epochs as f64,
                "pseudorange_rejected": pr_rejected as f64 / gnss_epochs as f64,
                "range_rate_used": rr_used as f64 / gnss_epochs as f64,
            },
            "full_run": { "imu_samples": s.imu_samples, "data_s": span, "wall_s": best_full, "real_time_factor": rtf_full },
            "gnss_input": { "epochs": prepared.epochs, "wall_s": best_gnss },
            "core_loop": { "imu_samples": core.imu_samples, "data_s": span_core, "wall_s": best_core, "real_time_factor": rtf_core, "samples_per_s": core.imu_samples as f64 / best_core },
            "repeat": repeat,
            "required_real_time_factor": REQUIRED_SPEEDUP,
            "pass": pass,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "scenario: {} cut to {duration_s} s ({} IMU samples at {} Hz, {} GNSS epochs; simulated in {sim_s:.2} s, not timed)",
            path.display(),
            sim.imu_samples,
            sim.imu_rate_hz,
            sim.gnss_epochs
        );
        println!(
            "satellites per epoch: obs.rnx min {} / mean {:.2} / max {}; with a pseudorange after the GNSS layer min {} / mean {:.2} / max {}",
            in_file.min, in_file.mean, in_file.max, prepared.min, prepared.mean, prepared.max
        );
        println!(
            "filter updates per GNSS epoch: {:.2} pseudoranges ({:.2} more rejected by the gate), {:.2} TDCP range rates",
            pr_used as f64 / gnss_epochs as f64,
            pr_rejected as f64 / gnss_epochs as f64,
            rr_used as f64 / gnss_epochs as f64
        );
        println!(
            "full tight run (read imu.txt + RINEX, navigate, write solution.nav at the IMU rate): {} samples, {span:.1} s of data in {best_full:.3} s (best of {repeat}) = {rtf_full:.0}x real time",
            s.imu_samples
        );
        println!(
            "  of which GNSS input (read RINEX, satellite positions, SPP): {best_gnss:.3} s for {} epochs",
            prepared.epochs
        );
        println!(
            "core loop (in memory, no output): {} samples in {best_core:.3} s = {:.2} M samples/s = {rtf_core:.0}x real time (best of {repeat})",
            core.imu_samples,
            core.imu_samples as f64 / best_core / 1e6
        );
        println!(
            "{verdict}: tight coupling, {:.0} satellites at {gnss_hz} Hz, {} Hz IMU: {rtf_full:.0}x real time (required {REQUIRED_SPEEDUP:.0}x)",
            prepared.mean, sim.imu_rate_hz
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn built_in() -> Scenario {
        builtin(SCENARIO_NAME, SCENARIO_TEXT).unwrap()
    }

    #[test]
    fn cut_keeps_whole_segments_then_fills_up() {
        let full = built_in();
        let n = full.file.segments.len();
        let sc = cut_scenario(full.clone(), 600.0).unwrap();
        assert!((sc.trajectory.duration() - 600.0).abs() < 1e-6);
        let k = sc.file.segments.len() - 1;
        assert!(k < n);
        assert_eq!(
            format!("{:?}", &sc.file.segments[..k]),
            format!("{:?}", &full.file.segments[..k])
        );
        assert!(matches!(
            sc.file.segments[k],
            SegmentSpec::Hold { .. } | SegmentSpec::Static { .. }
        ));
        // The copy the simulator writes says what was changed, then the file.
        assert!(sc
            .text
            .starts_with("# navfuse: Changed in code (navfuse bench: cut to 600 s"));
        assert!(sc.text.ends_with(SCENARIO_TEXT));
        // Everything else is the file's.
        assert_eq!(sc.file.seed, full.file.seed);
        assert_eq!(sc.imu.rate_hz, full.imu.rate_hz);
    }

    #[test]
    fn cut_to_the_full_length_or_beyond() {
        let full = built_in();
        let d = full.trajectory.duration();
        let same = cut_scenario(full.clone(), d).unwrap();
        assert_eq!(same.file.segments.len(), full.file.segments.len());
        assert_eq!(same.text, full.text);
        let e = cut_scenario(full, d + 1.0).unwrap_err().to_string();
        assert!(e.contains("is only"), "{e}");
    }
}
