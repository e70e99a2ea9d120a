//! Issue 15 (finding 5): the filter is consistent with time-correlated GNSS fix errors.
//! 20 Monte Carlo runs of scenarios/consistency_car.toml (the simulator's default
//! Gauss-Markov fix errors: 1.5 m / 3 m, 60 s): the normalised estimation error squared
//! (NEES) of position, velocity and attitude, averaged over the runs at each second,
//! against the two-sided 95 % chi-square band of 3N degrees of freedom over N. With
//! the Gauss-Markov fix-error states (the simulator's run.toml declares them) the
//! position is consistent; treating the same errors as white it is not.
//!
//! The filter's IMU bias model is set to the grade's own correlation time (100 s)
//! here: the run.toml that `navfuse sim` writes uses at least 1 h (so a turn-on bias
//! is not forgotten under weak aiding), which leaves velocity and attitude
//! overconfident (NEES 12-13) whatever the GNSS model; that is a separate choice.

mod common;

use common::{nees, nees_band as band, repo, run, simulate_seed, tmp};
use navfuse_io::config;

const RUNS: usize = 20;

#[test]
fn nees_is_consistent_with_gauss_markov_fix_errors() {
    let base = tmp("consistency");
    let scen = repo().join("scenarios/consistency_car.toml");
    // [variant][epoch] sums over the runs.
    let mut sums: Vec<Vec<[f64; 3]>> = vec![Vec::new(), Vec::new()];
    for seed in 1..=RUNS {
        let dir = base.join(format!("seed{seed}"));
        simulate_seed(&scen, &dir, Some(seed as u64));
        let mut cfg = config::load(&dir.join("run.toml")).unwrap();
        assert!(
            cfg.nav.gnss.fix_error.correlated(),
            "run.toml declares the GM fix errors"
        );
        cfg.nav.imu_noise.corr_time_s = 100.0;
        cfg.output.std = true;
        cfg.output.rate_hz = Some(1.0);
        let mut white = cfg.clone();
        white.nav.gnss.fix_error.corr_time_s = 0.0;
        for (v, c) in [cfg, white].into_iter().enumerate() {
            let toml = dir.join(format!("run{v}.toml"));
            std::fs::write(&toml, c.to_toml_string()).unwrap();
            let out = dir.join(format!("out{v}"));
            run(&toml, &out);
            let e = nees(
                &dir.join("truth.nav"),
                &out.join("solution.nav"),
                &out.join("std.txt"),
            );
            let s = &mut sums[v];
            if s.is_empty() {
                s.resize(e.len(), [0.0; 3]);
            }
            let n = s.len().min(e.len());
            s.truncate(n);
            for (acc, x) in s.iter_mut().zip(&e) {
                for k in 0..3 {
                    acc[k] += x[k];
                }
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    let (lo, hi) = band(RUNS);
    let mut means = [[0.0; 3]; 2];
    for (v, name) in ["Gauss-Markov states", "white"].iter().enumerate() {
        let avg: Vec<[f64; 3]> = sums[v].iter().map(|a| a.map(|x| x / RUNS as f64)).collect();
        for k in 0..3 {
            let m = avg.iter().map(|a| a[k]).sum::<f64>() / avg.len() as f64;
            let inside =
                avg.iter().filter(|a| a[k] >= lo && a[k] <= hi).count() as f64 / avg.len() as f64;
            means[v][k] = m;
            eprintln!(
                "{name}: {} NEES {m:.2} (band [{lo:.2}, {hi:.2}]), {:.0} % of the epochs inside",
                ["position", "velocity", "attitude"][k],
                inside * 100.0
            );
        }
    }
    let [pos, vel, att] = means[0];
    assert!(pos > lo && pos < hi, "position NEES {pos}");
    assert!(vel > lo && vel < hi, "velocity NEES {vel}");
    // Attitude: not overconfident (measured 1.9, slightly conservative: the yaw).
    assert!(att < hi, "attitude NEES {att}");
    // The same errors taken as white: position overconfident.
    assert!(means[1][0] > hi, "white position NEES {}", means[1][0]);
    let _ = std::fs::remove_dir_all(&base);
}
