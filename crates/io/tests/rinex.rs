//! RINEX navigation and observation readers/writers: round trips, versions, errors.

use nalgebra::Vector3;
use navfuse_gnss::{GpsEphemeris, GpsTime, GpstCalendar};
use navfuse_io::rinex_nav::{read_rinex_nav, write_rinex3_nav};
use navfuse_io::rinex_obs::{
    read_rinex3_obs, read_rinex_obs, ObsEpoch, ObsHeader, RinexObsWriter, SatObs,
};
use std::path::{Path, PathBuf};

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
    // A last record cut by the end of the file is dropped with a warning.
    let n = read_rinex_nav(&p).unwrap();
    assert!(n.gps.is_empty());
    let w = n.warnings.join("\n");
    assert!(
        w.contains(":6: damaged last line dropped (file cut mid-write?): GPS record truncated"),
        "{w}"
    );
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

// ---- RINEX 2.10/2.11 observations (fixtures in tests/data, see its README.md) ----

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn gpst(y: i32, mo: u32, d: u32, h: u32, mi: u32, s: f64) -> GpsTime {
    GpsTime::from_calendar(&GpstCalendar {
        year: y,
        month: mo,
        day: d,
        hour: h,
        minute: mi,
        second: s,
    })
    .unwrap()
}

fn sat(e: &ObsEpoch, prn: u8) -> &SatObs {
    e.sats.iter().find(|s| s.prn == prn).unwrap()
}

#[test]
fn reads_rinex211_hand_file() {
    let e = read_rinex_obs(&data("hand_v211.obs")).unwrap();
    // The event (flag 4) and the cycle-slip record (flag 6) are skipped.
    assert_eq!(e.len(), 2);

    let e0 = &e[0];
    assert_eq!(e0.t, gpst(2025, 8, 28, 18, 0, 0.0));
    assert_eq!(e0.flag, 0);
    assert_eq!(e0.rx_clock_offset_s, Some(-0.000123456));
    // 14 satellites on two lines, R21 skipped, `  7` is GPS; file order kept.
    let prns: Vec<u8> = e0.sats.iter().map(|s| s.prn).collect();
    assert_eq!(prns, [5, 7, 8, 10, 12, 13, 15, 18, 23, 24, 27, 29, 32]);
    // C1 (not P1) is the pseudorange; types are found wherever the header puts them
    // (D1 is on each satellite's second line).
    assert_eq!(
        *sat(e0, 5),
        SatObs {
            prn: 5,
            pseudorange_m: Some(20_576_396.770),
            carrier_cycles: Some(108_129_693.934),
            doppler_hz: Some(1_064.326),
            cn0_dbhz: Some(51.0),
            lli: 1,
        }
    );
    assert_eq!(
        *sat(e0, 7),
        SatObs {
            prn: 7,
            pseudorange_m: Some(21_875_361.121),
            carrier_cycles: Some(114_955_809.983),
            doppler_hz: Some(-2_668.175),
            cn0_dbhz: Some(36.0),
            lli: 0,
        }
    );
    // Only L2/P2/D2/S2: every L1 observable blank.
    assert_eq!(
        *sat(e0, 8),
        SatObs {
            prn: 8,
            pseudorange_m: None,
            carrier_cycles: None,
            doppler_hz: None,
            cn0_dbhz: None,
            lli: 0,
        }
    );
    // Second observation line empty: D1 absent; LLI 5 (lost lock + AS in RINEX 2).
    let g10 = sat(e0, 10);
    assert_eq!(
        (
            g10.pseudorange_m,
            g10.carrier_cycles,
            g10.doppler_hz,
            g10.cn0_dbhz,
            g10.lli
        ),
        (
            Some(20_675_528.834),
            Some(108_650_635.858),
            None,
            Some(47.0),
            5
        )
    );
    let g12 = sat(e0, 12);
    assert_eq!(
        (g12.doppler_hz, g12.cn0_dbhz, g12.lli),
        (Some(-1_375.564), None, 2)
    );
    // Satellites of the continuation line.
    let g32 = sat(e0, 32);
    assert_eq!(
        (g32.pseudorange_m, g32.carrier_cycles, g32.lli),
        (Some(25_760_672.070), Some(135_373_218.079), 1)
    );
    assert_eq!(sat(e0, 29).doppler_hz, Some(2_175.723));

    let e1 = &e[1];
    assert_eq!(e1.t, gpst(2025, 8, 28, 18, 0, 1.0));
    assert_eq!(e1.flag, 1);
    assert_eq!(e1.rx_clock_offset_s, None);
    assert_eq!(e1.sats.len(), 2);
    assert_eq!(
        e1.sats[0],
        SatObs {
            prn: 5,
            pseudorange_m: Some(20_576_346.113),
            carrier_cycles: Some(108_129_427.738),
            doppler_hz: Some(1_064.871),
            cn0_dbhz: Some(50.0),
            lli: 1,
        }
    );
    assert_eq!(
        e1.sats[1],
        SatObs {
            prn: 7,
            pseudorange_m: Some(21_875_488.073),
            carrier_cycles: Some(114_956_476.929),
            doppler_hz: None,
            cn0_dbhz: None,
            lli: 0,
        }
    );
}

#[test]
fn v2_and_v3_of_the_same_epochs_agree() {
    // walk_0827: 3 epochs as written by the receiver converter (3.04) and as converted
    // to 2.11 by RTKLIB convbin.
    let v3 = read_rinex_obs(&data("walk_0827_3ep_v304.obs")).unwrap();
    let v2 = read_rinex_obs(&data("walk_0827_3ep_v211.obs")).unwrap();
    assert_eq!(
        v3,
        read_rinex3_obs(&data("walk_0827_3ep_v304.obs")).unwrap()
    );
    assert_eq!(v2, v3);
    assert_eq!(v2.len(), 3);
    assert_eq!(v2[0].t, gpst(2025, 8, 28, 17, 30, 39.748));
    assert_eq!(v2[2].t, gpst(2025, 8, 28, 17, 30, 40.248));
    for e in &v2 {
        let prns: Vec<u8> = e.sats.iter().map(|s| s.prn).collect();
        assert_eq!(prns, [10, 18, 23, 27, 32, 24, 8]); // G08 on the continuation line
        let g08 = sat(e, 8);
        assert!(g08.pseudorange_m.is_none() && g08.carrier_cycles.is_none());
    }
    let g10 = sat(&v2[0], 10);
    assert_eq!(
        (
            g10.pseudorange_m,
            g10.carrier_cycles,
            g10.doppler_hz,
            g10.cn0_dbhz,
            g10.lli
        ),
        (
            Some(20_576_396.770),
            Some(108_129_693.934),
            Some(1_064.326),
            Some(51.0),
            1
        )
    );
}

#[test]
fn v2_read_v3_write_read_round_trip() {
    let v2 = read_rinex_obs(&data("hand_v211.obs")).unwrap();
    let mut w = RinexObsWriter::new(Vec::new(), &obs_header()).unwrap();
    for e in &v2 {
        w.write_epoch(e.t, &e.sats).unwrap();
    }
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    let v3 = read_rinex_obs(&tmp("hand_rt.rnx", &text)).unwrap();
    // The writer writes flag 0 and no receiver clock offset; all else is identical.
    let strip = |e: &[ObsEpoch]| -> Vec<ObsEpoch> {
        e.iter()
            .map(|e| ObsEpoch {
                flag: 0,
                rx_clock_offset_s: None,
                ..e.clone()
            })
            .collect()
    };
    assert_eq!(strip(&v3), strip(&v2));
}

fn v2_header(types: &[&str]) -> String {
    let hdr = |s: &str, l: &str| format!("{s:<60}{l}\n");
    let mut t = hdr(
        "     2.10           OBSERVATION DATA    G (GPS)",
        "RINEX VERSION / TYPE",
    );
    let mut line = format!("{:6}", types.len());
    for ty in types {
        line += &format!("{ty:>6}");
    }
    t += &hdr(&line, "# / TYPES OF OBSERV");
    t += &hdr("", "END OF HEADER");
    t
}

#[test]
fn v2_two_digit_years_pivot_at_80() {
    let mut t = v2_header(&["C1"]);
    for yy in ["80", "99", "00", "79"] {
        t += &format!(" {yy}  6 30 12  0  0.0000000  0  1G01\n");
        t += "  20000000.000\n";
    }
    let e = read_rinex_obs(&tmp("years.obs", &t)).unwrap();
    let years: Vec<i32> = e.iter().map(|e| e.t.to_calendar().year).collect();
    assert_eq!(years, [1980, 1999, 2000, 2079]);
    assert_eq!(e[2].t, gpst(2000, 6, 30, 12, 0, 0.0));
}

#[test]
fn v2_event_can_redefine_observation_types() {
    let mut t = v2_header(&["C1", "L1"]);
    t += " 25  8 28 18  0  0.0000000  0  1G01\n";
    t += "  20000000.000   100000000.000\n";
    // Flag 4: header records follow; the new list swaps the two types and adds one.
    t += "                            4  2\n";
    t += &format!("{:<60}{}\n", "new list", "COMMENT");
    t += &format!(
        "{:<60}{}\n",
        "     3    L1    S1    C1", "# / TYPES OF OBSERV"
    );
    t += " 25  8 28 18  0  1.0000000  0  1G01\n";
    t += &format!(
        "{:14.3}2 {:14.3}  {:14.3}\n",
        100_000_005.0, 45.0, 20_000_001.0
    );
    let e = read_rinex_obs(&tmp("redef.obs", &t)).unwrap();
    assert_eq!(e.len(), 2);
    let (a, b) = (&e[0].sats[0], &e[1].sats[0]);
    assert_eq!(
        (a.pseudorange_m, a.carrier_cycles, a.cn0_dbhz),
        (Some(20_000_000.0), Some(100_000_000.0), None)
    );
    assert_eq!(
        (b.pseudorange_m, b.carrier_cycles, b.cn0_dbhz, b.lli),
        (Some(20_000_001.0), Some(100_000_005.0), Some(45.0), 2)
    );
}

/// The hand-made file with `edit` applied to its (1-based) line `ln`.
fn hand_edited(name: &str, ln: usize, edit: impl Fn(&str) -> String) -> PathBuf {
    let text = std::fs::read_to_string(data("hand_v211.obs")).unwrap();
    let mut out = String::new();
    for (k, l) in text.lines().enumerate() {
        if k + 1 == ln {
            out += &edit(l);
        } else {
            out += l;
        }
        out.push('\n');
    }
    tmp(name, &out)
}

fn err_of(p: &Path) -> String {
    read_rinex_obs(p).unwrap_err().to_string()
}

#[test]
fn v2_errors_name_line_and_field() {
    let cases: Vec<(PathBuf, &str)> = vec![
        (
            hand_edited("e1.obs", 14, |l| l.replacen("20576396.770", "2057x396.770", 1)),
            ":14: field 'G05 C1': expected a number, found \"2057x396.770\"",
        ),
        (
            hand_edited("e2.obs", 22, |l| l.replacen(".85857", ".858x7", 1)),
            ":22: field 'G10 L1 LLI': expected a blank or a digit 0-7, found \"x\"",
        ),
        (
            hand_edited("e3.obs", 12, |l| l.replacen("G10", "G1x", 1)),
            ":12: field 'satellite list': satellite 5 of 14 (columns 45-47): expected a \
             system letter (blank = GPS) and a 2-digit number, found \"G1x\"",
        ),
        (
            hand_edited("e4.obs", 48, |l| l.trim_end_matches("  7").to_string()),
            ":48: field 'satellite list': expected satellite 3 of 3 in columns 39-41, found a blank",
        ),
        (
            hand_edited("e5.obs", 13, |_| "   G29G32".to_string()),
            ":13: expected a continuation of the satellite list of line 12 (32 blanks, then \
             satellites 13-14), found \"   G29G32\"",
        ),
        (
            hand_edited("e6.obs", 8, |l| l.replacen("    10", "    11", 1)),
            ":9: field '# / TYPES OF OBSERV': the number of types (11, columns 1-6) does not \
             match the types listed (10: P1 L1 C1 S1 L2 P2 D1 D2 S2 C5)",
        ),
        (
            hand_edited("e7.obs", 9, |l| l.replacen("     ", "    2", 1)),
            ":8: field '# / TYPES OF OBSERV': the number of types (10, columns 1-6) does \
             not match the types listed (9: P1 L1 C1 S1 L2 P2 D1 D2 S2)",
        ),
        (
            hand_edited("e8.obs", 12, |l| l.replacen(" 25  8", " 25 13", 1)),
            ":12: field 'month': expected 1..12, found 13",
        ),
        (
            hand_edited("e9.obs", 48, |l| l.replacen("1.0000000  1", "1.0000000  x", 1)),
            ":48: field 'epoch flag': expected an integer, found \"x\"",
        ),
        (
            hand_edited("e10.obs", 48, |l| l.replacen(" 1.0000000", "  1.00.000", 1)),
            ":48: field 'second': expected a number, found \"1.00.000\"",
        ),
        (
            hand_edited("e11.obs", 12, |l| l.replacen("-0.000123456", "-0.00012345x", 1)),
            ":12: field 'receiver clock offset': expected a number, found \"-0.00012345x\"",
        ),
        (
            hand_edited("e12.obs", 12, |l| l.replacen("G05", "G64", 1)),
            ":12: field 'satellite list': satellite 1 of 14: expected a GPS PRN 1..63, found 64",
        ),
        (
            hand_edited("e13.obs", 12, |l| l.replacen(" 25  8 28", " 25  2 30", 1)),
            ":12: field 'epoch': expected a valid GPST date and time, found 2025-02-30 18:00:0",
        ),
        (
            hand_edited("e14.obs", 42, |l| l.replacen("4  2", "4  3", 1)),
            // The 3rd "header record" is the flag 6 epoch line; then the epoch's
            // observation line is read as an epoch line.
            ":46: field 'year': expected an integer, found \"\"",
        ),
        (
            hand_edited("e15.obs", 1, |l| l.replacen("2.11", "5.00", 1)),
            ":1: field 'RINEX version': version 5 is not supported (2.xx, 3.0x and 4.0x are)",
        ),
        (
            hand_edited("e16.obs", 1, |l| l.replacen("OBSERVATION DATA", "NAVIGATION DATA ", 1)),
            ":1: field 'file type': expected an observation file (type O in column 21), \
             found \"N\"",
        ),
        (
            hand_edited("e17.obs", 8, |l| l.replacen("TYPES OF OBSERV", "TYPES OF OBS   ", 1)),
            ":9: field '# / TYPES OF OBSERV': expected the number of observation types in \
             columns 1-6",
        ),
        (
            hand_edited("e18.obs", 1, |l| {
                format!("{:<60}CRINEX VERS   / TYPE", &l[..20])
            }),
            // Compact RINEX is read now: a version it does not know is refused.
            ":1: cannot read: Compact RINEX line 1: CRINEX version 2.11 (1.0 and 3.0 are read)",
        ),
    ];
    for (p, want) in &cases {
        let err = err_of(p);
        assert!(err.contains(want), "want {want}\n got {err}");
        assert!(err.starts_with(&p.display().to_string()), "{err}");
    }

    // No type list at all.
    let p = tmp(
        "notypes.obs",
        &v2_header(&["C1"]).replace("# / TYPES OF OBSERV", "COMMENT"),
    );
    assert!(
        err_of(&p).ends_with(
            "field '# / TYPES OF OBSERV': expected a '# / TYPES OF OBSERV' header record, \
             found none"
        ),
        "{}",
        err_of(&p)
    );
    // Truncated inside an epoch: the epoch line is named.
    let text = std::fs::read_to_string(data("hand_v211.obs")).unwrap();
    let cut = |n: usize| text.lines().take(n).collect::<Vec<_>>().join("\n") + "\n";
    let err = err_of(&tmp("cut30.obs", &cut(30)));
    assert!(
        err.contains(
            ":12: epoch truncated: expected 2 observation lines for each of 14 \
                      satellites, the file ends in those of G18"
        ),
        "{err}"
    );
    let err = err_of(&tmp("cut12.obs", &cut(12)));
    assert!(
        err.contains(":12: epoch truncated: 14 satellites need 2"),
        "{err}"
    );
    let err = err_of(&tmp("cut43.obs", &cut(43)));
    assert!(
        err.contains(":42: event truncated: expected 2 header records"),
        "{err}"
    );
    let err = err_of(&tmp("cut45.obs", &cut(45)));
    assert!(
        err.contains(":45: epoch truncated: expected 2 cycle-slip"),
        "{err}"
    );
    let err = err_of(&tmp("cut10.obs", &cut(10)));
    assert!(err.ends_with(": no 'END OF HEADER' line"), "{err}");
    // read_rinex3_obs stays RINEX 3 only and says where 2.xx is read.
    let err = read_rinex3_obs(&data("hand_v211.obs"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(
            ":1: field 'RINEX version': version 2.11 is not supported (3.0x and 4.0x \
                      are; read_rinex_obs also reads 2.10/2.11)"
        ),
        "{err}"
    );
}

#[test]
fn v2_malformed_input_never_panics() {
    // Every line cut at every column, and every character replaced by 'x' or a blank
    // (a byte stride keeps the run short): the reader returns Ok or Err, never panics.
    let text = std::fs::read_to_string(data("hand_v211.obs")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut n_err = 0;
    for (i, l) in lines.iter().enumerate() {
        for cut in (0..l.len()).step_by(3) {
            let mut v = lines.clone();
            let short = &l[..cut];
            v[i] = short;
            if read_rinex_obs(&tmp("cut.obs", &(v.join("\n") + "\n"))).is_err() {
                n_err += 1;
            }
        }
    }
    let bytes = text.as_bytes();
    for k in (0..bytes.len()).step_by(5) {
        if bytes[k] == b'\n' {
            continue;
        }
        for c in [b'x', b' '] {
            let mut b = bytes.to_vec();
            b[k] = c;
            let p = tmp("subst.obs", std::str::from_utf8(&b).unwrap());
            if read_rinex_obs(&p).is_err() {
                n_err += 1;
            }
        }
        // The file cut after byte k.
        let p = tmp("prefix.obs", std::str::from_utf8(&bytes[..k]).unwrap());
        let _ = read_rinex_obs(&p);
    }
    assert!(n_err > 100, "{n_err}");
}
