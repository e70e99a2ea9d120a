//! Issue 15 (finding 5): the GNSS gate is on by default and works on real MEMS data.
//! On the shipped demo (and the full drive, with ../shared): no good fix rejected; 10
//! fixes moved by 5-100 m at random epochs are rejected, the accuracy stays near the
//! clean run's and the time offset within 5 ms of it; a 10-epoch 1 km burst is
//! rejected. Accuracy is against the receiver's own RTK solution (the demo's truth).

mod common;

use common::{navfuse_ok, repo, run, shared, tmp};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A small deterministic generator (the test needs no statistical quality).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

enum Damage {
    /// 10 fixes moved by 5-100 m in random directions.
    Outliers(u64),
    /// 10 consecutive fixes moved by 1 km.
    Burst(u64),
}

/// Copy an RTKLIB .pos file with some whole-second RTK-fixed epochs (the ones the
/// configs keep) moved; returns the damaged times.
fn damage(src: &Path, dst: &Path, how: &Damage) -> Vec<String> {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let cands: Vec<usize> = (0..lines.len())
        .filter(|&i| {
            let f: Vec<&str> = lines[i].split_whitespace().collect();
            !lines[i].starts_with('%')
                && f.len() > 5
                && f[1].ends_with(".999")
                && f[5].parse::<f64>() == Ok(1.0)
        })
        .skip(40) // after the alignment
        .collect();
    let mut picked: Vec<(usize, [f64; 3])> = Vec::new();
    match how {
        Damage::Outliers(seed) => {
            let mut r = Lcg(*seed);
            while picked.len() < 10 {
                let i = cands[(r.next() * cands.len() as f64) as usize];
                if picked.iter().any(|p| p.0 == i) {
                    continue;
                }
                let (d, a) = (5.0 + 95.0 * r.next(), std::f64::consts::TAU * r.next());
                picked.push((
                    i,
                    [d * a.cos(), d * a.sin(), 0.3 * d * (2.0 * r.next() - 1.0)],
                ));
            }
        }
        Damage::Burst(seed) => {
            let mut r = Lcg(*seed);
            let k = (r.next() * (cands.len() - 12) as f64) as usize;
            let a = std::f64::consts::TAU * r.next();
            for &i in &cands[k..k + 10] {
                picked.push((i, [1000.0 * a.cos(), 1000.0 * a.sin(), 0.0]));
            }
        }
    }
    let mut times = Vec::new();
    for (i, d) in &picked {
        let mut f: Vec<String> = lines[*i].split_whitespace().map(str::to_string).collect();
        let lat: f64 = f[2].parse().unwrap();
        let lon: f64 = f[3].parse().unwrap();
        let h: f64 = f[4].parse().unwrap();
        let r = 6_378_137.0;
        f[2] = format!("{:.9}", lat + (d[0] / r).to_degrees());
        f[3] = format!(
            "{:.9}",
            lon + (d[1] / (r * lat.to_radians().cos())).to_degrees()
        );
        f[4] = format!("{:.4}", h + d[2]);
        times.push(f[1].clone());
        lines[*i] = f.join("   ");
    }
    std::fs::write(dst, lines.join("\n") + "\n").unwrap();
    times
}

struct Outcome {
    rms_h_m: f64,
    rejected: u64,
    fixes: u64,
    tau_s: f64,
}

/// Run `config` with its GNSS file replaced by `pos`; horizontal RMS against `truth`.
fn outcome(config: &Path, pos: &Path, truth: &Path, out: &Path) -> Outcome {
    let mut cfg = navfuse_io::config::load(config).unwrap();
    cfg.gnss.as_mut().unwrap().path = pos.to_path_buf();
    let toml = out.with_extension("toml");
    std::fs::write(&toml, cfg.to_toml_string()).unwrap();
    run(&toml, out);
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let ev = navfuse_ok(&[
        "eval",
        out.join("solution.nav").to_str().unwrap(),
        truth.to_str().unwrap(),
        "--lever-arm",
        "0,-0.05,0",
    ]);
    let rms_h_m = ev
        .lines()
        .find(|l| l.starts_with("horizontal"))
        .and_then(|l| l.split_whitespace().nth(2))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no horizontal line in {ev}"));
    Outcome {
        rms_h_m,
        rejected: s["gnss"]["rejected"].as_u64().unwrap(),
        fixes: s["gnss"]["used"].as_u64().unwrap() + s["gnss"]["rejected"].as_u64().unwrap(),
        tau_s: s["time_offset"]["offset_s_at_start"].as_f64().unwrap(),
    }
}

/// Clean, 10 outliers (`seeds`), bursts; returns the mean accuracy ratio of the outlier
/// runs to the clean run after checking the rejections and the time offset.
fn check(name: &str, config: &Path, pos: &Path, seeds: &[u64], tau_tol_s: f64) -> f64 {
    let dir = tmp(&format!("gate-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    let clean = outcome(config, pos, pos, &dir.join("clean"));
    eprintln!(
        "{name} clean: {:.4} m, {} of {} fixes rejected, time offset {:.4} s",
        clean.rms_h_m, clean.rejected, clean.fixes, clean.tau_s
    );
    assert!(
        clean.rejected as f64 <= 0.02 * clean.fixes as f64,
        "{name}: clean fixes rejected"
    );
    let mut ratios = Vec::new();
    for &seed in seeds {
        let bad = dir.join(format!("outliers{seed}.pos"));
        damage(pos, &bad, &Damage::Outliers(seed));
        let o = outcome(config, &bad, pos, &dir.join(format!("outliers{seed}")));
        let ratio = o.rms_h_m / clean.rms_h_m;
        eprintln!(
            "{name} 10 outliers (seed {seed}): {:.4} m ({ratio:.3} x clean), {} rejected, time offset {:+.1} ms from clean",
            o.rms_h_m,
            o.rejected,
            (o.tau_s - clean.tau_s) * 1e3
        );
        assert!(
            o.rejected >= 10 && o.rejected <= 10 + clean.rejected + 2,
            "{name}: {} rejected",
            o.rejected
        );
        assert!(
            (o.tau_s - clean.tau_s).abs() < tau_tol_s,
            "{name}: time offset {} vs {}",
            o.tau_s,
            clean.tau_s
        );
        assert!(
            o.rms_h_m < 0.5,
            "{name}: outliers moved the solution ({} m)",
            o.rms_h_m
        );
        ratios.push(ratio);
    }
    for seed in [1, 2] {
        let bad = dir.join(format!("burst{seed}.pos"));
        let times = damage(pos, &bad, &Damage::Burst(seed));
        let o = outcome(config, &bad, pos, &dir.join(format!("burst{seed}")));
        eprintln!(
            "{name} 1 km burst {} .. {}: {:.4} m, {} rejected",
            times[0], times[9], o.rms_h_m, o.rejected
        );
        assert!(
            o.rejected >= 10,
            "{name}: burst let in ({} rejected)",
            o.rejected
        );
        assert!(
            o.rms_h_m < 1.0,
            "{name}: burst moved the solution ({} m)",
            o.rms_h_m
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    ratios.iter().sum::<f64>() / ratios.len() as f64
}

#[test]
fn demo_gate_rejects_outliers_and_no_good_fix() {
    let d = repo().join("examples/demo");
    // The 3 min excerpt is short: losing 10 of its 177 fixes (seed 1: three in its
    // hardest manoeuvre) costs more than on the full drive, and its time-offset fit
    // moves by up to ~5 ms; the 10 % and 5 ms figures are asserted on the drive.
    check(
        "demo",
        &d.join("drive_excerpt.toml"),
        &d.join("gnss.pos"),
        &[1, 2, 3],
        0.01,
    );
}

#[test]
fn drive_gate_keeps_accuracy_within_10_percent() {
    let Some(data) = shared() else { return };
    let pos: PathBuf = data.join("rtklibexplorer/drive_0708/gnss_1934_sf.pos");
    let cfg = repo().join("examples/drive_0708.toml");
    let mean = check("drive", &cfg, &pos, &[1, 2, 3, 4, 5], 5e-3);
    assert!(mean < 1.10, "drive: mean accuracy ratio {mean}");
}
