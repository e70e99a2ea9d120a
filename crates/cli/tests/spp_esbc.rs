//! Issue 19 (SPP on a real multi-GNSS station): ESBC00DNK, 3 h at 30 s, broadcast
//! ephemerides from the mixed navigation file, GPS only for now: `navfuse spp`
//! against RTKLIB's `rnx2rtkp` in single mode with the same settings (broadcast
//! Klobuchar, Saastamoinen, 10 deg mask, RTKLIB's weights), epoch by epoch, and both
//! against the station's known position (README of ../shared/data/igs). Skips with a
//! printed reason without ../shared/data or rnx2rtkp.

mod common;

use common::rtklib::{have_rnx2rtkp, run_rnx2rtkp, tmp_dir};
use common::{navfuse_ok, shared};
use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla, lla_to_ecef};
use navfuse_io::gnss::read_gnss;
use navfuse_io::input::{GnssFormat, GnssSource};

/// The station's position (the observation header's APPROX POSITION XYZ) [m].
const ESBC_ECEF_M: [f64; 3] = [3_582_105.2910, 532_589.7313, 5_232_754.8054];
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

#[test]
fn esbc_gps_spp_matches_rnx2rtkp_and_its_accuracy() {
    let Some(data) = shared() else { return };
    if !have_rnx2rtkp() {
        return;
    }
    let d = data.join("igs/ESBC00DNK_2020177");
    let obs = d.join("ESBC00DNK_R_20201770000_03H_30S_MO.rnx");
    let nav = d.join("ESBC00DNK_R_20201770000_01D_MN.rnx");
    let dir = tmp_dir("esbc");
    let ours = dir.join("ours.pos");
    navfuse_ok(&[
        "spp",
        obs.to_str().unwrap(),
        nav.to_str().unwrap(),
        "--systems",
        "G",
        "--rtklib-weights",
        "--no-fde",
        "--out",
        ours.to_str().unwrap(),
    ]);
    let rtk = run_rnx2rtkp(&dir, "rtk", &obs, &nav, "brdc", false);
    let mine = read_gnss(&GnssSource {
        path: ours,
        format: GnssFormat::RtklibPos { quality: vec![5] },
        decimate_s: None,
        time_offset_s: 0.0,
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
    let worst = diffs.iter().fold(0.0f64, |m, x| m.max(*x));
    eprintln!(
        "ESBC GPS: {} common epochs of {} (rnx2rtkp) / {} (navfuse); largest horizontal difference {worst:.3} m; \
         against the station: navfuse H {:.3} V {:.3} m RMS, rnx2rtkp H {:.3} V {:.3} m RMS",
        diffs.len(),
        rtk.len(),
        mine.fixes.len(),
        rms(&ours_h),
        rms(&ours_u),
        rms(&theirs_h),
        rms(&theirs_u)
    );
    assert!(diffs.len() >= 350, "{} common epochs", diffs.len());
    assert!(worst <= MAX_DIFF_M, "{worst} m");
    assert!(rms(&ours_h) <= rms(&theirs_h) * 1.01, "horizontal RMS");
    std::fs::remove_dir_all(&dir).ok();
}
