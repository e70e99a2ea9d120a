//! GPS satellite positions and velocities from navfuse-gnss (IS-GPS-200 Table 20-IV)
//! against the rinex crate's independent implementation (`Ephemeris::
//! kepler2position_velocity`, which `Rinex::sv_orbit` calls): both give the ECEF
//! frame at the evaluation time, no transit time or Sagnac rotation, so the same
//! quantity is compared. Every GPS ephemeris of the walk_0827 file, at toe and at
//! 13 other times within +-2 h of toe.

use navfuse_gnss::GpsTime;
use navfuse_io::rinex_nav::read_rinex_nav;
use rinex::prelude::{Constellation, Epoch, Rinex, TimeScale};
use std::path::PathBuf;

fn nav_path() -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/rtklibexplorer/walk_0827/derived_rinex/gnss_1730.nav");
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skip: {} not found", p.display());
        None
    }
}

fn epoch(t: GpsTime) -> Epoch {
    let ns = (t.sow * 1e9).round() as u64;
    Epoch::from_time_of_week(t.week as u32, ns, TimeScale::GPST)
}

#[test]
fn satellite_positions_match_rinex_crate_within_1mm() {
    let Some(path) = nav_path() else { return };
    let ours = read_rinex_nav(&path).expect("navfuse reads the file");
    let theirs = Rinex::from_file(&path).expect("rinex reads the file");
    let offsets_s = [
        0.0, 1.0, -1.0, 60.0, -60.0, 900.0, -900.0, 1_800.0, -1_800.0, 3_600.0, -3_600.0, 5_400.0,
        7_200.0, -7_200.0,
    ];
    let mut compared = 0usize;
    let mut max_pos_m = 0.0f64;
    let mut max_vel_mps = 0.0f64;
    for (key, eph) in theirs.nav_ephemeris_frames_iter() {
        if key.sv.constellation != Constellation::GPS {
            continue;
        }
        let (week, ns) = key.epoch.to_time_scale(TimeScale::GPST).to_time_of_week();
        let toc = GpsTime::new(week as i32, ns as f64 * 1e-9);
        let e = ours
            .gps
            .iter()
            .find(|e| e.prn == key.sv.prn && e.toc.diff_s(&toc).abs() < 1e-6)
            .unwrap_or_else(|| panic!("navfuse lacks {} at {}", key.sv, key.epoch));
        assert_eq!(eph.clock_bias, e.af0_s);
        for dt in offsets_s {
            let t = e.toe.add_s(dt);
            let (p_km, v_kmps) = eph
                .kepler2position_velocity(key.sv, epoch(t))
                .expect("rinex computes a GPS orbit");
            let s = e.sat_state(t);
            let dp = ((s.pos_ecef_m.x - p_km[0] * 1e3).powi(2)
                + (s.pos_ecef_m.y - p_km[1] * 1e3).powi(2)
                + (s.pos_ecef_m.z - p_km[2] * 1e3).powi(2))
            .sqrt();
            let dv = ((s.vel_ecef_mps.x - v_kmps[0] * 1e3).powi(2)
                + (s.vel_ecef_mps.y - v_kmps[1] * 1e3).powi(2)
                + (s.vel_ecef_mps.z - v_kmps[2] * 1e3).powi(2))
            .sqrt();
            max_pos_m = max_pos_m.max(dp);
            max_vel_mps = max_vel_mps.max(dv);
            compared += 1;
        }
    }
    println!(
        "oracle: {compared} comparisons ({} ephemerides), max |dpos| = {max_pos_m:.3e} m, \
         max |dvel| = {max_vel_mps:.3e} m/s",
        compared / offsets_s.len()
    );
    assert_eq!(compared / offsets_s.len(), ours.gps.len());
    assert!(compared > 0);
    assert!(max_pos_m < 1e-3, "max position difference {max_pos_m} m");
}
