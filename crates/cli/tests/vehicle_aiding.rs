//! Issue 4 through the binary: installation calibration on a simulated drive, the
//! papers' experiments (`navfuse reproduce`), and NHC + in-motion alignment on the
//! real drive (needs ../shared/data; skipped with a printed reason when absent).

mod common;

use common::{navfuse_ok as navfuse, repo, shared, tmp};
use serde_json::Value;

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Mounting angles and odometer scale converge on a 20 min simulated drive (issue 4:
/// within 0.1 deg and 0.1 %). The run aligns itself; the mounting starts at zero.
#[test]
fn mounting_and_odometer_scale_converge_on_a_20_min_drive() {
    let sim = tmp("calib");
    let scen = repo().join("scenarios/calib_20min.toml");
    navfuse(&[
        "sim",
        scen.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
        "-q",
    ]);
    // The simulator's run.toml (odometer, vehicle lever arm, mounting estimated) with
    // the truth attitude removed, plus NHC and ZUPT.
    let text = std::fs::read_to_string(sim.join("run.toml")).unwrap();
    let mut cfg: String = text
        .lines()
        .filter(|l| !l.starts_with("attitude_deg") && !l.starts_with("attitude_std_deg"))
        .map(|l| format!("{l}\n"))
        .collect();
    cfg = cfg.replace("[initial]\n", "[initial]\nattitude_std_deg = [1, 1, 3]\n");
    cfg.push_str("\n[nhc]\nmode = \"always\"\nrate_hz = 2\n\n[zupt]\nenabled = true\n");
    std::fs::write(sim.join("calib.toml"), cfg).unwrap();
    let out = sim.join("out");
    navfuse(&[
        "run",
        sim.join("calib.toml").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let m = &s["mounting"];
    let (pitch, yaw) = (num(&m["pitch_deg"]), num(&m["yaw_deg"]));
    let k_ppm = num(&s["odometer_scale"]["k_ppm"]);
    eprintln!("mounting pitch {pitch:.3} yaw {yaw:.3} deg (true 0.5, -0.7); scale {k_ppm:.0} ppm (true 2000)");
    assert!((pitch - 0.5).abs() < 0.1, "mounting pitch {pitch}");
    assert!((yaw + 0.7).abs() < 0.1, "mounting yaw {yaw}");
    assert!(
        (k_ppm - 2000.0).abs() < 1000.0,
        "odometer scale {k_ppm} ppm"
    );
    // A static start: levelling, the yaw from the first motion (velocity matching or
    // the course).
    assert!(s["events"]
        .to_string()
        .contains("aligned (static levelling"));
    let _ = std::fs::remove_dir_all(&sim);
}

fn reproduce(id: &str, seeds: &str) -> Value {
    let out = navfuse(&["reproduce", id, "--seeds", seeds, "--json", "-q"]);
    serde_json::from_str(&out).expect("reproduce --json")
}

fn per_seed(r: &Value, variant: &str, metric: &str) -> Vec<f64> {
    let v = r["variants"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["name"] == variant)
        .unwrap_or_else(|| panic!("variant {variant}"));
    v["metrics"][metric]["per_seed"]
        .as_array()
        .unwrap()
        .iter()
        .map(num)
        .collect()
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// Seed 004: IMU500 + odometer without GNSS on the 3010 m loop: return-to-start error
/// at most 0.21 % of the distance (RMS over 4 seeds), within 5 m of the truth after
/// 6 min, while the INS alone is tens of metres off.
#[test]
fn seed004_ins_odometer_loop() {
    let r = reproduce("seed004", "4");
    let end = per_seed(&r, "ins_odo", "end_error_pct_distance");
    let rms = (end.iter().map(|x| x * x).sum::<f64>() / end.len() as f64).sqrt();
    eprintln!("seed004 end error % of distance per seed {end:?}, RMS {rms:.3}");
    assert!(rms <= 0.21, "return-to-start RMS {rms} %");
    for e in per_seed(&r, "ins_odo", "error_6min_m") {
        assert!(e < 5.0, "INS/odometer after 6 min: {e} m");
    }
    for e in per_seed(&r, "ins", "error_6min_m") {
        assert!(e > 10.0, "INS alone after 6 min only {e} m off");
    }
}

/// Improvement of the mean over seeds, (base - variant) / base (seed 002 eq. 18).
fn improvement(r: &Value, metric: &str, base: &str, variant: &str) -> f64 {
    let b = mean(&per_seed(r, base, metric));
    let v = mean(&per_seed(r, variant, metric));
    (b - v) / b
}

/// Seed 002: NHC with 30 s and 60 s GNSS outages lowers the 3D position RMSE by at
/// least the paper's 38 % (mean over seeds), with GNSS velocity and with GNSS position
/// only (the paper's setting); the attitude figure is reported, not asserted at the
/// paper's 62 % (30 seeds: 43.8 % and 48.6 %; 60.1 % with the IMU mounting known,
/// docs/RESULTS.md §19). The known mounting must help the attitude: it is our
/// explanation of the gap.
#[test]
fn seed002_nhc_improves_position_and_attitude() {
    let r = reproduce("seed002", "2");
    for (base, nhc) in [("loose", "nhc"), ("loose_pos", "nhc_pos")] {
        let p = improvement(&r, "rmse_3d_m", base, nhc);
        let a = improvement(&r, "rmse_att3d_deg", base, nhc);
        eprintln!("seed002 {base} -> {nhc}: 3D {p:.3}, attitude {a:.3}");
        assert!(p >= 0.38, "{nhc}: position improvement {p}");
        assert!(a >= 0.4, "{nhc}: attitude improvement {a}");
    }
    let a_est = improvement(&r, "rmse_att3d_deg", "loose_pos", "nhc_pos");
    let a_known = improvement(&r, "rmse_att3d_deg", "loose_pos", "nhc_mounted");
    eprintln!("seed002 attitude, mounting estimated {a_est:.3}, known {a_known:.3}");
    assert!(
        a_known > a_est,
        "the known mounting did not help: {a_known} <= {a_est}"
    );
}

/// Seed 001's drive with seed 002's outages (`seed001_outages`): the dual-antenna
/// heading lowers the yaw RMSE by more than 80 % and moves the 3D position RMSE by
/// less than 10 % (30 seeds: 86.4 % and 3.1 %), while the NHC lowers the 3D RMSE by
/// more than 30 % (30 seeds: 54.9 %). A heading measurement does not hold the position
/// through an outage; a constraint on the velocity does (docs/RESULTS.md §19).
#[test]
fn seed001_outages_heading_fixes_yaw_not_position() {
    let r = reproduce("seed001_outages", "2");
    let yaw = improvement(&r, "rmse_yaw_deg", "loose", "dual_antenna");
    let pos = improvement(&r, "rmse_3d_m", "loose", "dual_antenna");
    let nhc = improvement(&r, "rmse_3d_m", "loose", "nhc");
    eprintln!("seed001_outages dual antenna: yaw {yaw:.3}, 3D {pos:.3}; NHC 3D {nhc:.3}");
    assert!(yaw > 0.8, "dual-antenna yaw improvement {yaw}");
    assert!(pos.abs() < 0.1, "dual-antenna 3D improvement {pos}");
    assert!(nhc > 0.3, "NHC 3D improvement {nhc}");
}

/// Seed 001: heading from GNSS lowers the yaw RMSE of the position-only loose filter:
/// the dual antenna by more than 80 % (measured 86 % on these 2 seeds, 88 % on 4; the
/// paper reports 83 %), the course of the fix velocity by more than 50 % (measured 65 %
/// on these 2 seeds, 68 % on 4).
/// Before the time-line fix
/// (issue 15) the heading records at GNSS epochs integrated IMU increments twice in
/// every variant (dual antenna 70 %) (docs/RESULTS.md §9).
#[test]
fn seed001_gnss_heading_improves_yaw() {
    let r = reproduce("seed001", "2");
    let y0 = mean(&per_seed(&r, "loose", "rmse_yaw_deg"));
    for (v, min) in [("course", 0.5), ("dual_antenna", 0.8)] {
        let y1 = mean(&per_seed(&r, v, "rmse_yaw_deg"));
        eprintln!("seed001 yaw {y0:.3} -> {y1:.3} deg with {v}");
        assert!(
            (y0 - y1) / y0 > min,
            "{v}: yaw improvement {}",
            (y0 - y1) / y0
        );
    }
}

/// Real drive, GNSS 1 Hz with 30 s outages every 90 s after the first 120 s: NHC plus
/// in-motion alignment (examples/drive_0708_nhc.toml) lowers the RMS of the per-outage
/// maximum horizontal error by at least 30 % against the plain loose filter.
#[test]
fn drive_0708_nhc_reduces_outage_drift() {
    let Some(d) = shared() else { return };
    let pos = d.join("rtklibexplorer/drive_0708/gnss_1934_sf.pos");
    let gaps = "30/90@243381.854";
    let mut rms = Vec::new();
    for cfg in ["drive_0708", "drive_0708_nhc"] {
        let out = tmp(cfg);
        navfuse(&[
            "run",
            &format!("examples/{cfg}.toml"),
            "--outages",
            gaps,
            "--out",
            out.to_str().unwrap(),
            "-q",
        ]);
        let e: Value = serde_json::from_str(&navfuse(&[
            "eval",
            out.join("solution.nav").to_str().unwrap(),
            pos.to_str().unwrap(),
            "--lever-arm",
            "0,-0.05,0",
            "--gaps",
            gaps,
            "--json",
        ]))
        .unwrap();
        rms.push(num(&e["gap_max_rms"]["horizontal_m"]));
        let _ = std::fs::remove_dir_all(&out);
    }
    eprintln!(
        "drive_0708 per-outage max horizontal RMS: loose {:.2} m, NHC + in-motion alignment {:.2} m",
        rms[0], rms[1]
    );
    assert!(rms[1] <= 0.7 * rms[0], "{rms:?}");
}
