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

/// `[gnss] orbits = "sp3"` in a run: the simulated drive's broadcast orbits and
/// clocks sampled every 5 min into SP3-d (clocks without the relativistic term) and
/// used by tight coupling instead of the navigation file's, with the GNSS errors set
/// to 0: the run follows the truth to centimetres, closer than the broadcast run
/// (the products' 0.1 m sigma replaces the broadcast URA in the weights, so the
/// filter trusts the error-free pseudoranges more).
#[test]
fn a_run_with_sp3_orbits_equals_the_broadcast_run() {
    let dir = tmp("tight_multi_gnss_sp3");
    let sim = dir.join("sim");
    let text = std::fs::read_to_string(repo().join("scenarios/multi_gnss_car.toml")).unwrap();
    let mut zero = text.clone();
    for key in [
        "iono_m",
        "tropo_m",
        "sat_clock_m",
        "orbit_m",
        "multipath_m",
        "noise_m",
    ] {
        let at = zero.find(&format!("\n{key} = ")).expect(key) + 1;
        let end = at + zero[at..].find('\n').unwrap();
        zero.replace_range(at..end, &format!("{key} = 0"));
    }
    assert_ne!(zero, text);
    let scenario = dir.join("zero.toml");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(&scenario, zero).unwrap();
    simulate(&scenario, &sim);
    let store = navfuse_io::rinex_nav::read_rinex_nav(&sim.join("nav.rnx"))
        .unwrap()
        .store();
    let c2 = 299_792_458.0f64.powi(2);
    let t0 = navfuse_gnss::GpsTime::new(2381, T0);
    let epochs: Vec<navfuse_io::sp3::Sp3Epoch> = (-6..=8)
        .map(|k| {
            let t = t0.add_s(300.0 * f64::from(k));
            let recs = store
                .sats()
                .into_iter()
                .filter_map(|sat| {
                    let (s, _) = store.sat_state(sat, t)?;
                    let clock = s.clock_bias_s + 2.0 * s.pos_ecef_m.dot(&s.vel_ecef_mps) / c2;
                    Some((sat, s.pos_ecef_m, Some(clock)))
                })
                .collect();
            (t, recs)
        })
        .collect();
    navfuse_io::sp3::write_sp3(&sim.join("brdc.sp3"), 300.0, "NAVF", &epochs).unwrap();
    let config = std::fs::read_to_string(sim.join("run.toml")).unwrap();
    let with_sp3 = config.replace(
        "nav = \"nav.rnx\"\n",
        "nav = \"nav.rnx\"\norbits = \"sp3\"\nsp3 = [\"brdc.sp3\"]\n",
    );
    assert_ne!(with_sp3, config);
    std::fs::write(sim.join("sp3.toml"), with_sp3).unwrap();
    let (a, b) = (dir.join("brdc"), dir.join("sp3"));
    run(&sim.join("run.toml"), &a);
    run(&sim.join("sp3.toml"), &b);
    let truth = sim.join("truth.nav");
    let end = T0 + 470.0;
    let ea = errors_ned(&a.join("solution.nav"), &truth, T0 + 10.0, end);
    let eb = errors_ned(&b.join("solution.nav"), &truth, T0 + 10.0, end);
    assert_eq!(ea.len(), eb.len());
    let diff = ea
        .iter()
        .zip(&eb)
        .map(|((_, x), (_, y))| (x - y).norm())
        .fold(0.0, f64::max);
    let max =
        |e: &[(f64, nalgebra::Vector3<f64>)]| e.iter().map(|(_, x)| x.norm()).fold(0.0, f64::max);
    let written = std::fs::read_to_string(b.join("config.toml")).unwrap();
    eprintln!(
        "tight G+E from SP3 against broadcast: largest position difference {diff:.3} m; largest \
         error against the truth {:.3} m (SP3), {:.3} m (broadcast)",
        max(&eb),
        max(&ea)
    );
    assert!(written.contains("orbits = \"sp3\""), "{written}");
    assert!(
        max(&eb) < 0.1 && max(&eb) <= max(&ea),
        "{} {}",
        max(&eb),
        max(&ea)
    );
    assert!(diff < 0.3, "{diff}");
    std::fs::remove_dir_all(&dir).ok();
}
