//! Compact RINEX 3.0 by hand: what the decoder expands (the ESBC00DNK full-day
//! file against its plain 3 h cut is in formats_data.rs).

use navfuse_io::rinex_obs::crx_to_rinex;

/// A Compact RINEX header: CRINEX version, RINEX version, the type records
/// (text, label), END OF HEADER.
fn crx_header(crx: &str, rinex: &str, types: &[(&str, &str)]) -> String {
    let hdr = |s: &str, l: &str| format!("{s:<60}{l}\n");
    let mut c = hdr(
        &format!("{crx}                 COMPACT RINEX FORMAT"),
        "CRINEX VERS   / TYPE",
    );
    c += &hdr("hand", "CRINEX PROG / DATE");
    c += &hdr(
        &format!("     {rinex}           OBSERVATION DATA    M"),
        "RINEX VERSION / TYPE",
    );
    for (s, l) in types {
        c += &hdr(s, l);
    }
    c + &hdr("", "END OF HEADER")
}

/// A small Compact RINEX 3.0 file written by hand per Hatanaka's description:
/// arcs of order 3, a blank field, a satellite leaving and coming back, the epoch
/// line and flags as text differences, the clock line.
#[test]
fn crx3_hand_written_expands_to_the_rinex_records() {
    let mut c = crx_header(
        "3.0",
        "3.05",
        &[
            ("G    2 C1C L1C", "SYS / # / OBS TYPES"),
            ("E    1 C5Q", "SYS / # / OBS TYPES"),
        ],
    );
    c += "> 2020 06 25 00 00 00.0000000  0  2      G05E11\n";
    c += "3&123456789\n";
    c += "3&20000000123 3&100000000456 &5 1\n";
    c += "3&25000000000  7\n";
    // Epoch 2: second 30 and one satellite (`&` erases E11), as a text difference.
    c += &format!("{:19}3{:14}1{:9}&&&\n", "", "", "");
    c += "10\n";
    c += "1000 2000  6\n";
    c += &format!("{:20}1{:13}2{:9}E11\n", "", "", "");
    c += "20\n";
    c += "-500    &&\n"; // L1C blank, its flags erased
    c += "3&25000000001\n";
    let out = String::from_utf8(crx_to_rinex(c.as_bytes()).unwrap()).unwrap();
    let body: Vec<&str> = out.lines().skip(4).collect();
    assert_eq!(
        body,
        [
            "> 2020 06 25 00 00 00.0000000  0  2       0.000123456789",
            "G05  20000000.123 5 100000000.456 1",
            "E11  25000000.000 7",
            "> 2020 06 25 00 00 30.0000000  0  1       0.000123456799",
            "G05  20000001.123 6 100000002.456 1",
            "> 2020 06 25 00 00 31.0000000  0  2       0.000123456829",
            "G05  20000001.623 6",
            "E11  25000000.001",
        ]
    );
    // A difference without an arc is an error naming the Compact RINEX line.
    let bad = c.replace("3&25000000001\n", "25000000001\n");
    let e = crx_to_rinex(bad.as_bytes()).unwrap_err().to_string();
    assert!(
        e.contains("Compact RINEX line 17: E11 observation 1: a difference"),
        "{e}"
    );
}

/// The Compact RINEX seed (3 epochs of ESBC00DNK, 43 satellites) reads like the
/// plain file: checked in full against the 3 h file in formats_data.rs; here the
/// counts and one value.
#[test]
fn esbc_3_epochs_crx() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/esbc_3ep.crx");
    let r = navfuse_io::rinex_obs::read_rinex_obs_all(&p).unwrap();
    assert_eq!(r.epochs.len(), 3);
    assert!(r.epochs.iter().all(|e| e.sats.len() == 43));
    let c05 = &r.epochs[0].sats[0];
    assert_eq!(c05.sat.to_string(), "C05");
    let c2i = c05.get(navfuse_gnss::ObsCode(*b"C2I")).unwrap();
    assert_eq!(
        (c2i.value, c2i.lli, c2i.ssi),
        (Some(40715949.461), None, Some(5))
    );
}

/// RINEX 2.11 types are mapped to RINEX 3 codes per system (docs/FORMATS.md "RINEX 2
/// observation codes"): hand_v211.obs has P1 L1 C1 S1 L2 P2 D1 D2 S2 C5 and a
/// GLONASS satellite.
#[test]
fn rinex2_types_map_to_rinex3_codes() {
    use navfuse_gnss::System;
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/hand_v211.obs");
    let r = navfuse_io::rinex_obs::read_rinex_obs_all(&p).unwrap();
    let codes = |s: System| -> Vec<String> {
        let (_, c) = r.header.types.iter().find(|(x, _)| *x == s).unwrap();
        c.iter().map(|c| c.to_string()).collect()
    };
    assert_eq!(
        codes(System::Gps),
        ["C1W", "L1C", "C1C", "S1C", "L2W", "C2W", "D1C", "D2W", "S2W", "C5X"]
    );
    assert_eq!(
        codes(System::Glonass),
        ["C1P", "L1C", "C1C", "S1C", "L2P", "C2P", "D1C", "D2P", "S2P"]
    );
    let e = &r.epochs[0];
    let g05 = &e.sats[0];
    assert_eq!(g05.sat.to_string(), "G05");
    let l1 = g05.get(navfuse_gnss::ObsCode(*b"L1C")).unwrap();
    assert_eq!(
        (l1.value, l1.lli, l1.ssi),
        (Some(108129693.934), Some(1), Some(8))
    );
    assert_eq!(
        g05.get(navfuse_gnss::ObsCode(*b"C1W")).unwrap().value,
        Some(20576397.282)
    );
    assert_eq!(e.sats[2].sat.to_string(), "R21");
    // The GPS L1 C/A view has only GPS satellites.
    let v = e.gps_l1ca();
    assert_eq!(v.sats.len(), e.sats.len() - 1);
    assert_eq!(v.sats[0].pseudorange_m, Some(20576396.770));
}

/// Compact RINEX 1.0 (RINEX 2): `&` starts the epoch line, the satellites follow at
/// column 33, the clock (x 1e9) is on the next line; the expanded text is read by the
/// RINEX 2 reader.
#[test]
fn crx1_hand_written_expands_to_rinex2() {
    let mut c = crx_header(
        "1.0",
        "2.11",
        &[("     2    C1    L1", "# / TYPES OF OBSERV")],
    );
    c += "&25  8 28 18  0  0.0000000  0  2G05R21\n";
    c += "3&-123456\n";
    c += "3&20000000123 3&100000000456   1\n"; // L1 LLI 1
    c += "3&21000000000\n";
    c += &format!("{:17}1\n", ""); // second 1
    c += "7\n";
    c += "1000 2000\n";
    c += "-5\n";
    let out = String::from_utf8(crx_to_rinex(c.as_bytes()).unwrap()).unwrap();
    let body: Vec<&str> = out.lines().skip(3).collect();
    let epoch =
        |s: &str, clk: &str| format!("{:<68}{clk}", format!(" 25  8 28 18  0  {s}  0  2G05R21"));
    assert_eq!(
        body,
        [
            epoch("0.0000000", "-0.000123456").as_str(),
            "  20000000.123   100000000.4561",
            "  21000000.000",
            epoch("1.0000000", "-0.000123449").as_str(),
            "  20000001.123   100000002.4561",
            "  20999999.995",
        ]
    );
    let dir = std::env::temp_dir().join(format!("navfuse_crx1_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("hand.crx");
    std::fs::write(&p, &c).unwrap();
    let r = navfuse_io::rinex_obs::read_rinex_obs_all(&p).unwrap();
    assert_eq!(r.epochs.len(), 2);
    assert_eq!(r.epochs[1].rx_clock_offset_s, Some(-0.000123449));
    assert_eq!(r.epochs[1].sats[1].signals[0].1.value, Some(20999999.995));
    let _ = std::fs::remove_dir_all(&dir);
}
