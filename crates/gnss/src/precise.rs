//! Precise orbits and clocks (IGS SP3 samples, RINEX clock records) and the
//! satellite state they give at any time: positions by Lagrange interpolation of
//! order 10 over the 11 samples around the time, velocity from the derivative of
//! the same polynomial, clocks linearly between the two samples around the time
//! (clocks are not smooth enough for a polynomial). Samples of several files
//! (consecutive days) are one series, so a day boundary is interpolated across
//! like any other time; no extrapolation past the first or last sample, and no
//! window across a gap in the series.

use crate::time::GpsTime;
use nalgebra::Vector3;
use navfuse_core::sat::SatId;
use std::collections::BTreeMap;

/// Samples in the interpolation window (order + 1).
pub const LAGRANGE_POINTS: usize = 11;

/// The state precise products give at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreciseState {
    /// Satellite centre of mass (SP3's reference point) in ECEF \[m\].
    pub pos_ecef_m: Vector3<f64>,
    /// The interpolant's derivative, ECEF [m/s].
    pub vel_ecef_mps: Vector3<f64>,
    /// Satellite clock bias \[s\] and drift [s/s], when the clocks cover the time.
    pub clock_bias_s: Option<f64>,
    pub clock_drift_s_per_s: Option<f64>,
}

#[derive(Clone, Debug, Default)]
struct Series {
    /// (t - reference \[s\], position \[m\]), sorted, one per time.
    orbit: Vec<(f64, Vector3<f64>)>,
    /// (t - reference \[s\], clock bias \[s\]), sorted.
    clock: Vec<(f64, f64)>,
}

/// Orbits and clocks of many satellites over one or more files.
#[derive(Clone, Debug)]
pub struct PreciseProducts {
    reference: GpsTime,
    sats: BTreeMap<SatId, Series>,
    /// A window's neighbouring samples may be at most this far apart \[s\].
    max_gap_s: f64,
    /// Two clock samples may be at most this far apart \[s\].
    max_clock_gap_s: f64,
}

impl PreciseProducts {
    /// Empty products with times counted from `reference`; `orbit_interval_s`,
    /// `clock_interval_s`: the nominal sample spacing (a spacing above 1.5 times it
    /// is a gap).
    pub fn new(reference: GpsTime, orbit_interval_s: f64, clock_interval_s: f64) -> Self {
        PreciseProducts {
            reference,
            sats: BTreeMap::new(),
            max_gap_s: 1.5 * orbit_interval_s,
            max_clock_gap_s: 1.5 * clock_interval_s,
        }
    }

    /// Add an orbit sample (and the SP3 clock, when the file gives one).
    pub fn add_orbit(
        &mut self,
        sat: SatId,
        t: GpsTime,
        pos_ecef_m: Vector3<f64>,
        clock_s: Option<f64>,
    ) {
        let dt = t.diff_s(&self.reference);
        let s = self.sats.entry(sat).or_default();
        s.orbit.push((dt, pos_ecef_m));
        if let Some(c) = clock_s {
            s.clock.push((dt, c));
        }
    }

    /// Add a clock sample (a RINEX clock file's `AS` record).
    pub fn add_clock(&mut self, sat: SatId, t: GpsTime, bias_s: f64) {
        let dt = t.diff_s(&self.reference);
        self.sats.entry(sat).or_default().clock.push((dt, bias_s));
    }

    /// Replace the clocks with those of a clock file (finer than SP3's).
    pub fn clear_clocks(&mut self) {
        for s in self.sats.values_mut() {
            s.clock.clear();
        }
    }

    /// Sort the samples and drop repeated times (consecutive daily files share
    /// midnight): call after adding.
    pub fn finish(&mut self) {
        for s in self.sats.values_mut() {
            s.orbit.sort_by(|a, b| a.0.total_cmp(&b.0));
            s.orbit.dedup_by(|b, a| (a.0 - b.0).abs() < 1e-6);
            s.clock.sort_by(|a, b| a.0.total_cmp(&b.0));
            s.clock.dedup_by(|b, a| (a.0 - b.0).abs() < 1e-6);
        }
    }

    pub fn satellites(&self) -> impl Iterator<Item = SatId> + '_ {
        self.sats.keys().copied()
    }

    /// The state of `sat` at `t`; None outside its samples, across a gap, or with
    /// fewer than [`LAGRANGE_POINTS`] samples.
    pub fn state(&self, sat: SatId, t: GpsTime) -> Option<PreciseState> {
        let s = self.sats.get(&sat)?;
        let x = t.diff_s(&self.reference);
        let (pos, vel) = lagrange(&s.orbit, x, self.max_gap_s)?;
        let (clock_bias_s, clock_drift_s_per_s) = match linear(&s.clock, x, self.max_clock_gap_s) {
            Some((c, d)) => (Some(c), Some(d)),
            None => (None, None),
        };
        Some(PreciseState {
            pos_ecef_m: pos,
            vel_ecef_mps: vel,
            clock_bias_s,
            clock_drift_s_per_s,
        })
    }
}

/// Value and derivative at `x` of the Lagrange polynomial through the
/// [`LAGRANGE_POINTS`] samples nearest `x` (the window shifted inward at the ends).
fn lagrange(
    s: &[(f64, Vector3<f64>)],
    x: f64,
    max_gap_s: f64,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let n = LAGRANGE_POINTS;
    if s.len() < n || x < s[0].0 - 1e-9 || x > s[s.len() - 1].0 + 1e-9 {
        return None;
    }
    let i = s.partition_point(|p| p.0 <= x);
    let start = i.saturating_sub(n / 2).min(s.len() - n);
    let w = &s[start..start + n];
    if w.windows(2).any(|p| p[1].0 - p[0].0 > max_gap_s) {
        return None;
    }
    // Abscissae about the window's centre, in units of its span (conditioning).
    let (c, span) = (w[n / 2].0, (w[n - 1].0 - w[0].0).max(1e-9));
    let u: Vec<f64> = w.iter().map(|p| (p.0 - c) / span).collect();
    let ux = (x - c) / span;
    let (mut value, mut slope) = (Vector3::zeros(), Vector3::zeros());
    for j in 0..n {
        // L_j(x) = prod_{m != j} (x - u_m) / (u_j - u_m); L_j'(x) by the product rule.
        let mut l = 1.0;
        let mut dl = 0.0;
        for m in (0..n).filter(|&m| m != j) {
            let den = u[j] - u[m];
            dl = dl * (ux - u[m]) / den + l / den;
            l *= (ux - u[m]) / den;
        }
        value += w[j].1 * l;
        slope += w[j].1 * dl;
    }
    Some((value, slope / span))
}

/// Linear interpolation at `x` between the two samples around it.
fn linear(s: &[(f64, f64)], x: f64, max_gap_s: f64) -> Option<(f64, f64)> {
    let i = s.partition_point(|p| p.0 <= x);
    let (a, b) = match (i.checked_sub(1).and_then(|j| s.get(j)), s.get(i)) {
        (Some(a), Some(b)) => (*a, *b),
        // Exactly on the last sample.
        (Some(a), None) if (x - a.0).abs() < 1e-9 && s.len() >= 2 => (s[s.len() - 2], *a),
        _ => return None,
    };
    let dt = b.0 - a.0;
    if dt <= 0.0 || dt > max_gap_s {
        return None;
    }
    let drift = (b.1 - a.1) / dt;
    Some((a.1 + drift * (x - a.0), drift))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constellation::nominal_gps24;

    /// Broadcast GPS orbits sampled every 900 s over two days, as two daily files
    /// would give them.
    fn sampled(reference: GpsTime) -> (PreciseProducts, Vec<crate::GpsEphemeris>) {
        let ephs = nominal_gps24(reference);
        let mut p = PreciseProducts::new(reference, 900.0, 900.0);
        for day in 0..2 {
            // Each day's file holds 00:00 .. 24:00 (the next midnight repeated).
            for k in 0..=96 {
                let t = reference.add_s(86_400.0 * f64::from(day) + 900.0 * f64::from(k));
                for e in &ephs {
                    let s = e.sat_state(t);
                    p.add_orbit(SatId::gps(e.prn), t, s.pos_ecef_m, Some(s.clock_bias_s));
                }
            }
        }
        p.finish();
        (p, ephs)
    }

    #[test]
    fn interpolated_broadcast_orbits_to_millimetres_across_midnight() {
        let reference = GpsTime::new(2111, 345_600.0);
        let (p, ephs) = sampled(reference);
        let (mut worst_pos, mut worst_vel) = (0.0f64, 0.0f64);
        // The first and last 5 intervals, where the window cannot be centred.
        let mut worst_edge = 0.0f64;
        // Every 97 s over both days, the midnight between them included.
        let mut k = 0.0;
        while k < 2.0 * 86_400.0 {
            let t = reference.add_s(k);
            let edge = !(4_500.0..=2.0 * 86_400.0 - 4_500.0).contains(&k);
            for e in &ephs {
                let truth = e.sat_state(t);
                let s = p.state(SatId::gps(e.prn), t).unwrap();
                let d = (s.pos_ecef_m - truth.pos_ecef_m).norm();
                if edge {
                    worst_edge = worst_edge.max(d);
                    continue;
                }
                worst_pos = worst_pos.max(d);
                worst_vel = worst_vel.max((s.vel_ecef_mps - truth.vel_ecef_mps).norm());
                let c = s.clock_bias_s.unwrap();
                assert!((c - truth.clock_bias_s).abs() < 1e-12, "clock");
            }
            k += 97.0;
        }
        eprintln!(
            "interpolation vs broadcast: {worst_pos:.6} m, {worst_vel:.7} m/s (first/last 5 intervals: {worst_edge:.6} m)"
        );
        assert!(worst_pos < 1e-3, "{worst_pos} m");
        assert!(worst_vel < 1e-5, "{worst_vel} m/s");
        assert!(worst_edge < 5e-3, "{worst_edge} m at the ends");
        // No extrapolation; a gap stops the window.
        let end = reference.add_s(2.0 * 86_400.0 + 1.0);
        assert!(p.state(SatId::gps(1), end).is_none());
        assert!(p.state(SatId::gps(1), reference.add_s(-1.0)).is_none());
        assert!(p.state(SatId::gps(30), reference).is_none());
    }

    #[test]
    fn a_gap_is_not_interpolated_across() {
        let reference = GpsTime::new(2111, 345_600.0);
        let ephs = nominal_gps24(reference);
        let mut p = PreciseProducts::new(reference, 900.0, 900.0);
        for k in (0..60).filter(|k| !(20..24).contains(k)) {
            let t = reference.add_s(900.0 * f64::from(k));
            let s = ephs[0].sat_state(t);
            p.add_orbit(SatId::gps(ephs[0].prn), t, s.pos_ecef_m, None);
        }
        p.finish();
        let sat = SatId::gps(ephs[0].prn);
        assert!(
            p.state(sat, reference.add_s(900.0 * 21.5)).is_none(),
            "in the gap"
        );
        assert!(
            p.state(sat, reference.add_s(900.0 * 18.5)).is_none(),
            "window over the gap"
        );
        let ok = p.state(sat, reference.add_s(900.0 * 40.5)).unwrap();
        assert!(ok.clock_bias_s.is_none());
    }
}
