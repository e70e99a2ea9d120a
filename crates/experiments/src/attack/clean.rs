//! `--clean-hours H`: false alarms on clean drives.

use anyhow::{Context, Result};
use navfuse_core::eval::{evaluate, EvalOptions};
use navfuse_core::integrity::IntegrityState;
use navfuse_io::config::RunConfig;
use navfuse_sim::scenario::Scenario;
use serde_json::{json, Value};

use super::reaction::transition_rows;
use super::variants::{monitor_defaults, odometer_nhc};
use super::{navigate, simulate};
use crate::reproduce::setup::user_start;
use crate::reproduce::spread;
use crate::scenarios::{builtin, changed};
use crate::track::load_nav;
use crate::work::WorkDir;

/// The clean drive's scenario (built in): 60 s standing, then one lap of the seed 004
/// loop from a stop to a stop and 20 s standing (a traffic light).
const CLEAN_SCENARIO: &str = "scenarios/seed004_clean.toml";
const CLEAN_TEXT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/seed004_clean.toml"
));
/// The lap's length [s] (about 332 s).
pub(super) const LAP_S: f64 = 332.0;

/// A clean drive of about `hours` (at least one lap): seed 004's car and GNSS with
/// an ADIS16405 at 50 Hz (turn-on biases 180 deg/h and 5 mg, as seed 002's scenario:
/// what is left after the start-up bias null), no attack: the built-in scenario with
/// its lap (every segment after the first) repeated and `seed`.
pub(super) fn clean_scenario(seed: u64, hours: f64) -> Result<Scenario> {
    let laps = (((hours * 3600.0 - 60.0) / LAP_S).ceil() as usize).max(1);
    let base = builtin(CLEAN_SCENARIO, CLEAN_TEXT)?;
    let mut file = base.file.clone();
    let lap = file.segments.split_off(1);
    for _ in 0..laps {
        file.segments.extend_from_slice(&lap);
    }
    file.seed = seed;
    file.description = format!("Clean drive, ADIS16405 + odometer + GNSS, {laps} laps");
    changed(
        &base,
        file,
        &format!("seed = {seed}, the lap driven {laps} times"),
    )
}

#[derive(Clone, Debug)]
pub(super) struct CleanCase {
    pub(super) run: usize,
    pub(super) seed: u64,
    pub(super) hours: f64,
}

#[derive(Clone, Debug)]
pub(super) struct CleanRun {
    pub(super) case: CleanCase,
    pub(super) hours: f64,
    pub(super) out_of_trusted: usize,
    pub(super) spoofed: usize,
    rmse_3d_m: f64,
    pub(super) transitions: Vec<(f64, String, String, String, f64, f64)>,
}

pub(super) fn clean_cases(hours: f64, first_seed: u64) -> Vec<CleanCase> {
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
pub(super) fn clean_config(cfg: &mut RunConfig, sc: &Scenario) {
    user_start(cfg, sc);
    odometer_nhc(cfg, sc);
    monitor_defaults(cfg);
}

pub(super) fn clean_run(c: &CleanCase, work: &WorkDir, quiet: bool) -> Result<CleanRun> {
    let dir = work
        .path()
        .join(format!("clean{:02}_seed{}", c.run, c.seed));
    let t_wall = std::time::Instant::now();
    let sc = clean_scenario(c.seed, c.hours)?;
    let sim = simulate(&sc, &dir)?;
    let t0 = sc.file.start.time_s;
    let out = dir.join("out");
    let run = navigate(&dir, &sc, clean_config, work, &out)
        .with_context(|| format!("clean run {} (seed {})", c.run, c.seed))?;
    let trs = run.transitions;
    let (truth, sol) = (
        load_nav(&dir.join("truth.nav"))?.points,
        run.nav.track().points,
    );
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
    if !work.keep() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(run)
}

pub(super) fn clean_summary(runs: &[CleanRun]) -> Value {
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

pub(super) fn clean_text_report(runs: &[CleanRun], v: &Value) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_hour_drive_repeats_the_lap() {
        let one = clean_scenario(7, 0.1).unwrap();
        let lap = one.file.segments.len() - 1;
        assert_eq!(one.file.seed, 7);
        let hour = clean_scenario(7, 1.0).unwrap();
        let laps = ((3600.0 - 60.0) / LAP_S).ceil() as usize;
        assert_eq!(hour.file.segments.len(), 1 + laps * lap);
        let (d1, dh) = (one.trajectory.duration(), hour.trajectory.duration());
        assert!(
            (dh - 60.0 - laps as f64 * (d1 - 60.0)).abs() < 1e-6,
            "{d1} {dh}"
        );
        assert!((d1 - 60.0 - LAP_S).abs() < 1.0, "lap {d1}");
    }
}
