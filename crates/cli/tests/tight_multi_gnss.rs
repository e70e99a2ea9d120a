//! Issue 19 item 5: tight coupling with GPS and Galileo where satellites are few. The
//! simulated car of scenarios/multi_gnss_car.toml (GPS + Galileo, Galileo ISB +3 m)
//! with a 60 s blockage that leaves one GPS and two Galileo satellites (the
//! strongest of each system at the blockage start): the horizontal drift over the
//! blockage of tight coupling with both systems (an inter-system bias state), of
//! tight coupling with GPS only (one satellite left), and of loose coupling (no fix
//! from three satellites).

mod common;

use common::{errors_ned, repo, run, simulate, tmp};
use navfuse_core::sat::{SatId, System};
use navfuse_gnss::ObsCode;
use navfuse_io::rinex_obs::read_rinex_obs_all;
use std::path::Path;

/// Blockage start and length after the scenario start [s] (the car is driving).
const BLOCK_START_S: f64 = 300.0;
const BLOCK_LEN_S: f64 = 60.0;
const T0: f64 = 345_600.0;

/// The strongest (C/N0 of the L1/E1 signal) GPS and two Galileo satellites at the
/// epoch `t_sow`.
fn pick(obs: &Path, t_sow: f64) -> Vec<SatId> {
    let all = read_rinex_obs_all(obs).unwrap();
    let e = all
        .epochs
        .iter()
        .find(|e| (e.t.sow - t_sow).abs() < 0.01)
        .expect("epoch at the blockage start");
    let strongest = |sys: System, n: usize| {
        let mut v: Vec<(f64, SatId)> = e
            .sats
            .iter()
            .filter(|s| s.sat.system == sys)
            .filter_map(|s| Some((s.get(ObsCode(*b"S1C"))?.value?, s.sat)))
            .collect();
        v.sort_by(|a, b| b.0.total_cmp(&a.0));
        v.into_iter().take(n).map(|x| x.1).collect::<Vec<_>>()
    };
    let mut sats = strongest(System::Gps, 1);
    sats.extend(strongest(System::Galileo, 2));
    assert_eq!(sats.len(), 3, "{sats:?}");
    sats
}

/// Largest horizontal error over the blockage [m].
fn drift(dir: &Path, truth: &Path) -> f64 {
    let t0 = T0 + BLOCK_START_S;
    errors_ned(&dir.join("solution.nav"), truth, t0, t0 + BLOCK_LEN_S)
        .iter()
        .map(|(_, e)| e.x.hypot(e.y))
        .fold(0.0, f64::max)
}

#[test]
fn one_gps_and_two_galileo_satellites_hold_the_tight_solution() {
    let dir = tmp("tight_multi_gnss");
    let scenario = repo().join("scenarios/multi_gnss_car.toml");
    let open = dir.join("open");
    simulate(&scenario, &open);
    let keep = pick(&open.join("obs.rnx"), T0 + BLOCK_START_S);
    // The same drive with the blockage (the same seed: the same errors elsewhere).
    let names: Vec<String> = keep.iter().map(|s| format!("\"{s}\"")).collect();
    let text = std::fs::read_to_string(&scenario).unwrap();
    let (head, segments) = text.split_at(text.find("[[segment]]").unwrap());
    let blocked_toml = dir.join("blocked.toml");
    std::fs::write(
        &blocked_toml,
        format!(
            "{head}[[gnss.event]]\ntype = \"blockage\"\nstart_s = {BLOCK_START_S}\n\
             end_s = {}\nprns = [{}]\n\n{segments}",
            BLOCK_START_S + BLOCK_LEN_S,
            names.join(", ")
        ),
    )
    .unwrap();
    let sim = dir.join("sim");
    simulate(&blocked_toml, &sim);
    let truth = sim.join("truth.nav");
    let config = std::fs::read_to_string(sim.join("run.toml")).unwrap();
    assert!(config.contains("systems = [\"G\", \"E\"]"), "{config}");
    let variant = |name: &str, from: &str, to: &str| {
        let p = sim.join(format!("{name}.toml"));
        assert!(config.contains(from), "{from}");
        std::fs::write(&p, config.replace(from, to)).unwrap();
        let out = dir.join(name);
        run(&p, &out);
        out
    };
    let both = dir.join("both");
    run(&sim.join("run.toml"), &both);
    let gps_only = variant("gps_only", "systems = [\"G\", \"E\"]", "systems = [\"G\"]");
    let loose = variant("loose", "coupling = \"tight\"", "coupling = \"loose\"");
    let (d_both, d_gps, d_loose) = (
        drift(&both, &truth),
        drift(&gps_only, &truth),
        drift(&loose, &truth),
    );
    let events = std::fs::read_to_string(both.join("events.log")).unwrap();
    eprintln!(
        "60 s blockage leaving {} ({:?}): largest horizontal error tight G+E {d_both:.2} m, \
         tight GPS only {d_gps:.2} m, loose {d_loose:.2} m; {}",
        names.join(" "),
        keep,
        events
            .lines()
            .find(|l| l.contains("Galileo inter-system bias"))
            .unwrap_or("no ISB event")
    );
    // The Galileo ISB was set and the solution used the three satellites.
    assert!(events.contains("Galileo inter-system bias set"), "{events}");
    assert!(
        d_both < 0.5 * d_gps,
        "tight G+E {d_both} vs GPS only {d_gps}"
    );
    assert!(
        d_both < 0.5 * d_loose,
        "tight G+E {d_both} vs loose {d_loose}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
