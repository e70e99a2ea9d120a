//! RINEX navigation and observation readers/writers: round trips, versions, errors.

use nalgebra::Vector3;
use navfuse_gnss::{GpsEphemeris, GpsTime};
use navfuse_io::rinex_nav::{read_rinex_nav, write_rinex3_nav};
use navfuse_io::rinex_obs::{read_rinex3_obs, ObsHeader, RinexObsWriter, SatObs};
use std::path::PathBuf;

fn tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("navfuse_rinex_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn real_nav() -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/rtklibexplorer/walk_0827/derived_rinex/gnss_1730.nav");
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skip: {} not found", p.display());
        None
    }
}

const V2: &str = "     2.11           N: GPS NAV DATA                         RINEX VERSION / TYPE
    0.1118D-07  0.1490D-07 -0.5960D-07 -0.1192D-06          ION ALPHA
    0.1147D+06  0.8192D+05 -0.1311D+06 -0.5243D+06          ION BETA
    18                                                      LEAP SECONDS
                                                            END OF HEADER
32 25  8 28 18  0  0.0-3.444845788180D-04 1.318767317570D-11 0.000000000000D+00
    8.300000000000D+01-1.678125000000D+01 4.714482091390D-09 2.734801783810D+00
   -8.977949619290D-07 8.634285419250D-03 5.612149834630D-06 5.153645277020D+03
    4.104000000000D+05 1.117587089540D-08 2.244920214390D+00-1.620501279830D-07
    9.657819927190D-01 2.717187500000D+02-2.061259292040D+00-7.959974422030D-09
    9.714690370130D-11 1.000000000000D+00 2.381000000000D+03 0.000000000000D+00
    2.000000000000D+00 0.000000000000D+00 9.313225746150D-10 8.300000000000D+01
    4.087560000000D+05 4.000000000000D+00
";

#[test]
fn reads_rinex2_gps_nav() {
    let p = tmp("v2.nav", V2);
    let nav = read_rinex_nav(&p).unwrap();
    assert_eq!(nav.gps.len(), 1);
    let e = &nav.gps[0];
    assert_eq!(e.prn, 32);
    assert_eq!((e.toc.week, e.toc.sow), (2381, 410_400.0));
    assert_eq!((e.toe.week, e.toe.sow), (2381, 410_400.0));
    assert_eq!(e.af0_s, -3.444845788180e-4);
    assert_eq!(e.sqrt_a_sqrt_m, 5.153645277020e3);
    assert_eq!(e.iode, 83);
    assert_eq!(e.transmission_time, Some(GpsTime::new(2381, 408_756.0)));
    assert_eq!(
        nav.iono_alpha,
        Some([0.1118e-7, 0.1490e-7, -0.5960e-7, -0.1192e-6])
    );
    assert_eq!(nav.iono_beta.map(|b| b[0]), Some(0.1147e6));
    assert_eq!(nav.leap_seconds, Some(18));
}

#[test]
fn nav_write_read_round_trip() {
    let p = tmp("v2b.nav", V2);
    let mut nav = read_rinex_nav(&p).unwrap();
    let mut e2: GpsEphemeris = nav.gps[0].clone();
    e2.prn = 7;
    e2.af2_s_per_s2 = -1.5e-19;
    e2.health = 1;
    e2.transmission_time = None;
    e2.toe = GpsTime::new(2382, 0.0);
    e2.toc = e2.toe;
    nav.gps.push(e2);
    let mut buf = Vec::new();
    write_rinex3_nav(&mut buf, &nav, "navfuse test").unwrap();
    let text = String::from_utf8(buf).unwrap();
    for line in text.lines() {
        assert!(line.len() <= 80, "line too long: {line}");
    }
    let q = tmp("rt.rnx", &text);
    let back = read_rinex_nav(&q).unwrap();
    assert_eq!(back.iono_alpha.map(|a| a[3]), nav.iono_alpha.map(|a| a[3]));
    assert_eq!(back.leap_seconds, Some(18));
    assert_eq!(back.gps.len(), 2);
    for (a, b) in nav.gps.iter().zip(&back.gps) {
        assert_eq!(a.prn, b.prn);
        assert_eq!(a.toc, b.toc);
        assert_eq!(a.toe, b.toe);
        assert_eq!(a.health, b.health);
        assert_eq!(a.transmission_time, b.transmission_time);
        let rel = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(1e-300);
        for (x, y) in [
            (a.af0_s, b.af0_s),
            (a.af2_s_per_s2, b.af2_s_per_s2),
            (a.m0_rad, b.m0_rad),
            (a.omega_dot_rad_per_s, b.omega_dot_rad_per_s),
            (a.crc_m, b.crc_m),
            (a.tgd_s, b.tgd_s),
        ] {
            assert!(rel(x, y), "{x} vs {y}");
        }
        let t = a.toe.add_s(1_800.0);
        assert!((a.sat_state(t).pos_ecef_m - b.sat_state(t).pos_ecef_m).norm() < 1e-4);
    }
}

#[test]
fn mixed_v3_skips_other_systems() {
    let Some(p) = real_nav() else { return };
    let nav = read_rinex_nav(&p).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    let count = |c: char| {
        text.lines()
            .filter(|l| l.starts_with(c) && l.as_bytes().get(1).is_some_and(u8::is_ascii_digit))
            .count()
    };
    assert_eq!(nav.gps.len(), count('G'));
    assert_eq!(
        nav.skipped_records,
        count('C') + count('S') + count('R') + count('E') + count('J')
    );
    assert!(nav.gps.iter().all(|e| e.toe.week == 2381 && e.health == 0));
}

fn header_v3() -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "{:<60}{}\n",
        "     3.04           N: GNSS NAV DATA    M: Mixed", "RINEX VERSION / TYPE"
    ));
    s.push_str(&format!("{:<60}{}\n", "", "END OF HEADER"));
    s
}

#[test]
fn nav_errors_name_line_and_field() {
    let p = tmp(
        "v2bad.nav",
        &V2.replace("5.153645277020D+03", "5.15364527x020D+3"),
    );
    let err = read_rinex_nav(&p).unwrap_err().to_string();
    assert!(
        err.contains(":8: field 'sqrt(A)': expected a number"),
        "{err}"
    );
    let p = tmp(
        "v2trunc.nav",
        &V2.lines().take(9).collect::<Vec<_>>().join("\n"),
    );
    let err = read_rinex_nav(&p).unwrap_err().to_string();
    assert!(err.contains(":6: GPS record truncated"), "{err}");
    let p = tmp(
        "v3x.nav",
        &format!("{}X01 2025 08 28 18 00 00\n", header_v3()),
    );
    let err = read_rinex_nav(&p).unwrap_err().to_string();
    assert!(err.contains(":3: field 'satellite system'"), "{err}");
    let p = tmp("v4.nav", &header_v3().replace("3.04", "4.01"));
    let err = read_rinex_nav(&p).unwrap_err().to_string();
    assert!(err.contains("not supported"), "{err}");
    let p = tmp("nohdr.nav", "hello\n");
    let err = read_rinex_nav(&p).unwrap_err().to_string();
    assert!(err.contains(":1: expected 'RINEX VERSION / TYPE'"), "{err}");
    let err = read_rinex_nav(&PathBuf::from("/nonexistent/x.nav"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("cannot open"), "{err}");
}

fn obs_header() -> ObsHeader {
    ObsHeader {
        marker_name: "SIM".into(),
        approx_pos_ecef_m: Vector3::new(-3_961_904.9, 3_348_993.8, 3_698_211.8),
        antenna_delta_hen_m: Vector3::new(0.1, 0.0, 0.0),
        interval_s: Some(1.0),
        first_obs: GpsTime::new(2381, 410_400.0),
        receiver: ["1".into(), "NAVFUSE SIM".into(), "0.1".into()],
        antenna: ["1".into(), "SIMANT".into()],
        program: "navfuse".into(),
        date: None,
    }
}

#[test]
fn obs_round_trip() {
    let h = obs_header();
    let mut w = RinexObsWriter::new(Vec::new(), &h).unwrap();
    let epochs: Vec<(GpsTime, Vec<SatObs>)> = (0..3)
        .map(|k| {
            let t = h.first_obs.add_s(f64::from(k) + 0.5);
            let sats = vec![
                SatObs {
                    prn: 3,
                    pseudorange_m: Some(21_000_123.456 + f64::from(k)),
                    carrier_cycles: Some(110_358_901.234),
                    doppler_hz: Some(-1_234.567),
                    cn0_dbhz: Some(44.0),
                    lli: if k == 1 { 1 } else { 0 },
                },
                SatObs {
                    prn: 27,
                    pseudorange_m: Some(24_500_000.001),
                    carrier_cycles: None,
                    doppler_hz: Some(3_000.0),
                    cn0_dbhz: None,
                    lli: 0,
                },
            ];
            (t, sats)
        })
        .collect();
    for (t, s) in &epochs {
        w.write_epoch(*t, s).unwrap();
    }
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    assert!(
        text.contains("G03  21000124.456 7 110358901.23417     -1234.567 7        44.000 7"),
        "{text}"
    );
    let p = tmp("rt.obs", &text);
    let back = read_rinex3_obs(&p).unwrap();
    assert_eq!(back.len(), 3);
    for ((t, sats), e) in epochs.iter().zip(&back) {
        assert!(e.t.diff_s(t).abs() < 1e-9);
        assert_eq!(e.flag, 0);
        assert_eq!(e.sats.len(), 2);
        for (a, b) in sats.iter().zip(&e.sats) {
            assert_eq!(a.prn, b.prn);
            assert_eq!(a.lli, b.lli);
            for (x, y) in [
                (a.pseudorange_m, b.pseudorange_m),
                (a.carrier_cycles, b.carrier_cycles),
                (a.doppler_hz, b.doppler_hz),
                (a.cn0_dbhz, b.cn0_dbhz),
            ] {
                assert_eq!(x.is_some(), y.is_some());
                if let (Some(x), Some(y)) = (x, y) {
                    assert!((x - y).abs() <= 0.0005 + 1e-9, "{x} vs {y}");
                }
            }
        }
    }
}

#[test]
fn obs_reader_mixed_systems_flags_and_type_order() {
    let hdr = |s: &str, l: &str| format!("{s:<60}{l}\n");
    let mut t = String::new();
    t += &hdr(
        "     3.04           OBSERVATION DATA    M: Mixed",
        "RINEX VERSION / TYPE",
    );
    t += &hdr("R    2 C1C L1C", "SYS / # / OBS TYPES");
    t += &hdr("G    3 S1C D1C C1C", "SYS / # / OBS TYPES");
    t += &hdr("", "END OF HEADER");
    t += "> 2025 08 28 18 00  0.0000000  0  2\n";
    t += "R05  20000000.000    100000000.000\n";
    t += &format!("G12{:14.3}  {:14.3}  {:14.3}\n", 40.25, -99.5, 22_000_000.5);
    t += "> 2025 08 28 18 00  1.0000000  4  1\n";
    t += &hdr("", "COMMENT");
    t += "> 2025 08 28 18 00  2.0000000  1  1\n";
    t += &format!("G12{:14.3}  {:14}  {:14.3}\n", 41.0, "", 22_000_001.0);
    let p = tmp("mixed.obs", &t);
    let e = read_rinex3_obs(&p).unwrap();
    assert_eq!(e.len(), 2);
    assert_eq!(e[0].sats.len(), 1);
    let s = &e[0].sats[0];
    assert_eq!(
        (s.prn, s.cn0_dbhz, s.doppler_hz, s.pseudorange_m),
        (12, Some(40.25), Some(-99.5), Some(22_000_000.5))
    );
    assert_eq!(s.carrier_cycles, None);
    assert_eq!(e[1].flag, 1);
    assert_eq!(e[1].sats[0].doppler_hz, None);
    assert!((e[1].t.diff_s(&e[0].t) - 2.0).abs() < 1e-12);

    let bad = t.replace("G12        41.000", "G12        4x.000");
    let p = tmp("bad.obs", &bad);
    let err = read_rinex3_obs(&p).unwrap_err().to_string();
    assert!(err.contains(":11: field 'S1C': expected a number"), "{err}");
    let bad = t.replace("> 2025 08 28 18 00  2.0000000  1  1\n", "2025 08 28\n");
    let err = read_rinex3_obs(&tmp("bad2.obs", &bad))
        .unwrap_err()
        .to_string();
    assert!(err.contains(":10: expected an epoch line"), "{err}");
}
