//! `navfuse bench --tight` (issue 5 speed requirement: tight coupling with 10
//! satellites at 1 Hz and a 200 Hz IMU at least 500x faster than real time). The
//! speed itself is not asserted here (debug builds, busy machines); these check that
//! the benchmark measures what it says.

mod common;
use common::{navfuse_ok, repo, simulate, tmp};
use serde_json::Value;
use std::process::Command;

/// The bench scenario has exactly 10 satellites in every epoch over its whole length
/// (simulated with a 10 Hz IMU to keep the test short: the sky does not depend on it).
#[test]
fn bench_scenario_has_10_satellites_in_every_epoch() {
    let text = std::fs::read_to_string(repo().join("scenarios/bench_tight_10sat.toml")).unwrap();
    assert_eq!(
        text.matches("\nrate_hz = 200\n").count(),
        1,
        "the [imu] rate line"
    );
    let dir = tmp("bench_sky");
    std::fs::create_dir_all(&dir).unwrap();
    let sc = dir.join("sky.toml");
    std::fs::write(&sc, text.replace("\nrate_hz = 200\n", "\nrate_hz = 10\n")).unwrap();
    let out = dir.join("sim");
    simulate(&sc, &out);
    let obs = std::fs::read_to_string(out.join("obs.rnx")).unwrap();
    // RINEX 3 epoch lines: "> yyyy mm dd hh mm ss.sssssss  flag nsat".
    let counts: Vec<usize> = obs
        .lines()
        .filter(|l| l.starts_with('>'))
        .map(|l| l.split_whitespace().last().unwrap().parse().unwrap())
        .collect();
    eprintln!(
        "bench scenario: {} epochs, {}-{} satellites",
        counts.len(),
        counts.iter().min().unwrap(),
        counts.iter().max().unwrap()
    );
    assert!(counts.len() >= 1800, "{} epochs", counts.len());
    assert!(counts.iter().all(|&n| n == 10), "{counts:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A short run of the bench itself: 10 satellites reach the filter, figures reported.
#[test]
fn bench_tight_reports() {
    let j: Value = serde_json::from_str(&navfuse_ok(&[
        "bench",
        "--tight",
        "--duration-s",
        "30",
        "--repeat",
        "1",
        "--json",
    ]))
    .unwrap();
    for k in ["obs_rnx", "prepared"] {
        let s = &j["satellites_per_epoch"][k];
        assert_eq!(s["min"], 10, "{k}: {s}");
        assert_eq!(s["max"], 10, "{k}: {s}");
    }
    let full = &j["full_run"];
    let n = full["imu_samples"].as_u64().unwrap();
    assert!((5990..=6000).contains(&n), "{full}");
    assert!(full["real_time_factor"].as_f64().unwrap() > 0.0, "{full}");
    assert!(j["core_loop"]["wall_s"].as_f64().unwrap() > 0.0);
    assert!(j["pass"].is_boolean());
    assert!(
        j["filter_updates_per_epoch"]["pseudorange_used"]
            .as_f64()
            .unwrap()
            > 8.0,
        "{}",
        j["filter_updates_per_epoch"]
    );
}

/// Fewer than 10 satellites per epoch: an error, not a benchmark of less work.
#[test]
fn bench_tight_refuses_fewer_satellites() {
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .current_dir(repo())
        .args([
            "bench",
            "--tight",
            "--scenario",
            "scenarios/blockage_2sat.toml",
            "--duration-s",
            "20",
            "--repeat",
            "1",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("satellites per epoch on average"), "{err}");
}
