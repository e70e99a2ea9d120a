//! Odometer and dual-antenna heading readers (docs/FORMATS.md "Odometer", "Heading"):
//! every format, separators and comments, and one test per error class, each error
//! naming the file, the line and the field.

use navfuse_io::heading::read_heading;
use navfuse_io::input::{OdometerFormat, OdometerSource};
use navfuse_io::odometer::read_odometer;
use navfuse_io::InputError;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

static COUNTER: AtomicUsize = AtomicUsize::new(0);

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("navfuse-formats-aiding-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    let p = dir.join(format!("{k}-{name}"));
    std::fs::write(&p, text).unwrap();
    p
}

const SPEED: OdometerFormat = OdometerFormat::Speed {
    speed_is_mean: true,
};
const PULSES: OdometerFormat = OdometerFormat::Pulses {
    meters_per_pulse: 0.004,
};
const NAVFUSE: OdometerFormat = OdometerFormat::Navfuse {
    meters_per_pulse: 0.004,
};

fn odo(
    text: &str,
    format: OdometerFormat,
) -> (
    PathBuf,
    Result<Vec<navfuse_core::OdometerSample>, InputError>,
) {
    let p = write("odometer.txt", text);
    let r = read_odometer(&OdometerSource {
        path: p.clone(),
        format,
        skip_lines: None,
    });
    (p, r)
}

#[track_caller]
fn close(a: f64, b: f64) {
    // seconds of week carry ~1e-10 s of rounding, so a speed over 0.1 s ~1e-9 relative
    assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{a} != {b}");
}

/// The error names `path`, `line` and `field` and its message contains `expect`.
#[track_caller]
fn check(e: &InputError, path: &PathBuf, line: usize, field: Option<&str>, expect: &str) {
    assert_eq!(&e.path, path, "{e}");
    assert_eq!(e.line, Some(line), "{e}");
    assert_eq!(e.field.as_deref(), field, "{e}");
    assert!(e.message.contains(expect), "{e}");
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("{}:{line}: ", path.display())),
        "{shown}"
    );
}

// ------------------------------------------------------------------- odometer: data

#[test]
fn speed_format_mean_and_instantaneous() {
    let text = "# t speed\n\n100.0 5.0\n100.1, 5.5\n% another comment\n100.3\t6.0\n";
    let (_, r) = odo(text, SPEED);
    let s = r.unwrap();
    // mean since the previous record: the first record only starts the intervals
    assert_eq!(s.len(), 2);
    close(s[0].t, 100.1);
    close(s[0].speed_mps, 5.5);
    close(s[0].interval_s, 0.1);
    close(s[1].t, 100.3);
    close(s[1].interval_s, 0.2);
    let (_, r) = odo(
        text,
        OdometerFormat::Speed {
            speed_is_mean: false,
        },
    );
    let s = r.unwrap();
    assert_eq!(s.len(), 3);
    assert!(s.iter().all(|o| o.interval_s == 0.0));
    close(s[0].speed_mps, 5.0);
    // reversing: negative speeds are kept
    let (_, r) = odo("1 -1.5\n2 -2\n", SPEED);
    close(r.unwrap()[0].speed_mps, -2.0);
}

#[test]
fn pulses_format() {
    let text = "# t pulses\n10.0 1000\n10.1,1250\n10.3 1250\n10.4 1300\n";
    let (_, r) = odo(text, PULSES);
    let s = r.unwrap();
    assert_eq!(s.len(), 3);
    close(s[0].t, 10.1);
    close(s[0].speed_mps, 0.004 * 250.0 / 0.1);
    close(s[0].interval_s, 0.1);
    close(s[1].speed_mps, 0.0);
    close(s[1].interval_s, 0.2);
    close(s[2].speed_mps, 0.004 * 50.0 / 0.1);
    // one record only starts the count
    let (_, r) = odo("10 5\n", PULSES);
    assert!(r.unwrap().is_empty());
    // an empty file gives no samples
    let (_, r) = odo("# nothing\n", PULSES);
    assert!(r.unwrap().is_empty());
}

#[test]
fn navfuse_format_is_the_simulator_file() {
    // as `navfuse sim` writes odometer.txt (crates/sim/src/generate.rs)
    let text = "# t [s of GPS week], pulses (cumulative), pulses in the interval, speed [m/s]\n\
                345600.100000000 308 308 12.472000\n\
                345600.200000000 617 309 12.512000\n\
                345600.300000000 926 309 12.498000\n";
    let (_, r) = odo(text, NAVFUSE);
    let s = r.unwrap();
    assert_eq!(s.len(), 2);
    close(s[0].t, 345600.2);
    close(s[0].speed_mps, 0.004 * 309.0 / 0.1);
    close(s[0].interval_s, 0.1);
    close(s[1].t, 345600.3);
}

// ----------------------------------------------------------------- odometer: errors

#[test]
fn odometer_wrong_column_count() {
    let (p, r) = odo("1 2\n2 3 4\n", SPEED);
    check(
        &r.unwrap_err(),
        &p,
        2,
        None,
        "expected 2 columns (t, speed [m/s]), found 3",
    );
    let (p, r) = odo("1 2\n3\n", PULSES);
    check(
        &r.unwrap_err(),
        &p,
        2,
        None,
        "expected 2 columns (t, cumulative pulses), found 1",
    );
    let (p, r) = odo("# c\n1 2 2 0.1\n2 3 1\n", NAVFUSE);
    check(&r.unwrap_err(), &p, 3, None, "expected 4 columns");
}

#[test]
fn odometer_not_a_number() {
    let (p, r) = odo("1 2\n2 fast\n", SPEED);
    check(
        &r.unwrap_err(),
        &p,
        2,
        Some("speed"),
        "expected a number, found \"fast\"",
    );
    let (p, r) = odo("t1 2\n", PULSES);
    check(&r.unwrap_err(), &p, 1, Some("t"), "expected a number");
    let (p, r) = odo("1 2 x 0.1\n", NAVFUSE);
    check(
        &r.unwrap_err(),
        &p,
        1,
        Some("pulses_in_interval"),
        "expected a number",
    );
    let (p, r) = odo("1 2 1 ?\n", NAVFUSE);
    check(&r.unwrap_err(), &p, 1, Some("speed"), "expected a number");
}

#[test]
fn odometer_nan_and_infinity() {
    let (p, r) = odo("1 2\n2 nan\n", SPEED);
    check(&r.unwrap_err(), &p, 2, Some("speed"), "NaN is not allowed");
    let (p, r) = odo("1 inf\n", PULSES);
    check(
        &r.unwrap_err(),
        &p,
        1,
        Some("pulses"),
        "infinity is not allowed",
    );
    let (p, r) = odo("-inf 1\n", PULSES);
    check(&r.unwrap_err(), &p, 1, Some("t"), "infinity is not allowed");
}

#[test]
fn odometer_time_not_increasing() {
    let (p, r) = odo("1 2\n2 3\n2 4\n", SPEED);
    check(&r.unwrap_err(), &p, 3, Some("time"), "duplicate record");
    let (p, r) = odo("1 2\n2 3\n1.5 4\n", PULSES);
    check(
        &r.unwrap_err(),
        &p,
        3,
        Some("time"),
        "goes backwards (previous 2)",
    );
}

#[test]
fn odometer_pulses_decreasing() {
    let (p, r) = odo("1 200\n2 300\n3 250\n", PULSES);
    check(
        &r.unwrap_err(),
        &p,
        3,
        Some("pulses"),
        "cumulative pulse count 250 goes backwards (previous 300)",
    );
    let (p, r) = odo("1 200 200 1\n2 150 0 1\n", NAVFUSE);
    check(&r.unwrap_err(), &p, 2, Some("pulses"), "goes backwards");
    let (p, r) = odo("1 200 -3 1\n", NAVFUSE);
    check(&r.unwrap_err(), &p, 1, Some("pulses_in_interval"), ">= 0");
}

#[test]
fn odometer_file_and_option_errors() {
    let p = std::env::temp_dir().join("navfuse-no-such-dir/odometer.txt");
    let e = read_odometer(&OdometerSource {
        path: p.clone(),
        format: SPEED,
        skip_lines: None,
    })
    .unwrap_err();
    assert_eq!(e.path, p);
    assert!(e.message.contains("cannot open"), "{e}");
    let (p, r) = odo(
        "1 2\n",
        OdometerFormat::Pulses {
            meters_per_pulse: 0.0,
        },
    );
    let e = r.unwrap_err();
    assert_eq!(
        (&e.path, e.line, e.field.as_deref()),
        (&p, None, Some("meters_per_pulse"))
    );
    assert!(e.message.contains("> 0"), "{e}");
}

// -------------------------------------------------------------------------- heading

fn heading(text: &str) -> (PathBuf, Result<Vec<navfuse_core::HeadingObs>, InputError>) {
    let p = write("heading.txt", text);
    let r = read_heading(&p);
    (p, r)
}

#[test]
fn heading_file() {
    // as `navfuse sim` writes heading.txt, plus commas, comments and the (-180, 180]
    // convention
    let text = "# t [s of GPS week], heading of the antenna baseline [deg, 0..360 from north], std [deg]\n\
                345600.000000000 359.500000000 0.300000000\n\
                \n\
                345601.0, -90.0, 0.5\n\
                % comment\n\
                345602.0\t180\t0.25\n";
    let (_, r) = heading(text);
    let h = r.unwrap();
    assert_eq!(h.len(), 3);
    close(h[0].t, 345600.0);
    close(h[0].heading_rad, 359.5f64.to_radians());
    close(h[0].std_rad, 0.3f64.to_radians());
    close(h[1].heading_rad, -std::f64::consts::FRAC_PI_2);
    close(h[2].heading_rad, std::f64::consts::PI);
    let (_, r) = heading("");
    assert!(r.unwrap().is_empty());
}

#[test]
fn heading_errors() {
    let (p, r) = heading("1 2 0.3\n2 3\n");
    check(
        &r.unwrap_err(),
        &p,
        2,
        None,
        "expected 3 columns (t, heading [deg], std [deg]), found 2",
    );
    let (p, r) = heading("1 north 0.3\n");
    check(
        &r.unwrap_err(),
        &p,
        1,
        Some("heading"),
        "expected a number, found \"north\"",
    );
    let (p, r) = heading("1 10 nan\n");
    check(&r.unwrap_err(), &p, 1, Some("std"), "NaN is not allowed");
    let (p, r) = heading("inf 10 0.3\n");
    check(&r.unwrap_err(), &p, 1, Some("t"), "infinity is not allowed");
    let (p, r) = heading("1 10 0.3\n1 11 0.3\n");
    check(&r.unwrap_err(), &p, 2, Some("time"), "duplicate record");
    let (p, r) = heading("1 10 0.3\n0.5 11 0.3\n");
    check(&r.unwrap_err(), &p, 2, Some("time"), "goes backwards");
    let (p, r) = heading("1 360 0.3\n");
    check(
        &r.unwrap_err(),
        &p,
        1,
        Some("heading"),
        "[0, 360) or (-180, 180]",
    );
    let (p, r) = heading("1 -180 0.3\n");
    check(
        &r.unwrap_err(),
        &p,
        1,
        Some("heading"),
        "[0, 360) or (-180, 180]",
    );
    let (p, r) = heading("1 10 0\n");
    check(
        &r.unwrap_err(),
        &p,
        1,
        Some("std"),
        "std must be > 0, found 0",
    );
    let (p, r) = heading("1 10 -0.1\n");
    check(&r.unwrap_err(), &p, 1, Some("std"), "std must be > 0");
    let p = std::env::temp_dir().join("navfuse-no-such-dir/heading.txt");
    let e = read_heading(&p).unwrap_err();
    assert!(e.message.contains("cannot open"), "{e}");
}
