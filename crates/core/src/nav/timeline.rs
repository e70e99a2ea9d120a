//! The time line: which measurement is due when, and how an IMU interval is cut at
//! the measurement times inside it so that each increment is integrated exactly once.
//!
//! Rules (docs/ALGORITHMS.md, "Order of updates and the time line"):
//! - A measurement is applied when the navigator has reached its time of validity:
//!   the IMU interval (t_k - dt, t_k] holding it is integrated up to that time, the
//!   measurement is applied, and integration continues from there.
//! - Times within [`SNAP_S`] of the time already reached, or of the interval's end,
//!   are taken as that time (no sliver of an interval is integrated).
//! - Optionally (`[gnss] time_snap_s`, [`Inbox::with_gnss_snap`]) an input on the GNSS
//!   clock within a tolerance tol of an IMU epoch is applied at that epoch, as
//!   KF-GINS does with 1 ms (its `isToUpdate`): in the interval (t_a, t_b] its time t
//!   is taken as t_a when |t - t_a| < tol, else as t_b when |t - t_b| <= tol (a fix up
//!   to tol after t_b comes due at t_b); the inputs are handed over in the order of
//!   these times. Moving a fix by up to tol costs up to v * tol of position.
//! - Measurements at equal times are applied in the order of the merged list
//!   (`merge_measurements`: GNSS, then odometer, then heading); the second one at a
//!   time integrates nothing.
//! - The GNSS-clock inputs come due at their time tag plus the GNSS-IMU time offset,
//!   the IMU-clock ones (odometer, barometer) at their own: each clock's inputs in
//!   their order, the two interleaved by effective time ([`Inbox`]).
//! - A measurement whose time is already behind the navigator (possible when the
//!   GNSS-IMU time offset estimate moves) is applied at once.

use crate::outage::OutageSchedule;
use crate::types::{ImuSample, Measurement};

/// Times closer than this to the time reached or to an interval end are taken as
/// equal to it \[s\].
pub const SNAP_S: f64 = 1e-9;

/// The part of one IMU interval not yet integrated: (t_reached, end.t].
#[derive(Clone, Copy, Debug)]
pub struct IntervalRest {
    rest: ImuSample,
}

impl IntervalRest {
    pub fn new(sample: ImuSample) -> Self {
        IntervalRest { rest: sample }
    }

    /// Time up to which the interval has been integrated \[s\].
    pub fn t_reached(&self) -> f64 {
        self.rest.t - self.rest.dt
    }

    /// The piece to integrate to reach `t` (the whole rest when `t` is at or after the
    /// interval's end); `None` when `t` is not after the time reached.
    pub fn cut_until(&mut self, t: f64) -> Option<ImuSample> {
        let r = self.rest;
        if r.dt <= 0.0 || t <= self.t_reached() + SNAP_S {
            return None;
        }
        if t >= r.t - SNAP_S {
            return self.take_rest();
        }
        // Linear share of the increments (constant rate inside the interval).
        let lambda = (t - self.t_reached()) / r.dt;
        let piece = ImuSample {
            t,
            dt: r.dt * lambda,
            dtheta: r.dtheta * lambda,
            dvel: r.dvel * lambda,
        };
        self.rest = ImuSample {
            t: r.t,
            dt: r.dt - piece.dt,
            dtheta: r.dtheta - piece.dtheta,
            dvel: r.dvel - piece.dvel,
        };
        Some(piece)
    }

    /// Whatever is left of the interval; afterwards nothing is.
    pub fn take_rest(&mut self) -> Option<ImuSample> {
        let r = self.rest;
        self.rest.dt = 0.0;
        self.rest.dtheta = Default::default();
        self.rest.dvel = Default::default();
        (r.dt > 0.0).then_some(r)
    }
}

/// Which way a run goes in time: forward (increasing t) or backward (the
/// time-reversed run of post-processing, nav/backward.rs). The sources measure
/// elapsed time and schedule their cadence with it, so that the same policy works
/// both ways; forward every helper is the plain expression it replaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimeDirection {
    #[default]
    Forward,
    Backward,
}

impl TimeDirection {
    /// Time elapsed along the run from `since` to `now` \[s\]: `now - since` forward,
    /// `since - now` backward (positive when `now` comes later in the run).
    #[inline]
    pub fn elapsed(self, since: f64, now: f64) -> f64 {
        match self {
            TimeDirection::Forward => now - since,
            TimeDirection::Backward => since - now,
        }
    }

    /// `t` moved by the duration `d` along the run: `t + d` forward, `t - d` backward.
    #[inline]
    pub fn advance(self, t: f64, d: f64) -> f64 {
        match self {
            TimeDirection::Forward => t + d,
            TimeDirection::Backward => t - d,
        }
    }

    /// `t` has reached `due` (within `tol` \[s\]) along the run: `t >= due - tol`
    /// forward, `t <= due + tol` backward.
    #[inline]
    pub fn reached(self, t: f64, due: f64, tol: f64) -> bool {
        match self {
            TimeDirection::Forward => t >= due - tol,
            TimeDirection::Backward => t <= due + tol,
        }
    }

    pub fn is_backward(self) -> bool {
        self == TimeDirection::Backward
    }
}

/// The part of one IMU interval (t_k - dt, t_k] not yet integrated by a backward
/// run, which goes from t_k down to t_k - dt: (t_k - dt, t_reached]. The pieces it
/// hands out are in the time-reversed form the backward mechanization takes
/// (nav/backward.rs): `t` the time the piece ends at (its lower end), `dt` < 0 and
/// the increments negated, so that t - dt is where the piece starts.
#[derive(Clone, Copy, Debug)]
pub struct ReverseRest {
    /// Lower end of the interval, t_k - dt.
    lower: f64,
    /// Time integrated down to so far.
    reached: f64,
    /// What is left, positive: length, angle and velocity increments.
    dt: f64,
    dtheta: nalgebra::Vector3<f64>,
    dvel: nalgebra::Vector3<f64>,
}

impl ReverseRest {
    pub fn new(sample: ImuSample) -> Self {
        ReverseRest {
            lower: sample.t - sample.dt,
            reached: sample.t,
            dt: sample.dt,
            dtheta: sample.dtheta,
            dvel: sample.dvel,
        }
    }

    /// Time down to which the interval has been integrated \[s\].
    pub fn t_reached(&self) -> f64 {
        self.reached
    }

    /// The piece to integrate (backward) to reach `t` (the whole rest when `t` is at or
    /// before the interval's lower end); `None` when `t` is not below the time
    /// reached. The mirror of [`IntervalRest::cut_until`].
    pub fn cut_until(&mut self, t: f64) -> Option<ImuSample> {
        if self.dt <= 0.0 || t >= self.reached - SNAP_S {
            return None;
        }
        if t <= self.lower + SNAP_S {
            return self.take_rest();
        }
        // Linear share of the increments (constant rate inside the interval).
        let lambda = (self.reached - t) / self.dt;
        let (dt, dtheta, dvel) = (self.dt * lambda, self.dtheta * lambda, self.dvel * lambda);
        self.reached = t;
        self.dt -= dt;
        self.dtheta -= dtheta;
        self.dvel -= dvel;
        Some(ImuSample {
            t,
            dt: -dt,
            dtheta: -dtheta,
            dvel: -dvel,
        })
    }

    /// Whatever is left of the interval (down to its lower end); afterwards nothing is.
    pub fn take_rest(&mut self) -> Option<ImuSample> {
        let piece = ImuSample {
            t: self.lower,
            dt: -self.dt,
            dtheta: -self.dtheta,
            dvel: -self.dvel,
        };
        let any = self.dt > 0.0;
        self.reached = self.lower;
        self.dt = 0.0;
        self.dtheta = Default::default();
        self.dvel = Default::default();
        any.then_some(piece)
    }
}

/// What the inbox hands over next.
#[derive(Debug)]
pub enum Due<'a> {
    /// Apply at `t_eff` (IMU time scale): the effective time, or the IMU epoch it
    /// is snapped to ([`Inbox::with_gnss_snap`]).
    Apply { m: &'a Measurement, t_eff: f64 },
    /// Inside a configured GNSS outage: not applied.
    Withheld(&'a Measurement),
}

/// The two clocks the inputs are tagged on: index 0 the GNSS receiver's (shifted by the
/// GNSS-IMU time offset), 1 the IMU's (odometer, barometer).
fn clock(m: &Measurement) -> usize {
    if m.on_gnss_clock() {
        0
    } else {
        1
    }
}

/// The merged, time-sorted measurements, handed over as the IMU time line reaches them.
/// The inputs of each clock keep their order; the two clocks are interleaved by
/// effective time (ties: the merged order), so that a GNSS-IMU time offset delays or
/// advances the GNSS inputs only: an odometer record tagged between a fix's time tag
/// and its effective time neither waits for the fix nor holds it back.
#[derive(Debug)]
pub struct Inbox<'a> {
    meas: &'a [Measurement],
    /// Index of the next input on each clock ([`clock`]; `meas.len()` when none).
    next: [usize; 2],
    outages: &'a OutageSchedule,
    /// Each clock's snap tolerance \[s\] ([`Inbox::with_gnss_snap`]).
    snap_s: [f64; 2],
}

/// Time of validity on the IMU time scale: GNSS-clock inputs shifted by the offset.
pub fn effective_time(m: &Measurement, time_offset_s: f64) -> f64 {
    m.t()
        + if m.on_gnss_clock() {
            time_offset_s
        } else {
            0.0
        }
}

/// Time `t` as applied in the forward IMU interval (t_a, t_b] with snap tolerance
/// `tol` (KF-GINS's `isToUpdate`, gi_engine.cpp): t_a when |t - t_a| < tol, else t_b
/// when |t - t_b| <= tol, else `t`.
#[inline]
fn snapped(t: f64, tol: f64, t_a: f64, t_b: f64) -> f64 {
    if tol <= 0.0 {
        t
    } else if (t - t_a).abs() < tol {
        t_a
    } else if (t - t_b).abs() <= tol {
        t_b
    } else {
        t
    }
}

/// The mirror of [`snapped`] for a backward run through [t_a, t_b): the upper end
/// (reached first) when |t - t_b| < tol, else t_a when |t - t_a| <= tol.
#[inline]
fn snapped_down(t: f64, tol: f64, t_a: f64, t_b: f64) -> f64 {
    if tol <= 0.0 {
        t
    } else if (t - t_b).abs() < tol {
        t_b
    } else if (t - t_a).abs() <= tol {
        t_a
    } else {
        t
    }
}

/// First index at or after `from` of an input on clock `c` (`meas.len()` when none).
fn seek_up(meas: &[Measurement], from: usize, c: usize) -> usize {
    meas[from.min(meas.len())..]
        .iter()
        .position(|m| clock(m) == c)
        .map_or(meas.len(), |k| from + k)
}

/// One past the last index below `below` of an input on clock `c` (0 when none).
fn seek_down(meas: &[Measurement], below: usize, c: usize) -> usize {
    meas[..below]
        .iter()
        .rposition(|m| clock(m) == c)
        .map_or(0, |k| k + 1)
}

impl<'a> Inbox<'a> {
    pub fn new(meas: &'a [Measurement], outages: &'a OutageSchedule) -> Self {
        Inbox {
            meas,
            next: [seek_up(meas, 0, 0), seek_up(meas, 0, 1)],
            outages,
            snap_s: [0.0; 2],
        }
    }

    /// GNSS-clock inputs within `snap_s` \[s\] of an IMU epoch are applied at it
    /// (module documentation); 0 (the default): at their own time.
    pub fn with_gnss_snap(mut self, snap_s: f64) -> Self {
        self.snap_s[0] = snap_s.max(0.0);
        self
    }

    /// The clock whose next input comes first at `time_offset_s` in the interval
    /// (t_a, t_b], with its index and application time ([`snapped`]).
    fn first(&self, time_offset_s: f64, t_a: f64, t_b: f64) -> Option<(usize, usize, f64)> {
        let cand = |c: usize| {
            let i = self.next[c];
            self.meas.get(i).map(|m| {
                let t = effective_time(m, time_offset_s);
                (c, i, snapped(t, self.snap_s[c], t_a, t_b))
            })
        };
        match (cand(0), cand(1)) {
            (Some(a), Some(b)) => Some(if (b.2, b.1) < (a.2, a.1) { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// Drop, on each clock, the leading measurements for which `unused` holds (at the
    /// current offset `unused` is monotone along each clock); returns them.
    pub fn skip_while(
        &mut self,
        mut unused: impl FnMut(&Measurement) -> bool,
    ) -> Vec<&'a Measurement> {
        let mut skipped = Vec::new();
        for c in 0..2 {
            while let Some(m) = self.meas.get(self.next[c]).filter(|m| unused(m)) {
                skipped.push(m);
                self.next[c] = seek_up(self.meas, self.next[c] + 1, c);
            }
        }
        skipped
    }

    /// The next measurement whose effective time is at or before `t_end`.
    pub fn next_due(&mut self, t_end: f64, time_offset_s: f64) -> Option<Due<'a>> {
        self.next_due_in(f64::NEG_INFINITY, t_end, time_offset_s)
    }

    /// The next measurement due in the IMU interval (t_start, t_end]: its effective
    /// time, snapped to t_start or t_end by its clock's tolerance, at or before t_end.
    pub fn next_due_in(&mut self, t_start: f64, t_end: f64, time_offset_s: f64) -> Option<Due<'a>> {
        let (c, i, t_eff) = self.first(time_offset_s, t_start, t_end)?;
        if t_eff > t_end {
            return None;
        }
        let m = &self.meas[i];
        self.next[c] = seek_up(self.meas, i + 1, c);
        if m.on_gnss_clock() && self.outages.contains(m.t()) {
            return Some(Due::Withheld(m));
        }
        Some(Due::Apply { m, t_eff })
    }
}

/// The time-sorted measurements handed over from the last to the first as a
/// backward run reaches them: the mirror of [`Inbox`]. Each clock's inputs come in
/// the reverse of their merged order, the two clocks interleaved by effective time
/// (ties: the reverse of the merged order); GNSS outages withhold the same inputs.
#[derive(Debug)]
pub struct ReverseInbox<'a> {
    meas: &'a [Measurement],
    /// One past the next input to hand over on each clock (counting down; 0: none).
    next: [usize; 2],
    outages: &'a OutageSchedule,
    snap_s: [f64; 2],
}

impl<'a> ReverseInbox<'a> {
    pub fn new(meas: &'a [Measurement], outages: &'a OutageSchedule) -> Self {
        let n = meas.len();
        ReverseInbox {
            meas,
            next: [seek_down(meas, n, 0), seek_down(meas, n, 1)],
            outages,
            snap_s: [0.0; 2],
        }
    }

    /// As [`Inbox::with_gnss_snap`].
    pub fn with_gnss_snap(mut self, snap_s: f64) -> Self {
        self.snap_s[0] = snap_s.max(0.0);
        self
    }

    /// The clock whose next input (going down) comes first in the interval
    /// [t_a, t_b), with its index and application time ([`snapped_down`]).
    fn last(&self, time_offset_s: f64, t_a: f64, t_b: f64) -> Option<(usize, usize, f64)> {
        let cand = |c: usize| {
            let i = self.next[c].checked_sub(1)?;
            let t = effective_time(&self.meas[i], time_offset_s);
            Some((c, i, snapped_down(t, self.snap_s[c], t_a, t_b)))
        };
        match (cand(0), cand(1)) {
            (Some(a), Some(b)) => Some(if (b.2, b.1) > (a.2, a.1) { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// Drop, on each clock, the trailing measurements for which `unused` holds;
    /// returns them.
    pub fn skip_while(
        &mut self,
        mut unused: impl FnMut(&Measurement) -> bool,
    ) -> Vec<&'a Measurement> {
        let mut skipped = Vec::new();
        for c in 0..2 {
            while let Some(m) = self.next[c]
                .checked_sub(1)
                .map(|i| &self.meas[i])
                .filter(|m| unused(m))
            {
                skipped.push(m);
                self.next[c] = seek_down(self.meas, self.next[c] - 1, c);
            }
        }
        skipped
    }

    /// The next (latest remaining) measurement whose effective time is at or after
    /// `t_low`, the lower end of the interval being integrated.
    pub fn next_due(&mut self, t_low: f64, time_offset_s: f64) -> Option<Due<'a>> {
        self.next_due_in(t_low, f64::INFINITY, time_offset_s)
    }

    /// The mirror of [`Inbox::next_due_in`]: the next (latest remaining) measurement
    /// due in [t_low, t_high), snapped by `snapped_down`, at or after t_low.
    pub fn next_due_in(&mut self, t_low: f64, t_high: f64, time_offset_s: f64) -> Option<Due<'a>> {
        let (c, i, t_eff) = self.last(time_offset_s, t_low, t_high)?;
        if t_eff < t_low {
            return None;
        }
        let m = &self.meas[i];
        self.next[c] = seek_down(self.meas, i, c);
        if m.on_gnss_clock() && self.outages.contains(m.t()) {
            return Some(Due::Withheld(m));
        }
        Some(Due::Apply { m, t_eff })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use rand::{RngExt, SeedableRng};

    fn sample(t: f64, dt: f64) -> ImuSample {
        ImuSample {
            t,
            dt,
            dtheta: Vector3::new(0.3, -1.1, 0.7) * dt,
            dvel: Vector3::new(9.8, 0.2, -3.0) * dt,
        }
    }

    /// Cuts at random times (on, within 1e-12..1e-6 s of, and between the interval's
    /// ends; duplicates; times already passed): the pieces add up to the interval.
    #[test]
    fn pieces_add_up_to_the_interval() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(15);
        for _ in 0..20_000 {
            let dt = 0.005;
            let s = sample(100.0 + dt, dt);
            let t0 = s.t - s.dt;
            let mut times: Vec<f64> = (0..rng.random_range(0..6))
                .map(|_| match rng.random_range(0..5) {
                    0 => t0,
                    1 => s.t,
                    2 => {
                        s.t + if rng.random() { 1.0 } else { -1.0 }
                            * 10f64.powf(rng.random_range(-12.0..-6.0))
                    }
                    3 => t0 + 10f64.powf(rng.random_range(-12.0..-6.0)),
                    _ => t0 + rng.random::<f64>() * dt,
                })
                .collect();
            if rng.random() {
                times.extend(times.clone());
            }
            times.sort_by(f64::total_cmp);
            let mut rest = IntervalRest::new(s);
            let mut sum = (0.0, Vector3::zeros(), Vector3::zeros());
            let mut t_prev = t0;
            for &t in &times {
                if let Some(p) = rest.cut_until(t) {
                    assert!(p.dt > 0.0 && p.t > t_prev && p.t <= s.t);
                    t_prev = p.t;
                    sum = (sum.0 + p.dt, sum.1 + p.dtheta, sum.2 + p.dvel);
                }
            }
            if let Some(p) = rest.take_rest() {
                assert_eq!(p.t, s.t);
                sum = (sum.0 + p.dt, sum.1 + p.dtheta, sum.2 + p.dvel);
            }
            assert!(rest.take_rest().is_none() && rest.cut_until(s.t + 1.0).is_none());
            // Equal up to floating-point rounding of the cuts (a few ulp).
            assert!(
                (sum.0 - s.dt).abs() <= 4.0 * f64::EPSILON * s.dt,
                "{times:?}"
            );
            assert!((sum.1 - s.dtheta).norm() <= 8.0 * f64::EPSILON * s.dtheta.norm());
            assert!((sum.2 - s.dvel).norm() <= 8.0 * f64::EPSILON * s.dvel.norm());
        }
    }

    /// A cut at the end, then a second measurement at the same time: nothing more.
    #[test]
    fn second_measurement_at_the_end_integrates_nothing() {
        let s = sample(1.0, 0.01);
        let mut rest = IntervalRest::new(s);
        let p = rest.cut_until(1.0).unwrap();
        assert_eq!((p.dt, p.dtheta, p.dvel), (s.dt, s.dtheta, s.dvel));
        assert!(rest.cut_until(1.0).is_none());
        assert!(rest.take_rest().is_none());
    }

    fn fix(t: f64) -> crate::types::GnssFix {
        crate::types::GnssFix {
            t,
            lla: Vector3::zeros(),
            std_ned: Vector3::repeat(1.0),
            vel_ned: None,
            vel_std_ned: None,
        }
    }

    fn odo(t: f64) -> crate::types::OdometerSample {
        crate::types::OdometerSample {
            t,
            speed_mps: 1.0,
            interval_s: 0.0,
        }
    }

    /// The inbox on its own: GNSS-clock inputs come due at t + offset, the odometer
    /// (IMU clock) at its own time, neither waiting for the other; a fix inside an
    /// outage is withheld, an odometer record at the same time is not; nothing is
    /// handed over twice.
    #[test]
    fn inbox_applies_the_offset_and_withholds_outages() {
        use crate::outage::Window;
        let meas = crate::types::merge_measurements(
            &[fix(1.0), fix(2.0), fix(3.0)],
            &[odo(1.0), odo(1.1), odo(2.0)],
            &[],
        );
        let outages = OutageSchedule {
            windows: vec![Window {
                start: 1.5,
                end: 2.5,
            }],
            periodic: Vec::new(),
        };
        let mut inbox = Inbox::new(&meas, &outages);
        let offset = 0.2;
        let due_at = |t_end: f64, inbox: &mut Inbox| {
            let mut got = Vec::new();
            while let Some(d) = inbox.next_due(t_end, offset) {
                got.push(match d {
                    Due::Apply { m, t_eff } => (m.on_gnss_clock(), t_eff, true),
                    Due::Withheld(m) => (m.on_gnss_clock(), m.t(), false),
                });
            }
            got
        };
        // Up to IMU time 1.1: the odometer at 1.0 and 1.1; the fix tagged 1.0 is due at
        // 1.2 and does not hold them back.
        assert_eq!(
            due_at(1.1, &mut inbox),
            vec![(false, 1.0, true), (false, 1.1, true)]
        );
        assert_eq!(due_at(1.2, &mut inbox), vec![(true, 1.2, true)]);
        // The odometer at 2.0 comes before the fix tagged 2.0 (due at 2.2), which is
        // inside the outage: withheld.
        assert_eq!(
            due_at(2.2, &mut inbox),
            vec![(false, 2.0, true), (true, 2.0, false)]
        );
        assert_eq!(due_at(10.0, &mut inbox), vec![(true, 3.2, true)]);
        assert!(due_at(10.0, &mut inbox).is_empty());
        // A negative offset: the fix tagged 2.0 is due at 1.8, before the odometer
        // records at 1.9 it is listed after.
        let meas2 =
            crate::types::merge_measurements(&[fix(2.0)], &[odo(1.7), odo(1.9), odo(2.1)], &[]);
        let none = OutageSchedule::default();
        let mut inbox = Inbox::new(&meas2, &none);
        let mut order = Vec::new();
        while let Some(Due::Apply { m, t_eff }) = inbox.next_due(10.0, -0.2) {
            order.push((m.on_gnss_clock(), t_eff));
        }
        assert_eq!(
            order,
            vec![(false, 1.7), (true, 1.8), (false, 1.9), (false, 2.1)]
        );
        // skip_while drops the leading inputs of each clock.
        let mut inbox = Inbox::new(&meas, &outages);
        assert_eq!(inbox.skip_while(|m| m.t() <= 1.0).len(), 2);
        assert!(matches!(
            inbox.next_due(10.0, 0.0),
            Some(Due::Apply { t_eff, .. }) if t_eff == 1.1
        ));
    }

    /// Random inputs on both clocks, random offsets: every input is handed over once;
    /// each clock's in its own order; the effective times never go back (the time line
    /// is followed); with a zero offset the order is exactly the merged list's.
    #[test]
    fn inbox_interleaves_the_clocks_by_effective_time() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(30);
        let none = OutageSchedule::default();
        for trial in 0..500 {
            let times = |n: usize, step: f64, rng: &mut rand_pcg::Pcg64| {
                let mut t = 0.0;
                (0..n)
                    .map(|_| {
                        // repeated times too
                        if rng.random::<f64>() > 0.1 {
                            t += rng.random::<f64>() * step;
                        }
                        t
                    })
                    .collect::<Vec<f64>>()
            };
            let g: Vec<_> = times(rng.random_range(0..20), 1.0, &mut rng)
                .into_iter()
                .map(fix)
                .collect();
            let o: Vec<_> = times(rng.random_range(0..60), 0.3, &mut rng)
                .into_iter()
                .map(odo)
                .collect();
            let meas = crate::types::merge_measurements(&g, &o, &[]);
            let offset = if trial % 5 == 0 {
                0.0
            } else {
                rng.random_range(-1.5..1.5)
            };
            let mut fwd = Vec::new();
            let mut inbox = Inbox::new(&meas, &none);
            let mut t_end = -2.0;
            while t_end < 30.0 {
                t_end += rng.random::<f64>() * 0.7;
                while let Some(Due::Apply { m, t_eff }) = inbox.next_due(t_end, offset) {
                    assert!(t_eff <= t_end);
                    fwd.push((m as *const Measurement, t_eff));
                }
            }
            assert_eq!(fwd.len(), meas.len(), "trial {trial}");
            assert!(fwd.windows(2).all(|w| w[0].1 <= w[1].1), "trial {trial}");
            let idx = |p: *const Measurement| meas.iter().position(|m| std::ptr::eq(m, p)).unwrap();
            for c in 0..2 {
                let mine: Vec<usize> = fwd
                    .iter()
                    .map(|x| idx(x.0))
                    .filter(|&i| clock(&meas[i]) == c)
                    .collect();
                assert!(mine.windows(2).all(|w| w[0] < w[1]));
            }
            if offset == 0.0 {
                let order: Vec<usize> = fwd.iter().map(|x| idx(x.0)).collect();
                assert_eq!(order, (0..meas.len()).collect::<Vec<_>>());
            }
            // Backward: the exact reverse of the forward order.
            let mut bwd = Vec::new();
            let mut inbox = ReverseInbox::new(&meas, &none);
            let mut t_low = 32.0;
            while t_low > -4.0 {
                t_low -= rng.random::<f64>() * 0.7;
                while let Some(Due::Apply { m, t_eff }) = inbox.next_due(t_low, offset) {
                    bwd.push((m as *const Measurement, t_eff));
                }
            }
            bwd.reverse();
            assert_eq!(
                bwd.iter().map(|x| idx(x.0)).collect::<Vec<_>>(),
                fwd.iter().map(|x| idx(x.0)).collect::<Vec<_>>(),
                "trial {trial}"
            );
        }
    }

    /// The backward mirror: cuts at random times going down; the pieces (time-reversed:
    /// dt < 0, increments negated) add up to the interval negated, each ends below the
    /// previous one, the last at the interval's lower end.
    #[test]
    fn reverse_pieces_add_up_to_the_interval() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(16);
        for _ in 0..20_000 {
            let dt = 0.005;
            let s = sample(100.0 + dt, dt);
            let t0 = s.t - s.dt;
            let mut times: Vec<f64> = (0..rng.random_range(0..6))
                .map(|_| match rng.random_range(0..5) {
                    0 => t0,
                    1 => s.t,
                    2 => s.t - 10f64.powf(rng.random_range(-12.0..-6.0)),
                    3 => {
                        t0 + if rng.random() { 1.0 } else { -1.0 }
                            * 10f64.powf(rng.random_range(-12.0..-6.0))
                    }
                    _ => t0 + rng.random::<f64>() * dt,
                })
                .collect();
            if rng.random() {
                times.extend(times.clone());
            }
            times.sort_by(|a, b| b.total_cmp(a));
            let mut rest = ReverseRest::new(s);
            let mut sum = (0.0, Vector3::zeros(), Vector3::zeros());
            let mut t_prev = s.t;
            for &t in &times {
                if let Some(p) = rest.cut_until(t) {
                    assert!(p.dt < 0.0 && p.t < t_prev && p.t >= t0, "{times:?}");
                    assert!((p.t - p.dt - t_prev).abs() < 1e-12);
                    t_prev = p.t;
                    sum = (sum.0 + p.dt, sum.1 + p.dtheta, sum.2 + p.dvel);
                }
            }
            if let Some(p) = rest.take_rest() {
                assert_eq!(p.t, t0);
                sum = (sum.0 + p.dt, sum.1 + p.dtheta, sum.2 + p.dvel);
            }
            assert_eq!(rest.t_reached(), t0);
            assert!(rest.take_rest().is_none() && rest.cut_until(t0 - 1.0).is_none());
            assert!(
                (sum.0 + s.dt).abs() <= 4.0 * f64::EPSILON * s.dt,
                "{times:?}"
            );
            assert!((sum.1 + s.dtheta).norm() <= 8.0 * f64::EPSILON * s.dtheta.norm());
            assert!((sum.2 + s.dvel).norm() <= 8.0 * f64::EPSILON * s.dvel.norm());
        }
    }

    /// The reverse inbox: from the last measurement down, GNSS-clock inputs due at
    /// t + offset, outages withheld, the trailing ones skipped.
    #[test]
    fn reverse_inbox_hands_over_from_the_end() {
        use crate::outage::Window;
        let meas = crate::types::merge_measurements(
            &[fix(1.0), fix(2.0), fix(3.0), fix(4.0)],
            &[odo(1.0), odo(2.0)],
            &[],
        );
        let outages = OutageSchedule {
            windows: vec![Window {
                start: 1.5,
                end: 2.5,
            }],
            periodic: Vec::new(),
        };
        let mut inbox = ReverseInbox::new(&meas, &outages);
        assert_eq!(inbox.skip_while(|m| m.t() >= 4.0).len(), 1);
        let offset = 0.2;
        let due_down_to = |t_low: f64, inbox: &mut ReverseInbox| {
            let mut got = Vec::new();
            while let Some(d) = inbox.next_due(t_low, offset) {
                got.push(match d {
                    Due::Apply { m, t_eff } => (m.on_gnss_clock(), t_eff, true),
                    Due::Withheld(m) => (m.on_gnss_clock(), m.t(), false),
                });
            }
            got
        };
        assert!(due_down_to(3.3, &mut inbox).is_empty());
        assert_eq!(due_down_to(3.2, &mut inbox), vec![(true, 3.2, true)]);
        // The fix tagged 2.0 (due at 2.2, withheld) before the odometer at 2.0.
        assert_eq!(
            due_down_to(1.9, &mut inbox),
            vec![(true, 2.0, false), (false, 2.0, true)]
        );
        // The fix tagged 1.0 is due at 1.2, before (going down) the odometer at 1.0.
        assert_eq!(due_down_to(1.1, &mut inbox), vec![(true, 1.2, true)]);
        assert_eq!(due_down_to(0.0, &mut inbox), vec![(false, 1.0, true)]);
        assert!(due_down_to(-10.0, &mut inbox).is_empty());
    }

    /// Where each input is applied: (its index in `meas`, the time reached when it
    /// is applied), walking the IMU epochs `epochs` forward (or backward) as the
    /// navigator does, with the GNSS snap tolerance `tol`.
    fn applied_at(
        meas: &[Measurement],
        epochs: &[f64],
        tol: f64,
        backward: bool,
    ) -> Vec<(usize, f64)> {
        let none = OutageSchedule::default();
        let idx = |m: &Measurement| meas.iter().position(|x| std::ptr::eq(x, m)).unwrap();
        let mut got = Vec::new();
        let pieces = epochs.windows(2).map(|w| sample(w[1], w[1] - w[0]));
        if !backward {
            let mut inbox = Inbox::new(meas, &none).with_gnss_snap(tol);
            for s in pieces {
                let mut rest = IntervalRest::new(s);
                while let Some(Due::Apply { m, t_eff }) = inbox.next_due_in(s.t - s.dt, s.t, 0.0) {
                    rest.cut_until(t_eff);
                    got.push((idx(m), rest.t_reached()));
                }
            }
        } else {
            let mut inbox = ReverseInbox::new(meas, &none).with_gnss_snap(tol);
            for s in pieces.rev() {
                let mut rest = ReverseRest::new(s);
                while let Some(Due::Apply { m, t_eff }) = inbox.next_due_in(s.t - s.dt, s.t, 0.0) {
                    rest.cut_until(t_eff);
                    got.push((idx(m), rest.t_reached()));
                }
            }
            got.reverse();
        }
        got
    }

    /// The snap rule (KF-GINS's `isToUpdate` with its tolerance): over random IMU
    /// rates with jittered epochs, random tolerances below half an interval and fixes
    /// on, within the tolerance of and between epochs, each fix is applied at the
    /// nearest IMU epoch when within the tolerance of it, else at its own time; the
    /// odometer (IMU clock) is never moved; forward and backward runs apply every
    /// input at the same time; a zero tolerance is the exact rule.
    #[test]
    fn gnss_inputs_within_the_snap_tolerance_are_applied_at_the_imu_epoch() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(30);
        for trial in 0..300 {
            let dt = 1.0 / rng.random_range(50.0..400.0);
            let mut epochs = vec![100.0];
            for _ in 0..200 {
                let last = *epochs.last().unwrap();
                epochs.push(last + dt * rng.random_range(0.8..1.2));
            }
            let tol = if trial % 4 == 0 {
                0.0
            } else {
                rng.random_range(0.01..0.39) * dt
            };
            let near = |t: f64| {
                let k = epochs.partition_point(|&e| e < t);
                [k.saturating_sub(1), k.min(epochs.len() - 1)]
                    .into_iter()
                    .map(|i| epochs[i])
                    .min_by(|a, b| (a - t).abs().total_cmp(&(b - t).abs()))
                    .unwrap()
            };
            let pick = |rng: &mut rand_pcg::Pcg64| {
                let e = epochs[rng.random_range(2..epochs.len() - 2)];
                match rng.random_range(0..3) {
                    0 => e,
                    1 => e + rng.random_range(-0.999..0.999) * tol,
                    _ => e + rng.random_range(-0.5..0.5) * dt,
                }
            };
            let mut tg: Vec<f64> = (0..8).map(|_| pick(&mut rng)).collect();
            let mut to: Vec<f64> = (0..8).map(|_| pick(&mut rng)).collect();
            tg.sort_by(f64::total_cmp);
            to.sort_by(f64::total_cmp);
            tg.dedup();
            to.dedup();
            let g: Vec<_> = tg.iter().map(|&t| fix(t)).collect();
            let o: Vec<_> = to.iter().map(|&t| odo(t)).collect();
            let meas = crate::types::merge_measurements(&g, &o, &[]);
            let fwd = applied_at(&meas, &epochs, tol, false);
            assert_eq!(fwd.len(), meas.len(), "trial {trial}");
            for &(i, t_applied) in &fwd {
                let t = meas[i].t();
                let e = near(t);
                let want = if meas[i].on_gnss_clock() && (t - e).abs() <= tol {
                    e
                } else {
                    t
                };
                assert!(
                    (t_applied - want).abs() <= 2.0 * SNAP_S,
                    "trial {trial}: input at {t} (gnss {}) applied at {t_applied}, want {want} (tol {tol})",
                    meas[i].on_gnss_clock()
                );
            }
            // Applied in time order (each clock in its own order).
            assert!(fwd.windows(2).all(|w| w[0].1 <= w[1].1 + 2.0 * SNAP_S));
            let mut bwd = applied_at(&meas, &epochs, tol, true);
            let mut f2 = fwd.clone();
            f2.sort_by_key(|x| x.0);
            bwd.sort_by_key(|x| x.0);
            for (a, b) in f2.iter().zip(&bwd) {
                assert_eq!(a.0, b.0);
                assert!(
                    (a.1 - b.1).abs() <= 2.0 * SNAP_S,
                    "trial {trial}: {a:?} {b:?} t {} gnss {} tol {tol} dt {dt}",
                    meas[a.0].t(),
                    meas[a.0].on_gnss_clock()
                );
            }
        }
    }
}
