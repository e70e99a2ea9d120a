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
    let (n, h, v) = max_difference(
        &dir.join("rinex/solution.nav"),
        &dir.join("ubx/solution.nav"),
    );
    eprintln!(
        "ubx vs rinex tight: {n} epochs, max horizontal difference {h:.4} m, vertical {v:.4} m"
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

/// Solutions of two runs: (epochs, max horizontal, max vertical difference) [m].
fn max_difference(a: &Path, b: &Path) -> (usize, f64, f64) {
    let a = read_nav(a).unwrap();
    let b = read_nav(b).unwrap();
    assert_eq!(a.len(), b.len());
    let (mut h, mut v) = (0f64, 0f64);
    for ((_, x), (_, y)) in a.iter().zip(&b) {
        assert!((x.t - y.t).abs() < 1e-9);
        let e = navfuse_core::earth::lla_diff_ned(&x.lla, &y.lla);
        h = h.max(e[0].hypot(e[1]));
        v = v.max(e[2].abs());
    }
    (a.len(), h, v)
}

/// GPS + Galileo tight on the walk, the orbits decoded from RXM-SFRBX against
/// convbin's: the observations are the RAWX epochs written as one RINEX file for
/// both runs; the navigation files are written by navfuse's writer from the decoded
/// records, and from convbin's records (its GPS file with the Galileo records it
/// writes from the E1-B pages padded to 9 words, crates/io/tests/data/README.md), so
/// only the decoding differs. Also: the log's BeiDou observations are of no signal a
/// D1 record serves (B2a pilot `C5X`: D1 has no B2a group delay; the B3I and B1C
/// sigIds 4 and 5 are not in the signal table), so a G+C run is GPS alone.
#[test]
fn ubx_nav_equals_convbin_nav_in_a_gps_galileo_run() {
    use navfuse_gnss::System;
    use navfuse_io::rinex_nav::{read_rinex_nav, write_rinex3_nav, RinexNav};
    use navfuse_io::rinex_obs::{ObsHeader, RinexMultiObsWriter};
    let Some(d) = shared() else { return };
    let dir = tmp("ubx_ge");
    std::fs::create_dir_all(&dir).unwrap();
    let walk = d.join("rtklibexplorer/walk_0827");
    let log = navfuse_io::ubx::read_ubx(&walk.join("gnss_1730.ubx")).unwrap();
    // The observations as RINEX.
    let mut types: Vec<(System, Vec<navfuse_gnss::signal::ObsCode>)> = Vec::new();
    for s in log.epochs.iter().flat_map(|e| &e.sats) {
        let i = match types.iter().position(|(sys, _)| *sys == s.sat.system) {
            Some(i) => i,
            None => {
                types.push((s.sat.system, Vec::new()));
                types.len() - 1
            }
        };
        for (c, _) in &s.signals {
            if !types[i].1.contains(c) {
                types[i].1.push(*c);
            }
        }
    }
    let hdr = ObsHeader {
        marker_name: "WALK".into(),
        approx_pos_ecef_m: nalgebra::Vector3::zeros(),
        antenna_delta_hen_m: nalgebra::Vector3::zeros(),
        interval_s: None,
        first_obs: log.epochs[0].t,
        receiver: ["1".into(), "UBX".into(), "0".into()],
        antenna: ["1".into(), "UBX".into()],
        program: "navfuse test".into(),
        date: Some("20260101 000000 UTC".into()),
    };
    let obs = dir.join("walk_ubx.obs");
    let file = std::io::BufWriter::new(std::fs::File::create(&obs).unwrap());
    let mut w = RinexMultiObsWriter::new(file, &hdr, &types, &[]).unwrap();
    for e in &log.epochs {
        w.write_epoch(e).unwrap();
    }
    w.finish().unwrap();
    let write = |name: &str, nav: &RinexNav| {
        let p = dir.join(name);
        let mut f = std::io::BufWriter::new(std::fs::File::create(&p).unwrap());
        write_rinex3_nav(&mut f, nav, "navfuse test").unwrap();
        p
    };
    let ubx_nav = write("walk_ubx.nav", &log.nav);
    let mut convbin = read_rinex_nav(&walk.join("derived_rinex/gnss_1730.nav")).unwrap();
    convbin.galileo =
        read_rinex_nav(&repo().join("crates/io/tests/data/walk_0827_galileo_convbin.nav"))
            .unwrap()
            .galileo;
    let convbin_nav = write("walk_convbin.nav", &convbin);
    let edit = |nav: &Path, systems: &'static str| {
        let (obs, nav) = (obs.clone(), nav.to_path_buf());
        move |line: &str| -> Option<String> {
            match line.split('=').next().unwrap_or("").trim() {
                "file" => Some(format!("file = {:?}", obs.to_str().unwrap())),
                "nav" => Some(format!(
                    "nav = {:?}\nsystems = {systems}\nsignals = {{ C = [\"C5X\"] }}",
                    nav.to_str().unwrap()
                )),
                _ => None,
            }
        }
    };
    let ge = r#"["G", "E"]"#;
    let runs = [
        ("convbin_ge", edit(&convbin_nav, ge)),
        ("ubx_ge", edit(&ubx_nav, ge)),
        ("ubx_gc", edit(&ubx_nav, r#"["G", "C"]"#)),
        ("ubx_g", edit(&ubx_nav, r#"["G"]"#)),
    ];
    for (name, e) in runs {
        run(
            &config(&dir, &d, &format!("{name}.toml"), e),
            &dir.join(name),
        );
    }
    let states = std::fs::read_to_string(dir.join("ubx_ge/states.csv")).unwrap();
    assert!(states.lines().next().unwrap().contains("isb_galileo_m"));
    let (n, h, v) = max_difference(
        &dir.join("convbin_ge/solution.nav"),
        &dir.join("ubx_ge/solution.nav"),
    );
    let (_, hg, vg) = max_difference(
        &dir.join("ubx_g/solution.nav"),
        &dir.join("ubx_ge/solution.nav"),
    );
    let (_, hc, vc) = max_difference(
        &dir.join("ubx_g/solution.nav"),
        &dir.join("ubx_gc/solution.nav"),
    );
    eprintln!(
        "G+E tight on the RAWX observations: SFRBX nav vs convbin nav: {n} epochs, max horizontal difference {h:.2e} m, vertical {v:.2e} m; G+E vs G alone {hg:.3} / {vg:.3} m; G+C vs G alone {hc:.1e} / {vc:.1e} m"
    );
    assert!(h < 1e-3 && v < 1e-3, "{h} {v}");
    // Galileo changes the solution; BeiDou does not (no usable signal).
    assert!(hg.max(vg) > 0.01, "{hg} {vg}");
    assert!(hc.max(vc) < 1e-9, "{hc} {vc}");
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
