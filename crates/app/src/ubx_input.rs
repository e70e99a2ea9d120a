//! u-blox UBX input for the run pipeline (`[gnss] format = "ubx"`, raw source): the
//! RXM-RAWX observations and RXM-SFRBX ephemerides of the log (plus an optional RINEX
//! navigation file) go through the same preparation as RINEX observations
//! (gnss_input.rs), so only the reading differs.

use crate::gnss_input::{prepare_observations, ReadObservations, RinexInput};
use crate::Error;
use navfuse_core::sat::System;
use navfuse_io::input::{GnssSource, RinexGnss};
use navfuse_io::rinex_nav::{read_rinex_nav, RinexNav};
use navfuse_io::ubx::read_ubx;

/// Read a UBX log and prepare its epochs with the settings `r` (`r.nav_path`: an
/// extra RINEX navigation file, empty for none).
pub fn load_ubx(src: &GnssSource, r: &RinexGnss, systems: &[System]) -> Result<RinexInput, Error> {
    let log = read_ubx(&src.path)?;
    let summary = format!("{}: {}", src.path.display(), log.summary());
    let mut nav = log.nav;
    let mut nav_name = format!("{} (RXM-SFRBX)", src.path.display());
    if !r.nav_path.as_os_str().is_empty() {
        let extra = &r.nav_path;
        let more = read_rinex_nav(extra)?;
        nav_name = format!("{nav_name} and {}", extra.display());
        merge_nav(&mut nav, more);
    }
    let mut out = prepare_observations(
        src,
        r,
        systems,
        ReadObservations {
            nav_name,
            nav,
            header: log.header,
            epochs: log.epochs,
            warnings: log.warnings,
        },
    )?;
    out.notes.insert(0, summary);
    Ok(out)
}

/// Add the records of `more` to `nav`: records already decoded (GPS/QZSS: same PRN,
/// IODE and toe; Galileo: PRN, IODnav, toe; BeiDou: PRN, toe, AODE; GLONASS: slot,
/// tb) are not repeated; the ionosphere and leap seconds fill what is missing.
fn merge_nav(nav: &mut RinexNav, more: RinexNav) {
    fn add<T>(to: &mut Vec<T>, from: Vec<T>, same: impl Fn(&T, &T) -> bool) {
        for e in from {
            if !to.iter().any(|x| same(x, &e)) {
                to.push(e);
            }
        }
    }
    let lnav = |a: &navfuse_gnss::GpsEphemeris, b: &navfuse_gnss::GpsEphemeris| {
        a.prn == b.prn && a.iode == b.iode && a.toe == b.toe
    };
    add(&mut nav.gps, more.gps, lnav);
    add(&mut nav.qzss, more.qzss, lnav);
    add(&mut nav.galileo, more.galileo, |a, b| {
        a.prn == b.prn && a.iodnav == b.iodnav && a.toe == b.toe
    });
    add(&mut nav.beidou, more.beidou, |a, b| {
        a.prn == b.prn && a.toe == b.toe && a.aode == b.aode
    });
    add(&mut nav.glonass, more.glonass, |a, b| {
        a.slot == b.slot && a.tb == b.tb
    });
    nav.iono_alpha = nav.iono_alpha.or(more.iono_alpha);
    nav.iono_beta = nav.iono_beta.or(more.iono_beta);
    let (io, mo) = (&mut nav.iono, more.iono);
    io.qzss_klobuchar = io.qzss_klobuchar.or(mo.qzss_klobuchar);
    io.beidou_klobuchar = io.beidou_klobuchar.or(mo.beidou_klobuchar);
    io.galileo_nequick = io.galileo_nequick.or(mo.galileo_nequick);
    nav.leap_seconds = nav.leap_seconds.or(more.leap_seconds);
    nav.warnings.extend(more.warnings);
}
