//! `gnss.outages` and `gnss.outage_every`: withheld GNSS epochs, as windows and as
//! periodic outages (core::outage::OutageSchedule), the latter possibly relative to
//! the run start ([`RelativeOutage`]).

use navfuse_core::outage::{OutageSchedule, Periodic, Window};
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::validate::{finite, non_negative, positive};
use super::values::OneOrMany;
use super::RelativeOutage;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TOutageEvery {
    pub(super) length_s: f64,
    pub(super) period_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) from: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) from_start_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) until: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) until_start_s: Option<f64>,
}

/// The schedule, and the periodic outages still relative to the run start (none
/// when `start`, `[time] start`, is known).
pub(super) fn convert(
    windows: Option<&Vec<Vec<f64>>>,
    every: Option<&OneOrMany<TOutageEvery>>,
    start: Option<f64>,
) -> KResult<(OutageSchedule, Vec<RelativeOutage>)> {
    let mut outages = OutageSchedule::default();
    for (k, w) in windows.into_iter().flatten().enumerate() {
        let key = format!("gnss.outages[{k}]");
        if w.len() != 2 {
            return Err(kerr(
                &key,
                format!(
                    "expected a [start, end] pair of times [s], got {} element(s)",
                    w.len()
                ),
            ));
        }
        let (a, b) = (finite(&key, w[0])?, finite(&key, w[1])?);
        if b <= a {
            return Err(kerr(&key, format!("expected end > start, got [{a}, {b}]")));
        }
        outages.windows.push(Window { start: a, end: b });
    }
    let mut relative = Vec::new();
    let every = every.map(|o| o.0.as_slice()).unwrap_or(&[]);
    for (k, p) in every.iter().enumerate() {
        let key = if every.len() == 1 {
            "gnss.outage_every".to_string()
        } else {
            format!("gnss.outage_every[{k}]")
        };
        let sub = |s: &str| format!("{key}.{s}");
        let length_s = positive(&sub("length_s"), p.length_s)?;
        let period_s = positive(&sub("period_s"), p.period_s)?;
        if period_s <= length_s {
            return Err(kerr(
                &sub("period_s"),
                format!("expected a period > length_s = {length_s}, got {period_s}"),
            ));
        }
        let until = p.until.map(|u| finite(&sub("until"), u)).transpose()?;
        let until_start_s = p
            .until_start_s
            .map(|u| finite(&sub("until_start_s"), u))
            .transpose()?;
        if until.is_some() && until_start_s.is_some() {
            return Err(kerr(
                &sub("until_start_s"),
                "give either until or until_start_s, not both",
            ));
        }
        match (p.from, p.from_start_s) {
            (Some(from), None) => {
                let from = finite(&sub("from"), from)?;
                if until_start_s.is_some() {
                    return Err(kerr(
                        &sub("until_start_s"),
                        "until_start_s needs from_start_s; with an absolute from use until",
                    ));
                }
                if let Some(u) = until {
                    if u <= from {
                        return Err(kerr(
                            &sub("until"),
                            format!("expected a time after from = {from}, got {u}"),
                        ));
                    }
                }
                outages.periodic.push(Periodic {
                    length: length_s,
                    period: period_s,
                    from,
                    until,
                });
            }
            (None, Some(rel)) => {
                let rel = non_negative(&sub("from_start_s"), rel)?;
                if let Some(u) = until_start_s {
                    if u <= rel {
                        return Err(kerr(
                            &sub("until_start_s"),
                            format!("expected a value > from_start_s = {rel}, got {u}"),
                        ));
                    }
                }
                let r = RelativeOutage {
                    length_s,
                    period_s,
                    from_start_s: rel,
                    until,
                    until_start_s,
                };
                match start {
                    Some(s) => outages.periodic.push(r.resolve(s)),
                    None => relative.push(r),
                }
            }
            (Some(_), Some(_)) => {
                return Err(kerr(
                    &sub("from_start_s"),
                    "give either from or from_start_s, not both",
                ))
            }
            (None, None) => return Err(kerr(
                &key,
                "expected from (absolute time [s]) or from_start_s (seconds after the run start)",
            )),
        }
    }
    Ok((outages, relative))
}

/// `gnss.outages`, `gnss.outage_every` (None when empty).
pub(super) fn to_toml(
    o: &OutageSchedule,
    relative: &[RelativeOutage],
) -> (Option<Vec<Vec<f64>>>, Option<OneOrMany<TOutageEvery>>) {
    let mut every: Vec<TOutageEvery> = o
        .periodic
        .iter()
        .map(|p| TOutageEvery {
            length_s: p.length,
            period_s: p.period,
            from: Some(p.from),
            from_start_s: None,
            until: p.until,
            until_start_s: None,
        })
        .collect();
    every.extend(relative.iter().map(|r| TOutageEvery {
        length_s: r.length_s,
        period_s: r.period_s,
        from: None,
        from_start_s: Some(r.from_start_s),
        until: r.until,
        until_start_s: r.until_start_s,
    }));
    let windows =
        (!o.windows.is_empty()).then(|| o.windows.iter().map(|w| vec![w.start, w.end]).collect());
    (windows, (!every.is_empty()).then_some(OneOrMany(every)))
}
