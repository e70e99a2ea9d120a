//! `--jump-runs N`: the jump-attack Monte Carlo on scenarios/seed004_loop.toml.

use anyhow::{Context, Result};
use navfuse_core::integrity::IntegrityState;
use navfuse_io::config::RunConfig;
use navfuse_sim::gnss_sim::{EventSpec, SpoofMode};
use navfuse_sim::random::Stream;
use navfuse_sim::scenario::Scenario;
use serde_json::{json, Value};

use super::reaction::reaction;
use super::variants::{attack_start, monitor_defaults, odometer_nhc};
use super::{navigate, simulate, LOOP_SCENARIO, LOOP_TEXT};
use crate::scenarios::{builtin, changed};
use crate::work::WorkDir;

/// Seed 004's loop (built in) with this case's jump in place of its one GNSS event,
/// and its seed.
fn jump_scenario(c: &JumpCase, end_s: f64) -> Result<Scenario> {
    let base = builtin(LOOP_SCENARIO, LOOP_TEXT)?;
    let mut file = base.file.clone();
    file.seed = c.seed;
    let gnss = file
        .gnss
        .as_mut()
        .with_context(|| format!("{LOOP_SCENARIO}: no [gnss]"))?;
    gnss.events = vec![EventSpec::Spoof {
        mode: SpoofMode::Jump,
        start_s: c.start_s,
        end_s,
        offset_m: c.offset_m,
        velocity_mps: [0.0; 3],
        delay_s: 0.0,
    }];
    let change = format!(
        "seed = {}; the [[gnss.event]] replaced by a jump spoof from {} s to {end_s} s, offset {:?} m",
        c.seed, c.start_s, c.offset_m
    );
    changed(&base, file, &change)
}

/// One jump attack of the Monte Carlo.
#[derive(Clone, Debug)]
pub(super) struct JumpCase {
    pub(super) run: usize,
    pub(super) seed: u64,
    pub(super) start_s: f64,
    pub(super) offset_m: [f64; 3],
}

#[derive(Clone, Debug)]
pub(super) struct JumpRun {
    pub(super) case: JumpCase,
    pub(super) delay_s: Option<f64>,
    pub(super) detector: Option<String>,
    pub(super) spoofed_delay_s: Option<f64>,
    /// Alarms before the attack: (t from the start, detector).
    pub(super) early: Vec<(f64, String)>,
    /// Entries to spoofed before the attack (confirmed false alarms).
    pub(super) early_spoofed: usize,
}

/// Jumps on seed004_loop.toml (one lap; the car drives from 61 s to about 372 s)
/// start while the car moves: uniform in [70, 330] s, last 30 s; magnitude uniform in
/// [20, 200] m, direction uniform on the sphere.
pub(super) fn jump_cases(n: usize, first_seed: u64) -> Vec<JumpCase> {
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

pub(super) fn jump_run(c: &JumpCase, work: &WorkDir, quiet: bool) -> Result<JumpRun> {
    let end_s = c.start_s + 30.0;
    let dir = work.path().join(format!("jump{:03}_seed{}", c.run, c.seed));
    let t_wall = std::time::Instant::now();
    let sc = jump_scenario(c, end_s)?;
    simulate(&sc, &dir)?;
    let t0 = sc.file.start.time_s;
    // The `monitor` variant, navigating until 2 s after the attack.
    let apply = |cfg: &mut RunConfig, sc: &Scenario| {
        attack_start(cfg, sc);
        odometer_nhc(cfg, sc);
        monitor_defaults(cfg);
        cfg.nav.end_time = Some(t0 + end_s + 2.0);
    };
    let trs = navigate(&dir, &sc, apply, work, &dir.join("out"))
        .with_context(|| format!("jump run {} (seed {})", c.run, c.seed))?
        .transitions;
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
    if !work.keep() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(run)
}

pub(super) fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let k = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[k.min(sorted.len() - 1)]
}

pub(super) fn jump_summary(runs: &[JumpRun]) -> Value {
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

pub(super) fn jump_text(runs: &[JumpRun], v: &Value) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jump_replaces_the_loops_event() {
        let c = &jump_cases(1, 3)[0];
        let sc = jump_scenario(c, c.start_s + 30.0).unwrap();
        assert_eq!(sc.file.seed, c.seed);
        let events = &sc.file.gnss.as_ref().unwrap().events;
        assert_eq!(events.len(), 1);
        match events[0] {
            EventSpec::Spoof {
                mode: SpoofMode::Jump,
                start_s,
                end_s,
                offset_m,
                ..
            } => {
                assert_eq!(start_s, c.start_s);
                assert_eq!(end_s, c.start_s + 30.0);
                assert_eq!(offset_m, c.offset_m);
            }
            ref e => panic!("{e:?}"),
        }
        let base = builtin(LOOP_SCENARIO, LOOP_TEXT).unwrap();
        assert_eq!(sc.trajectory.duration(), base.trajectory.duration());
    }
}
