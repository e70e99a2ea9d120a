//! Issue 18 (eval): on seed 000's UAV (pitch through the vertical) the attitude
//! error is the rotation between the attitudes, so there is no 156 deg artefact of
//! Euler-angle differences; the percentiles equal numpy's on the per-epoch file
//! (`method="inverted_cdf"`, nearest rank) when python3 with numpy is installed.

mod common;

use common::{navfuse_ok, sim_and_run};
use std::process::Command;

#[test]
fn seed000_uav_attitude_and_percentiles_against_numpy() {
    let (dir, sim, out) = sim_and_run("eval-uav", "scenarios/seed000_uav.toml", &[]);
    let errors = dir.join("errors.csv");
    let j = navfuse_ok(&[
        "eval",
        out.join("solution.nav").to_str().unwrap(),
        sim.join("truth.nav").to_str().unwrap(),
        "--errors",
        errors.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&j).unwrap();
    // The truth pitches through +-90 deg: Euler differences gave 156 deg there.
    let truth = std::fs::read_to_string(sim.join("truth.nav")).unwrap();
    let max_pitch = truth
        .lines()
        .filter_map(|l| l.split_whitespace().nth(9)?.parse::<f64>().ok())
        .fold(0.0f64, |m, p| m.max(p.abs()));
    assert!(
        max_pitch > 80.0,
        "the scenario's largest pitch is {max_pitch} deg"
    );
    for axis in ["roll", "pitch", "yaw", "total"] {
        let m = v["attitude_deg"][axis]["max"].as_f64().unwrap();
        assert!(m < 1.0, "attitude {axis} max {m} deg");
    }
    let python = Command::new("python3")
        .args([
            "-c",
            "import sys, numpy as np\n\
             d = np.genfromtxt(sys.argv[1], delimiter=',', names=True)\n\
             h = d['horizontal_m']\n\
             t = np.sqrt(d['d_north_m']**2 + d['d_east_m']**2 + d['d_down_m']**2)\n\
             q = [50, 68, 95, 99]\n\
             print(' '.join('%.9f' % x for x in np.percentile(h, q, method='inverted_cdf')))\n\
             print(' '.join('%.9f' % x for x in np.percentile(t, q, method='inverted_cdf')))\n\
             print(len(h))",
        ])
        .arg(&errors)
        .output();
    let out = match python {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).into_owned(),
        Ok(o) => {
            eprintln!(
                "skipped: the numpy comparison (python3 with numpy: {})",
                String::from_utf8_lossy(&o.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            );
            return;
        }
        Err(e) => {
            eprintln!("skipped: the numpy comparison (no python3: {e})");
            return;
        }
    };
    let lines: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(lines[2][0] as u64, v["epochs"].as_u64().unwrap());
    for (row, key) in [(0, "horizontal"), (1, "3d")] {
        for (k, p) in ["p50", "p68", "p95", "p99"].iter().enumerate() {
            let ours = v["percentiles_m"][key][p].as_f64().unwrap();
            let numpy = lines[row][k];
            // The file has 6 decimals (the 3D error is recomputed from three of them).
            assert!(
                (ours - numpy).abs() <= 2e-6,
                "{key} {p}: navfuse {ours} numpy {numpy}"
            );
            eprintln!("{key} {p}: navfuse {ours:.6} numpy {numpy:.6}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
