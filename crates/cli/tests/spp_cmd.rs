//! `navfuse spp OBS NAV --out FILE.pos` (issue 19, the command; GPS for now): on the
//! real walk_0827 u-blox data its RTKLIB .pos agrees with `rnx2rtkp` in single mode
//! with the same settings at every common epoch, reads back through navfuse's own
//! .pos reader and RTKLIB's `pos2kml`; other constellations are refused with a
//! message. Skips with a printed reason without ../shared/data or rnx2rtkp.

mod common;

use common::rtklib::{have_rnx2rtkp, run_rnx2rtkp, tmp_dir};
use common::{navfuse_ok, shared};
use navfuse_core::earth::{c_ne, ecef_to_lla, lla_to_ecef};
use navfuse_io::gnss::read_gnss;
use navfuse_io::input::{GnssFormat, GnssSource};
use std::process::Command;

#[test]
fn spp_command_matches_rnx2rtkp_on_the_walk() {
    let Some(data) = shared() else { return };
    if !have_rnx2rtkp() {
        return;
    }
    let walk = data.join("rtklibexplorer/walk_0827/derived_rinex");
    let (obs, nav) = (walk.join("gnss_1730.obs"), walk.join("gnss_1730.nav"));
    let dir = tmp_dir("cmd");
    let ours = dir.join("ours.pos");
    // The navigation file has no Klobuchar coefficients: both sides without.
    navfuse_ok(&[
        "spp",
        obs.to_str().unwrap(),
        nav.to_str().unwrap(),
        "--iono",
        "off",
        "--no-fde",
        "--out",
        ours.to_str().unwrap(),
    ]);
    let rtk = run_rnx2rtkp(&dir, "rtk", &obs, &nav, "off", false);
    let mine = read_gnss(&GnssSource {
        path: ours.clone(),
        format: GnssFormat::RtklibPos { quality: vec![5] },
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .expect("navfuse reads its own .pos back");
    assert!(mine.fixes.len() > 100, "{} epochs", mine.fixes.len());
    let (mut common_epochs, mut worst) = (0, 0.0f64);
    for r in rtk.iter().filter(|r| r.q == 5) {
        let k = mine.fixes.partition_point(|f| f.t < r.t.sow - 0.005);
        let Some(f) = mine.fixes.get(k).filter(|f| (f.t - r.t.sow).abs() <= 0.005) else {
            continue;
        };
        common_epochs += 1;
        let lla = ecef_to_lla(&r.pos_ecef_m);
        let d = c_ne(lla.x, lla.y).transpose() * (lla_to_ecef(&f.lla) - r.pos_ecef_m);
        worst = worst.max(d.x.hypot(d.y));
    }
    eprintln!(
        "navfuse spp vs rnx2rtkp: {} ours, {} theirs, {common_epochs} common epochs, largest horizontal difference {worst:.3} m",
        mine.fixes.len(),
        rtk.len()
    );
    assert!(
        common_epochs * 10 >= rtk.len() * 9,
        "{common_epochs} of {}",
        rtk.len()
    );
    assert!(worst <= 1.0, "{worst} m");
    // RTKLIB's own tool reads it.
    match Command::new("pos2kml").arg(&ours).output() {
        Ok(o) => {
            assert!(o.status.success(), "pos2kml failed");
            assert!(ours.with_extension("kml").is_file());
        }
        Err(e) => eprintln!("skipped: pos2kml ({e})"),
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_options_are_refused_with_a_reason() {
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
            .args(args)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let e = run(&["spp", "a.obs", "b.nav", "--systems", "GX"]);
    assert!(e.contains("--systems") && e.contains("'X'"), "{e}");
    let e = run(&["spp", "a.obs", "b.nav", "--signals", "R=C1P"]);
    assert!(e.contains("--signals") && e.contains("SYSTEM:CODE"), "{e}");
    let e = run(&["spp", "a.obs", "b.nav", "--systems", "G,E"]);
    assert!(e.contains("b.nav"), "{e}");
}
