//! How the monitor reacted: its transitions, scored against an attack window.

use navfuse_core::integrity::{IntegrityState, Transition};
use navfuse_core::Event;

/// The monitor's transitions of a run.
pub(super) fn transitions(events: &[Event]) -> Vec<Transition> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Integrity(tr) => Some(*tr),
            _ => None,
        })
        .collect()
}

/// How the monitor reacted to an attack over [a, b] (absolute times).
#[derive(Clone, Debug, Default)]
pub(super) struct Reaction {
    /// Transitions out of trusted, and entries to spoofed, before a.
    pub(super) alarms_before: usize,
    pub(super) spoofed_before: usize,
    /// Delay from a to the first transition out of trusted in [a, b), its detector;
    /// 0 with "already <state>" when the monitor was not trusted at a.
    pub(super) delay_s: Option<f64>,
    pub(super) detector: Option<String>,
    /// Delay from a to the first entry to spoofed in [a, b).
    pub(super) spoofed_delay_s: Option<f64>,
    /// Returns to trusted in (a, b): the false track accepted again.
    pub(super) readmitted_during: usize,
    /// Time from b to the first return to trusted at or after b (None: never, or the
    /// monitor was trusted anyway).
    pub(super) trusted_after_end_s: Option<f64>,
}

pub(super) fn reaction(trs: &[Transition], a: f64, b: f64) -> Reaction {
    let mut r = Reaction::default();
    let mut state = IntegrityState::Trusted;
    for tr in trs.iter().filter(|tr| tr.t < a) {
        r.alarms_before += usize::from(tr.from == IntegrityState::Trusted);
        r.spoofed_before += usize::from(tr.to == IntegrityState::Spoofed);
        state = tr.to;
    }
    if state != IntegrityState::Trusted {
        r.delay_s = Some(0.0);
        r.detector = Some(format!("already {}", state.name()));
    } else if let Some(tr) = trs
        .iter()
        .find(|tr| tr.t >= a && tr.t < b && tr.from == IntegrityState::Trusted)
    {
        r.delay_s = Some(tr.t - a);
        r.detector = Some(tr.detector.name().to_string());
    }
    r.spoofed_delay_s = trs
        .iter()
        .find(|tr| tr.t >= a && tr.t < b && tr.to == IntegrityState::Spoofed)
        .map(|tr| tr.t - a);
    r.readmitted_during = trs
        .iter()
        .filter(|tr| tr.t > a && tr.t < b && tr.to == IntegrityState::Trusted)
        .count();
    let state_at_b = trs
        .iter()
        .rfind(|tr| tr.t < b)
        .map_or(IntegrityState::Trusted, |tr| tr.to);
    if state_at_b != IntegrityState::Trusted {
        r.trusted_after_end_s = trs
            .iter()
            .find(|tr| tr.t >= b && tr.to == IntegrityState::Trusted)
            .map(|tr| tr.t - b);
    }
    r
}

pub(super) fn nan_or(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

pub(super) fn transition_rows(
    trs: &[Transition],
    t0: f64,
) -> Vec<(f64, String, String, String, f64, f64)> {
    trs.iter()
        .map(|tr| {
            (
                tr.t - t0,
                tr.from.name().to_string(),
                tr.to.name().to_string(),
                tr.detector.name().to_string(),
                tr.statistic,
                tr.threshold,
            )
        })
        .collect()
}
