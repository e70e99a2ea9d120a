//! Compact RINEX 3.0 by hand: what the decoder expands (the ESBC00DNK full-day
//! file against its plain 3 h cut is in formats_data.rs).

use navfuse_io::rinex_obs::crx_to_rinex;

/// A small Compact RINEX 3.0 file written by hand per Hatanaka's description:
/// arcs of order 3, a blank field, a satellite leaving and coming back, the epoch
/// line and flags as text differences, the clock line.
#[test]
fn crx3_hand_written_expands_to_the_rinex_records() {
    let hdr = |s: &str, l: &str| format!("{s:<60}{l}\n");
    let mut c = String::new();
    c += &hdr(
        "3.0                 COMPACT RINEX FORMAT",
        "CRINEX VERS   / TYPE",
    );
    c += &hdr("hand", "CRINEX PROG / DATE");
    c += &hdr(
        "     3.05           OBSERVATION DATA    M",
        "RINEX VERSION / TYPE",
    );
    c += &hdr("G    2 C1C L1C", "SYS / # / OBS TYPES");
    c += &hdr("E    1 C5Q", "SYS / # / OBS TYPES");
    c += &hdr("", "END OF HEADER");
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
