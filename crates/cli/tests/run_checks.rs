//! `navfuse run` on the shipped demo (examples/demo/drive_excerpt.toml) with
//! deliberate mistakes: each must give its message and exit status, and every run,
//! failed or not, must leave events.log and summary.json saying how it ended.

mod common;

use common::{repo, shared, tmp};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const DEMO_WEEK: i64 = 2374;

/// The demo's configuration with its input paths made absolute, edited by `edit`.
fn demo_config(edit: impl Fn(String) -> String) -> String {
    let demo = repo().join("examples/demo");
    let text = std::fs::read_to_string(demo.join("drive_excerpt.toml")).unwrap();
    let text = text
        .replace(
            "file = \"imu.csv\"",
            &format!("file = \"{}\"", demo.join("imu.csv").display()),
        )
        .replace(
            "file = \"gnss.pos\"",
            &format!("file = \"{}\"", demo.join("gnss.pos").display()),
        );
    let out = edit(text.clone());
    assert_ne!(out, text, "the edit changed nothing");
    out
}

/// Write `config` (and, given, a GNSS file `gnss.pos` it then uses) into a fresh
/// directory; returns the config path.
fn case(name: &str, config: String, gnss: Option<String>) -> PathBuf {
    let d = tmp(name);
    std::fs::create_dir_all(&d).unwrap();
    let mut config = config;
    if let Some(g) = gnss {
        std::fs::write(d.join("gnss.pos"), g).unwrap();
        let demo_pos = repo().join("examples/demo/gnss.pos");
        config = config.replace(&demo_pos.display().to_string(), "gnss.pos");
    }
    let p = d.join("run.toml");
    std::fs::write(&p, config).unwrap();
    p
}

/// What a run left: exit status, stderr, summary.json.
struct Outcome {
    code: Option<i32>,
    stderr: String,
    summary: Value,
    out: PathBuf,
}

fn run(config: &Path) -> Outcome {
    let out = config.parent().unwrap().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "run",
            config.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .expect("run navfuse");
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    let summary = std::fs::read_to_string(out.join("summary.json"))
        .unwrap_or_else(|e| panic!("no summary.json ({e}); stderr:\n{stderr}"));
    assert!(
        out.join("events.log").is_file(),
        "no events.log; stderr:\n{stderr}"
    );
    Outcome {
        code: o.status.code(),
        stderr,
        summary: serde_json::from_str(&summary).expect("summary.json is JSON"),
        out,
    }
}

impl Outcome {
    /// An unreliable run: every output file written with the whole run in it (the
    /// demo's 180 s at 10 Hz less the GNSS it lacks), the reasons in summary.json.
    fn expect_unreliable_with_files(&self) {
        self.expect_unreliable_with_rows(1_700);
    }

    fn expect_unreliable_with_rows(&self, min_rows: usize) {
        let reasons = self.summary["unreliable"].as_array().unwrap();
        assert!(!reasons.is_empty(), "{}", self.summary);
        assert!(
            self.stderr.contains("navfuse: unreliable: "),
            "{}",
            self.stderr
        );
        for f in [
            "solution.nav",
            "solution.csv",
            "innovations.csv",
            "events.log",
        ] {
            let len = std::fs::metadata(self.out.join(f)).map_or(0, |m| m.len());
            assert!(len > 0, "{f} missing or empty");
        }
        let rows = std::fs::read_to_string(self.out.join("solution.nav"))
            .unwrap()
            .lines()
            .count();
        assert!(rows > min_rows, "solution.nav has {rows} rows");
    }

    fn expect(&self, code: i32, status: &str, message: &str) -> &Self {
        assert_eq!(
            self.code,
            Some(code),
            "exit status; stderr:\n{}",
            self.stderr
        );
        assert_eq!(self.summary["status"], status, "{}", self.summary);
        assert!(
            self.stderr.contains(message),
            "stderr lacks {message:?}:\n{}",
            self.stderr
        );
        // The message is also kept in summary.json.
        assert!(self
            .summary
            .to_string()
            .contains(&message.replace('"', "\\\"")));
        self
    }
}

/// The demo's RTKLIB .pos with every epoch moved by `shift_s` seconds (and days).
fn shifted_pos(shift_s: i64) -> String {
    let text = std::fs::read_to_string(repo().join("examples/demo/gnss.pos")).unwrap();
    text.lines()
        .map(|l| {
            if l.starts_with('%') {
                return format!("{l}\n");
            }
            // "2025/07/08 19:34:18.499 ..."
            let day: i64 = l[8..10].parse().unwrap();
            let (h, m, s): (i64, i64, i64) = (
                l[11..13].parse().unwrap(),
                l[14..16].parse().unwrap(),
                l[17..19].parse().unwrap(),
            );
            let t = ((day * 24 + h) * 60 + m) * 60 + s + shift_s;
            let (day, rest) = (t / 86400, t % 86400);
            format!(
                "{}{day:02} {:02}:{:02}:{:02}{}\n",
                &l[..8],
                rest / 3600,
                rest / 60 % 60,
                rest % 60,
                &l[19..]
            )
        })
        .collect()
}

#[test]
fn clean_demo_warns_only_about_its_correlated_fix_velocities() {
    let cfg = case("clean", demo_config(|t| t + "\n"), None);
    let o = run(&cfg);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert_eq!(o.summary["status"], "completed");
    // The receiver's velocities come out of its own filter: their innovations are
    // correlated from one second to the next (lag-1 0.65 north and east), which the
    // check names; nothing else is suspicious.
    let w = o.summary["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    let w = w[0].as_str().unwrap();
    assert!(
        w.starts_with("gnss_velocity: its innovations are correlated")
            && w.contains("[gnss] use_velocity = false"),
        "{w}"
    );
    assert_eq!(o.stderr.matches("warning").count(), 1, "{}", o.stderr);
    // Without the velocities the demo is clean.
    let cfg = case(
        "clean-positions",
        demo_config(|t| t.replace("use_velocity = true", "use_velocity = false")),
        None,
    );
    let o = run(&cfg);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(!o.stderr.contains("warning"), "{}", o.stderr);
    assert_eq!(o.summary["warnings"].as_array().unwrap().len(), 0);
}

#[test]
fn imu_unit_and_axis_mistakes_are_named() {
    let gyro = case(
        "gyro-rad",
        demo_config(|t| t.replace("gyro_unit = \"deg\"", "gyro_unit = \"rad\"")),
        None,
    );
    // Each mistake is named, and the result it gives is meaningless: every file is
    // written, but the run says "unreliable" and exits with 3.
    run(&gyro)
        .expect(
            3,
            "unreliable",
            "gyro in deg/s declared as rad/s? set [imu.csv] gyro_unit = \"deg\"",
        )
        .expect_unreliable_with_files();
    let accel = case(
        "accel-m",
        demo_config(|t| t.replace("accel_unit = \"g\"", "accel_unit = \"m\"")),
        None,
    );
    run(&accel)
        .expect(
            3,
            "unreliable",
            "accelerometer in g declared as m/s²? set [imu.csv] accel_unit = \"g\"",
        )
        .expect_unreliable_with_files();
    let swap = case(
        "swapped",
        demo_config(|t| {
            t.replace("accel_cols = [1, 2, 3]", "accel_cols = [4, 5, 6]")
                .replace("gyro_cols = [4, 5, 6]", "gyro_cols = [1, 2, 3]")
        }),
        None,
    );
    let o = run(&swap);
    o.expect(
        3,
        "unreliable",
        "accelerometer and gyro columns swapped? set [imu.csv] accel_cols / gyro_cols",
    );
    o.expect_unreliable_with_files();
    assert!(
        !o.stderr.contains("declared as"),
        "one cause, not three:\n{}",
        o.stderr
    );
}

#[test]
fn gnss_in_utc_is_named() {
    // UTC labelled as GPS time: the tags are 18 s early.
    let cfg = case("utc", demo_config(|t| t + "\n"), Some(shifted_pos(-18)));
    // Named; and with GNSS 18 s off the result is meaningless (the run ends with the
    // GNSS, 18 s early).
    run(&cfg)
        .expect(3, "unreliable", "18 s: UTC vs GPST?")
        .expect_unreliable_with_rows(1_600);
}

#[test]
fn gnss_not_overlapping_is_an_error() {
    let cfg = case(
        "late-gnss",
        demo_config(|t| t + "\n"),
        Some(shifted_pos(3600)),
    );
    let o = run(&cfg);
    o.expect(1, "failed", "do not overlap the IMU data");
    // The (free-inertial) output is kept.
    assert!(std::fs::metadata(o.out.join("solution.nav")).unwrap().len() > 0);
}

#[test]
fn gnss_a_week_after_a_week_tagged_imu_is_a_week_mismatch() {
    // The IMU tagged in GPST-Unix (its week known), the GNSS a week later.
    let d = tmp("week-imu");
    std::fs::create_dir_all(&d).unwrap();
    let imu = std::fs::read_to_string(repo().join("examples/demo/imu.csv")).unwrap();
    let base = 315_964_800 + DEMO_WEEK * 604_800;
    let unix: String = imu
        .lines()
        .enumerate()
        .map(|(k, l)| match (k, l.split_once(',')) {
            (0 | 1, _) | (_, None) => format!("{l}\n"),
            (_, Some((t, rest))) => {
                format!("{:.4},{rest}\n", base as f64 + t.parse::<f64>().unwrap())
            }
        })
        .collect();
    std::fs::write(d.join("imu.csv"), unix).unwrap();
    let imu_demo = repo().join("examples/demo/imu.csv").display().to_string();
    let imu_new = d.join("imu.csv").display().to_string();
    let config = demo_config(|t| {
        t.replace(&imu_demo, &imu_new)
            .replace("time_scale = \"gps_sow\"", "time_scale = \"gpst_unix\"")
    });
    let cfg = case("week", config, Some(shifted_pos(7 * 86400)));
    let o = run(&cfg);
    o.expect(1, "failed", "week mismatch");
    assert!(
        o.stderr.contains("week 2374") && o.stderr.contains("week 2375"),
        "{}",
        o.stderr
    );
}

#[test]
fn empty_gnss_and_late_start_are_errors() {
    let cfg = case("empty-gnss", demo_config(|t| t + "\n"), Some(String::new()));
    let o = run(&cfg);
    o.expect(1, "failed", "no GNSS epochs");
    let cfg = case(
        "late-start",
        demo_config(|t| t + "\n[time]\nstart = 300000.0\n"),
        None,
    );
    let o = run(&cfg);
    o.expect(
        1,
        "failed",
        "[time] start = 300000.000 is after the end of the data",
    );
    assert!(o.stderr.contains("243440.999"), "{}", o.stderr);
}

#[test]
fn lever_arm_in_cm_and_wide_time_offset_prior_are_warned() {
    let cfg = case(
        "lever-cm",
        demo_config(|t| {
            t.replace(
                "lever_arm_m = [0.0, -0.05, 0.0]",
                "lever_arm_m = [20.0, -5.0, -35.0]",
            )
        }),
        None,
    );
    // Named; and a 40 m lever arm makes the result meaningless.
    run(&cfg)
        .expect(
            3,
            "unreliable",
            "[gnss] lever_arm_m = [20, -5, -35] is 40.6 m long: given in cm or mm?",
        )
        .expect_unreliable_with_files();
    let cfg = case(
        "prior-30",
        demo_config(|t| t.replace("std_s = 0.5", "std_s = 30.0")),
        None,
    );
    run(&cfg).expect(
        0,
        "completed",
        "lets the estimation lock onto a wrong epoch",
    );
}

#[test]
fn failed_alignment_still_writes_the_summary() {
    let cfg = case(
        "no-course",
        demo_config(|t| t.replace("min_speed_mps = 3", "min_speed_mps = 300")),
        None,
    );
    let o = run(&cfg);
    o.expect(1, "failed", "alignment");
    let ev = std::fs::read_to_string(o.out.join("events.log")).unwrap();
    assert!(ev.contains("# failed:"), "{ev}");
}

/// A long run (the KF-GINS stand-in at the IMU rate) stopped by `signal` once its
/// placeholder summary exists: exit 128 + signal, summary "interrupted", and every
/// output file ends at the same epoch.
fn interrupt(signal: &str, code: i32) {
    let Some(data) = shared() else { return };
    let out = tmp(&format!("signal-{signal}"));
    let child = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args(["run", "--kf-gins"])
        .arg(data.join("kf-gins/synthetic/kf-gins.yaml"))
        .arg("--out")
        .arg(&out)
        .arg("-q")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !out.join("summary.json").exists() && t0.elapsed().as_secs() < 20 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    std::thread::sleep(std::time::Duration::from_millis(100));
    let killed = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    if o.status.code() == Some(0) {
        eprintln!("skipped: the run ended before {signal} arrived");
        return;
    }
    assert_eq!(o.status.code(), Some(code), "{stderr}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "interrupted", "{summary}");
    assert!(
        stderr.contains(&format!("interrupted by SIG{signal}")),
        "{stderr}"
    );
    let lines = |f: &str| {
        std::fs::read_to_string(out.join(f))
            .unwrap()
            .lines()
            .count()
    };
    let n = lines("solution.nav");
    assert_eq!(n, lines("imu_err.txt"));
    assert_eq!(n, lines("std.txt"));
    assert_eq!(summary["outputs"].as_u64(), Some(n as u64), "{summary}");
}

#[test]
fn sigint_stops_cleanly() {
    interrupt("INT", 130);
}

#[test]
fn sigterm_stops_cleanly() {
    interrupt("TERM", 143);
}

/// A full disk (a 400 KiB tmpfs; needs root and mount): an error naming the file,
/// whole lines in the outputs, summary.json saying why.
#[test]
fn full_disk_keeps_whole_records() {
    let mnt = tmp("full-disk");
    std::fs::create_dir_all(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=400k", "tmpfs"])
        .arg(&mnt)
        .output()
        .is_ok_and(|o| o.status.success());
    if !mounted {
        eprintln!(
            "skipped: cannot mount a tmpfs at {} (not root?)",
            mnt.display()
        );
        return;
    }
    let cfg = case("full-disk-cfg", demo_config(|t| t + "\n"), None);
    let out = mnt.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "run",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    let nav = std::fs::read(out.join("solution.nav")).unwrap_or_default();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap_or_default();
    let _ = Command::new("umount").arg(&mnt).status();
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("No space left on device"), "{stderr}");
    assert!(
        !nav.is_empty() && nav.ends_with(b"\n"),
        "solution.nav: {} bytes",
        nav.len()
    );
    let summary: Value = serde_json::from_str(&summary).expect("summary.json");
    assert_eq!(summary["status"], "failed");
}
