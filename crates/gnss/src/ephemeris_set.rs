//! Selecting the broadcast ephemeris to use at a given time.

use crate::ephemeris::GpsEphemeris;
use crate::time::GpsTime;

/// A set of GPS ephemerides (any order, several per PRN).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EphemerisSet {
    ephs: Vec<GpsEphemeris>,
}

impl EphemerisSet {
    /// Wrap ephemerides.
    pub fn new(ephs: Vec<GpsEphemeris>) -> Self {
        EphemerisSet { ephs }
    }

    /// All ephemerides.
    pub fn all(&self) -> &[GpsEphemeris] {
        &self.ephs
    }

    /// The ephemeris for `prn` at `t`: healthy (health 0), |t - toe| within half the
    /// fit interval (IS-GPS-200 20.3.4.4: the fit interval is centred on toe, 4 h when
    /// the flag is 0), closest toe; ties go to the later toe, then the later
    /// transmission time. A toe up to half the fit interval in the future is accepted,
    /// as in post-processing (RTKLIB uses 2 h for GPS); a real-time user who must not
    /// use an ephemeris before its transmission should check `transmission_time`.
    pub fn select(&self, prn: u8, t: GpsTime) -> Option<&GpsEphemeris> {
        nearest_record(
            self.ephs.iter().filter(|e| e.prn == prn && e.health == 0),
            t,
            |e| (e.toe, e.transmission_time, 0.5 * e.fit_interval_s()),
        )
    }

    /// The PRNs present, sorted, without duplicates.
    pub fn prns(&self) -> Vec<u8> {
        let mut p: Vec<u8> = self.ephs.iter().map(|e| e.prn).collect();
        p.sort_unstable();
        p.dedup();
        p
    }
}

/// The record nearest `t` by its reference time, within its age limit; on a tie the
/// later toe, then the later transmission. `key`: (toe in GPST, transmission time,
/// age limit \[s\]). The one rule of `EphemerisSet` and `EphemerisStore`.
pub(crate) fn nearest_record<'a, E>(
    records: impl Iterator<Item = &'a E>,
    t: GpsTime,
    key: impl Fn(&E) -> (GpsTime, Option<GpsTime>, f64),
) -> Option<&'a E> {
    let mut best: Option<(&E, f64, GpsTime, Option<GpsTime>)> = None;
    for e in records {
        let (toe, tt, max_age_s) = key(e);
        let dt = t.diff_s(&toe);
        if dt.abs() > max_age_s {
            continue;
        }
        let better = match &best {
            None => true,
            Some((_, bdt, btoe, btt)) => {
                if dt.abs() != bdt.abs() {
                    dt.abs() < bdt.abs()
                } else if toe != *btoe {
                    toe.diff_s(btoe) > 0.0
                } else {
                    let w = |x: &Option<GpsTime>| x.map(|g| (g.week, g.sow));
                    w(&tt).partial_cmp(&w(btt)) == Some(std::cmp::Ordering::Greater)
                }
            }
        };
        if better {
            best = Some((e, dt, toe, tt));
        }
    }
    best.map(|b| b.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn select_rules() {
        let t0 = GpsTime::new(2381, 7_200.0);
        let mut a = GpsEphemeris::zeroed(5, t0);
        a.iode = 1;
        let mut b = GpsEphemeris::zeroed(5, t0.add_s(7_200.0));
        b.iode = 2;
        let mut sick = GpsEphemeris::zeroed(5, t0.add_s(3_600.0));
        sick.health = 1;
        let other = GpsEphemeris::zeroed(6, t0);
        let set = EphemerisSet::new(vec![a, b, sick, other]);
        assert_eq!(set.select(5, t0.add_s(1_000.0)).map(|e| e.iode), Some(1));
        assert_eq!(set.select(5, t0.add_s(5_000.0)).map(|e| e.iode), Some(2));
        // Tie at +3600 s: the later toe wins.
        assert_eq!(set.select(5, t0.add_s(3_600.0)).map(|e| e.iode), Some(2));
        // Beyond half the fit interval (2 h) of every ephemeris.
        assert!(set.select(5, t0.add_s(7_200.0 + 7_201.0)).is_none());
        assert!(set.select(5, t0.add_s(-7_201.0)).is_none());
        assert!(set.select(7, t0).is_none());
        assert_eq!(set.prns(), vec![5, 6]);
    }
}
