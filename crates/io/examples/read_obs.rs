//! Read a RINEX observation file (plain, gzip or Compact RINEX) and print its
//! systems, signals and reading speed:
//! `cargo run --release -p navfuse-io --example read_obs -- FILE`.

use navfuse_io::rinex_obs::read_rinex_obs_all;
use std::collections::BTreeMap;
use std::time::Instant;

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: read_obs FILE");
        std::process::exit(2);
    };
    let path = std::path::Path::new(&path);
    let t0 = Instant::now();
    let r = match read_rinex_obs_all(path) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let dt = t0.elapsed().as_secs_f64();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for s in r.epochs.iter().flat_map(|e| &e.sats) {
        for (c, v) in &s.signals {
            if v.value.is_some() {
                *counts
                    .entry(format!("{} {c}", s.sat.system.letter()))
                    .or_default() += 1;
            }
        }
    }
    let n: usize = counts.values().sum();
    let mb = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0) as f64 / 1e6;
    println!(
        "{}: RINEX {}, {} epochs, {n} observations in {dt:.3} s: {:.0} epochs/s, {:.1} MB/s of the file ({mb:.1} MB)",
        path.display(),
        r.header.version,
        r.epochs.len(),
        r.epochs.len() as f64 / dt,
        mb / dt
    );
    for (k, v) in &counts {
        println!("{k} {v}");
    }
    for w in &r.warnings {
        println!("warning: {w}");
    }
}
