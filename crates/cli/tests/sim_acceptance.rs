//! The simulator through the binary: perfect-IMU round trips through `navfuse run`,
//! byte-identical reruns, and every shipped scenario loads. Needs no ../shared data.

mod common;

use common::{navfuse_ok as navfuse, repo, tmp};
use std::process::Command;

fn json_at(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[*k];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("{path:?} missing in {v}"))
}

/// Issue 3, point 1: a perfect IMU through `navfuse run` without aiding reproduces the
/// truth within 0.05 m and 0.001 deg after 600 s.
fn round_trip(name: &str) {
    let scen = repo().join(format!("scenarios/roundtrip_{name}.toml"));
    let sim = tmp(&format!("rt-{name}"));
    let run = tmp(&format!("rt-{name}-run"));
    navfuse(&[
        "sim",
        scen.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
        "-q",
    ]);
    navfuse(&[
        "run",
        sim.join("run.toml").to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    let s = navfuse(&[
        "eval",
        run.join("solution.nav").to_str().unwrap(),
        sim.join("truth.nav").to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&s).expect("eval json");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sim.join("sim_summary.json")).unwrap())
            .unwrap();
    let dur = json_at(&summary, &["t_end"]) - json_at(&summary, &["t_start"]);
    let p3 = json_at(&v, &["position_m", "3d", "max"]);
    let att = ["roll", "pitch", "yaw"].map(|a| json_at(&v, &["attitude_deg", a, "max"]).abs());
    println!("{name}: {dur:.0} s, max 3D position error {p3:.4} m, max attitude error {att:?} deg");
    assert!(dur >= 600.0, "{name}: only {dur} s");
    assert!(p3 < 0.05, "{name}: 3D position error {p3} m");
    assert!(
        att.iter().all(|&a| a < 0.001),
        "{name}: attitude error {att:?} deg"
    );
    let _ = std::fs::remove_dir_all(&sim);
    let _ = std::fs::remove_dir_all(&run);
}

#[test]
fn perfect_imu_round_trip_car() {
    round_trip("car");
}

#[test]
fn perfect_imu_round_trip_uav() {
    round_trip("uav");
}

/// Issue 3, point 9: same scenario and seed give byte-identical output; another seed
/// changes the noise.
#[test]
fn same_seed_same_bytes() {
    let scen = repo().join("scenarios/seed004_loop.toml");
    let dirs = [tmp("det-a"), tmp("det-b"), tmp("det-c")];
    for (d, seed) in dirs.iter().zip(["1", "1", "2"]) {
        navfuse(&[
            "sim",
            scen.to_str().unwrap(),
            "--out",
            d.to_str().unwrap(),
            "--seed",
            seed,
            "-q",
        ]);
    }
    let mut names: Vec<_> = std::fs::read_dir(&dirs[0])
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n != "sim_summary.json") // holds the run time
        .collect();
    names.sort();
    assert!(names.len() >= 8, "{names:?}");
    for n in &names {
        let a = std::fs::read(dirs[0].join(n)).unwrap();
        let b = std::fs::read(dirs[1].join(n)).unwrap();
        assert!(a == b, "{n} differs between two runs with the same seed");
    }
    let a = std::fs::read(dirs[0].join("imu.txt")).unwrap();
    let c = std::fs::read(dirs[2].join("imu.txt")).unwrap();
    assert!(a != c, "another seed gave the same IMU noise");
    for d in &dirs {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Every shipped scenario is valid and generates (the short ones are run in full).
#[test]
fn shipped_scenarios_load() {
    let dir = repo().join("scenarios");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().and_then(|x| x.to_str()) != Some("toml") {
            continue;
        }
        navfuse_sim::scenario::Scenario::load(&p).unwrap_or_else(|e| panic!("{e}"));
        n += 1;
    }
    assert!(n >= 7, "only {n} scenarios");
}

#[test]
fn bad_scenario_names_file_line_and_key() {
    let d = tmp("bad");
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("bad.toml");
    std::fs::write(
        &p,
        "seed = 1\n[start]\ngps_week = 2381\ntime_s = 1000\nposition_deg_m = [30, 114, 0]\n\n[[segment]]\ntype = \"turn\"\nrate_dps = 5\nangle_deg = 90\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "sim",
            p.to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml:7") && err.contains("segment[1]") && err.contains("moving"),
        "{err}"
    );
    std::fs::write(&p, "seed = 1\n[start]\ngps_week = 2381\ntime_s = 1000\nposition_deg_m = [30, 114, 0]\nspeed = 3\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "sim",
            p.to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml:6") && err.contains("speed"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
