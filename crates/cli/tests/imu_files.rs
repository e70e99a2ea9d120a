//! An IMU in several CSV files (`[imu] files`): the demo's IMU split the way
//! simulators write it (time / gyro xyz / accel xyz, each with a header) runs through
//! `navfuse run` and gives the same solution as the one-file CSV; mismatched files are
//! errors with both files and the line.

mod common;

use common::{navfuse_ok, repo, tmp};
use std::path::Path;

/// Split examples/demo/imu.csv (t, accel xyz, gyro xyz) into three files.
fn split(dir: &Path, drop_last_accel: bool) {
    let text = std::fs::read_to_string(repo().join("examples/demo/imu.csv")).unwrap();
    let (mut t, mut g, mut a) = (
        String::from("time_s\n"),
        String::from("gx_dps,gy_dps,gz_dps\n"),
        String::from("ax_g;ay_g;az_g\n"),
    );
    let rows: Vec<&str> = text.lines().skip(2).collect();
    for (k, line) in rows.iter().enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        t.push_str(&format!("{}\n", f[0]));
        g.push_str(&format!("{},{},{}\n", f[4], f[5], f[6]));
        if !(drop_last_accel && k + 1 == rows.len()) {
            a.push_str(&format!("{} {} {}\n", f[1], f[2], f[3]));
        }
    }
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("time.csv"), t).unwrap();
    std::fs::write(dir.join("gyro.csv"), g).unwrap();
    std::fs::write(dir.join("accel.csv"), a.replace(';', ",")).unwrap();
}

/// The demo's configuration reading the three files.
fn config(dir: &Path) -> std::path::PathBuf {
    let demo = std::fs::read_to_string(repo().join("examples/demo/drive_excerpt.toml")).unwrap();
    let gnss = repo().join("examples/demo/gnss.pos");
    let cfg = demo
        .replace(
            "file = \"imu.csv\"",
            "files = { time = \"time.csv\", gyro = \"gyro.csv\", accel = \"accel.csv\" }",
        )
        .replace("skip_lines = 2              # comment + header\n", "")
        .replace("accel_cols = [1, 2, 3]", "accel_cols = [0, 1, 2]")
        .replace("gyro_cols = [4, 5, 6]", "gyro_cols = [0, 1, 2]")
        .replace(
            "file = \"gnss.pos\"",
            &format!("file = {:?}", gnss.to_str().unwrap()),
        );
    assert!(cfg.contains("files = {") && cfg.contains(gnss.to_str().unwrap()));
    let p = dir.join("run.toml");
    std::fs::write(&p, cfg).unwrap();
    p
}

#[test]
fn three_files_run_like_the_pasted_csv() {
    let dir = tmp("imu_files");
    split(&dir, false);
    let cfg = config(&dir);
    let (one, three) = (dir.join("one"), dir.join("three"));
    navfuse_ok(&[
        "run",
        "examples/demo/drive_excerpt.toml",
        "--out",
        one.to_str().unwrap(),
        "-q",
    ]);
    navfuse_ok(&[
        "run",
        cfg.to_str().unwrap(),
        "--out",
        three.to_str().unwrap(),
        "-q",
    ]);
    let a = std::fs::read(one.join("solution.nav")).unwrap();
    let b = std::fs::read(three.join("solution.nav")).unwrap();
    assert!(a.len() > 10_000);
    assert!(
        a == b,
        "solution.nav differs between one and three IMU files"
    );
    println!(
        "three IMU files: solution.nav identical to the one-file run ({} lines)",
        a.iter().filter(|&&c| c == b'\n').count()
    );
}

#[test]
fn mismatched_files_name_the_line() {
    let dir = tmp("imu_files_bad");
    split(&dir, true);
    let cfg = config(&dir);
    let c = navfuse_io::config::load(&cfg).unwrap();
    let e = navfuse_io::imu::open_imu(&c.imu).err().unwrap().to_string();
    println!("{e}");
    let n = std::fs::read_to_string(dir.join("time.csv"))
        .unwrap()
        .lines()
        .count();
    assert!(e.contains(&format!("time.csv:{n}:")), "{e}");
    assert!(e.contains("accel.csv has"), "{e}");
    // Joined on time: a gyro file with its own times, one of them off.
    let t = std::fs::read_to_string(dir.join("time.csv")).unwrap();
    let g = std::fs::read_to_string(dir.join("gyro.csv")).unwrap();
    let mut tg = String::from("t,gx,gy,gz\n");
    for (k, (tl, gl)) in t.lines().zip(g.lines()).skip(1).enumerate() {
        let tl = if k == 4 { "1.0" } else { tl };
        tg.push_str(&format!("{tl},{gl}\n"));
    }
    std::fs::write(dir.join("gyro.csv"), tg).unwrap();
    split_accel_whole(&dir);
    let text = std::fs::read_to_string(&cfg).unwrap().replace(
        "accel = \"accel.csv\" }",
        "accel = \"accel.csv\", gyro_time_col = 0 }",
    );
    let text = text.replace("gyro_cols = [0, 1, 2]", "gyro_cols = [1, 2, 3]");
    std::fs::write(&cfg, text).unwrap();
    let c = navfuse_io::config::load(&cfg).unwrap();
    let e = navfuse_io::imu::open_imu(&c.imu).err().unwrap().to_string();
    println!("{e}");
    assert!(e.contains("gyro.csv:6: field 'time'"), "{e}");
    assert!(e.contains("time.csv:6"), "{e}");
}

/// The accel file again with every row.
fn split_accel_whole(dir: &Path) {
    let text = std::fs::read_to_string(repo().join("examples/demo/imu.csv")).unwrap();
    let mut a = String::from("ax_g,ay_g,az_g\n");
    for line in text.lines().skip(2) {
        let f: Vec<&str> = line.split(',').collect();
        a.push_str(&format!("{},{},{}\n", f[1], f[2], f[3]));
    }
    std::fs::write(dir.join("accel.csv"), a).unwrap();
}
