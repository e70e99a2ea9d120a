//! Noise identification (`[tuning]`, `navfuse tune`; docs/ALGORITHMS.md "Noise
//! identification") on the shipped demo with every noise key left at its default: the
//! files it writes, the likelihood it climbs, the consistency it reaches, the tuned
//! configuration repeating the run, and the report's section. The accuracy against
//! hand-tuned runs over simulated cars, the stand-in and the real drive is `navfuse
//! bench --tune` (RESULTS.md §22).

mod common;
use common::{navfuse_ok, repo, tmp};

/// The demo's configuration with every noise key removed (files, frames, lever arm,
/// rates, alignment and time offset kept) and `extra` appended.
fn untuned_demo(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    let demo = repo().join("examples/demo");
    let text = std::fs::read_to_string(demo.join("drive_excerpt.toml")).unwrap();
    let mut out = String::new();
    let mut section = String::new();
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            section = t.to_string();
        }
        let key = t.split('=').next().unwrap_or("").trim();
        let noise = section == "[imu_noise]"
            || (section == "[gnss]"
                && [
                    "position_std_scale",
                    "velocity_std_scale",
                    "error_corr_time_s",
                    "error_corr_fraction",
                ]
                .contains(&key))
            || (section == "[initial]" && key.ends_with("_std_degph"))
            || (section == "[initial]" && key.ends_with("_std_mgal"));
        if noise && !t.starts_with('[') {
            continue;
        }
        let line = line.replace("file = \"", &format!("file = \"{}/", demo.display()));
        out.push_str(&line);
        out.push('\n');
    }
    out.push_str(extra);
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("untuned.toml");
    std::fs::write(&p, out).unwrap();
    p
}

fn json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn tuning_section_estimates_the_noise_model_and_runs_with_it() {
    let dir = tmp("tuning-demo");
    let cfg = untuned_demo(&dir, "\n[tuning]\niterations = 6\n");
    let out = dir.join("out");
    navfuse_ok(&[
        "run",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    for f in [
        "tuned.toml",
        "tuning.json",
        "tuning.txt",
        "solution.nav",
        "summary.json",
    ] {
        assert!(out.join(f).is_file(), "{f} not written");
    }
    let t = json(&out.join("tuning.json"));
    let passes = t["iterations"].as_array().unwrap();
    assert!(passes.len() >= 2, "{t}");
    let ll = |v: &serde_json::Value| v["log_likelihood"].as_f64().unwrap();
    let first = ll(&passes[0]);
    let tuned = ll(&t["tuned"]);
    eprintln!(
        "log-likelihood first pass {first:.1}, tuned {tuned:.1}; {} forward runs in {:.2} s",
        t["forward_runs"], t["wall_s"]
    );
    assert!(
        tuned > first + 100.0,
        "the likelihood did not climb: {first} -> {tuned}"
    );
    // The defaults were overconfident (NIS per row ~10 on the demo); tuned, each
    // source's NIS per row is within [0.7, 1.5].
    let s = json(&out.join("summary.json"));
    assert_eq!(s["status"], "completed", "{s}");
    for (src, nis) in t["tuned"]["nis_per_row"].as_object().unwrap() {
        let nis = nis.as_f64().unwrap();
        eprintln!("{src}: NIS per row {nis:.2}");
        assert!((0.7..=1.5).contains(&nis), "{src}: NIS per row {nis}");
    }
    // Every estimate has a value and the sample count it rests on.
    let est = t["estimates"].as_array().unwrap();
    assert!(est
        .iter()
        .any(|e| e["key"].as_str().unwrap().starts_with("imu_noise.arw")));
    assert!(est
        .iter()
        .all(|e| e["value"].as_f64().is_some_and(|v| v > 0.0)));
    // tuned.toml repeats the run bit for bit (without tuning again).
    let again = dir.join("again");
    navfuse_ok(&[
        "run",
        out.join("tuned.toml").to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
        "-q",
    ]);
    assert!(!again.join("tuning.json").exists());
    assert_eq!(
        std::fs::read(out.join("solution.nav")).unwrap(),
        std::fs::read(again.join("solution.nav")).unwrap()
    );
    // The difference from the input names what changed.
    let txt = std::fs::read_to_string(out.join("tuning.txt")).unwrap();
    assert!(
        txt.contains("[imu_noise]") && txt.contains("+ arw_deg_sqrth"),
        "{txt}"
    );
    // The report's Tuning section.
    navfuse_ok(&["report", out.to_str().unwrap()]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("<section id=\"tuning\">") && html.contains("fig-tuning_likelihood"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tuning_section_errors_name_the_key() {
    let dir = tmp("tuning-bad");
    let cfg = untuned_demo(&dir, "\n[tuning]\niterations = 0\n");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "run",
            cfg.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("tuning.iterations") && err.contains("1 to 100"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
