//! `[gnss] format = "ubx"` end to end on walk_0827 (issue 20): the tight run on the
//! u-blox log against the same run on convbin's RINEX of it, and a loose run on the
//! receiver's NAV-PVT fixes scored by `navfuse eval`. Skipped without ../shared.

mod common;
use common::{navfuse_ok, num, repo, run, shared, tmp};
use navfuse_io::nav::read_nav;
use std::path::{Path, PathBuf};

/// examples/walk_0827_tight.toml with absolute data paths and `edit` applied to
/// its `[gnss]` lines, written to `dir/name`.
fn config(dir: &Path, data: &Path, name: &str, edit: impl Fn(&str) -> Option<String>) -> PathBuf {
    let text = std::fs::read_to_string(repo().join("examples/walk_0827_tight.toml")).unwrap();
    let text = text.replace("../../shared/data", data.to_str().unwrap());
    let mut out = String::new();
    let mut in_gnss = false;
    for line in text.lines() {
        if line.starts_with('[') {
            in_gnss = line == "[gnss]";
        }
        match if in_gnss { edit(line) } else { None } {
            Some(l) if l.is_empty() => {}
            Some(l) => out.push_str(&format!("{l}\n")),
            None => out.push_str(&format!("{line}\n")),
        }
    }
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, out).unwrap();
    p
}

/// The `[gnss]` lines of a UBX source: the log instead of the RINEX files.
fn to_ubx(data: &Path, line: &str, pvt: bool) -> Option<String> {
    let key = line.split('=').next().unwrap_or("").trim();
    let ubx = data.join("rtklibexplorer/walk_0827/gnss_1730.ubx");
    match key {
        "file" => Some(format!("file = {:?}", ubx.to_str().unwrap())),
        "format" if pvt => Some("format = \"ubx\"\nubx_source = \"pvt\"".into()),
        "format" => Some("format = \"ubx\"".into()),
        "nav" => Some(String::new()),
        "coupling" | "range_rate" | "elevation_mask_deg" if pvt => Some(String::new()),
        _ => None,
    }
}

/// The tight run on the UBX log (RAWX + SFRBX) gives the RINEX run's solution
/// within the RINEX rounding: convbin writes observations to 1 mm / 0.001 cycle /
/// 0.001 Hz and ephemerides to 12 digits, the reader keeps the receiver's doubles.
#[test]
fn ubx_tight_equals_rinex_tight() {
    let Some(d) = shared() else { return };
    let dir = tmp("ubx_tight");
    let rinex = config(&dir, &d, "rinex.toml", |_| None);
    let ubx = config(&dir, &d, "ubx.toml", |l| to_ubx(&d, l, false));
    run(&rinex, &dir.join("rinex"));
    run(&ubx, &dir.join("ubx"));
    let a = read_nav(&dir.join("rinex/solution.nav")).unwrap();
    let b = read_nav(&dir.join("ubx/solution.nav")).unwrap();
    assert_eq!(a.len(), b.len());
    let (mut h, mut v) = (0f64, 0f64);
    for ((_, x), (_, y)) in a.iter().zip(&b) {
        assert!((x.t - y.t).abs() < 1e-9);
        let e = navfuse_core::earth::lla_diff_ned(&x.lla, &y.lla);
        h = h.max(e[0].hypot(e[1]));
        v = v.max(e[2].abs());
    }
    eprintln!(
        "ubx vs rinex tight: {} epochs, max horizontal difference {:.4} m, vertical {:.4} m",
        a.len(),
        h,
        v
    );
    assert!(h < 0.02 && v < 0.02, "{h} {v}");
    // The written configuration reads back to the same run.
    run(&dir.join("ubx/config.toml"), &dir.join("ubx2"));
    assert_eq!(
        std::fs::read(dir.join("ubx/solution.nav")).unwrap(),
        std::fs::read(dir.join("ubx2/solution.nav")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A loose run on the NAV-PVT fixes, scored against gnss_1730_sf.pos (whose heights
/// are the receiver's hMSL: the vertical error is the geoid separation).
#[test]
fn ubx_pvt_loose_run_is_scored() {
    let Some(d) = shared() else { return };
    let dir = tmp("ubx_pvt");
    let cfg = config(&dir, &d, "pvt.toml", |l| to_ubx(&d, l, true));
    let out = dir.join("pvt");
    run(&cfg, &out);
    let pos = d.join("rtklibexplorer/walk_0827/gnss_1730_sf.pos");
    let e: serde_json::Value = serde_json::from_str(&navfuse_ok(&[
        "eval",
        out.join("solution.nav").to_str().unwrap(),
        pos.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    let h = num(&e, &["position_m", "horizontal", "rms"]);
    let v = num(&e, &["position_m", "vertical", "rms"]);
    eprintln!(
        "ubx NAV-PVT loose vs gnss_1730_sf.pos: horizontal RMS {h:.4} m, vertical RMS {v:.3} m"
    );
    assert!(h < 0.1, "{h}");
    assert!((v - 21.4).abs() < 0.5, "{v}");
    run(&out.join("config.toml"), &dir.join("pvt2"));
    assert_eq!(
        std::fs::read(out.join("solution.nav")).unwrap(),
        std::fs::read(dir.join("pvt2/solution.nav")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
