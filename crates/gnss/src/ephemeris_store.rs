//! The broadcast ephemerides of every system and the choice of the record to use:
//! "state of satellite SatId at GPST t". The rule is [`EphemerisSet::select`]'s for
//! all systems (healthy, |t - toe| within the system's limit, closest toe; ties to
//! the later toe, then the later transmission time), so GPS gives the same record.
//! Galileo: the preferred message (I/NAV by default) when one is in reach, else the
//! other one; and of a message the latest record whose toe is not after t, when
//! there is one (Galileo predicts its orbits ahead from each upload, so a batch is
//! used from its toe on, as RTKLIB does; the nearest record otherwise).
//!
//! [`EphemerisSet::select`]: crate::ephemeris_set::EphemerisSet::select

use crate::ephemeris::{Ephemeris, GalileoMessage, SatState};
use crate::time::GpsTime;
use navfuse_core::sat::{SatId, System};
use std::collections::BTreeMap;

/// Ephemerides of all systems (any order, several per satellite).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EphemerisStore {
    by_sat: BTreeMap<SatId, Vec<Ephemeris>>,
    galileo_prefer: Option<GalileoMessage>,
}

/// Records per system: all, and those not used because unhealthy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SystemCount {
    pub records: usize,
    pub unhealthy: usize,
}

impl EphemerisStore {
    pub fn new(ephs: impl IntoIterator<Item = Ephemeris>) -> Self {
        let mut s = EphemerisStore::default();
        for e in ephs {
            s.push(e);
        }
        s
    }

    pub fn push(&mut self, e: Ephemeris) {
        self.by_sat.entry(e.sat()).or_default().push(e);
    }

    /// Prefer F/NAV (E5a users) or I/NAV (the default) for Galileo.
    pub fn with_galileo_preference(mut self, m: GalileoMessage) -> Self {
        self.galileo_prefer = Some(m);
        self
    }

    /// Satellites with at least one record, sorted.
    pub fn sats(&self) -> Vec<SatId> {
        self.by_sat.keys().copied().collect()
    }

    /// Every record.
    pub fn iter(&self) -> impl Iterator<Item = &Ephemeris> {
        self.by_sat.values().flatten()
    }

    /// Records and unhealthy records per system.
    pub fn counts(&self) -> BTreeMap<System, SystemCount> {
        let mut m: BTreeMap<System, SystemCount> = BTreeMap::new();
        for e in self.iter() {
            let c = m.entry(e.sat().system).or_default();
            c.records += 1;
            c.unhealthy += usize::from(!e.healthy());
        }
        m
    }

    /// The record to use for `sat` at GPST `t` (module documentation).
    pub fn select(&self, sat: SatId, t: GpsTime) -> Option<&Ephemeris> {
        let list = self.by_sat.get(&sat)?;
        if sat.system == System::Galileo {
            let pref = self.galileo_prefer.unwrap_or(GalileoMessage::INav);
            let of = |m: GalileoMessage| move |e: &&Ephemeris| matches!(e, Ephemeris::Galileo(g) if g.message() == m);
            let other = match pref {
                GalileoMessage::INav => GalileoMessage::FNav,
                GalileoMessage::FNav => GalileoMessage::INav,
            };
            let galileo = |m: GalileoMessage| {
                let of_m = || list.iter().filter(of(m));
                best(of_m().filter(|e| t.diff_s(&e.toe_gpst()) > 0.0), t)
                    .or_else(|| best(of_m(), t))
            };
            return galileo(pref).or_else(|| galileo(other));
        }
        best(list.iter(), t)
    }

    /// The state of `sat` at GPST `t` with the record used, or None when no healthy
    /// record is in reach.
    pub fn sat_state(&self, sat: SatId, t: GpsTime) -> Option<(SatState, &Ephemeris)> {
        self.select(sat, t).map(|e| (e.sat_state(t), e))
    }
}

fn best<'a>(it: impl Iterator<Item = &'a Ephemeris>, t: GpsTime) -> Option<&'a Ephemeris> {
    crate::ephemeris_set::nearest_record(it.filter(|e| e.healthy()), t, |e| {
        (e.toe_gpst(), e.transmission_time_gpst(), e.max_age_s())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ephemeris::GpsEphemeris;
    use crate::ephemeris_set::EphemerisSet;

    #[test]
    fn gps_selection_is_the_sets() {
        let t0 = GpsTime::new(2381, 7_200.0);
        let mut v = Vec::new();
        for (k, dt) in [0.0, 7_200.0, 3_600.0, 14_400.0].iter().enumerate() {
            let mut e = GpsEphemeris::zeroed(5, t0.add_s(*dt));
            e.iode = k as u16;
            e.health = u32::from(k == 2);
            v.push(e);
        }
        let set = EphemerisSet::new(v.clone());
        let store = EphemerisStore::new(v.into_iter().map(Ephemeris::Gps));
        for k in -10..40 {
            let t = t0.add_s(f64::from(k) * 600.0);
            let a = set.select(5, t).map(|e| e.iode);
            let b = store.select(SatId::gps(5), t).map(|e| e.iod());
            assert_eq!(a, b, "t = {k}");
        }
        let c = store.counts()[&System::Gps];
        assert_eq!((c.records, c.unhealthy), (4, 1));
        assert!(store.select(SatId::gps(6), t0).is_none());
    }
}
