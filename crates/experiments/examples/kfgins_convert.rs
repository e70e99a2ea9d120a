//! A navfuse run's inputs in KF-GINS's formats (issue 30, RESULTS.md §20):
//!
//!     cargo run --release -p navfuse-experiments --example kfgins_convert -- \
//!         examples/drive_0708.toml OUT_DIR [START_S]
//!
//! writes OUT_DIR/ref (navfuse's own run, which finds the GNSS-IMU time offset) and
//! OUT_DIR/kfgins/{IMU.txt, GNSS.txt, kf-gins.yaml} (IMU times moved to GNSS time),
//! for `navfuse run --kf-gins OUT_DIR/kfgins/kf-gins.yaml` or KF-GINS itself.

use navfuse_experiments::kfgins_convert::convert_run;
use std::path::PathBuf;

fn main() -> navfuse_experiments::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() < 2 {
        eprintln!("usage: kfgins_convert CONFIG OUT_DIR [START_S]");
        std::process::exit(2);
    }
    let start = a.get(2).map(|s| s.parse::<f64>()).transpose()?;
    let f = convert_run(&PathBuf::from(&a[0]), &PathBuf::from(&a[1]), start)?;
    println!(
        "{} IMU samples, {} fixes: {}",
        f.imu_samples,
        f.fixes,
        f.yaml.display()
    );
    Ok(())
}
