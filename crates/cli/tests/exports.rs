//! Issue 18 (exports): `navfuse run --formats` and `navfuse export` write RTKLIB
//! `.pos`, NMEA, KML, GeoJSON and GPX that the tools read (docs/FORMATS.md
//! "Exports"), on the shipped demo: `.pos` by RTKLIB's `pos2kml` (when installed) and
//! our reader, GPX / KML / GeoJSON by independent parsers (georust's `gpx`, `kml`,
//! `geojson`), NMEA checksums and fields checked here; each against the `.nav`.

mod common;

use common::{navfuse_ok, repo, tmp};
use navfuse_io::nav::read_nav;
use std::path::Path;
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
    // (the hundredths follow the fitted GNSS-IMU time offset)
    assert!(nmea.starts_with("$GPGGA,193403.8"), "{}", &nmea[..40]);
    // GPX, KML, GeoJSON by independent parsers, NMEA checked field by field: the
    // same epochs (10 Hz) and values as solution.nav / smoothed.nav.
    for stem in ["solution", "smoothed"] {
        let n = check_exports(&out, stem);
        eprintln!("{stem}: {n} epochs in GPX, KML, GeoJSON and NMEA match {stem}.nav");
        assert!(n > 1700, "{n}");
    }
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

/// GPS - UTC [s] for epochs from 2017 on (the leap second of 2016-12-31 was the last).
const GPS_UTC_S: i64 = 18;
/// 1980-01-06 00:00:00 (the GPS epoch) in Unix seconds.
const GPS_EPOCH_UNIX: i64 = 315_964_800;

/// One epoch of `STEM.nav` as the exports should hold it: lat, lon [deg], h [m], vN
/// vE [m/s], yaw [deg], and UTC as Unix nanoseconds.
struct Epoch {
    lat: f64,
    lon: f64,
    h: f64,
    vn: f64,
    ve: f64,
    yaw: f64,
    utc_ns: i128,
}

/// The epochs of `nav` the map and NMEA exports take (docs/FORMATS.md "Exports"): the
/// first of each 0.1 s of GPS time, here in integer microseconds.
fn decimated(nav: &Path) -> Vec<Epoch> {
    let mut last_bin = None;
    let mut out = Vec::new();
    for (week, n) in read_nav(nav).unwrap() {
        let us = (n.t * 1e6).round() as i64;
        let bin = i64::from(week) * 6_048_000 + (us + 1).div_euclid(100_000);
        if last_bin.is_some_and(|b| bin <= b) {
            continue;
        }
        last_bin = Some(bin);
        let gps_us = (GPS_EPOCH_UNIX + i64::from(week) * 604_800) * 1_000_000 + us;
        let yaw = navfuse_core::attitude::euler_from_q_bn(&n.q_bn)
            .z
            .to_degrees();
        out.push(Epoch {
            lat: n.lla.x.to_degrees(),
            lon: n.lla.y.to_degrees(),
            h: n.lla.z,
            vn: n.v_n.x,
            ve: n.v_n.y,
            yaw: yaw.rem_euclid(360.0),
            utc_ns: i128::from(gps_us - GPS_UTC_S * 1_000_000) * 1000,
        });
    }
    out
}

fn utc(ns: i128) -> time::OffsetDateTime {
    let t = time::OffsetDateTime::from_unix_timestamp_nanos(ns).unwrap();
    assert!(t.year() >= 2017, "GPS - UTC = 18 s holds from 2017 on: {t}");
    t
}

/// Positions to the formats' precision: 9 decimals of a degree for the map formats
/// (the .nav has 9 too), 3 of a metre; every difference at most half the last digit
/// of each file's rounding.
const DEG9: f64 = 1.0e-9 + 1e-12;
const M3: f64 = 0.5e-3 + 0.5e-9 + 1e-12;

/// Largest difference seen per quantity, for the test's report.
type Worst = std::collections::BTreeMap<&'static str, f64>;

fn close(worst: &mut Worst, a: f64, b: f64, tol: f64, what: &'static str) {
    let d = (a - b).abs();
    assert!(d <= tol, "{what}: {a} vs {b} (tolerance {tol})");
    let w = worst.entry(what).or_insert(0.0);
    *w = w.max(d);
}

/// Every map and NMEA export of `dir/STEM.*` read by an independent parser (georust's
/// gpx, kml, geojson; NMEA by hand) and compared with `dir/STEM.nav`: the counts of the
/// 10 Hz decimation, positions to the formats' precision, UTC = GPST - 18 s. Returns
/// the number of epochs.
fn check_exports(dir: &Path, stem: &str) -> usize {
    let want = decimated(&dir.join(format!("{stem}.nav")));
    let mut worst = Worst::new();
    let file = |ext: &str| dir.join(format!("{stem}.{ext}"));
    // At most 10 Hz: no whole second of GPS time holds more than 10 epochs.
    let mut per_second = std::collections::HashMap::new();
    for w in &want {
        *per_second
            .entry(w.utc_ns.div_euclid(1_000_000_000))
            .or_insert(0) += 1;
    }
    assert!(
        per_second.values().all(|&n| n <= 10),
        "{stem}: over 10 epochs in a second"
    );
    // GPX 1.1 (gpx crate).
    let g = gpx::read(std::io::BufReader::new(
        std::fs::File::open(file("gpx")).unwrap(),
    ))
    .unwrap();
    assert_eq!(g.version, gpx::GpxVersion::Gpx11);
    assert_eq!((g.tracks.len(), g.tracks[0].segments.len()), (1, 1));
    let pts = &g.tracks[0].segments[0].points;
    assert_eq!(pts.len(), want.len(), "{stem}.gpx points");
    for (p, w) in pts.iter().zip(&want) {
        close(&mut worst, p.point().y(), w.lat, DEG9, "gpx lat");
        close(&mut worst, p.point().x(), w.lon, DEG9, "gpx lon");
        close(&mut worst, p.elevation.unwrap(), w.h, M3, "gpx ele");
        let t = time::OffsetDateTime::from(p.time.unwrap()).unix_timestamp_nanos();
        // Milliseconds, rounded.
        assert!(
            (t - w.utc_ns).abs() <= 500_000 + 1000,
            "gpx time {t} vs {}",
            w.utc_ns
        );
    }

    // KML (kml crate): one LineString placemark, absolute altitudes.
    let k: kml::Kml = std::fs::read_to_string(file("kml"))
        .unwrap()
        .parse()
        .unwrap();
    let mut lines = Vec::new();
    line_strings(&k, &mut lines);
    assert_eq!(lines.len(), 1, "{stem}.kml line strings");
    assert_eq!(lines[0].altitude_mode, kml::types::AltitudeMode::Absolute);
    assert_eq!(lines[0].coords.len(), want.len(), "{stem}.kml points");
    for (c, w) in lines[0].coords.iter().zip(&want) {
        close(&mut worst, c.y, w.lat, DEG9, "kml lat");
        close(&mut worst, c.x, w.lon, DEG9, "kml lon");
        close(&mut worst, c.z.unwrap(), w.h, M3, "kml h");
    }

    // GeoJSON (geojson crate): a FeatureCollection of one LineString, [lon, lat, h].
    let gj: geojson::GeoJson = std::fs::read_to_string(file("geojson"))
        .unwrap()
        .parse()
        .unwrap();
    let geojson::GeoJson::FeatureCollection(fc) = gj else {
        panic!("{stem}.geojson: not a FeatureCollection")
    };
    assert_eq!(fc.features.len(), 1);
    let Some(geojson::GeometryValue::LineString { coordinates }) =
        fc.features[0].geometry.as_ref().map(|g| &g.value)
    else {
        panic!("{stem}.geojson: not a LineString")
    };
    assert_eq!(coordinates.len(), want.len(), "{stem}.geojson points");
    for (c, w) in coordinates.iter().zip(&want) {
        assert_eq!(c.len(), 3);
        close(&mut worst, c[1], w.lat, DEG9, "geojson lat");
        close(&mut worst, c[0], w.lon, DEG9, "geojson lon");
        close(&mut worst, c[2], w.h, M3, "geojson h");
    }

    // NMEA: GGA, RMC, HDT per epoch, each `$BODY*CS\r\n` with CS the XOR of BODY.
    let text = std::fs::read_to_string(file("nmea")).unwrap();
    assert!(text.ends_with("\r\n"));
    let sentences: Vec<&str> = text.trim_end_matches("\r\n").split("\r\n").collect();
    assert_eq!(sentences.len(), 3 * want.len(), "{stem}.nmea sentences");
    for s in &sentences {
        let body_cs = s.strip_prefix('$').unwrap_or_else(|| panic!("no $: {s}"));
        let (body, cs) = body_cs
            .split_once('*')
            .unwrap_or_else(|| panic!("no *: {s}"));
        let xor = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(u8::from_str_radix(cs, 16).unwrap(), xor, "checksum of {s}");
        assert_eq!(cs.len(), 2);
    }
    // ddmm.mmmmmm (dddmm.mmmmmm) with its hemisphere: 1e-6 minute.
    let angle = |v: &str, hemi: &str, deg_digits: usize| -> f64 {
        let d: f64 = v[..deg_digits].parse().unwrap();
        let m: f64 = v[deg_digits..].parse().unwrap();
        assert!(
            m < 60.0 && v[deg_digits..].split_once('.').unwrap().1.len() == 6,
            "{v}"
        );
        let a = d + m / 60.0;
        if hemi == "S" || hemi == "W" {
            -a
        } else {
            a
        }
    };
    const MIN6: f64 = 0.5e-6 / 60.0 + 1.0e-9;
    for (e, w) in sentences.chunks(3).zip(&want) {
        let gga: Vec<&str> = e[0].split('*').next().unwrap().split(',').collect();
        let rmc: Vec<&str> = e[1].split('*').next().unwrap().split(',').collect();
        let hdt: Vec<&str> = e[2].split('*').next().unwrap().split(',').collect();
        assert_eq!((gga[0], rmc[0], hdt[0]), ("$GPGGA", "$GPRMC", "$GPHDT"));
        close(&mut worst, angle(gga[2], gga[3], 2), w.lat, MIN6, "gga lat");
        close(&mut worst, angle(gga[4], gga[5], 3), w.lon, MIN6, "gga lon");
        assert!(["N", "S"].contains(&gga[3]) && ["E", "W"].contains(&gga[5]));
        close(&mut worst, gga[9].parse().unwrap(), w.h, M3, "gga height");
        assert_eq!((gga[10], gga[11], gga[12]), ("M", "0.000", "M"));
        // UTC hhmmss.ss (10 ms, rounded) and RMC's ddmmyy.
        let u = utc(w.utc_ns);
        let sod_ms = |hms: &str| -> i64 {
            let (h, m, s): (i64, i64, f64) = (
                hms[..2].parse().unwrap(),
                hms[2..4].parse().unwrap(),
                hms[4..].parse().unwrap(),
            );
            (h * 3600 + m * 60) * 1000 + (s * 1000.0).round() as i64
        };
        let want_ms =
            (i64::from(u.hour()) * 3600 + i64::from(u.minute()) * 60 + i64::from(u.second()))
                * 1000
                + i64::from(u.millisecond());
        assert!(
            (sod_ms(gga[1]) - want_ms).abs() <= 5,
            "gga time {} vs {u}",
            gga[1]
        );
        assert_eq!(rmc[1], gga[1]);
        assert_eq!(
            rmc[9],
            format!(
                "{:02}{:02}{:02}",
                u.day(),
                u8::from(u.month()),
                u.year() % 100
            ),
            "rmc date vs {u}"
        );
        assert_eq!((rmc[2], &rmc[3..7]), ("A", &gga[2..6]));
        let speed = w.vn.hypot(w.ve);
        close(
            &mut worst,
            rmc[7].parse().unwrap(),
            speed * 3600.0 / 1852.0,
            0.5e-3 + 1e-9,
            "rmc knots",
        );
        if speed > 0.5 {
            let course = w.ve.atan2(w.vn).to_degrees().rem_euclid(360.0);
            let d: f64 = rmc[8].parse::<f64>().unwrap() - course;
            assert!(
                (d + 180.0).rem_euclid(360.0) - 180.0 <= 0.005 + 1e-6,
                "course {} vs {course}",
                rmc[8]
            );
        }
        let dy = hdt[1].parse::<f64>().unwrap() - w.yaw;
        assert!(
            ((dy + 180.0).rem_euclid(360.0) - 180.0).abs() <= 0.5e-3 + 1e-6,
            "hdt {} vs {}",
            hdt[1],
            w.yaw
        );
        assert_eq!(hdt[2], "T");
    }
    eprintln!("{stem}: largest differences from {stem}.nav: {worst:?}");
    want.len()
}

fn line_strings<'a>(k: &'a kml::Kml, out: &mut Vec<&'a kml::types::LineString>) {
    match k {
        kml::Kml::KmlDocument(d) => d.elements.iter().for_each(|e| line_strings(e, out)),
        kml::Kml::Document { elements, .. } => elements.iter().for_each(|e| line_strings(e, out)),
        kml::Kml::Folder(f) => f.elements.iter().for_each(|e| line_strings(e, out)),
        kml::Kml::Placemark(p) => {
            if let Some(kml::types::Geometry::LineString(l)) = &p.geometry {
                out.push(l);
            }
        }
        kml::Kml::LineString(l) => out.push(l),
        _ => {}
    }
}

/// `navfuse export` of a 200 Hz solution south of the equator and east of Greenwich
/// (the demo is north and west), across a UTC minute: 10 Hz exactly, every value as
/// the independent parsers read it.
#[test]
fn exports_of_a_200hz_solution() {
    let dir = tmp("exports-200hz");
    std::fs::create_dir_all(&dir).unwrap();
    let mut nav = String::new();
    for k in 0..2001 {
        // GPS week 2374 (July 2025); 243073 s GPST = 19:30:55 UTC (Tuesday), so
        // the UTC minute turns 5 s in.
        let t = 243_073.0 + k as f64 * 0.005;
        let (lat, lon) = (-33.86 - k as f64 * 9e-8, 151.21 + k as f64 * 1.1e-7);
        let yaw = (120.0 + k as f64 * 0.1) % 360.0;
        nav.push_str(&format!(
            "2374 {t:.9} {lat:.9} {lon:.9} {:.9} -1.000000000 1.100000000 0.010000000 0.5 -1.0 {yaw:.9}\n",
            30.0 + k as f64 * 1e-3
        ));
    }
    std::fs::write(dir.join("solution.nav"), nav).unwrap();
    navfuse_ok(&[
        "export",
        dir.to_str().unwrap(),
        "--formats",
        "nmea,kml,geojson,gpx",
    ]);
    assert_eq!(check_exports(&dir, "solution"), 101);
    let _ = std::fs::remove_dir_all(&dir);
}
