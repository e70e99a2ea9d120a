//! Issue 19 item 6: the multi-constellation simulator. A static receiver simulated
//! with GPS, GLONASS, Galileo and BeiDou, read back from obs.rnx / nav.rnx: every pseudorange
//! minus its model from the broadcast records (geometric range with light time and
//! Sagnac, the configured inter-system bias, the satellite clock with its group
//! delay, Klobuchar scaled to the signal's frequency, Saastamoinen) is below 1 mm
//! with every error at 0, and within the error budget with errors on, where it also
//! equals the error total of gnss_errors.csv.

mod common;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{simulate, tmp};
use nalgebra::Vector3;
use navfuse_core::earth::lla_to_ecef;
use navfuse_core::sat::{SatId, System};
use navfuse_gnss::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m};
use navfuse_gnss::ephemeris::SPEED_OF_LIGHT_MPS;
use navfuse_gnss::geometry::{az_el, signal_path};
use navfuse_gnss::signal::{carrier_frequency_hz, ObsCode};
use navfuse_io::rinex_nav::read_rinex_nav;
use navfuse_io::rinex_obs::read_rinex_obs_all;

const LAT: f64 = 45.07;
const LON: f64 = 7.69;
const H: f64 = 250.0;

fn scenario(errors: &str) -> String {
    format!(
        "seed = 7\ndescription = \"static, G+E+C\"\n\n[start]\ngps_week = 2381\n\
         time_s = 345600.0\nposition_deg_m = [{LAT}, {LON}, {H}]\nheading_deg = 0\n\n\
         [imu]\ngrade = \"adis16405\"\nrate_hz = 10\n\n[gnss]\nrate_hz = 0.1\nraw = true\n\
         systems = [\"G\", \"E\", \"C\", \"R\"]\n\n[gnss.errors]\n{errors}\n\n\
         [[segment]]\ntype = \"static\"\nduration_s = 1800\n"
    )
}

/// Residual of every pseudorange against the broadcast models, per satellite, with
/// (t, sat) keys.
fn residuals(sim: &Path, isb: &BTreeMap<System, f64>) -> BTreeMap<(i64, SatId), f64> {
    let nav = read_rinex_nav(&sim.join("nav.rnx")).unwrap();
    let store = nav.store();
    let (alpha, beta) = (nav.iono_alpha.unwrap(), nav.iono_beta.unwrap());
    let all = read_rinex_obs_all(&sim.join("obs.rnx")).unwrap();
    let epochs = all.epochs;
    let systems: Vec<System> = all.header.types.iter().map(|(s, _)| *s).collect();
    assert_eq!(
        systems,
        [
            System::Gps,
            System::Glonass,
            System::Galileo,
            System::BeiDou
        ]
    );
    assert_eq!(all.header.glonass_channels.len(), 24);
    let lla = Vector3::new(LAT.to_radians(), LON.to_radians(), H);
    let rx = lla_to_ecef(&lla);
    let mut out = BTreeMap::new();
    for ep in &epochs {
        for s in &ep.sats {
            let code = if s.sat.system == System::BeiDou {
                ObsCode(*b"C2I")
            } else {
                ObsCode(*b"C1C")
            };
            let p = s.get(code).and_then(|v| v.value).expect("code");
            let eph = store.select(s.sat, ep.t).expect("a record");
            let path = signal_path(eph, &rx, &Vector3::zeros(), ep.t);
            let (az, el) = az_el(&lla, &path.los_unit);
            let channel = all.header.glonass_channel(s.sat.prn);
            let f = carrier_frequency_hz(s.sat.system, code.band(), channel).unwrap();
            let scale = (1_575.42e6 / f).powi(2);
            let iono = scale * klobuchar_l1_delay_m(&alpha, &beta, lla.x, lla.y, az, el, ep.t.sow);
            let tropo = saastamoinen_slant_m(lla.x, lla.z, el);
            let dts = path.sat_clock_bias_s - eph.group_delay_s();
            let model = path.geometric_range_m + isb.get(&s.sat.system).copied().unwrap_or(0.0)
                - SPEED_OF_LIGHT_MPS * dts
                + iono
                + tropo;
            out.insert(((ep.t.sow * 1e3).round() as i64, s.sat), p - model);
        }
    }
    out
}

/// Simulate [`scenario`] with `errors` into dir/name.
fn simulate_with(dir: &Path, name: &str, errors: &str) -> PathBuf {
    let sc = dir.join(format!("{name}.toml"));
    std::fs::write(&sc, scenario(errors)).unwrap();
    let sim = dir.join(name);
    simulate(&sc, &sim);
    sim
}

#[test]
fn mixed_pseudoranges_match_the_broadcast_models() {
    let dir = tmp("sim-multi");
    std::fs::create_dir_all(&dir).unwrap();
    // Galileo as configured, BeiDou and GLONASS the defaults.
    let isb: BTreeMap<System, f64> = [
        (System::Galileo, 2.5),
        (System::BeiDou, -5.0),
        (System::Glonass, 7.0),
    ]
    .into();

    // 1. Every error 0: the pseudoranges are the models to the file's 1 mm.
    let zero = "iono_m = 0\ntropo_m = 0\nsat_clock_m = 0\norbit_m = 0\nmultipath_m = 0\n\
                noise_m = 0\nrx_clock_m = 0\nsa_m = 0\nisb_m = { E = 2.5 }";
    let sim = simulate_with(&dir, "zero", zero);
    let res = residuals(&sim, &isb);
    let mut per_sys: BTreeMap<System, (usize, f64)> = BTreeMap::new();
    for ((_, sat), r) in &res {
        let e = per_sys.entry(sat.system).or_default();
        e.0 += 1;
        e.1 = e.1.max(r.abs());
    }
    eprintln!("errors off, per system (count, max |residual| m): {per_sys:?}");
    assert_eq!(per_sys.len(), 4);
    for (sys, (n, worst)) in &per_sys {
        assert!(*n > 181 * 4, "{sys:?}: {n} pseudoranges");
        assert!(*worst < 1e-3, "{sys:?}: residual {worst} m");
    }
    // The header and the signals of each system.
    let obs = std::fs::read_to_string(sim.join("obs.rnx")).unwrap();
    assert!(obs.lines().next().unwrap().contains("M: Mixed"));
    for l in [
        "G    4 C1C L1C D1C S1C",
        "E    4 C1C L1C D1C S1C",
        "C    4 C2I L2I D2I S2I",
        "R    4 C1C L1C D1C S1C",
        " 24 R01  1 R02 -4 R03  5 R04  6 R05  1 R06 -4 R07  5 R08  6 GLONASS SLOT / FRQ #",
    ] {
        assert!(obs.contains(l), "{l}");
    }

    // 2. Errors on (SA off): within the budget, and the residual is the total of
    // gnss_errors.csv (to the files' 1e-4 m and 1 mm).
    let on = "sa_m = 0\niono_m = 1.0\ntropo_m = 0.3\nsat_clock_m = 1.0\norbit_m = 1.0\n\
              multipath_m = 0.3\nnoise_m = 0.3\nrx_clock_m = 0\nisb_m = { E = 2.5 }";
    let sim = simulate_with(&dir, "on", on);
    let res = residuals(&sim, &isb);
    let csv = std::fs::read_to_string(sim.join("gnss_errors.csv")).unwrap();
    let mut totals: HashMap<(i64, SatId), f64> = HashMap::new();
    for l in csv.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        let t = (f[0].parse::<f64>().unwrap() * 1e3).round() as i64;
        let sat = f[1]
            .parse::<u8>()
            .map(SatId::gps)
            .unwrap_or_else(|_| SatId::parse(f[1]).unwrap());
        totals.insert((t, sat), f[12].parse().unwrap());
    }
    let (mut worst, mut worst_book, mut sum2) = (0.0f64, 0.0f64, 0.0);
    for (k, r) in &res {
        worst = worst.max(r.abs());
        sum2 += r * r;
        // The csv's rx_clock_m (so its total) holds the system's ISB.
        let total = totals[k] - isb.get(&k.1.system).copied().unwrap_or(0.0);
        worst_book = worst_book.max((r - total).abs());
    }
    let rms = (sum2 / res.len() as f64).sqrt();
    eprintln!(
        "errors on: {} pseudoranges, RMS {rms:.3} m, max {worst:.3} m, max |residual - csv total| {worst_book:.5} m",
        res.len()
    );
    assert!(
        worst_book < 1.5e-3,
        "residual vs gnss_errors.csv total: {worst_book}"
    );
    assert!(rms > 0.5 && rms < 6.0, "RMS {rms}");
    assert!(worst < 20.0, "max {worst}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_system_letters_and_satellite_names_are_refused_naming_the_key() {
    let dir = tmp("sim-multi-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        ("systems = [\"G\", \"X\"]\n", "", "systems"),
        ("", "isb_m = { G = 1.0 }", "isb_m"),
        (
            "[[gnss.event]]\ntype = \"cycle_slip\"\nprn = \"Q7\"\nat_s = 10\ncycles = 3\n",
            "",
            "prn",
        ),
    ];
    for (k, (gnss, errors, key)) in cases.iter().enumerate() {
        let text = scenario(errors).replace(
            "systems = [\"G\", \"E\", \"C\", \"R\"]\n",
            if gnss.starts_with("systems") {
                gnss
            } else {
                ""
            },
        );
        let text = if gnss.starts_with("[[") {
            text.replace("[[segment]]", &format!("{gnss}\n[[segment]]"))
        } else {
            text
        };
        let sc = dir.join(format!("bad{k}.toml"));
        std::fs::write(&sc, text).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
            .args(["sim", sc.to_str().unwrap(), "--out"])
            .arg(dir.join(format!("o{k}")))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "case {k} accepted");
        assert!(err.contains(key), "case {k}: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_isb_random_walk_is_common_to_a_systems_satellites_and_spares_gps() {
    let dir = tmp("sim-multi-walk");
    std::fs::create_dir_all(&dir).unwrap();
    let zero = "iono_m = 0\ntropo_m = 0\nsat_clock_m = 0\norbit_m = 0\nmultipath_m = 0\n\
                noise_m = 0\nrx_clock_m = 0\nsa_m = 0\nisb_walk_m_per_sqrth = 10.0";
    let sim = simulate_with(&dir, "walk", zero);
    let isb: BTreeMap<System, f64> = [
        (System::Galileo, 3.0),
        (System::BeiDou, -5.0),
        (System::Glonass, 7.0),
    ]
    .into();
    let res = residuals(&sim, &isb);
    // Per epoch and system: one value (the walk), spread < 1 mm; GPS 0.
    let mut by: BTreeMap<(i64, System), (f64, f64)> = BTreeMap::new();
    for ((t, sat), r) in &res {
        let e = by.entry((*t, sat.system)).or_insert((f64::MAX, f64::MIN));
        e.0 = e.0.min(*r);
        e.1 = e.1.max(*r);
    }
    let mut last: BTreeMap<System, f64> = BTreeMap::new();
    for ((_, sys), (lo, hi)) in &by {
        assert!(hi - lo < 1e-3, "{sys:?}: spread {}", hi - lo);
        if *sys == System::Gps {
            assert!(hi.abs() < 1e-3);
        }
        last.insert(*sys, 0.5 * (lo + hi));
    }
    eprintln!("ISB walk after 30 min [m]: {last:?}");
    for sys in [System::Galileo, System::BeiDou, System::Glonass] {
        // 10 m/sqrt(h) over 0.5 h: sigma 7.1 m; a walk that moved at all, not wildly.
        let w = last[&sys];
        assert!(w.abs() > 1e-3 && w.abs() < 40.0, "{sys:?}: {w}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The single point solver on the simulator's output (issue 19 items 4 and 6 against
/// each other): with every error at 0, `navfuse_app::spp` on the mixed files finds
/// the station to millimetres at every epoch and the inter-system biases the
/// scenario set (Galileo 2.5 m, BeiDou -5 m, GLONASS +7 m, the defaults but E).
#[test]
fn spp_of_an_error_free_mixed_simulation_finds_the_station_and_the_biases() {
    let dir = tmp("sim-multi-spp");
    std::fs::create_dir_all(&dir).unwrap();
    let zero = "iono_m = 0\ntropo_m = 0\nsat_clock_m = 0\norbit_m = 0\nmultipath_m = 0\n\
                noise_m = 0\nrx_clock_m = 0\nsa_m = 0\nisb_m = { E = 2.5 }";
    let sim = simulate_with(&dir, "spp", zero);
    let job = navfuse_app::spp::SppJob::new(
        sim.join("obs.rnx"),
        vec![sim.join("nav.rnx")],
        vec![
            System::Gps,
            System::Galileo,
            System::BeiDou,
            System::Glonass,
        ],
    );
    let run = navfuse_app::spp::run_spp(&job).unwrap();
    let rx = lla_to_ecef(&Vector3::new(LAT.to_radians(), LON.to_radians(), H));
    let mut worst: f64 = 0.0;
    let mut isb_err: BTreeMap<System, f64> = BTreeMap::new();
    let want: BTreeMap<System, f64> = [
        (System::Galileo, 2.5),
        (System::BeiDou, -5.0),
        (System::Glonass, 7.0),
    ]
    .into();
    for (_, r) in &run.epochs {
        let s = r.as_ref().unwrap();
        assert_eq!(s.reference_system, System::Gps);
        assert!(s.excluded_sats.is_empty(), "{:?}", s.excluded_sats);
        worst = worst.max((s.pos_ecef_m - rx).norm());
        for (sys, b, _) in &s.isb_m {
            let e = isb_err.entry(*sys).or_default();
            *e = e.max((b - want[sys]).abs());
        }
    }
    eprintln!(
        "error-free G+E+C+R simulation: {} epochs, largest position error {:.4} m, largest \
         ISB error {isb_err:?} m",
        run.epochs.len(),
        worst
    );
    assert_eq!(run.solved(), run.epochs.len());
    assert!(worst < 0.01, "{worst}");
    assert_eq!(isb_err.len(), 3);
    assert!(isb_err.values().all(|e| *e < 0.01), "{isb_err:?}");
    std::fs::remove_dir_all(&dir).ok();
}
