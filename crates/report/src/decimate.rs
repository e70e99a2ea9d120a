//! Fewer points for plotting, keeping what the eye must see.
//!
//! - [`min_max`]: time series. The x range is cut into `buckets` equal intervals;
//!   each keeps its first, lowest, highest and last point, in time order. Peaks and
//!   jumps survive (a spike one sample wide is still drawn), and a chart of any
//!   length has at most 4 x `buckets` points.
//! - [`by_distance`]: tracks. A point is kept when it is at least `step` from the
//!   last kept one (and the last point always).

/// Min/max decimation of `pts` (sorted by x) into at most 4 x `buckets` points.
pub fn min_max(pts: &[(f64, f64)], buckets: usize) -> Vec<(f64, f64)> {
    let finite: Vec<(f64, f64)> = pts
        .iter()
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if finite.len() <= 4 * buckets.max(1) {
        return finite;
    }
    let (x0, x1) = (finite[0].0, finite[finite.len() - 1].0);
    let width = (x1 - x0) / buckets as f64;
    if width.is_nan() || width <= 0.0 {
        return finite;
    }
    let mut out = Vec::with_capacity(4 * buckets);
    let mut i = 0;
    while i < finite.len() {
        let b = (((finite[i].0 - x0) / width) as usize).min(buckets - 1);
        let start = i;
        let (mut lo, mut hi) = (i, i);
        while i < finite.len() && (((finite[i].0 - x0) / width) as usize).min(buckets - 1) == b {
            if finite[i].1 < finite[lo].1 {
                lo = i;
            }
            if finite[i].1 > finite[hi].1 {
                hi = i;
            }
            i += 1;
        }
        let mut keep = [start, lo, hi, i - 1];
        keep.sort_unstable();
        let mut last = usize::MAX;
        for k in keep {
            if k != last {
                out.push(finite[k]);
                last = k;
            }
        }
    }
    out
}

/// Keep points at least `step` apart along the track (Euclidean in the plane).
pub fn by_distance(pts: &[(f64, f64)], step: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for &p in pts.iter().filter(|(x, y)| x.is_finite() && y.is_finite()) {
        match out.last() {
            Some(q) if (p.0 - q.0).hypot(p.1 - q.1) < step => {}
            _ => out.push(p),
        }
    }
    if let Some(&last) = pts
        .iter()
        .rev()
        .find(|(x, y)| x.is_finite() && y.is_finite())
    {
        if out.last() != Some(&last) {
            out.push(last);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_max_keeps_a_one_sample_spike_and_the_ends() {
        let mut pts: Vec<(f64, f64)> = (0..100_000).map(|i| (f64::from(i) * 0.005, 0.0)).collect();
        pts[54_321].1 = 7.0;
        pts[77_777].1 = -3.0;
        let d = min_max(&pts, 500);
        assert!(d.len() <= 2000, "{}", d.len());
        assert!(d.contains(&pts[54_321]) && d.contains(&pts[77_777]));
        assert_eq!(d.first(), pts.first());
        assert_eq!(d.last(), pts.last());
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0), "time order");
    }

    #[test]
    fn by_distance_thins_a_track() {
        let pts: Vec<(f64, f64)> = (0..10_001).map(|i| (f64::from(i) * 0.01, 0.0)).collect();
        let d = by_distance(&pts, 1.0);
        assert_eq!(d.len(), 101);
        assert_eq!(d.last(), Some(&(100.0, 0.0)));
    }
}
