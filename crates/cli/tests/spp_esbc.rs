//! Issue 19 (SPP on a real multi-GNSS station): ESBC00DNK, 3 h at 30 s, broadcast
//! ephemerides from the mixed navigation file: `navfuse spp` for GPS, GPS+GLONASS,
//! GPS+GLONASS+Galileo and GPS+GLONASS+Galileo+BeiDou against RTKLIB's `rnx2rtkp`
//! in single mode with the same settings (broadcast Klobuchar, Saastamoinen, 10 deg
//! mask, RTKLIB's weights; both take GLONASS C1C), epoch by epoch, and both against the
//! station's known position (README of ../shared/data/igs). Skips with a printed
//! reason without ../shared/data or rnx2rtkp.

mod common;

use common::rtklib::{have_rnx2rtkp, navsys, run_rnx2rtkp_systems, tmp_dir};
use common::{navfuse_ok, shared};
use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla, lla_to_ecef};
use navfuse_io::gnss::read_gnss;
use navfuse_io::input::{GnssFormat, GnssSource};

/// The station's position (the observation header's APPROX POSITION XYZ) [m].
const ESBC_ECEF_M: [f64; 3] = [3_582_105.291, 532_589.731_3, 5_232_754.805_4];
/// The bound on the per-epoch horizontal difference to rnx2rtkp [m].
const MAX_DIFF_M: f64 = 0.3;

/// (horizontal, up) of `p` from `reference` [m].
fn hu(p: &Vector3<f64>, reference: &Vector3<f64>) -> (f64, f64) {
    let lla = ecef_to_lla(reference);
    let d = c_ne(lla.x, lla.y).transpose() * (p - reference);
    (d.x.hypot(d.y), -d.z)
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// One system set: (largest per-epoch horizontal difference, common epochs, our
/// H/V RMS, RTKLIB's H/V RMS, our mean satellites).
struct Compared {
    worst_m: f64,
    common: usize,
    ours: (f64, f64),
    theirs: (f64, f64),
}

fn compare(systems: &str, extra: &[&str], fde: bool) -> Option<Compared> {
    let data = shared()?;
    if !have_rnx2rtkp() {
        return None;
    }
    let d = data.join("igs/ESBC00DNK_2020177");
    let obs = d.join("ESBC00DNK_R_20201770000_03H_30S_MO.rnx");
    let nav = d.join("ESBC00DNK_R_20201770000_01D_MN.rnx");
    let dir = tmp_dir(&format!("esbc-{}", systems.replace(',', "")));
    let ours = dir.join("ours.pos");
    let mut args = vec![
        "spp",
        obs.to_str().unwrap(),
        nav.to_str().unwrap(),
        "--systems",
        systems,
        "--rtklib-weights",
        "--out",
        ours.to_str().unwrap(),
    ];
    if !fde {
        args.push("--no-fde");
    }
    args.extend_from_slice(extra);
    navfuse_ok(&args);
    let rtk = run_rnx2rtkp_systems(&dir, "rtk", &obs, &nav, "brdc", false, navsys(systems));
    let mine = read_gnss(&GnssSource {
        path: ours,
        format: GnssFormat::RtklibPos { quality: vec![5] },
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap();
    let station = Vector3::from(ESBC_ECEF_M);
    let (mut diffs, mut ours_h, mut ours_u, mut theirs_h, mut theirs_u) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for r in rtk.iter().filter(|r| r.q == 5) {
        let k = mine.fixes.partition_point(|f| f.t < r.t.sow - 0.005);
        let Some(f) = mine.fixes.get(k).filter(|f| (f.t - r.t.sow).abs() <= 0.005) else {
            continue;
        };
        let p = lla_to_ecef(&f.lla);
        diffs.push(hu(&p, &r.pos_ecef_m).0);
        let (h, u) = hu(&p, &station);
        ours_h.push(h);
        ours_u.push(u);
        let (h, u) = hu(&r.pos_ecef_m, &station);
        theirs_h.push(h);
        theirs_u.push(u);
    }
    let c = Compared {
        worst_m: diffs.iter().fold(0.0f64, |m, x| m.max(*x)),
        common: diffs.len(),
        ours: (rms(&ours_h), rms(&ours_u)),
        theirs: (rms(&theirs_h), rms(&theirs_u)),
    };
    eprintln!(
        "ESBC {systems} {extra:?}{}: {} common epochs of {} (rnx2rtkp) / {} (navfuse); largest \
         horizontal difference {:.3} m; against the station: navfuse H {:.3} V {:.3} m RMS, \
         rnx2rtkp H {:.3} V {:.3} m RMS",
        if fde { " (FDE on)" } else { "" },
        c.common,
        rtk.len(),
        mine.fixes.len(),
        c.worst_m,
        c.ours.0,
        c.ours.1,
        c.theirs.0,
        c.theirs.1
    );
    std::fs::remove_dir_all(&dir).ok();
    Some(c)
}

#[test]
fn esbc_spp_matches_rnx2rtkp_for_each_system_set() {
    for systems in ["G", "G,R", "G,R,E", "G,R,E,C"] {
        let Some(c) = compare(systems, &[], false) else {
            return;
        };
        assert!(c.common >= 350, "{systems}: {} common epochs", c.common);
        assert!(c.worst_m <= MAX_DIFF_M, "{systems}: {} m", c.worst_m);
        // Equal to or better than rnx2rtkp at the data README's precision (cm).
        assert!(
            c.ours.0 <= (c.theirs.0 * 100.0).round() / 100.0 + 0.005,
            "{systems}: horizontal RMS {} > {}",
            c.ours.0,
            c.theirs.0
        );
    }
}

/// navfuse's own defaults (its elevation weighting, FDE on) on all four systems,
/// single and dual frequency: no worse than RTKLIB against the station (the data
/// README's 0.95 m, at its precision).
#[test]
fn esbc_spp_all_systems_with_navfuse_defaults() {
    let Some(data) = shared() else { return };
    let d = data.join("igs/ESBC00DNK_2020177");
    let obs = d.join("ESBC00DNK_R_20201770000_03H_30S_MO.rnx");
    let nav = d.join("ESBC00DNK_R_20201770000_01D_MN.rnx");
    let dir = tmp_dir("esbc-defaults");
    let ours = dir.join("ours.pos");
    for extra in [None, Some("--dual-frequency")] {
        let mut args = vec![
            "spp",
            obs.to_str().unwrap(),
            nav.to_str().unwrap(),
            "--systems",
            "G,R,E,C",
            "--out",
            ours.to_str().unwrap(),
        ];
        args.extend(extra);
        navfuse_ok(&args);
        let mine = read_gnss(&GnssSource {
            path: ours.clone(),
            format: GnssFormat::RtklibPos { quality: vec![5] },
            decimate_s: None,
            time_offset_s: 0.0,
            skip_lines: None,
        })
        .unwrap();
        let station = Vector3::from(ESBC_ECEF_M);
        let (h, u): (Vec<f64>, Vec<f64>) = mine
            .fixes
            .iter()
            .map(|f| hu(&lla_to_ecef(&f.lla), &station))
            .unzip();
        eprintln!(
            "ESBC G,R,E,C navfuse defaults {}: {} epochs, H {:.3} V {:.3} m RMS",
            extra.unwrap_or("single frequency"),
            h.len(),
            rms(&h),
            rms(&u)
        );
        assert_eq!(h.len(), 360);
        assert!(rms(&h) <= 0.955, "{}", rms(&h));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Doppler velocity of the static station with all four systems (each system's own
/// wavelengths, GLONASS by channel): centimetres per second.
#[test]
fn esbc_doppler_velocity_of_a_static_station() {
    let Some(data) = shared() else { return };
    let d = data.join("igs/ESBC00DNK_2020177");
    let job = navfuse_app::spp::SppJob::new(
        d.join("ESBC00DNK_R_20201770000_03H_30S_MO.rnx"),
        vec![d.join("ESBC00DNK_R_20201770000_01D_MN.rnx")],
        navfuse_gnss::signal_plan::parse_systems("G,R,E,C").unwrap(),
    );
    let run = navfuse_app::spp::run_spp(&job).unwrap();
    let speeds: Vec<f64> = run
        .epochs
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok()?.vel_ecef_mps.map(|v| v.norm()))
        .collect();
    let isb: Vec<String> = run.epochs[0]
        .1
        .as_ref()
        .unwrap()
        .isb_m
        .iter()
        .map(|(s, b, sd)| format!("{} {b:.2} ± {sd:.2} m", s.letter()))
        .collect();
    eprintln!(
        "ESBC G,R,E,C Doppler: {} epochs with a velocity, speed RMS {:.4} m/s, max {:.4} m/s; \
         inter-system biases at the first epoch: {}",
        speeds.len(),
        rms(&speeds),
        speeds.iter().fold(0.0f64, |m, x| m.max(*x)),
        isb.join(", ")
    );
    assert_eq!(speeds.len(), 360);
    assert!(rms(&speeds) < 0.05, "{}", rms(&speeds));
}

/// Precise orbits through the whole path: one broadcast record per GPS, Galileo and
/// BeiDou satellite (the one in use at 01:30; GLONASS records reach only 15 min)
/// sampled every 5 min into an SP3-d file (clocks without the periodic relativistic
/// term, as IGS products give them), read back with `read_precise` and solved with
/// `PreciseSource`: with the same weights, the solutions equal those from the same
/// records used directly to millimetres. Then `navfuse spp --sp3` on the command line.
#[test]
fn esbc_spp_with_sp3_equals_broadcast() {
    use navfuse_gnss::signal_plan::SignalPlan;
    use navfuse_gnss::spp::{IonoModel, SppConfig};
    let Some(data) = shared() else { return };
    let d = data.join("igs/ESBC00DNK_2020177");
    let obs_path = d.join("ESBC00DNK_R_20201770000_03H_30S_MO.rnx");
    let nav_path = d.join("ESBC00DNK_R_20201770000_01D_MN.rnx");
    let nav = navfuse_io::rinex_nav::read_rinex_nav(&nav_path).unwrap();
    let full = nav.store();
    let t0 = navfuse_gnss::GpsTime::new(2111, 345_600.0); // 2020-06-25 00:00 GPST
    let mid = t0.add_s(5_400.0);
    let one_each = navfuse_gnss::EphemerisStore::new(
        full.sats()
            .into_iter()
            .filter(|s| "GEC".contains(s.system.letter()))
            .filter_map(|s| full.select(s, mid).cloned()),
    );
    let c2 = 299_792_458.0f64.powi(2);
    let epochs: Vec<navfuse_io::sp3::Sp3Epoch> = (0..=40)
        .map(|k| {
            let t = t0.add_s(-300.0 + 300.0 * f64::from(k));
            let recs = one_each
                .iter()
                .map(|e| {
                    let s = e.sat_state(t);
                    let clock = s.clock_bias_s + 2.0 * s.pos_ecef_m.dot(&s.vel_ecef_mps) / c2;
                    (e.sat(), s.pos_ecef_m, Some(clock))
                })
                .collect();
            (t, recs)
        })
        .collect();
    let dir = tmp_dir("esbc-sp3");
    let sp3 = dir.join("brdc.sp3");
    navfuse_io::sp3::write_sp3(&sp3, 300.0, "NAVF", &epochs).unwrap();
    let products = navfuse_app::spp::read_precise(std::slice::from_ref(&sp3), &[]).unwrap();
    let obs = navfuse_io::rinex_obs::read_rinex_obs_all(&obs_path).unwrap();
    let plan = SignalPlan::systems(navfuse_gnss::signal_plan::parse_systems("G,E,C").unwrap());
    // The same weights on both sides: the broadcast URA and the 0.1 m of precise
    // products would otherwise weight the satellites differently.
    let mut cfg = SppConfig {
        iono: IonoModel::from_broadcast(nav.iono_alpha, nav.iono_beta),
        fde: false,
        ..SppConfig::default()
    };
    cfg.errors.use_ura = false;
    let solve = |orbits: &dyn navfuse_gnss::OrbitSource| {
        navfuse_app::spp::solve_multi(
            &obs.epochs,
            &obs.header,
            &one_each,
            orbits,
            &plan,
            cfg.clone(),
        )
    };
    let direct = solve(&one_each);
    let precise = solve(&navfuse_gnss::PreciseSource {
        products: &products,
        broadcast: &one_each,
    });
    let mut d3: Vec<f64> = direct
        .iter()
        .zip(&precise)
        .filter_map(|((_, a), (_, b))| {
            let (a, b) = (a.as_ref().ok()?, b.as_ref().ok()?);
            assert_eq!(a.used_sats, b.used_sats);
            Some((a.pos_ecef_m - b.pos_ecef_m).norm())
        })
        .collect();
    d3.sort_by(f64::total_cmp);
    let max = *d3.last().unwrap();
    eprintln!(
        "ESBC G,E,C from SP3 (one broadcast record per satellite sampled every 300 s) \
         against the records directly: {} of 360 epochs, 3D difference median {:.5} m, max \
         {:.5} m",
        d3.len(),
        d3[d3.len() / 2],
        max
    );
    assert_eq!(d3.len(), 360);
    assert!(max < 0.003, "{max}");
    // The command line: the same products, every record of the day for health and
    // group delays.
    let out = dir.join("sp3.pos");
    navfuse_ok(&[
        "spp",
        obs_path.to_str().unwrap(),
        nav_path.to_str().unwrap(),
        "--systems",
        "G,E,C",
        "--sp3",
        sp3.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("SP3 orbits"), "header of {}", out.display());
    std::fs::remove_dir_all(&dir).ok();
}
