//! An aiding source of your own: a vehicle on flat ground whose height is known to
//! within 0.3 m (a car on a test track, a surface vessel). The source fuses the
//! pseudo-measurement y = h_INS - h_known ~ -dr_D once a second after the IMU steps,
//! through the same `Fuser` the built-in sources use. On a simulated car in an urban
//! canyon (tight coupling, 60 s with only 2 satellites) the known height is a third
//! measurement where the satellites give two: compare the errors with and without.
//!
//!     cargo run --release -p navfuse-app --example custom_source

use nalgebra::{DMatrix, DVector};
use navfuse_app::prelude::*;
use navfuse_core::earth::lla_diff_ned;
use navfuse_core::state::POS;
use navfuse_io::nav::read_nav;
use navfuse_sim::{generate::generate, scenario::Scenario};
use std::path::Path;

/// The scenario's ground height [m] (scenarios/blockage_2sat.toml, a flat drive).
const GROUND_HEIGHT_M: f64 = 15.0;

/// Known height h [m] with 1-sigma `std_m`, fused every `period_s` of IMU time.
struct KnownHeight {
    height_m: f64,
    std_m: f64,
    period_s: f64,
    next_t: f64,
}

impl AidingSource for KnownHeight {
    fn name(&self) -> &'static str {
        "known_height"
    }

    fn after_imu(&mut self, f: &mut Fuser) {
        let t = f.nav().t;
        if t < self.next_t {
            return;
        }
        self.next_t = t + self.period_s;
        // y = h_est - h_known; the position error dr_D = D_est - D_true = -(h_est - h_true).
        let mut h = DMatrix::zeros(1, f.layout().len());
        h[(0, POS + 2)] = -1.0;
        let lin = Linearized {
            y: DVector::from_element(1, f.nav().lla.z - self.height_m),
            h,
            r: DMatrix::from_element(1, 1, self.std_m * self.std_m),
        };
        let gate = Some(navfuse_core::chi2::chi2_threshold(1, 1e-4));
        f.fuse_rows("known_height", &lin, gate, true);
    }
}

/// What `RunOptions::extra_sources` calls at the start (t0: IMU time).
fn known_height(_cfg: &NavConfig, t0: f64) -> Vec<Box<dyn AidingSource>> {
    vec![Box::new(KnownHeight {
        height_m: GROUND_HEIGHT_M,
        std_m: 0.3,
        period_s: 1.0,
        next_t: t0,
    })]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scenario = Scenario::load(&root.join("scenarios/blockage_2sat.toml"))?;
    let dir = std::env::temp_dir().join(format!("navfuse-example-custom-{}", std::process::id()));
    generate(&scenario, &dir)?;
    let truth = read_nav(&dir.join("truth.nav"))?;
    for extra in [None, Some(known_height as SourceFactory)] {
        let cfg = load_config(&dir.join("run.toml"))?;
        let mut sink = MemorySink::new();
        let opts = RunOptions {
            extra_sources: extra,
            ..Default::default()
        };
        let job = run(cfg, &mut sink, &opts)?;
        // RMS horizontal and vertical error against the truth at common epochs.
        let (mut h2, mut v2, mut n, mut k) = (0.0, 0.0, 0usize, 0);
        for (_, t) in &truth {
            while k + 1 < sink.records.len() && sink.records[k].nav.t < t.t - 1e-6 {
                k += 1;
            }
            let r = &sink.records[k];
            if (r.nav.t - t.t).abs() < 1e-6 {
                let e = lla_diff_ned(&r.nav.lla, &t.lla);
                h2 += e.x * e.x + e.y * e.y;
                v2 += e.z * e.z;
                n += 1;
            }
        }
        let used = job
            .summary
            .aiding_used
            .get("known_height")
            .copied()
            .unwrap_or(0);
        println!(
            "{:<22} known-height updates {used:>3}; RMS error horizontal {:.2} m, vertical {:.2} m",
            if extra.is_some() {
                "with the custom source:"
            } else {
                "without it:"
            },
            (h2 / n.max(1) as f64).sqrt(),
            (v2 / n.max(1) as f64).sqrt(),
        );
    }
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
