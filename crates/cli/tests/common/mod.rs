//! Helpers shared by the binary's integration tests.
#![allow(dead_code)]

use nalgebra::Vector3;
use navfuse_core::earth::lla_diff_ned;
use navfuse_io::nav::read_nav;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `../shared/data`, or None with the skip reason printed.
pub fn shared() -> Option<PathBuf> {
    let p = repo().join("../shared/data");
    if p.is_dir() {
        Some(p)
    } else {
        eprintln!(
            "skipped: {} not found (tests that need ../shared/data skip)",
            p.display()
        );
        None
    }
}

/// A fresh, empty scratch directory path for this test process.
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Run the binary from the repository root; panics with its stderr on failure and
/// returns its stdout.
pub fn navfuse_ok(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .current_dir(repo())
        .args(args)
        .output()
        .expect("run navfuse");
    assert!(
        out.status.success(),
        "navfuse {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `navfuse sim SCENARIO --out OUT -q` (scenario relative to the repository root or
/// absolute).
pub fn simulate(scenario: &Path, out: &Path) {
    simulate_seed(scenario, out, None);
}

/// [`simulate`] with the scenario's seed replaced by `seed`.
pub fn simulate_seed(scenario: &Path, out: &Path, seed: Option<u64>) {
    let seed = seed.map(|s| s.to_string());
    let mut args = vec![
        "sim",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ];
    if let Some(s) = &seed {
        args.extend(["--seed", s.as_str()]);
    }
    navfuse_ok(&args);
}

/// `navfuse run CONFIG --out OUT -q`.
pub fn run(config: &Path, out: &Path) {
    run_with(config, out, &[]);
}

/// `navfuse run CONFIG --out OUT -q EXTRA...`.
pub fn run_with(config: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec![
        "run",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    navfuse_ok(&args);
}

/// Position error vectors NED [m] of `solution.nav` against `truth.nav` at the whole
/// seconds `t0 .. t1` (both files hold those epochs).
pub fn errors_ned(sol: &Path, truth: &Path, t0: f64, t1: f64) -> Vec<(f64, Vector3<f64>)> {
    let key = |t: f64| (t * 100.0).round() as i64;
    let truth: HashMap<i64, Vector3<f64>> = read_nav(truth)
        .unwrap()
        .into_iter()
        .map(|(_, s)| (key(s.t), s.lla))
        .collect();
    read_nav(sol)
        .unwrap()
        .into_iter()
        .filter(|(_, s)| s.t >= t0 - 1e-6 && s.t <= t1 + 1e-6 && (s.t - s.t.round()).abs() < 1e-6)
        .map(|(_, s)| (s.t, lla_diff_ned(&s.lla, &truth[&key(s.t)])))
        .collect()
}
