//! Issue 30 part B: alignment on the data users bring, with the default `auto` mode
//! and no attitude given (docs/RESULTS.md §17). Simulated cars idling with engine
//! vibration and started in motion, a UAV whose heading is not its course, a creeping
//! car; the real drive, walk and PX4 logs (skipped with a message when ../shared is
//! absent). The attitude at the first output is scored against the truth (or a
//! reference: an RTS-smoothed run, EKF2), and the horizontal RMS against a level start
//! from the first fix (roll and pitch 0, the first GNSS course as yaw, the first
//! fix's velocity).

mod common;

use common::{navfuse_ok, repo, shared, simulate_seed, tmp};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One epoch of `navfuse eval --errors`: time, horizontal error \[m\], roll, pitch,
/// yaw errors \[deg\].
#[derive(Clone, Copy, Debug)]
struct Row {
    t: f64,
    dh: f64,
    att: [f64; 3],
}

/// The per-epoch errors of `sol` against `truth` (extra eval arguments allowed).
fn errors(sol: &Path, truth: &Path, extra: &[&str]) -> Vec<Row> {
    let csv = sol.with_extension("errors.csv");
    let mut args = vec![
        "eval",
        sol.to_str().unwrap(),
        truth.to_str().unwrap(),
        "--errors",
        csv.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    navfuse_ok(&args);
    std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            Row {
                t: v[0],
                dh: v[4],
                att: [v[10], v[11], v[12]],
            }
        })
        .collect()
}

fn hrms(rows: &[Row]) -> f64 {
    (rows.iter().map(|r| r.dh * r.dh).sum::<f64>() / rows.len() as f64).sqrt()
}

fn summary(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// `navfuse run CFG --out OUT -q`.
fn run(cfg: &Path, out: &Path) {
    navfuse_ok(&[
        "run",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
}

/// Horizontal RMS `a` no worse than `b`: within 2 %. Once converged, both runs track
/// the same time-correlated GNSS errors; where the first fix puts the IMU (the lever
/// arm turned by each start's attitude, centimetres) persists through the fix-error
/// states and moves the RMS by up to 1 % either way (measured: 1.052 against 1.043 m
/// on the idling car of seed 1, whose level start is 4 deg off in yaw, 2 in pitch).
fn no_worse(a: f64, b: f64) -> bool {
    a <= 1.02 * b
}

/// Roll and pitch within 1 deg, yaw within 2 deg.
fn within(att: [f64; 3]) -> bool {
    att[0].abs() <= 1.0 && att[1].abs() <= 1.0 && att[2].abs() <= 2.0
}

/// A simulation's run.toml as a user's `auto` configuration: no attitude, position
/// (the first fix) or velocity, a user's uncertainties, the start `offset_s` into the
/// data. With `level` (yaw \[deg\], velocity), instead a level start from the first
/// fix with that yaw and velocity.
fn user_config(sim: &Path, name: &str, offset_s: f64, level: Option<(f64, [f64; 3])>) -> PathBuf {
    let text = std::fs::read_to_string(sim.join("run.toml")).unwrap();
    let mut out = String::new();
    for l in text.lines() {
        if l.starts_with("position_deg_m")
            || l.starts_with("velocity_mps")
            || l.starts_with("attitude_deg")
        {
            continue;
        }
        let l = match l {
            "position_std_m = 0.01" => "position_std_m = 1.0".to_string(),
            "velocity_std_mps = 0.001" => "velocity_std_mps = 0.1".to_string(),
            "attitude_std_deg = 0.01" => "attitude_std_deg = [1.0, 1.0, 5.0]".to_string(),
            l if l.starts_with("start = ") => {
                let t: f64 = l[8..].trim().parse().unwrap();
                format!("start = {}", t + offset_s)
            }
            l => l.to_string(),
        };
        out.push_str(&l);
        out.push('\n');
        if l == "[initial]" {
            if let Some((yaw, v)) = level {
                out.push_str(&format!(
                    "attitude_deg = [0.0, 0.0, {yaw}]\nvelocity_mps = [{}, {}, {}]\n",
                    v[0], v[1], v[2]
                ));
            }
        }
    }
    let p = sim.join(name);
    std::fs::write(&p, out).unwrap();
    p
}

/// A user's level start from the GNSS at or after `t` (a KF-GINS gnss.txt with
/// velocity): the first fix's velocity, and as yaw the course of the first fix at
/// 3 m/s or more (what a user without alignment would take).
fn level_from_gnss(gnss: &Path, t: f64) -> (f64, [f64; 3]) {
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(gnss)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .filter(|v: &Vec<f64>| v[0] >= t - 1e-6)
        .collect();
    let v = [rows[0][7], rows[0][8], rows[0][9]];
    let course = rows
        .iter()
        .find(|r| r[7].hypot(r[8]) >= 3.0)
        .map(|r| r[8].atan2(r[7]).to_degrees())
        .unwrap();
    (course, v)
}

/// What one simulated case gave.
struct Case {
    method: String,
    reason: String,
    skipped_s: f64,
    first_t: f64,
    first: Row,
    hrms: f64,
    level_hrms: f64,
    /// Over the first 60 s (where the start matters; later both track the GNSS).
    hrms_60: f64,
    level_hrms_60: f64,
    rows: Vec<Row>,
}

/// Simulate `scenario` (its [start] position and heading replaced) with `seed`, run it
/// as a user would (`auto`) and as a level start, starting `offset_s` in.
fn sim_case(scenario: &str, seed: u64, site: (f64, f64, f64), heading: f64, offset_s: f64) -> Case {
    sim_case_with(scenario, seed, site, heading, offset_s, &|t| t, &|t| t)
}

/// [`sim_case`] with the scenario text changed by `edit` first and the run.toml the
/// simulator writes by `run_edit`.
fn sim_case_with(
    scenario: &str,
    seed: u64,
    site: (f64, f64, f64),
    heading: f64,
    offset_s: f64,
    edit: &dyn Fn(String) -> String,
    run_edit: &dyn Fn(String) -> String,
) -> Case {
    let dir = tmp(&format!(
        "align-{}-{seed}-{offset_s}",
        Path::new(scenario).file_stem().unwrap().to_str().unwrap()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(repo().join(scenario)).unwrap();
    let mut sc = String::new();
    for l in text.lines() {
        let l = if l.starts_with("position_deg_m") {
            format!("position_deg_m = [{}, {}, {}]", site.0, site.1, site.2)
        } else if l.starts_with("heading_deg") {
            format!("heading_deg = {heading}")
        } else {
            l.to_string()
        };
        sc.push_str(&l);
        sc.push('\n');
    }
    let scen = dir.join("scenario.toml");
    std::fs::write(&scen, edit(sc)).unwrap();
    let sim = dir.join("sim");
    simulate_seed(&scen, &sim, Some(seed));
    let truth = sim.join("truth.nav");
    let run_toml = sim.join("run.toml");
    std::fs::write(
        &run_toml,
        run_edit(std::fs::read_to_string(&run_toml).unwrap()),
    )
    .unwrap();
    let auto = user_config(&sim, "auto.toml", offset_s, None);
    let out = dir.join("auto");
    run(&auto, &out);
    let s = summary(&out);
    let a = &s["alignment"];
    let rows = errors(&out.join("solution.nav"), &truth, &[]);
    let t0: f64 = std::fs::read_to_string(sim.join("run.toml"))
        .unwrap()
        .lines()
        .find_map(|l| {
            l.strip_prefix("start = ")
                .map(|x| x.trim().parse().unwrap())
        })
        .unwrap();
    let level = user_config(
        &sim,
        "level.toml",
        offset_s,
        Some(level_from_gnss(&sim.join("gnss.txt"), t0 + offset_s)),
    );
    let lout = dir.join("level");
    run(&level, &lout);
    let lrows = errors(&lout.join("solution.nav"), &truth, &[]);
    let level_hrms = hrms(&lrows);
    let first60 = |r: &[Row]| {
        let t = r[0].t;
        hrms(
            &r.iter()
                .copied()
                .filter(|x| x.t < t + 60.0)
                .collect::<Vec<_>>(),
        )
    };
    let case = Case {
        method: a["method"].as_str().unwrap().to_string(),
        reason: a["reason"].as_str().unwrap().to_string(),
        skipped_s: a["imu_skipped_s"].as_f64().unwrap(),
        first_t: rows[0].t,
        first: rows[0],
        hrms: hrms(&rows),
        level_hrms,
        hrms_60: first60(&rows),
        level_hrms_60: first60(&lrows),
        rows,
    };
    let _ = std::fs::remove_dir_all(&dir);
    case
}

/// Sites and headings of the simulated sweeps: (seed, (lat, lon, h), heading).
const SITES: [(u64, (f64, f64, f64), f64); 4] = [
    (1, (40.097, -105.147, 1600.0), 30.0),
    (2, (-33.87, 151.21, 40.0), 200.0),
    (3, (64.13, -21.9, 20.0), 95.0),
    (4, (1.35, 103.82, 15.0), -150.0),
];

/// A car parked 30 s with its engine idling (0.15 m/s², 2.5 deg/s of vibration, far
/// above the [zupt] thresholds the old `auto` judged by), then driving: `auto` levels
/// on the static start, takes the yaw from the first motion, and navigates from the
/// first IMU sample; attitude at the start within 1 / 1 / 2 deg, horizontal RMS no
/// worse than a level start from the first fix.
#[test]
fn idling_car_aligns_static_over_seeds_sites_headings() {
    for (seed, site, heading) in SITES {
        let c = sim_case("scenarios/align_engine_car.toml", seed, site, heading, 0.0);
        eprintln!(
            "engine idle seed {seed} heading {heading}: {} | first output error roll {:.2} pitch {:.2} yaw {:.2} deg | horizontal RMS {:.3} m (level start {:.3} m), first 60 s {:.3} m ({:.3} m)",
            c.method, c.first.att[0], c.first.att[1], c.first.att[2], c.hrms, c.level_hrms, c.hrms_60, c.level_hrms_60
        );
        assert!(
            c.method.starts_with("static levelling"),
            "{}: {}",
            c.method,
            c.reason
        );
        assert!(c.reason.contains("window 10.0 s static"), "{}", c.reason);
        assert_eq!(c.skipped_s, 0.0);
        assert!(within(c.first.att), "seed {seed}: {:?}", c.first);
        assert!(
            no_worse(c.hrms, c.level_hrms),
            "seed {seed}: {} > {}",
            c.hrms,
            c.level_hrms
        );
        // 30 s into the motion (it starts at 30 s) the filter holds the attitude.
        let r = c.rows.iter().find(|r| r.t >= c.first_t + 60.0).unwrap();
        assert!(within(r.att), "seed {seed} at +60 s: {r:?}");
    }
}

/// The same car started 60 s in, driving at 12 m/s: the old `auto` read a 10 s
/// window, found motion, aligned on one pair of fixes and dropped the rest of the
/// window: its first output came 10 s late and 62 m from the car (RESULTS.md §17).
/// Now the output starts at the first GNSS epoch (at most one IMU interval after the
/// start) with the GNSS state there.
#[test]
fn car_started_in_motion_navigates_from_its_first_epoch() {
    for (seed, site, heading) in SITES {
        let c = sim_case("scenarios/align_engine_car.toml", seed, site, heading, 60.0);
        let first_s: Vec<f64> = c
            .rows
            .iter()
            .take_while(|r| r.t < c.first_t + 1.0)
            .map(|r| r.dh)
            .collect();
        let worst = first_s.iter().copied().fold(0.0, f64::max);
        eprintln!(
            "in motion seed {seed}: {} | skipped {:.3} s | first second's horizontal error up to {worst:.2} m | attitude error {:.2} {:.2} {:.2} deg | RMS {:.3} m (level start {:.3} m), first 60 s {:.3} m ({:.3} m)",
            c.method, c.skipped_s, c.first.att[0], c.first.att[1], c.first.att[2], c.hrms, c.level_hrms, c.hrms_60, c.level_hrms_60
        );
        assert!(c.method.starts_with("in motion"), "{}", c.method);
        assert!(c.skipped_s <= 0.011, "{}", c.skipped_s);
        assert!(worst < 3.0, "seed {seed}: {worst} m");
        assert!(
            within(c.first.att),
            "seed {seed}: {:?} ({})",
            c.first,
            c.reason
        );
        assert!(
            no_worse(c.hrms, c.level_hrms),
            "seed {seed}: {} > {}",
            c.hrms,
            c.level_hrms
        );
    }
}

/// The same car creeping at 0.8 m/s for its first 30 s with the engine's vibration:
/// not static (its GNSS speed; the IMU alone cannot tell constant creeping from rest),
/// so in motion, aligned once the car accelerates, within 1 / 1 / 2 deg. The user
/// gives the IMU mounting here: the first window that determines the attitude takes
/// the yaw from the course (the fit alone: 1-sigma over 1 deg), and with the 4 deg
/// mounting yaw unconfigured it errs by 2.0-2.2 deg.
#[test]
fn creeping_car_is_not_static() {
    let creep = |t: String| {
        let t = t.replacen(
            "[[segment]]\ntype = \"static\"\nduration_s = 30",
            "[[segment]]\ntype = \"hold\"\nduration_s = 30",
            1,
        );
        t.replacen("heading_deg = ", "speed_mps = 0.8\nheading_deg = ", 1)
    };
    for (seed, site, heading) in SITES.iter().take(2).copied() {
        let mounting = |t: String| {
            t.replace(
                "mounting_rpy_deg = [0.0, 0.0, 0.0]",
                "mounting_rpy_deg = [0.0, 2.0, 4.0]",
            )
        };
        let c = sim_case_with(
            "scenarios/align_engine_car.toml",
            seed,
            site,
            heading,
            0.0,
            &creep,
            &mounting,
        );
        eprintln!(
            "creeping seed {seed}: {} | skipped {:.1} s | attitude error {:.2} {:.2} {:.2} deg | {}",
            c.method, c.skipped_s, c.first.att[0], c.first.att[1], c.first.att[2], c.reason
        );
        assert!(c.method.starts_with("in motion"), "{}", c.method);
        assert!(
            c.reason
                .starts_with("the first 10.0 s moved (GNSS speed up to 0."),
            "{}",
            c.reason
        );
        assert!(within(c.first.att), "seed {seed}: {:?}", c.first);
    }
}

/// A UAV in flight with its IMU yawed 35 deg off the flight direction (not in the
/// configuration): the course is not the heading; the yaw comes from the horizontal
/// acceleration (the velocity matching), within 2 deg.
#[test]
fn uav_whose_heading_is_not_its_course() {
    for (seed, site, heading) in SITES {
        let c = sim_case("scenarios/align_uav.toml", seed, site, heading, 0.0);
        eprintln!(
            "UAV seed {seed}: {} | attitude error {:.2} {:.2} {:.2} deg | RMS {:.3} m (level start {:.3} m), first 60 s {:.3} m ({:.3} m)",
            c.method, c.first.att[0], c.first.att[1], c.first.att[2], c.hrms, c.level_hrms, c.hrms_60, c.level_hrms_60
        );
        assert!(
            c.reason.contains("yaw from the horizontal acceleration"),
            "{}",
            c.reason
        );
        assert!(within(c.first.att), "seed {seed}: {:?}", c.first);
        assert!(
            no_worse(c.hrms, c.level_hrms),
            "seed {seed}: {} > {}",
            c.hrms,
            c.level_hrms
        );
    }
}

/// An example configuration's text with its data paths made absolute.
fn example_text(name: &str) -> String {
    let text = std::fs::read_to_string(repo().join("examples").join(name)).unwrap();
    let shared_abs = format!("\"{}/", repo().join("../shared").display());
    text.replace("\"../../shared/", &shared_abs)
}

/// A configuration text with the `[initial.alignment]` table and `attitude_deg`
/// removed (the default `auto`), an optional start time, and lines added after
/// `[initial]`, written to `dir/file`.
fn auto_of(text: &str, start: Option<f64>, initial_extra: &str, dir: &Path, file: &str) -> PathBuf {
    let mut out = String::new();
    let mut skip = false;
    for l in text.lines() {
        if l.starts_with('[') {
            skip = l.trim() == "[initial.alignment]";
        }
        if skip || l.starts_with("attitude_deg") {
            continue;
        }
        out.push_str(l);
        out.push('\n');
        if l.trim() == "[time]" {
            if let Some(t) = start {
                out.push_str(&format!("start = {t}\n"));
            }
        }
        if l.trim() == "[initial]" {
            out.push_str(initial_extra);
        }
    }
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(file);
    std::fs::write(&p, out).unwrap();
    p
}

/// [`auto_of`] an example (paths made absolute).
fn example_auto(name: &str, start: Option<f64>, initial_extra: &str, dir: &Path) -> PathBuf {
    auto_of(
        &example_text(name),
        start,
        initial_extra,
        dir,
        &name.replace(".toml", "_auto.toml"),
    )
}

/// (t, NED velocity, yaw \[deg\]) of a .nav at or after `t`, and the course \[deg\] of
/// its first epoch at or after `t` with a horizontal speed of at least `speed`.
fn nav_at(nav: &Path, t: f64, speed: f64) -> (f64, [f64; 3], f64, f64) {
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(nav)
        .unwrap()
        .lines()
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .filter(|v: &Vec<f64>| v[1] >= t - 1e-6)
        .collect();
    let r = &rows[0];
    let course = rows
        .iter()
        .find(|v| v[5].hypot(v[6]) >= speed)
        .map(|v| v[6].atan2(v[5]).to_degrees())
        .unwrap();
    (r[1], [r[5], r[6], r[7]], r[10], course)
}

/// The real car (drive_0708, 1 Hz RTK fixes, consumer IMU on the roof, 35 s parked
/// with the engine running: 0.10-0.15 m/s² and 1.6-2.8 deg/s of vibration). Attitude
/// reference: the RTS-smoothed attitude of examples/drive_0708.toml (it agrees with the
/// smoothed NHC run within 0.03 / 0.02 / 0.20 deg RMS). `auto` from the start: static
/// (the old detector said moving and aligned 42 s later), navigates from the first
/// IMU sample. `auto` from 243400 s, driving at 9 m/s (the old `auto` lost 9 s of the
/// window and diverged, 144 km RMS): in motion from the first epoch; with the
/// mounting configured (examples/drive_0708_nhc.toml) within 1 / 1 / 2 deg; without
/// it (drive_0708.toml) the course-held yaw carries the unconfigured 5.35 deg mounting
/// yaw. Horizontal RMS against all RTK-fixed 4 Hz epochs, no worse than a level start
/// from the first fix.
#[test]
fn drive_0708_auto_static_and_in_motion() {
    let Some(d) = shared() else { return };
    let pos = d.join("rtklibexplorer/drive_0708/gnss_1934_sf.pos");
    let dir = tmp("align-drive");
    let reference = dir.join("ref");
    navfuse_ok(&[
        "run",
        repo().join("examples/drive_0708.toml").to_str().unwrap(),
        "--smooth",
        "--out",
        reference.to_str().unwrap(),
        "-q",
    ]);
    let ref_nav = reference.join("smoothed.nav");
    let lever = ["--lever-arm", "0,-0.05,0"];
    let score = |out: &Path| hrms(&errors(&out.join("solution.nav"), &pos, &lever));
    for (name, start, strict_yaw) in [
        ("drive_0708.toml", None, true),
        ("drive_0708_nhc.toml", Some(243400.0), true),
        ("drive_0708.toml", Some(243400.0), false),
    ] {
        let cfg = example_auto(name, start, "", &dir.join(format!("{name}-{start:?}")));
        let out = dir.join(format!("{name}-{start:?}-out"));
        run(&cfg, &out);
        let s = summary(&out);
        let a = &s["alignment"];
        let first = errors(&out.join("solution.nav"), &ref_nav, &[])[0];
        let h = score(&out);
        // The level start: roll and pitch 0, the first course of 3 m/s, the velocity
        // at the start (reference).
        let t_start = start.unwrap_or(243261.854);
        let (_, v, _, course) = nav_at(&ref_nav, t_start, 3.0);
        let v = if start.is_some() { v } else { [0.0; 3] };
        let level = example_auto(
            name,
            start,
            &format!(
                "attitude_deg = [0.0, 0.0, {course}]\nvelocity_mps = [{}, {}, {}]\n",
                v[0], v[1], v[2]
            ),
            &dir.join(format!("{name}-{start:?}-level")),
        );
        let text = std::fs::read_to_string(&level).unwrap();
        // (drive_0708.toml has its own static velocity line)
        let text = text.replace("velocity_mps = [0.0, 0.0, 0.0]   # static start\n", "");
        std::fs::write(&level, text).unwrap();
        let lout = dir.join(format!("{name}-{start:?}-level-out"));
        run(&level, &lout);
        let hl = score(&lout);
        eprintln!(
            "{name} auto from {:?}: {} at {:.3} (skipped {:.3} s) | attitude error roll {:.2} pitch {:.2} yaw {:.2} deg | horizontal RMS {h:.4} m (level start {hl:.4} m)",
            start,
            a["method"],
            a["t"].as_f64().unwrap(),
            a["imu_skipped_s"].as_f64().unwrap(),
            first.att[0],
            first.att[1],
            first.att[2]
        );
        let method = a["method"].as_str().unwrap();
        if start.is_none() {
            assert!(method.starts_with("static levelling"), "{method}");
            assert_eq!(a["imu_skipped_s"].as_f64().unwrap(), 0.0);
        } else {
            assert!(method.starts_with("in motion"), "{method}");
            assert!(a["imu_skipped_s"].as_f64().unwrap() < 0.2);
        }
        if strict_yaw {
            assert!(within(first.att), "{first:?}");
        } else {
            assert!(
                first.att[0].abs() <= 1.0 && first.att[1].abs() <= 1.0,
                "{first:?}"
            );
            assert!((first.att[2].abs() - 5.35).abs() < 1.5, "{first:?}");
        }
        assert!(no_worse(h, hl), "{h} > {hl}");
        assert!(h < 0.06, "{h}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The handheld walk (walk_0827: still 11 s while the hand shakes the IMU, then
/// walking at 1.3 m/s in tight turns, never 3 m/s): `auto` levels on the start and
/// takes the yaw from the horizontal acceleration of the first walking (no course at
/// walking speed). Reference: the RTS-smoothed run of the same loose configuration
/// with levelling and the first course at 0.8 m/s. Tight coupling on the 4 GPS
/// satellites: their single point velocities cannot give the yaw; the run says so.
#[test]
fn walk_0827_auto_loose_and_tight() {
    let Some(d) = shared() else { return };
    let w = d.join("rtklibexplorer/walk_0827");
    let pos = w.join("gnss_1730_sf.pos");
    let dir = tmp("align-walk");
    // The loose configuration: walk_0827_tight.toml on the receiver's .pos.
    let tight = example_text("walk_0827_tight.toml");
    let shared_abs = repo().join("../shared/data/rtklibexplorer/walk_0827");
    let obs = format!(
        "file = \"{0}/derived_rinex/gnss_1730.obs\"\nformat = \"rinex\"\nnav = \"{0}/derived_rinex/gnss_1730.nav\"\ncoupling = \"tight\"          # \"loose\": single point fixes instead\nrange_rate = \"tdcp\"         # \"doppler\" | \"tdcp\" | \"none\"\nelevation_mask_deg = 10",
        shared_abs.display()
    );
    let loose = tight
        .replace(
            &obs,
            &format!(
                "file = \"{}\"\nformat = \"rtklib-pos\"\nquality = [1, 2]\nuse_velocity = true",
                pos.display()
            ),
        )
        .replace(
            "position_std_m = [10.0, 10.0, 20.0]   # from the first single point fix",
            "position_std_m = [0.1, 0.1, 0.2]",
        );
    assert_ne!(loose, tight);
    std::fs::create_dir_all(&dir).unwrap();
    let loose_cfg = dir.join("walk_loose.toml");
    std::fs::write(&loose_cfg, &loose).unwrap();
    let reference = dir.join("ref");
    navfuse_ok(&[
        "run",
        loose_cfg.to_str().unwrap(),
        "--smooth",
        "--out",
        reference.to_str().unwrap(),
        "-q",
    ]);
    let auto = auto_of(&loose, None, "", &dir, "walk_loose_auto.toml");
    let ref_nav = reference.join("smoothed.nav");
    let out = dir.join("loose");
    run(&auto, &out);
    let a = &summary(&out)["alignment"];
    let first = errors(&out.join("solution.nav"), &ref_nav, &[])[0];
    let h = hrms(&errors(&out.join("solution.nav"), &pos, &[]));
    eprintln!(
        "walk loose auto: {} | attitude error roll {:.2} pitch {:.2} yaw {:.2} deg | horizontal RMS {h:.4} m",
        a["method"], first.att[0], first.att[1], first.att[2]
    );
    assert_eq!(a["method"], "static levelling + GNSS velocity matching");
    assert!(a["reason"]
        .as_str()
        .unwrap()
        .contains("the horizontal acceleration"));
    assert!(within(first.att), "{first:?}");
    // RESULTS.md §9.8: 0.047 m with the levelling and course of a new user's config.
    assert!(h < 0.047, "{h}");
    let tight_auto = example_auto("walk_0827_tight.toml", None, "", &dir);
    let tout = dir.join("tight");
    run(&tight_auto, &tout);
    let s = summary(&tout);
    eprintln!(
        "walk tight auto: {} | warnings {}",
        s["alignment"]["method"], s["warnings"]
    );
    assert!(s["warnings"]
        .to_string()
        .contains("the data did not give the initial yaw"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// PX4: the SITL flight (examples/px4_sitl.toml without its given attitude) sits level
/// on the ground, then climbs and descends without moving horizontally: `auto` levels
/// (roll and pitch within 1 deg of EKF2), and says the yaw is unknown (no course, no
/// horizontal acceleration, simulated gyros without Earth rate; EKF2 takes it from
/// the magnetometer). The hardware log (IMU only) is handled for its first 2 s, then
/// moved by hand: `auto` levels on that static beginning.
#[test]
fn px4_logs_auto() {
    let Some(d) = shared() else { return };
    let dir = tmp("align-px4");
    let sitl = d.join("px4/sample_px4_events.ulg");
    let cfg = example_auto("px4_sitl.toml", None, "", &dir);
    let out = dir.join("sitl");
    run(&cfg, &out);
    let s = summary(&out);
    let rows = errors(&out.join("solution.nav"), &sitl, &[]);
    let first = rows[0];
    eprintln!(
        "PX4 SITL auto: {} | roll {:.2} pitch {:.2} yaw {:.2} deg against EKF2 at {:.1} s | horizontal RMS {:.4} m",
        s["alignment"]["method"], first.att[0], first.att[1], first.att[2], first.t, hrms(&rows)
    );
    assert!(s["alignment"]["method"]
        .as_str()
        .unwrap()
        .starts_with("static levelling"));
    assert!(
        first.att[0].abs() < 1.0 && first.att[1].abs() < 1.0,
        "{first:?}"
    );
    assert!(s["warnings"]
        .to_string()
        .contains("the yaw starts at 0 deg"));

    // Hardware, IMU only: levelling on the static beginning.
    let hw = d.join("px4/sample.ulg");
    let cfg = dir.join("hw.toml");
    std::fs::write(
        &cfg,
        format!(
            "[imu]\nfile = {:?}\nformat = \"ulog\"\nrate_hz = 250\n\n\
             [initial]\nposition_deg_m = [47.4, 8.5, 500.0]\nposition_std_m = 1.0\n\
             velocity_std_mps = 0.1\nattitude_std_deg = [1.0, 1.0, 10.0]\n\n\
             [imu_noise]\narw_deg_sqrth = 0.5\nvrw_mps_sqrth = 0.3\ngyro_bias_std_degph = 100\n\
             accel_bias_std_mgal = 3000\ngyro_scale_std_ppm = 1000\naccel_scale_std_ppm = 1000\n\
             corr_time_h = 1\n",
            hw.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.join("hw");
    run(&cfg, &out);
    let a = summary(&out)["alignment"].clone();
    let (t0, roll, pitch) = (
        a["t"].as_f64().unwrap(),
        a["roll_deg"].as_f64().unwrap(),
        a["pitch_deg"].as_f64().unwrap(),
    );
    let u = navfuse_io::ulog::Ulog::parse(std::fs::read(&hw).unwrap()).unwrap();
    let att = u.topic("vehicle_attitude", 0).unwrap();
    let q: Vec<_> = (0..4)
        .map(|i| att.field(&format!("q[{i}]")).unwrap().clone())
        .collect();
    let mut ekf = Vec::new();
    for k in 0..att.len() {
        let t = att.timestamp_us(k).unwrap() as f64 * 1e-6;
        if t >= t0 && t <= t0 + 2.0 {
            let qq = nalgebra::Quaternion::new(
                att.value(k, &q[0]),
                att.value(k, &q[1]),
                att.value(k, &q[2]),
                att.value(k, &q[3]),
            );
            let rpy = navfuse_core::attitude::euler_from_q_bn(
                &nalgebra::UnitQuaternion::from_quaternion(qq),
            );
            ekf.push((rpy.x.to_degrees(), rpy.y.to_degrees()));
        }
    }
    let n = ekf.len() as f64;
    let (er, ep) = (
        ekf.iter().map(|e| e.0).sum::<f64>() / n,
        ekf.iter().map(|e| e.1).sum::<f64>() / n,
    );
    eprintln!(
        "PX4 hardware auto: {} | roll {roll:.2} pitch {pitch:.2} deg, EKF2 {er:.2} {ep:.2} deg | {}",
        a["method"], a["reason"]
    );
    assert!(a["reason"]
        .as_str()
        .unwrap()
        .contains("levelling on its first 2.0 s"));
    assert!((roll - er).abs() < 1.0 && (pitch - ep).abs() < 1.0);
    let _ = std::fs::remove_dir_all(&dir);
}
