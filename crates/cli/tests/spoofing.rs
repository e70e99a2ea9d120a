//! GNSS spoofing detection (issue 6): seed 004's car (IMU500 + odometer + NHC) with
//! a spoofing attack from the simulator, the integrity monitor on (`[spoofing]` with
//! its defaults: R = 10 m, chi-square 1e-5, 5-epoch window 1e-5, 2 epochs to
//! confirm, 10 s to re-admit).
//!
//! Both tests encode the acceptance figures and are ignored while issue 6 is
//! open (run them with `--ignored`); what they measure today is in docs/RESULTS.md §8.

mod common;
use common::{run, simulate, tmp};

const ATTACK_START_S: f64 = 150.0;
const T0: f64 = 345600.0;

/// seed004_loop.toml with its attack replaced by `event` (a `[[gnss.event]]` body) and
/// the given seed; simulate, run with NHC and the monitor; the integrity transitions
/// as (t, to, detector).
fn attacked_run(name: &str, seed: u64, event: &str) -> Vec<(f64, String, String)> {
    let base = std::fs::read_to_string(common::repo().join("scenarios/seed004_loop.toml")).unwrap();
    let a = base.find("[[gnss.event]]").unwrap();
    let b = a + base[a..].find("\n\n").unwrap();
    let text = format!("{}[[gnss.event]]\n{event}{}", &base[..a], &base[b..])
        .replace("seed = 1\n", &format!("seed = {seed}\n"));
    let dir = tmp(name);
    std::fs::create_dir_all(&dir).unwrap();
    let sc = dir.join("scenario.toml");
    std::fs::write(&sc, text).unwrap();
    let sim = dir.join("sim");
    simulate(&sc, &sim);
    let mut cfg_text = std::fs::read_to_string(sim.join("run.toml")).unwrap();
    cfg_text.push_str("\n[nhc]\nmode = \"always\"\n\n[spoofing]\n");
    std::fs::write(sim.join("run_monitor.toml"), cfg_text).unwrap();
    let out = dir.join("out");
    run(&sim.join("run_monitor.toml"), &out);
    let csv = std::fs::read_to_string(out.join("integrity.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    csv.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse::<f64>().unwrap() - T0,
                f[2].to_string(),
                f[3].to_string(),
            )
        })
        .collect()
}

/// First transition out of trusted at or after the attack start, and whether any
/// happened before it (a false alarm).
fn detection(tr: &[(f64, String, String)]) -> (Option<(f64, String)>, bool) {
    let early = tr.iter().any(|(t, _, _)| *t < ATTACK_START_S);
    let first = tr
        .iter()
        .find(|(t, to, _)| *t >= ATTACK_START_S && to != "trusted")
        .map(|(t, _, d)| (*t - ATTACK_START_S, d.clone()));
    (first, early)
}

/// Jumps of 20 m and more are refused at the first spoofed epoch (within 1 s), with
/// no alarm before the attack, over several seeds and directions.
#[test]
#[ignore = "issue 6 open: a window-test false alarm during the static start (t = 32 s, seed 11)"]
fn jump_attacks_detected_within_1s() {
    let mut n = 0;
    for (k, (offset, seed)) in [
        ([20.0, 0.0, 0.0], 11),
        ([0.0, -20.0, 0.0], 12),
        ([14.2, 14.2, 0.0], 13),
        ([0.0, 0.0, 20.0], 14),
        ([50.0, 0.0, 0.0], 15),
        ([0.0, 200.0, 0.0], 16),
    ]
    .into_iter()
    .enumerate()
    {
        let ev = format!(
            "type = \"spoof\"\nmode = \"jump\"\nstart_s = {ATTACK_START_S}\nend_s = 210\noffset_m = [{}, {}, {}]\n",
            offset[0], offset[1], offset[2]
        );
        let tr = attacked_run(&format!("jump{k}"), seed, &ev);
        let (first, early) = detection(&tr);
        let (delay, det) = first.unwrap_or_else(|| panic!("jump {offset:?}: not detected: {tr:?}"));
        eprintln!("jump {offset:?} seed {seed}: detected after {delay:.1} s by {det}");
        assert!(!early, "jump {offset:?}: alarm before the attack: {tr:?}");
        assert!(delay <= 1.0, "jump {offset:?}: {delay} s");
        n += 1;
    }
    assert_eq!(n, 6);
}

/// Slow drifts (PX4 #27340 was 5 m/s): detected before the spoofed position is 15 m
/// from the truth; delay and deviation printed.
#[test]
#[ignore = "issue 6 open: 5 m/s drift detected at 15.0 m (3 epochs), the limit is < 15 m"]
fn drift_attacks_detected_before_15m() {
    for (k, v) in [0.5, 1.0, 2.0, 5.0].into_iter().enumerate() {
        let ev = format!(
            "type = \"spoof\"\nmode = \"drift\"\nstart_s = {ATTACK_START_S}\nend_s = 250\nvelocity_mps = [0.0, {v}, 0.0]\n"
        );
        let tr = attacked_run(&format!("drift{k}"), 21 + k as u64, &ev);
        let (first, early) = detection(&tr);
        let (delay, det) = first.unwrap_or_else(|| panic!("drift {v} m/s: not detected: {tr:?}"));
        // The false track leaves the truth at v from the attack start.
        let deviation = v * delay;
        eprintln!("drift {v} m/s: detected after {delay:.1} s by {det}, spoofed position {deviation:.1} m from the truth");
        assert!(!early, "drift {v}: alarm before the attack: {tr:?}");
        assert!(
            deviation < 15.0,
            "drift {v} m/s: {deviation:.1} m at detection"
        );
    }
}
