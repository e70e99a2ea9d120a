//! `navfuse allan`: on a simulated IMU at rest (known white noise and bias
//! instability, `navfuse sim`) the random walks come back within 10 %; errors name the
//! file; the KF-GINS stand-in in ../shared/data runs.

mod common;

use common::{navfuse_ok, shared, simulate, tmp};
use std::path::Path;
use std::process::Command;

use navfuse_sim::imu_model::preset;

/// A static scenario: `grade` at rest for 900 s at 100 Hz.
fn static_scenario(dir: &Path, grade: &str) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("static.toml");
    std::fs::write(
        &p,
        format!(
            "seed = 5\ndescription = \"IMU at rest\"\n\n[start]\ngps_week = 2381\n\
             time_s = 345600.0\nposition_deg_m = [21.0285, 105.8542, 15.0]\nheading_deg = 30\n\n\
             [imu]\ngrade = \"{grade}\"\nrate_hz = 100\n\n[[segment]]\ntype = \"static\"\n\
             duration_s = 900\n"
        ),
    )
    .unwrap();
    p
}

/// The read-offs CSV: axis -> (random walk, bias instability).
fn readoffs(path: &Path) -> Vec<(String, f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("axis,random_walk,random_walk_unit,"));
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[0].to_string(), c[1].parse().unwrap(), c[2].to_string())
        })
        .collect()
}

#[test]
fn random_walks_of_a_simulated_imu_within_10_percent() {
    for grade in ["adis16405", "imu500"] {
        let dir = tmp(&format!("allan-{grade}"));
        simulate(&static_scenario(&dir, grade), &dir.join("sim"));
        let imu = dir.join("sim/imu.txt");
        let out = dir.join("allan.csv");
        let text = navfuse_ok(&[
            "allan",
            imu.to_str().unwrap(),
            "--rate",
            "100",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(text.contains("ARW [deg/sqrt(h)]") && text.contains("VRW [m/s/sqrt(h)]"));
        let g = preset(grade).unwrap();
        // Configured densities in the datasheet units (rad/sqrt(s) -> deg/sqrt(h);
        // m/s/sqrt(s) -> m/s/sqrt(h)).
        let arw = g.gyro.white_noise_density.to_degrees() * 60.0;
        let vrw = g.accel.white_noise_density * 60.0;
        let ro = readoffs(&dir.join("allan_readoffs.csv"));
        assert_eq!(ro.len(), 6);
        for (axis, rw, unit) in &ro {
            let (want, want_unit) = if axis.starts_with("gyro") {
                (arw, "deg/sqrt(h)")
            } else {
                (vrw, "m/s/sqrt(h)")
            };
            eprintln!("{grade} {axis}: {rw:.5} {unit} (configured {want:.5})");
            assert_eq!(unit, want_unit);
            assert!(
                (rw / want - 1.0).abs() < 0.10,
                "{grade} {axis}: {rw} vs {want}"
            );
        }
        // The curves: a row per tau, the six axes.
        let curves = std::fs::read_to_string(&out).unwrap();
        assert!(curves.lines().count() > 30);
        assert_eq!(curves.lines().nth(1).unwrap().split(',').count(), 10);
        // The run configuration the simulator wrote names the same IMU: same figures.
        let cfg = dir.join("sim/run.toml");
        let svg = dir.join("svg");
        let by_config = navfuse_ok(&[
            "allan",
            "--config",
            cfg.to_str().unwrap(),
            "--svg",
            svg.to_str().unwrap(),
        ]);
        let strip = |s: &str| s.lines().skip(1).collect::<Vec<_>>().join("\n");
        assert_eq!(strip(&by_config), strip(&text));
        // The plots: one per sensor, every axis with its random-walk line.
        for sensor in ["gyro", "accel"] {
            let s = std::fs::read_to_string(svg.join(format!("allan_{sensor}.svg"))).unwrap();
            assert!(s.starts_with("<svg") && !s.contains("NaN"), "{sensor}");
            let name = if sensor == "gyro" { "ARW" } else { "VRW" };
            assert_eq!(s.matches(name).count(), 3, "{sensor}: three {name} lines");
            assert!(
                s.matches("<polyline").count() >= 6,
                "{sensor}: curves and fits"
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

fn navfuse_err(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args(args)
        .output()
        .expect("run navfuse");
    assert!(!out.status.success(), "navfuse {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn missing_or_bad_files_are_named() {
    let dir = tmp("allan-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("no_such_imu.txt");
    let e = navfuse_err(&["allan", missing.to_str().unwrap()]);
    assert!(e.contains("no_such_imu.txt"), "{e}");
    let bad = dir.join("bad_imu.txt");
    std::fs::write(&bad, "345600.0 1 2 3\nthis is not an IMU line\n1 2\n").unwrap();
    let e = navfuse_err(&["allan", bad.to_str().unwrap(), "--rate", "100"]);
    assert!(e.contains("bad_imu.txt"), "{e}");
    let short = dir.join("short_imu.txt");
    std::fs::write(&short, "345600.01 0 0 0 0 0 0\n345600.02 0 0 0 0 0 0\n").unwrap();
    let e = navfuse_err(&["allan", short.to_str().unwrap(), "--rate", "100"]);
    assert!(e.contains("short_imu.txt") && e.contains("at least"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn kf_gins_stand_in_runs() {
    let Some(data) = shared() else { return };
    let imu = data.join("kf-gins/synthetic/IMU.txt");
    if !imu.is_file() {
        eprintln!("skipped: {} not found", imu.display());
        return;
    }
    let text = navfuse_ok(&["allan", imu.to_str().unwrap()]);
    // 200 Hz measured from the tags; six axes in the tables.
    assert!(text.contains("at 200.000 Hz"), "{text}");
    for axis in [
        "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z",
    ] {
        assert!(text.contains(axis), "{axis}");
    }
}
