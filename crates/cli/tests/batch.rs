//! `navfuse batch` (issue 21): many runs in one process. The tables are the same bytes
//! whatever the number of jobs and with or without case folders; a case folder holds
//! what `navfuse run` writes; a case scored in memory gives the row it gives with its
//! files written, in any thread; bad manifests are errors naming the file, line and
//! key; a failing case is a row, and the exit status says so after the tables are
//! written.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{navfuse_ok, repo, tmp};
use navfuse_experiments::batch::{run_batch, run_case, Manifest, METRICS};

/// scenarios/seed001_car.toml cut to about 65 s: a start at rest, a straight, a turn.
fn tiny_scenario() -> String {
    let full = std::fs::read_to_string(repo().join("scenarios/seed001_car.toml")).unwrap();
    let head = &full[..full.find("[[segment]]").unwrap()];
    format!(
        "{head}[[segment]]\ntype = \"static\"\nduration_s = 20\n\n\
         [[segment]]\ntype = \"accelerate\"\naccel_mps2 = 1.5\nto_speed_mps = 12\nramp_s = 1\n\n\
         [[segment]]\ntype = \"hold\"\nduration_s = 20\n\n\
         [[segment]]\ntype = \"turn\"\nrate_dps = 12\nangle_deg = 90\nramp_s = 1.5\n\n\
         [[segment]]\ntype = \"hold\"\nduration_s = 10\n"
    )
}

/// A scratch folder with tiny.toml and the manifest `text` as m.toml in it.
fn setup(name: &str, text: &str) -> (PathBuf, PathBuf) {
    let dir = tmp(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tiny.toml"), tiny_scenario()).unwrap();
    let m = dir.join("m.toml");
    std::fs::write(&m, text).unwrap();
    (dir, m)
}

fn batch(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .current_dir(repo())
        .arg("batch")
        .args(args)
        .output()
        .expect("run navfuse batch")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The absolute path of examples/demo/FILE.
fn demo(file: &str) -> String {
    let p = repo()
        .join("examples/demo")
        .join(file)
        .canonicalize()
        .unwrap();
    s(&p).to_string()
}

const MC: &str = "[monte_carlo]\nscenario = \"tiny.toml\"\nseeds = 4\nfirst_seed = 7\nname = \"mc\"\noutages = \"10/30@345630\"\ngaps = \"10/30@345630\"\n";

#[test]
fn monte_carlo_tables_are_the_same_bytes_whatever_the_jobs_and_files() {
    let (dir, m) = setup("batch-jobs", MC);
    let (a, b) = (dir.join("a"), dir.join("b"));
    let one = batch(&[s(&m), "--out", s(&a), "--jobs", "1"]);
    // With 3 jobs and no case folders: the same tables.
    let three = batch(&[s(&m), "--out", s(&b), "--jobs", "3", "-q", "--tables-only"]);
    let err = String::from_utf8_lossy(&one.stderr);
    assert!(one.status.success(), "{err}");
    assert!(
        three.status.success(),
        "{}",
        String::from_utf8_lossy(&three.stderr)
    );
    for f in ["batch.csv", "batch.json"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs between --jobs 1 and --jobs 3");
    }
    // One line per case (unless -q), and the total.
    assert_eq!(err.matches("] mc_seed00").count(), 4, "{err}");
    assert!(err.contains("cases/s"), "{err}");
    let e3 = String::from_utf8_lossy(&three.stderr);
    assert!(!e3.contains("] mc_seed"), "{e3}");
    let csv = std::fs::read_to_string(a.join("batch.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5, "{csv}");
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(&header[..5], ["index", "name", "seed", "status", "epochs"]);
    assert_eq!(header.len(), 5 + METRICS.len() + 1);
    let h = header.iter().position(|c| *c == "h_rms_m").unwrap();
    let gap = header.iter().position(|c| *c == "gap_h_max_rms_m").unwrap();
    for (k, l) in lines[1..].iter().enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f[1], format!("mc_seed{:04}", 7 + k));
        assert_eq!(f[2], (7 + k).to_string());
        assert_eq!(f[3], "completed", "{l}");
        let h: f64 = f[h].parse().unwrap();
        assert!(h > 0.0 && h < 10.0, "{l}");
        assert!(f[gap].parse::<f64>().unwrap() > 0.0, "{l}");
    }
    // Seeds differ, so do their figures.
    assert_ne!(lines[1].split(',').nth(h), lines[2].split(',').nth(h));
    // The case folders: the run's files and the simulated data.
    for f in [
        "solution.nav",
        "summary.json",
        "events.log",
        "config.toml",
        "sim/truth.nav",
    ] {
        assert!(a.join("mc_seed0007").join(f).is_file(), "{f}");
    }
    assert!(!b.join("mc_seed0007").exists());
    let timing = std::fs::read_to_string(a.join("batch_timing.csv")).unwrap();
    assert!(
        timing.starts_with("index,name,wall_s\n0,mc_seed0007,"),
        "{timing}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_case_folder_is_what_navfuse_run_writes_and_its_figures_what_eval_gives() {
    let text = format!(
        "[[run]]\nconfig = \"{}\"\ntruth = \"{}\"\nlever_arm = [0.0, -0.05, 0.0]\n",
        demo("drive_excerpt.toml"),
        demo("gnss.pos")
    );
    let (dir, m) = setup("batch-run", &text);
    let out = dir.join("out");
    let o = batch(&[s(&m), "--out", s(&out), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let case = out.join("drive_excerpt");
    let run = dir.join("run");
    // The same configuration path as the manifest's (config.toml's header names it).
    let cfg = demo("drive_excerpt.toml");
    navfuse_ok(&["run", &cfg, "--out", s(&run), "-q"]);
    let names = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names(&case), names(&run));
    for f in [
        "solution.nav",
        "innovations.csv",
        "config.toml",
        "states.csv",
    ] {
        if run.join(f).exists() {
            let same = std::fs::read(case.join(f)).unwrap() == std::fs::read(run.join(f)).unwrap();
            assert!(same, "{f} differs from navfuse run's");
        }
    }
    // The figures are `navfuse eval`'s of the written solution, bit for bit.
    let eval = navfuse_ok(&[
        "eval",
        s(&case.join("solution.nav")),
        "examples/demo/gnss.pos",
        "--lever-arm",
        "0,-0.05,0",
        "--json",
    ]);
    let e: serde_json::Value = serde_json::from_str(&eval).unwrap();
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("batch.json")).unwrap()).unwrap();
    let row = &j["rows"][0]["metrics"];
    assert_eq!(row["h_rms_m"], e["position_m"]["horizontal"]["rms"]);
    assert_eq!(row["max_3d_m"], e["position_m"]["3d"]["max"]);
    assert_eq!(row["scored_epochs"].as_f64(), e["epochs"].as_f64());
    let vel = e.pointer("/velocity_mps/3d/rms").cloned();
    assert_eq!(
        row["vel_3d_rms_mps"],
        vel.unwrap_or(serde_json::Value::Null)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_row_is_the_same_in_memory_with_files_and_in_another_thread() {
    let (dir, m) = setup("batch-rows", MC);
    let m = Manifest::load(&m).unwrap();
    assert_eq!(m.len(), 4);
    assert_eq!(
        m.case_names(),
        ["mc_seed0007", "mc_seed0008", "mc_seed0009", "mc_seed0010"]
    );
    let in_memory = run_case(&m, 1, None);
    assert_eq!(in_memory.status, "completed", "{:?}", in_memory.error);
    assert_eq!(in_memory.seed, Some(8));
    assert!(in_memory.epochs > 1000);
    let names: Vec<&str> = in_memory.metrics.iter().map(|(k, _)| k.as_str()).collect();
    let order: Vec<&str> = METRICS
        .iter()
        .map(|m| m.0)
        .filter(|k| names.contains(k))
        .collect();
    assert_eq!(names, order);
    let with_files = run_case(&m, 1, Some(&dir.join("out")));
    assert_eq!(in_memory, with_files);
    assert!(dir.join("out/mc_seed0008/solution.nav").is_file());
    let other = std::thread::scope(|t| t.spawn(|| run_case(&m, 1, None)).join().unwrap());
    assert_eq!(in_memory, other);
    // The pool: the same rows, in manifest order.
    let r = run_batch(&m, None, 2, false).unwrap();
    assert_eq!(r.rows[1], in_memory);
    assert_eq!(
        r.rows.iter().map(|r| r.index).collect::<Vec<_>>(),
        [0, 1, 2, 3]
    );
    assert_eq!(r.wall_s.len(), 4);
    let _ = std::fs::remove_dir_all(&dir);
}

fn manifest_error(text: &str) -> String {
    let (dir, m) = setup("batch-bad", text);
    let e = Manifest::load(&m).map(|_| ()).unwrap_err();
    let _ = std::fs::remove_dir_all(&dir);
    format!("{e:#}")
}

#[test]
fn bad_manifests_name_the_file_line_and_key() {
    let cfg = demo("drive_excerpt.toml");
    let e = manifest_error(&format!(
        "[[run]]\nconfig = \"{cfg}\"\n\n[[run]]\nconfig = \"{cfg}\"\nnmae = \"x\"\n"
    ));
    assert!(e.contains("m.toml:6") && e.contains("run[1].nmae"), "{e}");
    let e = manifest_error(&format!(
        "[[run]]\nconfig = \"{cfg}\"\nname = \"a\"\n\n[[run]]\nconfig = \"{cfg}\"\nname = \"a\"\n"
    ));
    assert!(e.contains("m.toml:7") && e.contains("run[1].name"), "{e}");
    assert!(e.contains("run[0]") && e.contains("line 1"), "{e}");
    // Without names, both default to the config's stem.
    let e = manifest_error(&format!(
        "[[run]]\nconfig = \"{cfg}\"\n\n[[run]]\nconfig = \"{cfg}\"\n"
    ));
    assert!(e.contains("'drive_excerpt'") && e.contains("run[0]"), "{e}");
    let e = manifest_error("[[run]]\nname = \"x\"\nconfig = \"nowhere/missing.toml\"\n");
    assert!(
        e.contains("m.toml:3") && e.contains("run[0] 'x'") && e.contains("missing.toml"),
        "{e}"
    );
    let e = manifest_error("[monte_carlo]\nscenario = \"tiny.toml\"\nseeds = 2\nseed = 3\n");
    assert!(
        e.contains("m.toml:4") && e.contains("monte_carlo.seed"),
        "{e}"
    );
    let e = manifest_error("[monte_carlo]\nscenario = \"tiny.toml\"\nseeds = 2\ngaps = \"1:x\"\n");
    assert!(
        e.contains("m.toml:4") && e.contains("monte_carlo.gaps"),
        "{e}"
    );
    let e = manifest_error(&format!(
        "[monte_carlo]\nscenario = \"tiny.toml\"\nseeds = 1\n\n[[run]]\nconfig = \"{cfg}\"\n"
    ));
    assert!(e.contains("not both"), "{e}");
}

#[test]
fn a_failing_case_is_a_row_and_the_exit_status_says_so() {
    let (dir, _) = setup("batch-fail", "");
    // A configuration that loads but names an IMU file that is not there.
    let cfg = std::fs::read_to_string(repo().join("examples/demo/drive_excerpt.toml"))
        .unwrap()
        .replace("file = \"imu.csv\"", "file = \"no_such_imu.csv\"");
    std::fs::write(dir.join("broken.toml"), cfg).unwrap();
    let text = format!(
        "[[run]]\nconfig = \"broken.toml\"\n\n[[run]]\nconfig = \"{}\"\nname = \"good\"\n",
        demo("drive_excerpt.toml")
    );
    let m = dir.join("m.toml");
    std::fs::write(&m, text).unwrap();
    let out = dir.join("out");
    let o = batch(&[s(&m), "--out", s(&out), "--jobs", "2"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("1 of 2 cases failed"), "{err}");
    let csv = std::fs::read_to_string(out.join("batch.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert!(rows[0].starts_with("0,broken,,failed,0,"), "{csv}");
    assert!(rows[0].contains("no_such_imu.csv"), "{csv}");
    assert!(rows[1].starts_with("1,good,,completed,"), "{csv}");
    assert!(out.join("batch.json").is_file() && out.join("batch_timing.csv").is_file());
    // The failed case's folder says why, as `navfuse run` does.
    let summary = std::fs::read_to_string(out.join("broken/summary.json")).unwrap();
    assert!(summary.contains("\"failed\""), "{summary}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sigint_stops_handing_out_cases_and_the_tables_are_written() {
    use std::io::{BufRead, BufReader};
    let (dir, m) = setup(
        "batch_sigint",
        "[monte_carlo]\nscenario = \"tiny.toml\"\nseeds = 400\nname = \"mc\"\n",
    );
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args([
            "batch",
            s(&m),
            "--out",
            s(&out),
            "--jobs",
            "1",
            "--tables-only",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start navfuse batch");
    // After the first finished case, SIGINT.
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    assert!(
        first.starts_with("[1/400] mc_seed0001: completed"),
        "{first}"
    );
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    assert!(kill.is_ok_and(|k| k.success()));
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{rest:?}");
    assert!(
        rest.iter().any(|l| l.contains("navfuse batch stopped")),
        "{rest:?}"
    );
    let csv = std::fs::read_to_string(out.join("batch.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 400);
    let not_run = rows
        .iter()
        .filter(|r| r.ends_with("not run: the batch was interrupted"))
        .count();
    let completed = rows.iter().filter(|r| r.contains(",completed,")).count();
    assert!(
        completed >= 1 && not_run >= 1 && completed + not_run == 400,
        "{csv}"
    );
}
