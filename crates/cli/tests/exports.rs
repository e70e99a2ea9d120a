//! Issue 18 (exports): `navfuse run --formats` and `navfuse export` write RTKLIB
//! `.pos`, NMEA, KML, GeoJSON and GPX that the tools read (docs/FORMATS.md
//! "Exports"), on the shipped demo.

mod common;

use common::{navfuse_ok, repo, tmp};
use std::process::Command;

#[test]
fn exports_are_readable() {
    let dir = tmp("exports");
    let out = dir.join("run");
    let o = out.to_str().unwrap();
    navfuse_ok(&[
        "run",
        "examples/demo/drive_excerpt.toml",
        "--out",
        o,
        "-q",
        "--smooth",
        "--formats",
        "pos,nmea,kml,geojson,gpx",
    ]);
    for stem in ["solution", "smoothed"] {
        for ext in ["pos", "nmea", "kml", "geojson", "gpx"] {
            assert!(out.join(format!("{stem}.{ext}")).is_file(), "{stem}.{ext}");
        }
    }
    // .pos: our reader (quality 5) gives back the solution to 0.1 mm.
    let e = navfuse_ok(&[
        "eval",
        out.join("solution.nav").to_str().unwrap(),
        out.join("solution.pos").to_str().unwrap(),
        "--quality",
        "5",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&e).unwrap();
    let epochs = v["epochs"].as_u64().unwrap();
    assert!(epochs > 1700, "{epochs}");
    let hmax = v["position_m"]["horizontal"]["max"].as_f64().unwrap();
    assert!(hmax < 1e-4, "{hmax}");
    // NMEA: every sentence's checksum; UTC = GPST - 18 s in 2025.
    let nmea = std::fs::read_to_string(out.join("solution.nmea")).unwrap();
    let mut gga = 0;
    for l in nmea.lines() {
        let (body, cs) = l[1..].split_once('*').expect("checksum");
        let x = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(format!("{x:02X}"), cs, "{l}");
        gga += usize::from(body.starts_with("GPGGA"));
    }
    assert!(gga > 1700);
    let first_pos = std::fs::read_to_string(out.join("solution.pos")).unwrap();
    let pos_line = first_pos.lines().find(|l| !l.starts_with('%')).unwrap();
    // 19:34:21.8 GPST -> 19:34:03.8 UTC.
    assert!(pos_line.contains("19:34:21.8"), "{pos_line}");
    assert!(nmea.starts_with("$GPGGA,193403.80,"), "{}", &nmea[..40]);
    // GeoJSON parses; KML and GPX are closed.
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("solution.geojson")).unwrap())
            .unwrap();
    assert!(
        g["features"][0]["geometry"]["coordinates"]
            .as_array()
            .unwrap()
            .len()
            > 1700
    );
    assert!(std::fs::read_to_string(out.join("solution.kml"))
        .unwrap()
        .trim_end()
        .ends_with("</kml>"));
    assert!(std::fs::read_to_string(out.join("solution.gpx"))
        .unwrap()
        .trim_end()
        .ends_with("</gpx>"));
    // `navfuse export` of the finished run writes the same .pos.
    let again = dir.join("again");
    std::fs::create_dir_all(&again).unwrap();
    for f in ["solution.nav", "std.txt"] {
        std::fs::copy(out.join(f), again.join(f)).unwrap();
    }
    navfuse_ok(&["export", again.to_str().unwrap(), "--formats", "pos"]);
    // The same epochs and positions (the .nav file's 9 decimals; std.txt's rounding).
    let cols = |text: &str| -> Vec<Vec<f64>> {
        text.lines()
            .filter(|l| !l.starts_with('%'))
            .map(|l| {
                l.split_whitespace()
                    .skip(2)
                    .take(6)
                    .filter_map(|x| x.parse().ok())
                    .collect()
            })
            .collect()
    };
    let (a, b) = (
        cols(&first_pos),
        cols(&std::fs::read_to_string(again.join("solution.pos")).unwrap()),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!(
            (x[0] - y[0]).abs() < 2e-9 && (x[1] - y[1]).abs() < 2e-9,
            "{x:?} {y:?}"
        );
        assert!((x[2] - y[2]).abs() < 2e-4, "{x:?} {y:?}");
        assert!((x[5] - y[5]).abs() < 2e-4, "{x:?} {y:?}");
    }
    // RTKLIB's pos2kml reads the .pos, when installed.
    match Command::new("pos2kml")
        .arg(again.join("solution.pos"))
        .output()
    {
        Ok(o) if o.status.success() => {
            let k = std::fs::read_to_string(again.join("solution.kml")).unwrap();
            let n = k.matches("<Placemark>").count();
            eprintln!("pos2kml: {n} placemarks");
            assert!(n as u64 > 1700, "{n}");
        }
        _ => eprintln!("skipped: pos2kml (RTKLIB) not installed; the pos2kml check did not run"),
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = repo();
}

#[test]
fn unknown_format_is_refused() {
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .current_dir(repo())
        .args([
            "run",
            "examples/demo/drive_excerpt.toml",
            "--formats",
            "kml,shp",
            "--out",
        ])
        .arg(tmp("exports-bad"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("shp") && e.contains("geojson"), "{e}");
}

/// `navfuse eval --errors`: one row per scored epoch; along/cross-track in the JSON;
/// no attitude figures against a reference without attitude (.pos).
#[test]
fn eval_writes_per_epoch_errors() {
    let dir = tmp("eval-errors");
    let out = dir.join("run");
    navfuse_ok(&[
        "run",
        "examples/demo/drive_excerpt.toml",
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let csv = dir.join("errors.csv");
    let j = navfuse_ok(&[
        "eval",
        out.join("solution.nav").to_str().unwrap(),
        "examples/demo/gnss.pos",
        "--lever-arm",
        "0,-0.05,0",
        "--errors",
        csv.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&j).unwrap();
    let epochs = v["epochs"].as_u64().unwrap() as usize;
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("t_s,d_north_m"));
    assert_eq!(lines.len(), epochs + 1);
    assert!(v["position_m"]["along_track"]["rms"].as_f64().unwrap() > 0.0);
    assert!(
        v["percentiles_m"]["cep"].as_f64().unwrap() <= v["percentiles_m"]["r95"].as_f64().unwrap()
    );
    assert!(
        v.get("attitude_deg").is_none(),
        "a .pos reference has no attitude"
    );
    // The horizontal column equals hypot(north, east).
    for l in &lines[1..] {
        let f: Vec<f64> = l.split(',').take(5).map(|x| x.parse().unwrap()).collect();
        assert!((f[1].hypot(f[2]) - f[4]).abs() < 2e-6, "{l}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `navfuse sim` writes the truth as KML beside truth.nav.
#[test]
fn simulator_writes_truth_kml() {
    let dir = tmp("sim-kml");
    common::simulate(&repo().join("scenarios/roundtrip_car.toml"), &dir);
    let kml = std::fs::read_to_string(dir.join("truth.kml")).unwrap();
    assert!(kml.trim_end().ends_with("</kml>"));
    let coords = kml
        .split("<coordinates>")
        .nth(1)
        .and_then(|c| c.split("</coordinates>").next())
        .unwrap();
    let n = coords.split_whitespace().count();
    let nav = std::fs::read_to_string(dir.join("truth.nav"))
        .unwrap()
        .lines()
        .count();
    assert!(n > 10 && n <= nav, "{n} points for {nav} truth epochs");
    let _ = std::fs::remove_dir_all(&dir);
}
