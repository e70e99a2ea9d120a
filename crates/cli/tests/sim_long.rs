//! Issue 19 (simulator): the synthetic constellations are re-issued every 2 h, so a
//! raw-GNSS scenario longer than one ephemeris' fit has satellites at every epoch
//! (before, the GNSS stopped 2 h after the start). Six hours at rest, GNSS every 10 s.

mod common;

use common::{simulate, tmp};

#[test]
fn six_hours_of_raw_gnss_have_satellites_at_every_epoch() {
    let dir = tmp("sim-long");
    std::fs::create_dir_all(&dir).unwrap();
    let sc = dir.join("long.toml");
    std::fs::write(
        &sc,
        "seed = 3\ndescription = \"6 h at rest, raw GNSS\"\n\n[start]\ngps_week = 2381\n\
         time_s = 345600.0\nposition_deg_m = [21.0285, 105.8542, 15.0]\nheading_deg = 20\n\n\
         [imu]\ngrade = \"adis16405\"\nrate_hz = 10\n\n[gnss]\nrate_hz = 0.1\nraw = true\n\n\
         [gnss.errors]\nsa_m = 0\n\n[[segment]]\ntype = \"static\"\nduration_s = 21600\n",
    )
    .unwrap();
    let sim = dir.join("sim");
    simulate(&sc, &sim);
    let obs = std::fs::read_to_string(sim.join("obs.rnx")).unwrap();
    let counts: Vec<usize> = obs
        .lines()
        .filter(|l| l.starts_with('>'))
        .map(|l| l.split_whitespace().last().unwrap().parse().unwrap())
        .collect();
    assert_eq!(counts.len(), 2161, "an epoch every 10 s for 6 h");
    let min = counts.iter().min().unwrap();
    assert!(*min >= 5, "fewest satellites at an epoch: {min}");
    // The navigation file holds the re-issues: one record per satellite every 2 h.
    let nav = std::fs::read_to_string(sim.join("nav.rnx")).unwrap();
    let records = nav
        .lines()
        .filter(|l| l.starts_with('G') && l.as_bytes().get(1).is_some_and(u8::is_ascii_digit))
        .count();
    assert_eq!(records, 24 * 4, "24 satellites, toe 0, 2, 4, 6 h");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 19 item 6: 24 h at rest with GPS, GLONASS, Galileo and BeiDou (GNSS every
/// 60 s): satellites of every system at every epoch, the mixed files hold each
/// system's records: GPS every 2 h, Galileo and BeiDou hourly, GLONASS every 30 min.
#[test]
fn a_day_of_gps_glonass_galileo_beidou_has_every_system_at_every_epoch() {
    let dir = tmp("sim-long-multi");
    std::fs::create_dir_all(&dir).unwrap();
    let sc = dir.join("day.toml");
    std::fs::write(
        &sc,
        "seed = 5\ndescription = \"24 h at rest, raw G+E+C\"\n\n[start]\ngps_week = 2381\n\
         time_s = 302400.0\nposition_deg_m = [48.15, 11.58, 520.0]\nheading_deg = 0\n\n\
         [imu]\ngrade = \"adis16405\"\nrate_hz = 1\n\n[gnss]\nrate_hz = 0.016666666666666666\n\
         raw = true\nsystems = [\"G\", \"E\", \"C\", \"R\"]\n\n\
         [gnss.errors]\nsa_m = 0\n\n[[segment]]\ntype = \"static\"\nduration_s = 86400\n",
    )
    .unwrap();
    let sim = dir.join("sim");
    simulate(&sc, &sim);
    let all = navfuse_io::rinex_obs::read_rinex_obs_all(&sim.join("obs.rnx")).unwrap();
    assert_eq!(all.epochs.len(), 1441, "an epoch every 60 s for 24 h");
    use navfuse_core::sat::System;
    let mut stats = Vec::new();
    for sys in [
        System::Gps,
        System::Glonass,
        System::Galileo,
        System::BeiDou,
    ] {
        let n: Vec<usize> = all
            .epochs
            .iter()
            .map(|e| e.sats.iter().filter(|s| s.sat.system == sys).count())
            .collect();
        let min = *n.iter().min().unwrap();
        let mean = n.iter().sum::<usize>() as f64 / n.len() as f64;
        stats.push(format!("{}: min {min} mean {mean:.1}", sys.letter()));
        assert!(min >= 4, "{sys:?}: fewest satellites at an epoch {min}");
    }
    eprintln!(
        "satellites above 10 deg per epoch over 24 h: {}",
        stats.join(", ")
    );
    let nav = navfuse_io::rinex_nav::read_rinex_nav(&sim.join("nav.rnx")).unwrap();
    assert_eq!(nav.gps.len(), 24 * 13, "GPS toe every 2 h, 0..24 h");
    assert_eq!(nav.galileo.len(), 24 * 25, "Galileo toe every hour");
    assert_eq!(nav.beidou.len(), 27 * 25, "BeiDou toe every hour");
    // tb every 30 min on hh:15 / hh:45 UTC, the nearest ones to the start and end.
    assert_eq!(nav.glonass.len(), 24 * 51, "GLONASS tb every 30 min");
    std::fs::remove_dir_all(&dir).ok();
}
