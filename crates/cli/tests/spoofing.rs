//! GNSS spoofing detection (issue 6): seed 004's car (IMU500 + odometer + NHC) with
//! a spoofing attack from the simulator, the integrity monitor on (`[spoofing]` with
//! its defaults: R = 10 m, chi-square 1e-5, 30-epoch displacement window 1e-5, 2
//! epochs to confirm, 10 s to re-admit; and the simulator's fix error correlation
//! time, `gnss_corr_time_s = 30`).

mod common;
use common::{errors_ned, run, simulate, tmp};

const ATTACK_START_S: f64 = 150.0;
const T0: f64 = 345600.0;

/// seed004_loop.toml with its attack replaced by `event` (a `[[gnss.event]]` body) and
/// the given seed; simulate, run with NHC and the monitor (testing the fix velocity
/// too when `use_velocity`); the integrity transitions as (t, to, detector).
fn attacked_run(
    name: &str,
    seed: u64,
    event: &str,
    use_velocity: bool,
) -> Vec<(f64, String, String)> {
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
    let mut cfg_text = std::fs::read_to_string(sim.join("run.toml"))
        .unwrap()
        .replace(
            "[gnss]\n",
            &format!("[gnss]\nuse_velocity = {use_velocity}\n"),
        );
    cfg_text.push_str("\n[nhc]\nmode = \"always\"\n\n[spoofing]\ngnss_corr_time_s = 30\n");
    std::fs::write(sim.join("run_monitor.toml"), cfg_text).unwrap();
    let out = dir.join("out");
    run(&sim.join("run_monitor.toml"), &out);
    let tr = integrity_transitions(&out);
    let _ = std::fs::remove_dir_all(&dir);
    tr
}

/// A run's integrity.csv as (t - T0, to, detector).
fn integrity_transitions(out: &std::path::Path) -> Vec<(f64, String, String)> {
    let csv = std::fs::read_to_string(out.join("integrity.csv")).unwrap();
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
        let tr = attacked_run(&format!("jump{k}"), seed, &ev, true);
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
/// from the truth, with fixes that carry a velocity (tested too) and with position
/// only; delay and deviation printed.
#[test]
fn drift_attacks_detected_before_15m() {
    for use_velocity in [true, false] {
        for (k, v) in [0.5, 1.0, 2.0, 5.0].into_iter().enumerate() {
            let ev = format!(
                "type = \"spoof\"\nmode = \"drift\"\nstart_s = {ATTACK_START_S}\nend_s = 250\nvelocity_mps = [0.0, {v}, 0.0]\n"
            );
            let name = format!("drift{k}{use_velocity}");
            let tr = attacked_run(&name, 21 + k as u64, &ev, use_velocity);
            let (first, early) = detection(&tr);
            let what = if use_velocity {
                "position + velocity"
            } else {
                "position only"
            };
            let (delay, det) =
                first.unwrap_or_else(|| panic!("drift {v} m/s ({what}): not detected: {tr:?}"));
            // The false track leaves the truth at v from the attack start.
            let deviation = v * delay;
            eprintln!("drift {v} m/s, {what}: detected after {delay:.1} s by {det}, spoofed position {deviation:.1} m from the truth");
            assert!(
                !early,
                "drift {v} ({what}): alarm before the attack: {tr:?}"
            );
            assert!(
                deviation < 15.0,
                "drift {v} m/s ({what}): {deviation:.1} m at detection"
            );
        }
    }
}

/// `navfuse reproduce seed004 ARGS --json -q`, parsed.
fn reproduce_json(args: &[&str]) -> serde_json::Value {
    let mut a = vec!["reproduce", "seed004"];
    a.extend_from_slice(args);
    a.extend_from_slice(&["--json", "-q"]);
    let out = common::navfuse_ok(&a);
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("navfuse {a:?}: not JSON ({e}): {out}"))
}

/// Issue 6 Monte Carlo: 100 jump attacks (random seed, direction, 20-200 m, start
/// while moving) on seed 004's car with the `[spoofing]` defaults are all detected
/// within 1 s of the attack start, and no run declares spoofing before its attack (a
/// false alarm; single held-back epochs, "suspect", are printed).
#[test]
fn jump_monte_carlo_100_runs() {
    let v = reproduce_json(&["--jump-runs", "100"]);
    let j = &v["jump_monte_carlo"];
    eprintln!(
        "jump Monte Carlo: {} of {} within 1 s, detected {}, delay median {} s max {} s, detectors {}, runs with a suspect epoch before the attack {}, declared spoofed before it {}",
        j["detected_within_1s"],
        j["runs"],
        j["detected"],
        j["delay_s"]["median"],
        j["delay_s"]["max"],
        j["detectors"],
        j["runs_with_alarm_before_attack"],
        j["runs_declared_spoofed_before_attack"]
    );
    let bad: Vec<&serde_json::Value> = j["per_run"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| {
            !r["delay_s"].as_f64().is_some_and(|d| d <= 1.0)
                || r["spoofed_before_attack"].as_u64() != Some(0)
        })
        .collect();
    assert_eq!(j["runs"], 100);
    assert_eq!(j["detected_within_1s"], 100, "late or missed: {bad:#?}");
    assert_eq!(
        j["runs_declared_spoofed_before_attack"], 0,
        "false alarms before the attack: {bad:#?}"
    );
}

/// Issue 6 false alarms: 20 h of clean driving (1-hour drives, ADIS16405 MEMS IMU at
/// 50 Hz + odometer + NHC, no attack) with the `[spoofing]` defaults enter spoofed at
/// most twice.
#[test]
fn false_alarms_20h_mems() {
    let v = reproduce_json(&["--clean-hours", "20"]);
    let f = &v["false_alarms"];
    eprintln!(
        "clean drives: {:.2} h, {} transitions out of trusted ({:.2} per 10 h), {} entries to spoofed ({:.2} per 10 h)",
        f["hours"].as_f64().unwrap(),
        f["out_of_trusted"],
        f["out_of_trusted_per_10h"].as_f64().unwrap(),
        f["spoofed"],
        f["spoofed_per_10h"].as_f64().unwrap()
    );
    let alarms: Vec<&serde_json::Value> = f["per_run"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["out_of_trusted"].as_u64() != Some(0))
        .collect();
    for r in &alarms {
        eprintln!(
            "  run {} seed {}: {}",
            r["run"], r["seed"], r["transitions"]
        );
    }
    assert!(f["hours"].as_f64().unwrap() >= 20.0);
    assert!(
        f["spoofed"].as_u64().unwrap() <= 2,
        "entries to spoofed: {}; runs with alarms: {alarms:#?}",
        f["spoofed"]
    );
}

/// Issue 6, seed 004's attack (`reproduce seed004 --attack`, 4 seeds, a 2 m/s drift for
/// 300 s): with the monitor the error stays within the INS/odometer dead-reckoning bound
/// (GNSS removed over the attack) while without it the false track takes the solution
/// hundreds of metres away; with seed 004's free INS-only dead reckoning as the
/// reference, R = 10 m false-alarms before the attack and the chi-square test with the
/// dead reckoning's own covariance does not.
#[test]
fn attack_bounded_by_dead_reckoning_and_ins_only_reference() {
    let v = reproduce_json(&["--attack", "--seeds", "4"]);
    let variants = v["attack"]["variants"].as_array().unwrap();
    let metric = |name: &str, m: &str| -> Vec<f64> {
        let var = variants
            .iter()
            .find(|x| x["name"] == name)
            .unwrap_or_else(|| panic!("variant {name}"));
        var["metrics"][m]["per_seed"]
            .as_array()
            .unwrap_or_else(|| panic!("{name}.{m}"))
            .iter()
            .map(|x| x.as_f64().unwrap_or(f64::NAN))
            .collect()
    };
    // Per seed, the monitored variant's max horizontal error in the attack is within
    // its dead-reckoning bound (GNSS removed over the attack) + 0.5 m.
    let within_bound = |monitored: &str, bound: &str| {
        let (m, b) = (
            metric(monitored, "max_h_attack_m"),
            metric(bound, "max_h_attack_m"),
        );
        eprintln!("max horizontal error in the attack: {monitored} {m:?}, {bound} {b:?}");
        for k in 0..m.len() {
            assert!(
                m[k] <= b[k] + 0.5,
                "seed {k}: {monitored} {} m, {bound} {} m",
                m[k],
                b[k]
            );
        }
    };
    within_bound("monitor", "dead_reckoning");
    // Seed 004's 6-state fusion with the monitor (chi-square with the fix velocity)
    // stays within that architecture's own (poor) bound.
    within_bound("six_state_monitor", "six_state_dead_reckoning");
    let open = metric("no_monitor", "max_h_attack_m");
    eprintln!("no monitor: {open:?}");
    assert!(
        open.iter().all(|&h| h > 300.0),
        "no monitor only {open:?} m"
    );
    assert!(metric("monitor", "alarms_before").iter().all(|&a| a == 0.0));
    let r_alarms = metric("ins_only_R", "alarms_before");
    let chi2_alarms = metric("ins_only_chi2", "alarms_before");
    eprintln!(
        "alarms before the attack, INS-only reference: R {r_alarms:?}, chi-square {chi2_alarms:?}"
    );
    assert!(r_alarms.iter().any(|&a| a > 0.0), "R = 10 m: {r_alarms:?}");
    assert!(
        chi2_alarms.iter().all(|&a| a == 0.0),
        "chi-square: {chi2_alarms:?}"
    );
}

/// Tight coupling under seed 004's attack: scenarios/seed004_attack.toml with raw
/// measurements instead of fixes (the spoofer synthesises every satellite's signal
/// for the false track, 2 m/s east for 300 s; SA off), NHC on. The monitor tests each
/// epoch's single point fix against the INS/odometer prediction: the attack is
/// declared at its first epoch, nothing before it, the error over the attack equals
/// the dead-reckoning bound (the same run with GNSS withheld over the attack), and
/// GNSS is re-admitted after it. The initial position sigma is set to 30 m: with
/// seed 000's error budget the single point fix is about 24 m off here, and the
/// simulator's 1 cm at the truth would itself (rightly) be flagged.
#[test]
fn tight_coupling_attack_held_by_odometer_reference() {
    let base =
        std::fs::read_to_string(common::repo().join("scenarios/seed004_attack.toml")).unwrap();
    let fix = base.find("raw = false\n\n[gnss.fix]").expect("fix table");
    let after = fix + base[fix..].find("\n\n[[").unwrap();
    let text = format!(
        "{}raw = true\n\n[gnss.errors]\nsa_m = 0.0\n{}",
        &base[..fix],
        &base[after..]
    );
    let dir = tmp("tight_attack");
    std::fs::create_dir_all(&dir).unwrap();
    let sc = dir.join("scenario.toml");
    std::fs::write(&sc, text).unwrap();
    let sim = dir.join("sim");
    simulate(&sc, &sim);
    let mut run_cfg = navfuse_io::config::load(&sim.join("run.toml")).unwrap();
    run_cfg.nav.initial.pos_std = nalgebra::Vector3::repeat(30.0);
    assert!(run_cfg.nav.tight.enabled);
    let (attack_start, attack_end) = (ATTACK_START_S, 450.0);
    // (name, monitor on, GNSS withheld over the attack: the dead-reckoning bound).
    let variants = [
        ("monitor", true, false),
        ("no_monitor", false, false),
        ("dead_reckoning", false, true),
    ];
    let mut max_attack = std::collections::HashMap::new();
    let mut end_error = std::collections::HashMap::new();
    for (name, monitor, withhold) in variants {
        let mut c = run_cfg.clone();
        if withhold {
            c.nav
                .gnss
                .outages
                .windows
                .push(navfuse_core::outage::Window {
                    start: T0 + attack_start - 1.0,
                    end: T0 + attack_end,
                });
        }
        c.nav.nhc.mode = navfuse_core::config::NhcMode::Always;
        if monitor {
            c.nav.integrity = navfuse_core::integrity::IntegrityOptions {
                enabled: true,
                ..Default::default()
            };
        }
        let path = sim.join(format!("run_{name}.toml"));
        std::fs::write(&path, c.to_toml_string()).unwrap();
        let out = dir.join(name);
        run(&path, &out);
        let e: Vec<(f64, f64)> = errors_ned(
            &out.join("solution.nav"),
            &sim.join("truth.nav"),
            T0,
            f64::INFINITY,
        )
        .into_iter()
        .map(|(t, d)| (t - T0, d.rows(0, 2).norm()))
        .collect();
        let m = e
            .iter()
            .filter(|(t, _)| *t >= attack_start && *t <= attack_end)
            .map(|(_, h)| *h)
            .fold(0.0, f64::max);
        max_attack.insert(name, m);
        end_error.insert(name, e.last().unwrap().1);
        if monitor {
            let tr = integrity_transitions(&out);
            eprintln!("tight attack, monitor transitions: {tr:?}");
            let (first, early) = detection(&tr);
            assert!(!early, "alarm before the attack: {tr:?}");
            let delay = first.expect("attack not detected").0;
            assert!(delay <= 1.0, "detected after {delay} s");
            assert!(
                tr.iter()
                    .any(|(t, to, _)| *t > attack_end && to == "trusted"),
                "GNSS not re-admitted after the attack: {tr:?}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!(
        "tight attack, max horizontal error over the attack: monitor {:.2} m, dead reckoning {:.2} m, no monitor {:.2} m; at the end {:.2} / {:.2} / {:.2} m",
        max_attack["monitor"],
        max_attack["dead_reckoning"],
        max_attack["no_monitor"],
        end_error["monitor"],
        end_error["dead_reckoning"],
        end_error["no_monitor"]
    );
    assert!(max_attack["monitor"] <= max_attack["dead_reckoning"] + 0.5);
    assert!(end_error["monitor"] <= end_error["dead_reckoning"] + 1.0);
    // The tight filter's own pseudorange gates reject most of the false signals, but
    // not all: without the monitor the error leaves the bound.
    assert!(max_attack["no_monitor"] > max_attack["dead_reckoning"] + 5.0);
}
