//! Helpers shared by the binary's integration tests.
#![allow(dead_code)]

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
    navfuse_ok(&[
        "sim",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
}

/// `navfuse run CONFIG --out OUT -q`.
pub fn run(config: &Path, out: &Path) {
    navfuse_ok(&[
        "run",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
}
