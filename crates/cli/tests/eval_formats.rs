//! Issue 18 (eval): `navfuse eval` reads either file in any of the four formats,
//! recognised by content (KF-GINS .nav, navfuse CSV, RTKLIB .pos, KF-GINS GNSS text),
//! with `--solution-format` / `--truth-format` overrides; velocity and attitude
//! figures only where both files carry them (docs/FORMATS.md "Trajectories to score").

mod common;

use common::{eval_json, navfuse_ok, num, repo, shared, tmp};
use navfuse_io::nav::read_nav;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

/// `navfuse ARGS` expected to fail: its stderr.
fn navfuse_err(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .current_dir(repo())
        .args(args)
        .output()
        .unwrap();
    assert!(!out.status.success(), "navfuse {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `nav` rewritten as a KF-GINS GNSS file: 7 columns, or 13 with the velocity.
fn write_kfgins_gnss(nav: &Path, out: &Path, with_velocity: bool) {
    let mut t = String::new();
    for (_, n) in read_nav(nav).unwrap() {
        let _ = write!(
            t,
            "{:.9} {:.10} {:.10} {:.4} 0.010 0.010 0.020",
            n.t,
            n.lla.x.to_degrees(),
            n.lla.y.to_degrees(),
            n.lla.z
        );
        if with_velocity {
            let v = n.v_n;
            let _ = write!(t, " {:.6} {:.6} {:.6} 0.05 0.05 0.05", v.x, v.y, v.z);
        }
        t.push('\n');
    }
    std::fs::write(out, t).unwrap();
}

#[test]
fn eval_reads_every_format_by_content() {
    let dir = tmp("eval-formats");
    let run = dir.join("run");
    navfuse_ok(&[
        "run",
        "examples/demo/drive_excerpt.toml",
        "--out",
        s(&run),
        "-q",
        "--formats",
        "pos",
    ]);
    let (nav, csv, pos) = (
        run.join("solution.nav"),
        run.join("solution.csv"),
        run.join("solution.pos"),
    );
    let gnss = repo().join("examples/demo/gnss.pos");
    let lever = ["--lever-arm", "0,-0.05,0"];
    let base = eval_json(&nav, &gnss, &lever);
    assert!(num(&base, &["epochs"]) > 700.0);
    assert!(base.get("velocity_mps").is_some() && base.get("attitude_deg").is_none());

    // navfuse's CSV as the solution: the same figures, to the bit (same 9 decimals).
    assert_eq!(eval_json(&csv, &gnss, &lever), base);
    // Wrong extensions, right content: a .nav named .pos, a .pos named .nav.
    let (nav_as_pos, pos_as_nav) = (dir.join("sol.pos"), dir.join("truth.nav"));
    std::fs::copy(&nav, &nav_as_pos).unwrap();
    std::fs::copy(&gnss, &pos_as_nav).unwrap();
    assert_eq!(eval_json(&nav_as_pos, &pos_as_nav, &lever), base);
    // ... and the overrides say the same.
    let forced = [
        "--solution-format",
        "nav",
        "--truth-format",
        "pos",
        "--lever-arm",
        "0,-0.05,0",
    ];
    assert_eq!(eval_json(&nav_as_pos, &pos_as_nav, &forced), base);

    // A CSV as the truth: both sides have velocity and attitude.
    let v = eval_json(&nav, &csv, &[]);
    assert!(num(&v, &["position_m", "3d", "max"]) < 1e-6);
    assert!(num(&v, &["attitude_deg", "total", "max"]) < 1e-6);
    assert!(num(&v, &["velocity_mps", "3d", "max"]) < 1e-6);

    // The exported .pos (15 columns: no velocity, no attitude) as the solution: every
    // epoch is scored whatever its Q (5), and only position figures are printed.
    let v = eval_json(&pos, &csv, &[]);
    assert!(num(&v, &["epochs"]) > 1700.0);
    assert!(num(&v, &["position_m", "horizontal", "max"]) < 1e-4);
    assert!(v.get("velocity_mps").is_none() && v.get("attitude_deg").is_none());
    let text = navfuse_ok(&["eval", s(&pos), s(&csv), "--gaps", "243300:243340"]);
    assert!(!text.contains("deg") && !text.contains("vel "), "{text}");
    assert!(text.contains("outages: 1"), "{text}");
    // The outage figures too: attitude maxima only against a reference with attitude.
    let gaps = ["--gaps", "243300:243340", "--lever-arm", "0,-0.05,0"];
    let v = eval_json(&nav, &gnss, &gaps);
    assert!(num(&v, &["gap_max_rms", "horizontal_m"]) > 0.0);
    assert!(v["gap_max_rms"].get("yaw_deg").is_none() && v["gaps"][0].get("max_yaw_deg").is_none());
    let v = eval_json(&nav, &csv, &["--gaps", "243300:243340"]);
    assert!(v["gap_max_rms"].get("yaw_deg").is_some() && v["gaps"][0].get("max_yaw_deg").is_some());
    let e = navfuse_err(&["eval", s(&pos), s(&csv), "--lever-arm", "0,0,1"]);
    assert!(
        e.contains("needs attitude") && e.contains("RTKLIB .pos"),
        "{e}"
    );

    // KF-GINS GNSS text: 7 columns (position), 13 (and velocity); no attitude.
    let (g7, g13) = (dir.join("gnss7.pos"), dir.join("gnss13.txt"));
    write_kfgins_gnss(&nav, &g7, false);
    write_kfgins_gnss(&nav, &g13, true);
    let v = eval_json(&nav, &g7, &[]);
    assert!(num(&v, &["epochs"]) > 1700.0);
    assert!(num(&v, &["position_m", "horizontal", "max"]) < 1e-4);
    assert!(v.get("velocity_mps").is_none() && v.get("attitude_deg").is_none());
    let v = eval_json(&nav, &g13, &["--truth-format", "kfgins-gnss"]);
    assert!(num(&v, &["velocity_mps", "3d", "max"]) < 1e-5);
    assert!(v.get("attitude_deg").is_none());
    // The GNSS file as the solution, the .nav as the truth.
    let v = eval_json(&g13, &nav, &[]);
    assert!(num(&v, &["position_m", "horizontal", "max"]) < 1e-4);
    assert!(v.get("attitude_deg").is_none());

    // Overrides that do not fit: the reader says why, naming file and line.
    let e = navfuse_err(&["eval", s(&nav), s(&gnss), "--truth-format", "nav"]);
    assert!(
        e.contains("gnss.pos:2: expected 11 columns") && e.contains("found 24"),
        "{e}"
    );
    let e = navfuse_err(&["eval", s(&nav), s(&csv), "--truth-format", "pos"]);
    assert!(e.contains("solution.csv:1:"), "{e}");
    let e = navfuse_err(&["eval", s(&nav), s(&gnss), "--truth-format", "kml"]);
    assert!(e.contains("kfgins-gnss"), "{e}");

    // Detection errors: the file, the line, what was expected, the option.
    let five = dir.join("five.nav");
    std::fs::write(&five, "# comment\n456300.0 30.4 114.4 20.0 0.1\n").unwrap();
    let e = navfuse_err(&["eval", s(&nav), s(&five)]);
    assert!(
        e.contains(
            "five.nav:2: 5 columns; expected 11 (KF-GINS .nav), 7 or 13 (KF-GINS GNSS), \
             a navfuse CSV header (gps_week,t_s,lat_deg,...) or an RTKLIB .pos"
        ),
        "{e}"
    );
    assert!(e.contains("--truth-format"), "{e}");
    let e = navfuse_err(&["eval", s(&five), s(&gnss)]);
    assert!(
        e.contains("--solution-format") && e.contains("five.nav:2"),
        "{e}"
    );
    let sep = dir.join("separation.csv");
    std::fs::write(&sep, "gps_week,gps_sow,d_north_m\n2374,1,2\n").unwrap();
    let e = navfuse_err(&["eval", s(&nav), s(&sep)]);
    assert!(
        e.contains("separation.csv:1: found \"gps_week,gps_sow,d_north_m\""),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The KF-GINS stand-in's GNSS file (7 columns, antenna) as the truth of the exact
/// IMU-centre trajectory: the GNSS noise (1-2 cm), no velocity or attitude figures.
#[test]
fn eval_against_a_kfgins_gnss_truth() {
    let Some(data) = shared() else { return };
    let k = data.join("kf-gins/synthetic");
    let gnss = k.join("GNSS.txt");
    if !gnss.is_file() {
        eprintln!("skipped: {} not found", gnss.display());
        return;
    }
    // The antenna lever arm of kf-gins.yaml.
    let lever = ["--lever-arm", "0.136,-0.301,-0.184"];
    let v = eval_json(&k.join("truth.nav"), &gnss, &lever);
    let (epochs, h) = (
        num(&v, &["epochs"]),
        num(&v, &["position_m", "horizontal", "rms"]),
    );
    eprintln!("truth.nav vs GNSS.txt: {epochs} epochs, horizontal RMS {h:.4} m");
    assert!(epochs > 3400.0, "{epochs}");
    assert!((0.005..0.03).contains(&h), "{h}");
    assert!(v.get("velocity_mps").is_none() && v.get("attitude_deg").is_none());
    // Renamed, and as the solution's format forced.
    let dir = tmp("eval-kfgins-gnss");
    std::fs::create_dir_all(&dir).unwrap();
    let renamed = dir.join("gnss.nav");
    std::fs::copy(&gnss, &renamed).unwrap();
    assert_eq!(eval_json(&k.join("truth.nav"), &renamed, &lever), v);
    let text = navfuse_ok(&[
        "eval",
        s(&k.join("truth.nav")),
        s(&renamed),
        "--truth-format",
        "kfgins-gnss",
        "--lever-arm",
        "0.136,-0.301,-0.184",
    ]);
    assert!(!text.contains("deg") && !text.contains("vel "), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}
