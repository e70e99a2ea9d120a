//! GNSS outage schedules: explicit windows and periodic "L seconds every P seconds
//! from T". A window (a, b) removes the GNSS epochs with a < t < b, so the last fix
//! before it is at a and the next one at b (the KF-GINS paper's protocol).

/// One outage window (start, end) \[s\]; epochs strictly inside are withheld.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub start: f64,
    pub end: f64,
}

/// Periodic outages: windows \[from + k*period, from + k*period + length\] for k >= 0,
/// with window starts before `until` (if given).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periodic {
    pub length: f64,
    pub period: f64,
    pub from: f64,
    pub until: Option<f64>,
}

/// A set of outage windows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutageSchedule {
    pub windows: Vec<Window>,
    pub periodic: Vec<Periodic>,
}

impl OutageSchedule {
    /// True when a measurement at `t` falls inside an outage.
    pub fn contains(&self, t: f64) -> bool {
        self.windows.iter().any(|w| t > w.start && t < w.end)
            || self.periodic.iter().any(|p| {
                if t <= p.from || p.until.is_some_and(|u| t >= u + p.length) {
                    return false;
                }
                let k = ((t - p.from) / p.period).floor();
                let start = p.from + k * p.period;
                if p.until.is_some_and(|u| start >= u) {
                    return false;
                }
                t > start && t < start + p.length
            })
    }

    /// All windows that start inside \[t0, t1\], periodic ones expanded, sorted.
    pub fn windows_in(&self, t0: f64, t1: f64) -> Vec<Window> {
        let mut out: Vec<Window> = self
            .windows
            .iter()
            .filter(|w| w.end > t0 && w.start < t1)
            .copied()
            .collect();
        for p in &self.periodic {
            if p.period <= 0.0 {
                continue;
            }
            let mut k = 0.0;
            loop {
                let start = p.from + k * p.period;
                if start >= t1 || p.until.is_some_and(|u| start >= u) {
                    break;
                }
                if start + p.length > t0 {
                    out.push(Window {
                        start,
                        end: start + p.length,
                    });
                }
                k += 1.0;
            }
        }
        out.sort_by(|a, b| a.start.total_cmp(&b.start));
        out
    }

    pub fn is_empty(&self) -> bool {
        self.windows.is_empty() && self.periodic.is_empty()
    }

    /// Parse the command-line form: comma-separated items, each `a:b` (a window) or
    /// `L/P@T` (L seconds every P seconds from T) with an optional `..U` (until U).
    pub fn parse(spec: &str) -> Result<Self, String> {
        let mut s = OutageSchedule::default();
        for item in spec.split(',').map(str::trim).filter(|x| !x.is_empty()) {
            let num = |x: &str| -> Result<f64, String> {
                x.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("outage '{item}': '{x}' is not a number"))
            };
            if let Some((lp, rest)) = item.split_once('@') {
                let (l, p) = lp
                    .split_once('/')
                    .ok_or_else(|| format!("outage '{item}': expected L/P@T[..U]"))?;
                let (from, until) = match rest.split_once("..") {
                    Some((f, u)) => (num(f)?, Some(num(u)?)),
                    None => (num(rest)?, None),
                };
                let (length, period) = (num(l)?, num(p)?);
                if length <= 0.0 || period <= length {
                    return Err(format!("outage '{item}': need 0 < L < P"));
                }
                s.periodic.push(Periodic {
                    length,
                    period,
                    from,
                    until,
                });
            } else if let Some((a, b)) = item.split_once(':') {
                let (start, end) = (num(a)?, num(b)?);
                if end <= start {
                    return Err(format!("outage '{item}': end must be after start"));
                }
                s.windows.push(Window { start, end });
            } else {
                return Err(format!("outage '{item}': expected a:b or L/P@T[..U]"));
            }
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_matches_kfgins_protocol() {
        let s = OutageSchedule::parse("60/180@456900..459500").unwrap();
        assert!(!s.contains(456900.0));
        assert!(s.contains(456901.0));
        assert!(!s.contains(456960.0));
        assert!(s.contains(457100.0));
        assert!(!s.contains(459610.0));
        let w = s.windows_in(456300.0, 459662.0);
        assert_eq!(w.len(), 15);
        assert_eq!(w[14].start, 459420.0);
        let open = OutageSchedule::parse("60/180@456900").unwrap();
        assert_eq!(open.windows_in(456300.0, 459662.0).len(), 16);
        assert!(open.contains(459610.0));
    }

    #[test]
    fn windows_and_errors() {
        let s = OutageSchedule::parse("10:20, 30:35").unwrap();
        assert!(s.contains(15.0) && s.contains(31.0) && !s.contains(20.0) && !s.contains(25.0));
        assert!(OutageSchedule::parse("20:10").is_err());
        assert!(OutageSchedule::parse("x:10").is_err());
        assert!(OutageSchedule::parse("60/50@0").is_err());
    }
}
