//! Issue 30 part E: GNSS-IMU time-offset estimation that converges and is never worse
//! than none. scenarios/time_offset_car.toml (15 min car, ADIS16405, odometer, receiver
//! fixes and raw GPS) simulated with the IMU clock `tau` ahead of GPS time ([gnss]
//! time_offset_s), navigated loosely (fixes) and tightly (raw, pseudorange + TDCP),
//! with the INS alone and with odometer + NHC, estimating the offset from the default
//! prior (0 +- 0.5 s): the estimate within 5 ms of tau (with no offset: the initial 0
//! kept, or within 2 sigma), the horizontal RMS within 10 % of the run given the true
//! offset. The full table (3 seeds, offsets -1 to +1 s) is RESULTS.md §18.

mod common;

use common::{eval_json, num, repo, run, simulate_seed, tmp};
use navfuse_core::config::{NhcMode, TimeOffsetConfig};
use navfuse_io::config;
use std::path::Path;

/// The scenario with offset `tau`; `tight`: without receiver fixes (the simulator's
/// run.toml then couples tightly on the raw observations).
fn scenario(dir: &Path, tau: f64, tight: bool) -> std::path::PathBuf {
    let text = std::fs::read_to_string(repo().join("scenarios/time_offset_car.toml")).unwrap();
    assert!(text.contains("time_offset_s = 0.5\n"));
    let mut text = text.replace("time_offset_s = 0.5\n", &format!("time_offset_s = {tau}\n"));
    if tight {
        let a = text.find("[gnss.fix]").unwrap();
        let b = a + text[a..].find("\n\n").unwrap();
        text.replace_range(a..b, "");
    }
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(format!("scenario_{tau}_{tight}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// (horizontal RMS [m], summary.json) of the run of `dir`'s run.toml with `aid`
/// ("ins": no odometer; "odo_nhc": odometer + NHC) and the time offset `to`.
fn navigate(dir: &Path, aid: &str, to: TimeOffsetConfig, name: &str) -> (f64, serde_json::Value) {
    let mut cfg = config::load(&dir.join("run.toml")).unwrap();
    match aid {
        "ins" => {
            cfg.odometer = None;
            cfg.nav.odometer.enabled = false;
        }
        _ => cfg.nav.nhc.mode = NhcMode::Always,
    }
    cfg.nav.filter.time_offset = Some(to);
    cfg.output.rate_hz = Some(10.0);
    let toml = dir.join(format!("{name}.toml"));
    std::fs::write(&toml, cfg.to_toml_string()).unwrap();
    let out = dir.join(name);
    run(&toml, &out);
    let e = eval_json(&out.join("solution.nav"), &dir.join("truth.nav"), &[]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    (num(&e, &["position_m", "horizontal", "rms"]), s)
}

#[test]
fn time_offset_converges_loose_and_tight_with_and_without_vehicle_aiding() {
    let base = tmp("time-offset");
    for tight in [false, true] {
        for tau in [-1.0, 0.0, 0.5] {
            let dir = base.join(format!(
                "tau{tau}_{}",
                if tight { "tight" } else { "loose" }
            ));
            simulate_seed(&scenario(&base, tau, tight), &dir, Some(1));
            for aid in ["ins", "odo_nhc"] {
                let (rms, s) = navigate(&dir, aid, TimeOffsetConfig::default(), "est");
                let known = TimeOffsetConfig {
                    initial_s: tau,
                    std_s: 0.0,
                    ..TimeOffsetConfig::default()
                };
                let (rms_true, _) = navigate(&dir, aid, known, "true");
                let t = &s["time_offset"];
                let est = num(t, &["offset_s_at_start"]);
                let sd = num(t, &["offset_sigma_s_at_end"]);
                let source = t["source"].as_str().unwrap();
                eprintln!(
                    "{} {aid} tau {tau:+.1}: estimate {est:+.4} s ({source}, 1-sigma {sd:.4}; search {}, pass {:+.4}), horizontal RMS {rms:.3} m, with the true offset {rms_true:.3} m",
                    if tight { "tight" } else { "loose" },
                    t["search_offset_s"],
                    num(t, &["pass_offset_s_at_start"]),
                );
                if tau == 0.0 {
                    assert!(
                        source == "initial" || est.abs() < 2.0 * sd,
                        "no offset: estimate {est} +- {sd} ({source})"
                    );
                } else {
                    assert!((est - tau).abs() < 0.005, "tau {tau}: estimate {est}");
                }
                assert!(
                    rms <= 1.1 * rms_true,
                    "tau {tau} {aid}: RMS {rms} against {rms_true} with the true offset"
                );
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    let _ = std::fs::remove_dir_all(&base);
}
