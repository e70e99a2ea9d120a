//! THE list of aiding sources. A source constructs itself from the configuration
//! (None when it is not used); the order is the order in which they see each
//! measurement and run after each IMU step, and in which their state blocks are
//! appended to the filter.

use super::baro::Barometer;
use super::gnss_loose::GnssLoose;
use super::gnss_six_state::GnssSixState;
use super::heading::DualAntennaHeading;
use super::nhc::NhcSource;
use super::odometer::OdometerSource;
use super::source::AidingSource;
use super::tight::TightGnss;
use super::zupt::Zupt;
use crate::config::NavConfig;

/// The sources the configuration asks for; `t0`: the start time (IMU time).
pub fn sources(cfg: &NavConfig, t0: f64) -> Vec<Box<dyn AidingSource>> {
    let mut list = Vec::new();
    add(&mut list, Zupt::from_config(cfg, t0)); // before the NHC: sets the static state
    add(&mut list, NhcSource::from_config(cfg, t0));
    add(&mut list, OdometerSource::from_config(cfg));
    add(&mut list, DualAntennaHeading::from_config(cfg));
    add(&mut list, TightGnss::from_config(cfg));
    add(&mut list, GnssLoose::from_config(cfg));
    add(&mut list, GnssSixState::from_config(cfg));
    add(&mut list, Barometer::from_config(cfg));
    list
}

fn add<S: AidingSource + 'static>(list: &mut Vec<Box<dyn AidingSource>>, s: Option<S>) {
    if let Some(s) = s {
        list.push(Box::new(s));
    }
}
