//! Helpers shared by the binary's integration tests.
#![allow(dead_code)]

pub mod rtklib;

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

/// `navfuse run examples/demo/drive_excerpt.toml --out DIR/run -q EXTRA...` in a
/// fresh scratch directory `tmp(name)`; returns (scratch directory, run directory).
pub fn run_demo(name: &str, extra: &[&str]) -> (PathBuf, PathBuf) {
    let dir = tmp(name);
    let out = dir.join("run");
    let o = out.to_str().unwrap().to_string();
    let mut args = vec!["run", "examples/demo/drive_excerpt.toml", "--out", &o, "-q"];
    args.extend_from_slice(extra);
    navfuse_ok(&args);
    (dir, out)
}

/// Simulate `scenario` into `tmp(name)/sim` and run its run.toml into
/// `tmp(name)/out` with `extra` run arguments; returns (scratch, sim, out).
pub fn sim_and_run(name: &str, scenario: &str, extra: &[&str]) -> (PathBuf, PathBuf, PathBuf) {
    let dir = tmp(name);
    let sim = dir.join("sim");
    simulate(Path::new(scenario), &sim);
    let out = dir.join("out");
    let (cfg, o) = (
        sim.join("run.toml").to_str().unwrap().to_string(),
        out.to_str().unwrap().to_string(),
    );
    let mut args = vec!["run", &cfg, "--out", &o, "-q"];
    args.extend_from_slice(extra);
    navfuse_ok(&args);
    (dir, sim, out)
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

/// `navfuse eval SOLUTION TRUTH --json EXTRA...`, parsed.
pub fn eval_json(solution: &Path, truth: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "eval",
        solution.to_str().unwrap(),
        truth.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    serde_json::from_str(&navfuse_ok(&args)).expect("eval --json output")
}

/// The number at `path` in `v` (panics naming the path when absent).
pub fn num(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[*k];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("no number at {path:?} in {v}"))
}

/// A KF-GINS STD file: time [10 ms ticks] -> the 21 standard deviations (KF-GINS
/// units: position N E D [m], velocity [m/s], attitude [deg], ...).
pub fn read_std(path: &Path) -> HashMap<i64, Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            ((v[0] * 100.0).round() as i64, v[1..].to_vec())
        })
        .collect()
}

/// Per epoch after the first minute: (position, velocity, attitude) NEES of `sol`
/// (a .nav file) with the 1-sigma of `std` against `truth` (a .nav file). The
/// attitude error is the rotation from the true to the estimated attitude, in n.
pub fn nees(truth: &Path, sol: &Path, std: &Path) -> Vec<[f64; 3]> {
    let key = |t: f64| (t * 100.0).round() as i64;
    let truth: HashMap<i64, navfuse_core::NavState> = read_nav(truth)
        .unwrap()
        .into_iter()
        .map(|(_, s)| (key(s.t), s))
        .collect();
    let std = read_std(std);
    let sol = read_nav(sol).unwrap();
    let t0 = sol[0].1.t;
    let norm2 = |e: Vector3<f64>, s: &[f64]| (0..3).map(|i| (e[i] / s[i]).powi(2)).sum::<f64>();
    sol.iter()
        .filter(|(_, s)| s.t - t0 >= 60.0)
        .filter_map(|(_, s)| {
            let (tr, sd) = (truth.get(&key(s.t))?, std.get(&key(s.t))?);
            let e_att = (s.q_bn * tr.q_bn.inverse())
                .scaled_axis()
                .map(f64::to_degrees);
            Some([
                norm2(lla_diff_ned(&s.lla, &tr.lla), &sd[0..3]),
                norm2(s.v_n - tr.v_n, &sd[3..6]),
                norm2(e_att, &sd[6..9]),
            ])
        })
        .collect()
}

/// Two-sided 95 % band of the N-run average NEES of 3 dof (Wilson-Hilferty).
pub fn nees_band(n: usize) -> (f64, f64) {
    let k = 3.0 * n as f64;
    let a = 2.0 / (9.0 * k);
    let q = |z: f64| k * (1.0 - a + z * a.sqrt()).powi(3) / n as f64;
    (q(-1.959964), q(1.959964))
}
