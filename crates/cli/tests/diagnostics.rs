//! Issue 18 (diagnostics): the per-epoch solution state in solution.csv, the
//! innovations log and the forward extra states, on the shipped demo with an outage
//! (docs/FORMATS.md "CSV", "Innovations").

mod common;

use common::{navfuse_ok, run_demo};

/// The `state` column of a CSV, with its time column.
fn states(path: &std::path::Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let t = header.iter().position(|h| *h == "t_s").unwrap();
    let s = header
        .iter()
        .position(|h| *h == "state")
        .expect("state column");
    assert_eq!(s, header.len() - 1, "state is the last column");
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[t].parse().unwrap(), f[s].to_string())
        })
        .collect()
}

#[test]
fn state_column_innovations_and_states_on_the_demo() {
    // The demo's GNSS starts at 243262 s; a 30 s outage from 243350 s.
    let (dir, out) = run_demo(
        "diagnostics",
        &["--outages", "243350:243380", "--formats", "nmea"],
    );
    let st = states(&out.join("solution.csv"));
    let in_outage = |t: f64| (243352.5..243380.0).contains(&t);
    let mut counts = std::collections::BTreeMap::new();
    for (t, s) in &st {
        *counts.entry(s.as_str()).or_insert(0) += 1;
        if in_outage(*t) {
            assert_eq!(
                s, "inertial",
                "t = {t}: no GNSS, no vehicle aiding in the demo"
            );
        }
        // (the demo has a 3 s gap of its own, 243300-243303 s)
        if (243304.0..243350.0).contains(t) {
            assert_eq!(s, "gnss", "t = {t}");
        }
    }
    // Back to GNSS after the outage.
    assert!(st.iter().any(|(t, s)| *t > 243385.0 && s == "gnss"));
    assert!(counts["inertial"] >= 270, "{counts:?}");

    // NMEA: quality 6 (dead reckoning) exactly where the state is not GNSS (the
    // demo's 10 Hz solution is exported at every epoch).
    let nmea = std::fs::read_to_string(out.join("solution.nmea")).unwrap();
    let gga: Vec<&str> = nmea.lines().filter(|l| l.starts_with("$GPGGA")).collect();
    assert_eq!(gga.len(), st.len());
    for (g, (t, s)) in gga.iter().zip(&st) {
        let q = g.split(',').nth(6).unwrap();
        let want = if s == "gnss" || s == "static" {
            "1"
        } else {
            "6"
        };
        assert_eq!(q, want, "t = {t}: state {s}, GGA {g}");
    }

    // innovations.csv: one row per update tried, as many as summary.json counts.
    let sum: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(out.join("innovations.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t_s,source,rows,y1,y2,y3,nis,gate,outcome"
    );
    let mut per_source = std::collections::BTreeMap::<String, usize>::new();
    let mut last_t = f64::NEG_INFINITY;
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        let t: f64 = f[0].parse().unwrap();
        assert!(t >= last_t, "time order");
        last_t = t;
        assert!(
            !in_outage(t) || t < 243350.5,
            "an update inside the outage at {t}"
        );
        assert_eq!(f[2], "3");
        let nis: f64 = f[6].parse().unwrap();
        assert!(nis.is_finite() && nis >= 0.0);
        if f[8] == "applied" {
            *per_source.entry(f[1].to_string()).or_default() += 1;
        }
    }
    for (src, n) in &per_source {
        assert_eq!(
            sum["aiding_used"][src].as_u64(),
            Some(*n as u64),
            "{src}: innovations.csv against summary.json"
        );
    }
    assert!(per_source.contains_key("gnss_position"));

    // states.csv: the forward run's extra states (the demo estimates the time offset
    // and the GNSS fix bias), one row per output epoch.
    let states_csv = std::fs::read_to_string(out.join("states.csv")).unwrap();
    let header = states_csv.lines().next().unwrap();
    assert!(header.starts_with("gps_week,gps_sow,"), "{header}");
    assert!(
        header.contains("gnss_fix_bias_n_m,sd_gnss_fix_bias_n_m"),
        "{header}"
    );
    // At most one row per 0.1 s of GPS time (all of the demo's 10 Hz epochs).
    let buckets: Vec<i64> = states_csv
        .lines()
        .skip(1)
        .map(|l| {
            (l.split(',').nth(1).unwrap().parse::<f64>().unwrap() * 10.0 + 1e-5).floor() as i64
        })
        .collect();
    assert!(buckets.windows(2).all(|w| w[0] < w[1]), "one row per 0.1 s");
    assert!(
        buckets.len() <= st.len() && buckets.len() * 100 >= st.len() * 95,
        "{} rows",
        buckets.len()
    );
    let files = sum["files"].as_array().unwrap();
    for f in ["states.csv", "innovations.csv"] {
        assert!(
            files.iter().any(|p| p.as_str().unwrap().ends_with(f)),
            "{f} listed"
        );
    }
    // config.toml repeats the run (the outage from the command line included).
    let again = dir.join("again");
    navfuse_ok(&[
        "run",
        out.join("config.toml").to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
        "-q",
    ]);
    for f in ["solution.nav", "innovations.csv", "states.csv"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(again.join(f)).unwrap(),
            "{f} from config.toml"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
