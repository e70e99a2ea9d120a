//! The multi-system navigation reader on the ESBC00DNK 2020-06-25 mixed RINEX 3.05
//! file (every record of every system read or counted), the same records written as
//! RINEX 4.00 (`> EPH` lines, a CNAV record, STO and ION records), and errors that
//! name the file, line and field. Skips with a message when ../shared is missing.

use navfuse_gnss::{GpsTime, SatId, System};
use navfuse_io::rinex_nav::read_rinex_nav;
use std::path::PathBuf;

fn esbc() -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/igs/ESBC00DNK_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
    if p.exists() {
        Some(p)
    } else {
        println!("skipped: {} not found", p.display());
        None
    }
}

fn tmp(name: &str, text: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse_nav_multi_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn count(text: &str, c: char) -> usize {
    text.lines()
        .filter(|l| l.starts_with(c) && l.as_bytes().get(1).is_some_and(u8::is_ascii_digit))
        .count()
}

#[test]
fn mixed_305_every_system() {
    let Some(p) = esbc() else { return };
    let text = std::fs::read_to_string(&p).unwrap();
    let nav = read_rinex_nav(&p).unwrap();
    assert_eq!(nav.gps.len(), count(&text, 'G'));
    assert_eq!(nav.glonass.len(), count(&text, 'R'));
    assert_eq!(nav.galileo.len(), count(&text, 'E'));
    assert_eq!(nav.beidou.len(), count(&text, 'C'));
    assert_eq!(nav.qzss.len(), count(&text, 'J'));
    assert_eq!(nav.skipped.sbas, count(&text, 'S'));
    assert_eq!(nav.leap_seconds, Some(18));
    assert!(nav.iono.galileo_nequick.is_some() && nav.iono_alpha.is_some());
    let store = nav.store();
    let counts = store.counts();
    println!("{counts:?}");
    // Both Galileo messages present; F/NAV and I/NAV told apart by the data sources.
    use navfuse_gnss::GalileoMessage;
    assert!(nav
        .galileo
        .iter()
        .any(|e| e.message() == GalileoMessage::FNav));
    assert!(nav
        .galileo
        .iter()
        .any(|e| e.message() == GalileoMessage::INav));
    // BeiDou toe in BDT week 755 (GPS week 2111); GLONASS tb = UTC + 18 s.
    assert!(nav
        .beidou
        .iter()
        .all(|e| e.toe.week == 755 || e.toe.week == 756));
    let r01 = &nav.glonass[0];
    assert_eq!(r01.slot, 1);
    assert_eq!(r01.tb, GpsTime::new(2111, 342_900.0 + 18.0));
    // Every system has a state at 01:00 GPST for some satellite.
    let t = GpsTime::new(2111, 345_600.0 + 3_600.0);
    for sys in [
        System::Gps,
        System::Glonass,
        System::Galileo,
        System::BeiDou,
        System::Qzss,
    ] {
        let n = store
            .sats()
            .into_iter()
            .filter(|s| s.system == sys && store.sat_state(*s, t).is_some())
            .count();
        assert!(n > 0, "{}", sys.name());
        println!("{}: {n} satellites with a state at 01:00", sys.name());
    }
    // GEOs (C01-C05): nearly fixed over the Earth (ECEF speed far below a MEO's km/s).
    let mut geos = 0;
    for prn in 1..=5 {
        if let Some((st, _)) = store.sat_state(SatId::new(System::BeiDou, prn), t) {
            assert!(
                st.vel_ecef_mps.norm() < 300.0,
                "C0{prn}: {}",
                st.vel_ecef_mps.norm()
            );
            geos += 1;
        }
    }
    assert!(geos > 0);
}

/// The first record of each system, written as RINEX 4.00, plus a CNAV record, an
/// STO record and ION records.
#[test]
fn rinex4_records() {
    let Some(p) = esbc() else { return };
    let text = std::fs::read_to_string(&p).unwrap();
    let v3 = read_rinex_nav(&p).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let end = lines
        .iter()
        .position(|l| l.contains("END OF HEADER"))
        .unwrap();
    let mut out = String::from(
        "     4.00           NAVIGATION DATA     M                   RINEX VERSION / TYPE\n",
    );
    for l in &lines[1..=end] {
        if !l.contains("IONOSPHERIC CORR") {
            out.push_str(l);
            out.push('\n');
        }
    }
    let rec = |c: char, n: usize| -> Vec<&str> {
        let i = lines
            .iter()
            .position(|l| l.starts_with(c) && l.as_bytes()[1].is_ascii_digit())
            .unwrap();
        lines[i..i + n].to_vec()
    };
    for (c, msg, n) in [
        ('G', "LNAV", 8),
        ('E', "INAV", 8),
        ('C', "D1", 8),
        ('R', "FDMA", 5),
        ('J', "LNAV", 8),
    ] {
        let r = rec(c, n);
        out.push_str(&format!("> EPH {} {msg}\n", &r[0][..3]));
        for l in r {
            out.push_str(l);
            out.push('\n');
        }
    }
    out.push_str("> EPH G01 CNAV\n");
    for _ in 0..9 {
        out.push_str("    1.0\n");
    }
    out.push_str("> STO G01 LNAV\n    2020 06 25 00 00 00 GPUT\n    1.0 2.0 3.0 4.0\n");
    out.push_str("> ION G01 LNAV\n    2020 06 25 00 00 00 4.656612873077e-09 1.490116119385e-08-5.960464477539e-08\n    -1.192092895508e-07 8.192000000000e+04 9.830400000000e+04-6.553600000000e+04\n    -5.242880000000e+05 1.000000000000e+00\n");
    out.push_str("> ION E01 IFNV\n    2020 06 25 00 00 00 2.825000000000e+01 7.812500000000e-03 1.007080078125e-02\n     0.000000000000e+00\n");
    let q = tmp("v4.rnx", &out);
    let v4 = read_rinex_nav(&q).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v4.gps[0], v3.gps[0]);
    assert_eq!(v4.galileo[0], v3.galileo[0]);
    assert_eq!(v4.beidou[0], v3.beidou[0]);
    assert_eq!(v4.glonass[0], v3.glonass[0]);
    assert_eq!(v4.qzss[0], v3.qzss[0]);
    assert_eq!(v4.skipped.other_messages, 1);
    assert_eq!(v4.skipped.sto_eop, 1);
    assert_eq!(v4.iono_alpha.unwrap()[0], 4.656612873077e-09);
    assert_eq!(v4.iono_beta.unwrap()[3], -5.24288e5);
    assert_eq!(v4.iono.galileo_nequick.unwrap()[0], 28.25);
    // Errors name the line and field.
    let bad = out.replacen("> EPH E", "> EPH X", 1);
    let err = read_rinex_nav(&tmp("v4bad.rnx", &bad))
        .unwrap_err()
        .to_string();
    assert!(err.contains("field 'record type': unknown record"), "{err}");
    let bad = out.replacen("> STO", "STO  ", 1);
    let err = read_rinex_nav(&tmp("v4bad2.rnx", &bad))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("field 'record type': expected a '> EPH'"),
        "{err}"
    );
}

#[test]
fn other_system_errors_name_line_and_field() {
    let Some(p) = esbc() else { return };
    let text = std::fs::read_to_string(&p).unwrap();
    // Break the first Galileo record's sqrt(A) (line 3071 - 5 = its orbit line 2).
    let i = text.find("\nE01 ").unwrap();
    let ln = text[..i].lines().count() + 1 + 2;
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[ln - 1] = lines[ln - 1].replacen("5.440602037430e+03", "5.44060203x430e+03", 1);
    let err = read_rinex_nav(&tmp("bad_gal.rnx", &lines.join("\n")))
        .unwrap_err()
        .to_string();
    assert!(err.contains(&format!(":{ln}: field 'sqrt(A)'")), "{err}");
}

/// On real data the store picks, for GPS, exactly the record `EphemerisSet` picks.
#[test]
fn store_keeps_the_gps_selection() {
    let Some(p) = esbc() else { return };
    let nav = read_rinex_nav(&p).unwrap();
    let set = navfuse_gnss::EphemerisSet::new(nav.gps.clone());
    let store = nav.store();
    let mut n = 0;
    for k in 0..(24 * 6) {
        let t = GpsTime::new(2111, 345_600.0 + 600.0 * f64::from(k) + 0.3);
        for prn in set.prns() {
            let a = set.select(prn, t);
            let b = store.select(SatId::gps(prn), t);
            match (a, b) {
                (Some(a), Some(navfuse_gnss::Ephemeris::Gps(b))) => assert_eq!(a, b),
                (None, None) => {}
                other => panic!("G{prn:02} at {t:?}: {other:?}"),
            }
            n += usize::from(a.is_some());
        }
    }
    assert!(n > 1_000, "{n}");
}
