//! Issue 30 part D: opt-in adaptive measurement noise (`[filter] adaptive_noise`).
//! The simulated car of seed 001 (scenarios/seed001_car.toml, ADIS16405, 1 Hz fixes
//! with 1.5 / 3 m Gauss-Markov errors, dual-antenna heading) over three seeds, with
//! the fixes' position std configured 4x too small (`position_std_scale = 0.25`):
//! the adaptive run's horizontal RMS is no worse than the non-adaptive run's and its
//! GNSS position NIS per row is much closer to 1; with the configured std right, the
//! adaptive run is within 6 % of the non-adaptive one. The adapted scales go to
//! summary.json (`adaptive_noise`). Figures: docs/RESULTS.md §21.

mod common;

use common::{eval_json, repo, run, simulate_seed, tmp};
use navfuse_core::aiding::adaptive::AdaptiveNoiseOptions;
use navfuse_io::config;
use std::path::Path;

struct Outcome {
    horizontal_rms_m: f64,
    nis_per_row: f64,
    scale: Option<f64>,
}

fn navigate(dir: &Path, name: &str, std_scale: f64, adaptive: bool) -> Outcome {
    let mut cfg = config::load(&dir.join("run.toml")).unwrap();
    cfg.nav.gnss.position_std_scale = std_scale;
    cfg.nav.filter.adaptive_noise = adaptive.then(AdaptiveNoiseOptions::default);
    let toml = dir.join(format!("{name}.toml"));
    std::fs::write(&toml, cfg.to_toml_string()).unwrap();
    // The written configuration reads back the same (the new keys round-trip).
    let back = config::load(&toml).unwrap();
    assert_eq!(
        back.nav.filter.adaptive_noise,
        cfg.nav.filter.adaptive_noise
    );
    let out = dir.join(name);
    run(&toml, &out);
    let e = eval_json(&out.join("solution.nav"), &dir.join("truth.nav"), &[]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["adaptive_noise"].is_null(), !adaptive);
    Outcome {
        horizontal_rms_m: e["position_m"]["horizontal"]["rms"].as_f64().unwrap(),
        nis_per_row: s["nis_per_row"]["gnss_position"].as_f64().unwrap(),
        scale: s["adaptive_noise"]["gnss_position"]["scale"].as_f64(),
    }
}

#[test]
fn adaptive_noise_corrects_a_too_small_fix_std() {
    let base = tmp("adaptive-noise");
    let scenario = repo().join("scenarios/seed001_car.toml");
    for seed in 1..=3u64 {
        let dir = base.join(format!("seed{seed}"));
        simulate_seed(&scenario, &dir, Some(seed));
        let off = navigate(&dir, "small", 0.25, false);
        let on = navigate(&dir, "small_adaptive", 0.25, true);
        let right = navigate(&dir, "right", 1.0, false);
        let right_on = navigate(&dir, "right_adaptive", 1.0, true);
        eprintln!(
            "seed {seed}: std 4x too small: horizontal RMS {:.3} m -> {:.3} m adaptive, NIS/row {:.2} -> {:.2} (scale {:.1}); right std: {:.3} m -> {:.3} m adaptive",
            off.horizontal_rms_m,
            on.horizontal_rms_m,
            off.nis_per_row,
            on.nis_per_row,
            on.scale.unwrap(),
            right.horizontal_rms_m,
            right_on.horizontal_rms_m
        );
        assert!(
            on.horizontal_rms_m <= off.horizontal_rms_m,
            "seed {seed}: adaptive {} m against {} m",
            on.horizontal_rms_m,
            off.horizontal_rms_m
        );
        assert!(off.nis_per_row > 3.0, "seed {seed}: the mistake shows");
        assert!(
            on.nis_per_row.ln().abs() < 0.25 * off.nis_per_row.ln().abs(),
            "seed {seed}: NIS per row {} against {}",
            on.nis_per_row,
            off.nis_per_row
        );
        // The variance scale is at least the 16 of the mistake.
        assert!(on.scale.unwrap() > 16.0, "seed {seed}");
        let ratio = right_on.horizontal_rms_m / right.horizontal_rms_m;
        assert!(
            (ratio - 1.0).abs() < 0.06,
            "seed {seed}: right std, ratio {ratio}"
        );
    }
}

/// The keys are checked: a window <= 0, iterations outside 1..=50 and the adaptive
/// keys without `adaptive_noise = true` are errors that name the key.
#[test]
fn adaptive_keys_are_checked() {
    let dir = tmp("adaptive-keys");
    std::fs::create_dir_all(&dir).unwrap();
    let demo = std::fs::read_to_string(repo().join("examples/demo/drive_excerpt.toml")).unwrap();
    let demo = demo.replace(
        "file = \"",
        &format!("file = \"{}/", repo().join("examples/demo").display()),
    );
    for (extra, key) in [
        (
            "adaptive_noise = true\nadaptive_window_s = 0",
            "filter.adaptive_window_s",
        ),
        (
            "adaptive_noise = true\nadaptive_iterations = 0",
            "filter.adaptive_iterations",
        ),
        ("adaptive_window_s = 30", "filter.adaptive_window_s"),
        (
            "adaptive_noise = false\nadaptive_sources = [\"nhc\"]",
            "filter.adaptive_sources",
        ),
    ] {
        let text = if demo.contains("[filter]") {
            demo.replacen("[filter]", &format!("[filter]\n{extra}"), 1)
        } else {
            format!("{demo}\n[filter]\n{extra}\n")
        };
        let p = dir.join("bad.toml");
        std::fs::write(&p, text).unwrap();
        let err = config::load(&p).unwrap_err().to_string();
        assert!(err.contains(key), "{extra}: {err}");
    }
}
