//! Seed 004's six-state fusion of GNSS with the INS/odometer output (SYSTEM.md §5;
//! seed 004 §3; `[gnss] fusion = "six_state"`) on the simulated 3010 m loop with
//! clean GNSS: the error-state filter dead-reckons (IMU500 + odometer + NHC) and a
//! 6-state KF X = [r^n, v^n], H = I_6 takes the fixes.
//!
//! Bounds from the fixes' error model (scenarios/seed004_loop.toml: 1.5 m per
//! horizontal axis, 3 m vertical, 1-sigma): a fusion must beat the fixes alone, so
//! its RMSE is below sigma_3D = sqrt(1.5² + 1.5² + 3²) = 3.67 m, sigma_H = 2.12 m and
//! sigma_V = 3 m; and it must be clearly better (at least 2x) than the dead
//! reckoning alone. The error-state loose run is printed beside it.

mod common;

use common::{navfuse_ok, repo, run, simulate, tmp};
use serde_json::Value;
use std::path::Path;

const SIGMA_H_AXIS_M: f64 = 1.5;
const SIGMA_V_M: f64 = 3.0;

/// Position RMSE (3D, horizontal, vertical) [m] of a solution against the truth.
fn rmse(solution: &Path, truth: &Path) -> [f64; 3] {
    let out = navfuse_ok(&[
        "eval",
        solution.to_str().unwrap(),
        truth.to_str().unwrap(),
        "--json",
    ]);
    let v: Value = serde_json::from_str(&out).expect("eval --json");
    let p = &v["position_m"];
    ["3d", "horizontal", "vertical"].map(|k| p[k]["rms"].as_f64().expect("rms"))
}

/// seed004_loop.toml without its spoofing event, simulated into `dir/sim`.
fn simulate_clean_loop(dir: &Path) -> std::path::PathBuf {
    let base = std::fs::read_to_string(repo().join("scenarios/seed004_loop.toml")).unwrap();
    let a = base
        .find("[[gnss.event]]")
        .expect("the scenario has a gnss event");
    let b = a + base[a..]
        .find("\n\n")
        .expect("a blank line after the event");
    let text = format!("{}{}", &base[..a], &base[b + 2..]);
    assert!(!text.contains("[[gnss.event]]"));
    std::fs::create_dir_all(dir).unwrap();
    let sc = dir.join("scenario.toml");
    std::fs::write(&sc, text).unwrap();
    let sim = dir.join("sim");
    simulate(&sc, &sim);
    sim
}

/// Run `config` (written into `sim` as `name.toml`), return the output directory.
fn run_variant(sim: &Path, name: &str, config: &str) -> std::path::PathBuf {
    let cfg = sim.join(format!("{name}.toml"));
    std::fs::write(&cfg, config).unwrap();
    let out = sim.join(format!("out_{name}"));
    run(&cfg, &out);
    out
}

#[test]
fn six_state_fusion_on_the_clean_seed004_loop() {
    let dir = tmp("six_state");
    let sim = simulate_clean_loop(&dir);
    let truth = sim.join("truth.nav");
    // Seed 004's INS/odometer navigator with the NHC (as in tests/spoofing.rs).
    let base =
        std::fs::read_to_string(sim.join("run.toml")).unwrap() + "\n[nhc]\nmode = \"always\"\n";
    assert!(base.contains("[gnss]\n"));
    let six = base.replace("[gnss]\n", "[gnss]\nfusion = \"six_state\"\n");
    let six5 = base.replace(
        "[gnss]\n",
        "[gnss]\nfusion = \"six_state\"\nsix_state_every = 5\n",
    );
    // Dead reckoning alone: no [gnss] section (the initial position is given).
    let g = base.find("[gnss]\n").unwrap();
    let g_end = g + 1 + base[g + 1..].find("\n[").unwrap();
    let dr = format!("{}{}", &base[..g], &base[g_end + 1..]);

    let loose = rmse(
        &run_variant(&sim, "loose", &base).join("solution.nav"),
        &truth,
    );
    let out_six = run_variant(&sim, "six", &six);
    let six_rmse = rmse(&out_six.join("solution.nav"), &truth);
    let out_six5 = run_variant(&sim, "six5", &six5);
    let six5_rmse = rmse(&out_six5.join("solution.nav"), &truth);
    let dr_rmse = rmse(&run_variant(&sim, "dr", &dr).join("solution.nav"), &truth);
    for (name, r) in [
        ("six-state (every fix)", six_rmse),
        ("six-state (every 5th fix)", six5_rmse),
        ("error-state loose", loose),
        ("dead reckoning only", dr_rmse),
    ] {
        eprintln!(
            "seed004 clean loop, {name}: position RMSE 3D {:.3} m, horizontal {:.3} m, vertical {:.3} m",
            r[0], r[1], r[2]
        );
    }

    let sigma_h = SIGMA_H_AXIS_M * 2f64.sqrt();
    let sigma_3d = sigma_h.hypot(SIGMA_V_M);
    for (name, r) in [("every fix", six_rmse), ("every 5th fix", six5_rmse)] {
        assert!(r[0] < sigma_3d, "six-state, {name}: 3D RMSE {} m", r[0]);
        assert!(
            r[1] < sigma_h,
            "six-state, {name}: horizontal RMSE {} m",
            r[1]
        );
        assert!(
            r[2] < SIGMA_V_M,
            "six-state, {name}: vertical RMSE {} m",
            r[2]
        );
        assert!(
            r[0] < dr_rmse[0] / 2.0,
            "six-state, {name}: 3D RMSE {} m vs dead reckoning {} m",
            r[0],
            dr_rmse[0]
        );
    }

    // Every fix used once (the fix that gave the start is not), or every 5th.
    let used = |out: &Path| -> (u64, u64) {
        let s: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let g = &s["gnss"];
        (
            g["used"].as_u64().unwrap(),
            g["fixes"].as_u64().unwrap() - g["before_start"].as_u64().unwrap(),
        )
    };
    let (u1, n1) = used(&out_six);
    assert_eq!(u1, n1, "every fix");
    let (u5, n5) = used(&out_six5);
    assert_eq!(u5, n5.div_ceil(5), "every 5th fix");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad values name the key and what was expected; six_state with tight coupling is
/// refused at load time.
#[test]
fn six_state_config_errors() {
    let dir = tmp("six_state_cfg");
    std::fs::create_dir_all(&dir).unwrap();
    let base = "[imu]\nfile = \"imu.txt\"\nformat = \"kf-gins\"\nrate_hz = 100\n\n\
                [gnss]\nfile = \"gnss.txt\"\nGNSS\n\n\
                [initial]\nposition_deg_m = [21, 105, 15]\nattitude_deg = [0, 0, 0]\n\
                position_std_m = 1\nvelocity_std_mps = 0.1\nattitude_std_deg = 1\n\n\
                [imu_noise]\narw_deg_sqrth = 0.01\nvrw_mps_sqrth = 0.01\ngyro_bias_std_degph = 1\n\
                accel_bias_std_mgal = 100\ngyro_scale_std_ppm = 100\naccel_scale_std_ppm = 100\n\
                corr_time_h = 1\n";
    for (k, (gnss, expect)) in [
        (
            "format = \"kf-gins\"\nfusion = \"six_state\"\nsix_state_every = 0",
            "key 'gnss.six_state_every': expected a whole number of GNSS epochs >= 1",
        ),
        (
            "format = \"kf-gins\"\nfusion = \"six_state\"\nsix_state_every = 2.5",
            "key 'gnss.six_state_every': expected a whole number of GNSS epochs >= 1",
        ),
        (
            "format = \"kf-gins\"\nsix_state_every = 2",
            "key 'gnss.six_state_every': applies only to gnss.fusion = \"six_state\"",
        ),
        (
            "format = \"kf-gins\"\nfusion = \"six-state\"",
            "key 'gnss.fusion': unknown variant `six-state`, expected `error_state` or `six_state`",
        ),
        (
            "format = \"rinex\"\nnav = \"nav.rnx\"\nfusion = \"six_state\"",
            "key 'gnss.fusion': \"six_state\" fuses GNSS fixes (loose coupling) only",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let cfg = dir.join(format!("bad{k}.toml"));
        std::fs::write(&cfg, base.replace("GNSS", gnss)).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_navfuse"))
            .args(["run", cfg.to_str().unwrap(), "--out"])
            .arg(dir.join("out"))
            .output()
            .expect("run navfuse");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{gnss}: accepted");
        assert!(err.contains(expect), "{gnss}: {err}");
        assert!(!err.contains("panicked"), "{gnss}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
