//! DGPS correction reader (docs/FORMATS.md "DGPS corrections"): the simulator's
//! dgps.csv, week rollover, and one test per error class, each naming the file, the
//! line and the field.

use navfuse_io::dgps::{read_dgps_corrections, read_dgps_file};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

fn write(text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("navfuse-dgps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    let p = dir.join(format!("{k}-dgps.csv"));
    std::fs::write(&p, text).unwrap();
    p
}

const HEAD: &str = "# navfuse DGPS corrections v1; reference station lat 40.1 deg lon -105.1 deg h 1600.000 m; corrected P = P + prc_m + rrc_mps (t - t_s)\nt_s,prn,prc_m,rrc_mps,iode\n";

fn err(body: &str) -> String {
    let p = write(&format!("{HEAD}{body}"));
    let e = read_dgps_corrections(&p).unwrap_err();
    let s = e.to_string();
    assert!(s.starts_with(&p.display().to_string()), "{s}");
    s.strip_prefix(&p.display().to_string())
        .unwrap()
        .to_string()
}

#[test]
fn reads_the_simulator_file() {
    let p = write(&format!(
        "{HEAD}410400.000,5,-12.3456,0.012345,45\n410400.000,12,3.5000,-0.000100,7\n\n# note\n410401.000,5,-12.3330,0.012300,\n"
    ));
    let c = read_dgps_corrections(&p).unwrap();
    assert_eq!(c.len(), 3);
    assert_eq!(
        (c[0].t_s, c[0].prn, c[0].prc_m, c[0].rrc_mps, c[0].iode),
        (410400.0, 5, -12.3456, 0.012345, Some(45))
    );
    assert_eq!((c[1].prn, c[1].iode), (12, Some(7)));
    assert_eq!((c[2].t_s, c[2].iode), (410401.0, None));
    let f = read_dgps_file(&p).unwrap();
    assert_eq!(f.corrections, c);
    let lla = f.reference_lla.unwrap();
    assert!(
        (lla.x.to_degrees() - 40.1).abs() < 1e-12 && (lla.y.to_degrees() + 105.1).abs() < 1e-12
    );
    assert_eq!(lla.z, 1600.0);
    // Without the station line: no position.
    let p = write("t_s,prn,prc_m,rrc_mps,iode\n1,5,1.0,0.0,1\n");
    assert_eq!(read_dgps_file(&p).unwrap().reference_lla, None);
    // Only the header: no corrections.
    assert!(read_dgps_corrections(&write(HEAD)).unwrap().is_empty());
}

#[test]
fn week_rollover_keeps_one_time_scale() {
    let p = write(&format!(
        "{HEAD}604799.000,5,1.0,0.0,1\n0.000,5,1.1,0.0,1\n1.000,5,1.2,0.0,1\n"
    ));
    let t: Vec<f64> = read_dgps_corrections(&p)
        .unwrap()
        .iter()
        .map(|c| c.t_s)
        .collect();
    assert_eq!(t, vec![604_799.0, 604_800.0, 604_801.0]);
}

#[test]
fn errors_name_file_line_and_field() {
    assert_eq!(
        err("410400,5,1.0,0.0\n410399,5,1.0,0.0\n"),
        ":4: field 'time': time 410399 goes backwards (previous 410400)"
    );
    assert_eq!(
        err("410400,33,1.0,0.0,1\n"),
        ":3: field 'prn': expected an integer 1-32, found \"33\""
    );
    assert_eq!(
        err("410400,G05,1.0,0.0,1\n"),
        ":3: field 'prn': expected an integer 1-32, found \"G05\""
    );
    assert_eq!(
        err("410400,5,abc,0.0,1\n"),
        ":3: field 'prc_m': expected a number, found \"abc\""
    );
    assert_eq!(
        err("410400,5,1.0,nan,1\n"),
        ":3: field 'rrc_mps': NaN is not allowed"
    );
    assert_eq!(
        err("410400,5,1.0,0.0,-1\n"),
        ":3: field 'iode': expected an integer 0-65535, found \"-1\""
    );
    assert_eq!(
        err("-1,5,1.0,0.0,1\n"),
        ":3: field 't_s': expected GPS seconds of week in [0, 604800), found -1"
    );
    assert_eq!(
        err("410400,5,1.0\n"),
        ":3: expected 5 columns (t_s, prn, prc_m, rrc_mps, iode), found 3"
    );
    assert_eq!(
        err("410400,5,1.0,0.0,1,9\n"),
        ":3: expected 5 columns (t_s, prn, prc_m, rrc_mps, iode), found 6"
    );
    // A malformed station line.
    let p = write(
        "# reference station lat 40.1 deg lon -105.1 deg h tall m\nt_s,prn,prc_m,rrc_mps,iode\n",
    );
    let e = read_dgps_file(&p).unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(1), Some("reference station"))
    );
    // Header missing or wrong.
    let p = write("# comment\n410400,5,1.0,0.0,1\n");
    let e = read_dgps_corrections(&p).unwrap_err();
    assert_eq!(e.line, Some(2));
    assert_eq!(e.field.as_deref(), Some("header"));
    assert!(
        e.to_string()
            .contains("expected the header \"t_s,prn,prc_m,rrc_mps,iode\""),
        "{e}"
    );
    let p = write("# only comments\n");
    let e = read_dgps_corrections(&p).unwrap_err();
    assert!(e.to_string().contains("no header line"), "{e}");
    let e =
        read_dgps_corrections(std::path::Path::new("/nonexistent/navfuse/dgps.csv")).unwrap_err();
    assert!(
        e.to_string()
            .ends_with("cannot open: No such file or directory"),
        "{e}"
    );
}
