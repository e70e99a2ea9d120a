//! Loose coupling from files, as a Rust user calls it: load the shipped demo
//! configuration (a 3-minute excerpt of a real car drive: u-blox IMU and RTKLIB
//! fixes), run the complete `navfuse run` pipeline into memory, look at the result.
//!
//!     cargo run --release -p navfuse-app --example loose_from_files

use navfuse_app::{config, run, MemorySink, RunOptions};
use std::path::Path;

fn main() -> Result<(), navfuse_app::Error> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo/drive_excerpt.toml");
    let cfg = config::load(&path)?;
    let mut sink = MemorySink::new();
    let job = run(cfg, &mut sink, &RunOptions::default())?;
    println!("{}", job.summary_line());
    let (first, last) = (&sink.records[0], sink.records.last().expect("epochs"));
    println!(
        "{} epochs from {:.1} to {:.1} s of GPS week {}",
        sink.records.len(),
        first.nav.t,
        last.nav.t,
        last.gps_week
    );
    let (lla, v) = (last.nav.lla, last.nav.v_n);
    println!(
        "last epoch: lat {:.7} deg, lon {:.7} deg, h {:.2} m, speed {:.2} m/s",
        lla.x.to_degrees(),
        lla.y.to_degrees(),
        lla.z,
        v.norm()
    );
    let rejected: usize = job.summary.aiding_rejected.values().sum();
    println!(
        "events: {}, rejected updates: {rejected}",
        sink.events.len()
    );
    Ok(())
}
