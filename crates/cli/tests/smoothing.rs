//! Issue 17: the smoother (docs/ALGORITHMS.md "Smoothing"). RTS over the forward
//! filter: outages pinned at both ends (KF-GINS stand-in, the real drive), never
//! worse than forward with all GNSS, consistent (NEES over 20 seeds, std never above
//! the forward filter's), tight coupling, and spoofed epochs kept out.

mod common;

use common::{
    eval_json, nees, nees_band as band, num as f, read_std, repo, run_with, shared, simulate_seed,
    tmp,
};
use navfuse_io::config;
use serde_json::Value;
use std::path::Path;

/// A config file `dir/NAME.toml` from `cfg` with the output at `rate_hz`.
fn write_cfg(
    mut cfg: config::RunConfig,
    rate_hz: f64,
    dir: &Path,
    name: &str,
) -> std::path::PathBuf {
    cfg.output.rate_hz = Some(rate_hz);
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, cfg.to_toml_string()).unwrap();
    p
}

/// KF-GINS stand-in, 60 s outages every 180 s from 456900 (15 outages): the RMS of
/// the per-outage maximum horizontal error smoothed is at most 0.25x the forward
/// filter's; with all GNSS the smoothed solution is not worse anywhere.
#[test]
fn kfgins_standin_outages_pinned_at_both_ends() {
    let Some(data) = shared() else { return };
    let syn = data.join("kf-gins/synthetic");
    let base = tmp("smooth-kfgins");
    let cfg = config::load_kfgins_yaml(&syn.join("kf-gins.yaml")).unwrap();
    let toml = write_cfg(cfg, 10.0, &base, "run");
    let truth = syn.join("truth.nav");
    let gaps = "60/180@456900..459500";
    let out = base.join("gaps");
    run_with(&toml, &out, &["--outages", gaps, "--smooth"]);
    let fwd = eval_json(&out.join("solution.nav"), &truth, &["--gaps", gaps]);
    let sm = eval_json(&out.join("smoothed.nav"), &truth, &["--gaps", gaps]);
    let (hf, hs) = (
        f(&fwd, &["gap_max_rms", "horizontal_m"]),
        f(&sm, &["gap_max_rms", "horizontal_m"]),
    );
    eprintln!(
        "outages: RMS of per-outage horizontal maxima forward {hf:.4} m, smoothed {hs:.4} m ({:.3}x)",
        hs / hf
    );
    assert!(hs <= 0.25 * hf, "smoothed {hs} vs forward {hf}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["smoother"]["mode"], "rts");
    assert!(f(&summary, &["smoother", "epochs"]) > 30000.0);
    let _ = std::fs::remove_dir_all(&out);
    // Mode "combined" (an independent backward filter, weighted state by state).
    let out = base.join("combined");
    run_with(
        &toml,
        &out,
        &["--outages", gaps, "--smooth-mode", "combined"],
    );
    let hc = f(
        &eval_json(&out.join("smoothed.nav"), &truth, &["--gaps", gaps]),
        &["gap_max_rms", "horizontal_m"],
    );
    eprintln!("outages, combined: {hc:.4} m ({:.3}x)", hc / hf);
    assert!(hc <= 0.25 * hf, "combined {hc} vs forward {hf}");
    let _ = std::fs::remove_dir_all(&out);
    // All GNSS.
    let out = base.join("all");
    run_with(&toml, &out, &["--smooth"]);
    let fwd = eval_json(&out.join("solution.nav"), &truth, &[]);
    let sm = eval_json(&out.join("smoothed.nav"), &truth, &[]);
    for path in [
        ["position_m", "horizontal", "rms"],
        ["position_m", "vertical", "rms"],
        ["attitude_deg", "roll", "rms"],
        ["attitude_deg", "pitch", "rms"],
        ["attitude_deg", "yaw", "rms"],
    ] {
        let (a, b) = (f(&fwd, &path), f(&sm, &path));
        eprintln!("all GNSS {path:?}: forward {a:.5}, smoothed {b:.5}");
        assert!(b <= a, "{path:?}: smoothed {b} > forward {a}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// The real drive, 30 s outages every 90 s after the first 120 s, with NHC: the
/// smoothed RMS of per-outage maxima is at most 0.35x the forward figure.
#[test]
fn drive_outages_with_nhc() {
    let Some(data) = shared() else { return };
    let pos = data.join("rtklibexplorer/drive_0708/gnss_1934_sf.pos");
    let out = tmp("smooth-drive");
    let gaps = "30/90@243381.854";
    run_with(
        &repo().join("examples/drive_0708_nhc.toml"),
        &out,
        &["--outages", gaps, "--smooth"],
    );
    let ex = ["--lever-arm", "0,-0.05,0", "--gaps", gaps];
    let fwd = eval_json(&out.join("solution.nav"), &pos, &ex);
    let sm = eval_json(&out.join("smoothed.nav"), &pos, &ex);
    let (hf, hs) = (
        f(&fwd, &["gap_max_rms", "horizontal_m"]),
        f(&sm, &["gap_max_rms", "horizontal_m"]),
    );
    eprintln!(
        "drive: forward {hf:.2} m, smoothed {hs:.2} m ({:.3}x)",
        hs / hf
    );
    assert!(hs <= 0.35 * hf, "smoothed {hs} vs forward {hf}");
    let out_c = tmp("smooth-drive-combined");
    run_with(
        &repo().join("examples/drive_0708_nhc.toml"),
        &out_c,
        &["--outages", gaps, "--smooth-mode", "combined"],
    );
    let hc = f(
        &eval_json(&out_c.join("smoothed.nav"), &pos, &ex),
        &["gap_max_rms", "horizontal_m"],
    );
    eprintln!("drive, combined: {hc:.2} m ({:.3}x)", hc / hf);
    assert!(hc <= 0.35 * hf, "combined {hc} vs forward {hf}");
    let _ = std::fs::remove_dir_all(&out_c);
    // The extra states (mounting, fix errors) are smoothed too.
    let states = std::fs::read_to_string(out.join("smoothed_states.csv")).unwrap();
    assert!(states
        .lines()
        .next()
        .unwrap()
        .contains("mounting_pitch_rad"));
    assert!(out.join("separation.csv").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

/// 20 seeds of scenarios/consistency_car.toml (Gauss-Markov fix errors, their
/// states in the filter) with 40 s outages every 150 s: the smoothed position and
/// velocity NEES averaged over the runs are inside the 95 % band, the attitude's not
/// above it, and no smoothed standard deviation is above the forward one.
#[test]
fn smoothed_nees_consistent_and_std_never_larger() {
    const RUNS: usize = 20;
    let base = tmp("smooth-consistency");
    let scen = repo().join("scenarios/consistency_car.toml");
    let mut sums: Vec<[f64; 3]> = Vec::new();
    let mut fwd_sums: Vec<[f64; 3]> = Vec::new();
    let mut worst_ratio: f64 = 0.0;
    let mut compared = 0usize;
    for seed in 1..=RUNS {
        let dir = base.join(format!("seed{seed}"));
        simulate_seed(&scen, &dir, Some(seed as u64));
        let mut cfg = config::load(&dir.join("run.toml")).unwrap();
        assert!(cfg.nav.gnss.fix_error.correlated());
        // As tests/consistency.rs: the IMU bias model at the grade's own 100 s.
        cfg.nav.imu_noise.corr_time_s = 100.0;
        cfg.output.std = true;
        let toml = write_cfg(cfg, 1.0, &dir, "run_smooth");
        let out = dir.join("out");
        run_with(&toml, &out, &["--outages", "40/150@345720", "--smooth"]);
        let truth = dir.join("truth.nav");
        // A consistent filter: the separation report raises no warning.
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        assert!(
            !summary.contains("smoothing:"),
            "seed {seed}: a separation warning"
        );
        for (acc, e) in [
            (
                &mut sums,
                nees(
                    &truth,
                    &out.join("smoothed.nav"),
                    &out.join("smoothed_std.txt"),
                ),
            ),
            (
                &mut fwd_sums,
                nees(&truth, &out.join("solution.nav"), &out.join("std.txt")),
            ),
        ] {
            if acc.is_empty() {
                acc.resize(e.len(), [0.0; 3]);
            }
            let n = acc.len().min(e.len());
            acc.truncate(n);
            for (a, x) in acc.iter_mut().zip(&e) {
                for k in 0..3 {
                    a[k] += x[k];
                }
            }
        }
        // Every smoothed standard deviation (all 21 states) at most the forward one
        // (up to the files' printed precision).
        let (sf, ss) = (
            read_std(&out.join("std.txt")),
            read_std(&out.join("smoothed_std.txt")),
        );
        assert_eq!(sf.len(), ss.len());
        for (t, f) in &sf {
            for (a, b) in f.iter().zip(&ss[t]) {
                compared += 1;
                if *a > 0.0 {
                    worst_ratio = worst_ratio.max(b / a);
                }
                assert!(
                    *b <= a * (1.0 + 1e-6) + 1e-9,
                    "t {t}: smoothed std {b} > forward {a}"
                );
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    let (lo, hi) = band(RUNS);
    let mean = |s: &[[f64; 3]], k: usize| {
        s.iter().map(|a| a[k] / RUNS as f64).sum::<f64>() / s.len() as f64
    };
    let names = ["position", "velocity", "attitude"];
    for (k, name) in names.iter().enumerate() {
        eprintln!(
            "{}: NEES forward {:.2}, smoothed {:.2} (band [{lo:.2}, {hi:.2}])",
            name,
            mean(&fwd_sums, k),
            mean(&sums, k)
        );
    }
    eprintln!("{compared} standard deviations compared, largest smoothed/forward {worst_ratio:.4}");
    let (pos, vel, att) = (mean(&sums, 0), mean(&sums, 1), mean(&sums, 2));
    assert!(pos > lo && pos < hi, "smoothed position NEES {pos}");
    assert!(vel > lo && vel < hi, "smoothed velocity NEES {vel}");
    assert!(att < hi, "smoothed attitude NEES {att}");
    let _ = std::fs::remove_dir_all(&base);
}

/// Smoothed against forward mean 3D error: tight coupling on the blockage scenario
/// (60 s with 2 satellites) and on seed 000's UAV.
#[test]
fn tight_coupling_smoothed() {
    let base = tmp("smooth-tight");
    for (sc, limit) in [("blockage_2sat", 1.0), ("seed000_uav", 1.0)] {
        let dir = base.join(sc);
        simulate_seed(&repo().join(format!("scenarios/{sc}.toml")), &dir, None);
        let out = dir.join("out");
        run_with(&dir.join("run.toml"), &out, &["--smooth"]);
        let truth = dir.join("truth.nav");
        let fwd = f(
            &eval_json(&out.join("solution.nav"), &truth, &[]),
            &["position_m", "3d", "mean"],
        );
        let sm = f(
            &eval_json(&out.join("smoothed.nav"), &truth, &[]),
            &["position_m", "3d", "mean"],
        );
        eprintln!("{sc}: mean 3D error forward {fwd:.3} m, smoothed {sm:.3} m");
        assert!(sm <= limit * fwd, "{sc}: smoothed {sm} vs forward {fwd}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// Seed 004's drift attack with the monitor: the spoofed epochs stay out of the
/// smoothed solution (its error over the attack stays at the dead-reckoning level
/// or better, far from the 600 m the attacker drags the fixes).
#[test]
fn spoofed_epochs_are_not_pulled_back_in() {
    let dir = tmp("smooth-spoof");
    simulate_seed(&repo().join("scenarios/seed004_attack.toml"), &dir, None);
    let text = std::fs::read_to_string(dir.join("run.toml")).unwrap() + "\n[spoofing]\n";
    std::fs::write(dir.join("run_mon.toml"), text).unwrap();
    let out = dir.join("out");
    run_with(&dir.join("run_mon.toml"), &out, &["--smooth"]);
    let truth = dir.join("truth.nav");
    let w = ["--window", "345750:346050"];
    let fwd = f(
        &eval_json(&out.join("solution.nav"), &truth, &w),
        &["position_m", "horizontal", "max"],
    );
    let sm = f(
        &eval_json(&out.join("smoothed.nav"), &truth, &w),
        &["position_m", "horizontal", "max"],
    );
    eprintln!("attack window: horizontal max forward {fwd:.2} m, smoothed {sm:.2} m");
    assert!(sm <= fwd && sm < 5.0, "smoothed {sm} vs forward {fwd}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Smoothing a six-state run is refused before anything is read, naming the keys.
#[test]
fn six_state_fusion_is_refused_before_the_run() {
    let dir = tmp("smooth-six");
    std::fs::create_dir_all(&dir).unwrap();
    let demo = repo().join("examples/demo");
    let text = std::fs::read_to_string(demo.join("drive_excerpt.toml"))
        .unwrap()
        .replace(
            "use_velocity = true",
            "use_velocity = true\nfusion = \"six_state\"",
        );
    let cfg = demo.join(format!("_six_{}.toml", std::process::id()));
    std::fs::write(&cfg, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "run",
            cfg.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "-q",
            "--smooth",
        ])
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&cfg);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("six_state") && err.contains("--smooth"),
        "{err}"
    );
    assert!(!dir.join("out/solution.nav").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
