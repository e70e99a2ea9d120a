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

/// Add the records of `more` to `nav`: GPS records already decoded (same PRN, IODE
/// and toe) are not repeated; the ionosphere and leap seconds fill what is missing.
fn merge_nav(nav: &mut RinexNav, more: RinexNav) {
    for e in more.gps {
        if !nav
            .gps
            .iter()
            .any(|g| g.prn == e.prn && g.iode == e.iode && g.toe == e.toe)
        {
            nav.gps.push(e);
        }
    }
    nav.qzss.extend(more.qzss);
    nav.galileo.extend(more.galileo);
    nav.beidou.extend(more.beidou);
    nav.glonass.extend(more.glonass);
    nav.iono_alpha = nav.iono_alpha.or(more.iono_alpha);
    nav.iono_beta = nav.iono_beta.or(more.iono_beta);
    nav.leap_seconds = nav.leap_seconds.or(more.leap_seconds);
    nav.warnings.extend(more.warnings);
}
