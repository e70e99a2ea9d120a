//! Stopping a run from outside: a [`StopFlag`] the pipeline polls at every IMU sample
//! before the first output epoch and at every output epoch after it, and the
//! [`Interrupted`] error it then ends with (every output file at the same epoch).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// A shared request to stop a run: 0 while it may go on, otherwise the signal number
/// that asked it to stop ([`StopFlag::REQUEST`] for a request that is not a signal).
/// The CLI hands [`StopFlag::atomic`] to `signal_hook::flag::register_usize`.
#[derive(Clone, Debug, Default)]
pub struct StopFlag(Arc<AtomicUsize>);

impl StopFlag {
    /// The value [`StopFlag::request`] stores (not a signal number).
    pub const REQUEST: usize = usize::MAX;

    pub fn new() -> Self {
        Self::default()
    }

    /// The shared value (0: go on; a signal number, or [`StopFlag::REQUEST`]: stop).
    pub fn atomic(&self) -> &Arc<AtomicUsize> {
        &self.0
    }

    /// Ask the run to stop (from another thread), not on a signal.
    pub fn request(&self) {
        self.0.store(Self::REQUEST, Ordering::SeqCst);
    }

    /// Whether a stop was asked for: `Some(None)` on [`StopFlag::request`],
    /// `Some(Some(signal))` on a signal.
    pub fn requested(&self) -> Option<Option<i32>> {
        match self.0.load(Ordering::SeqCst) {
            0 => None,
            Self::REQUEST => Some(None),
            s => Some(Some(s as i32)),
        }
    }

    /// The [`Interrupted`] error once a stop was asked for, `r` otherwise.
    pub(crate) fn check<T, E: From<Interrupted>>(&self, r: Result<T, E>) -> Result<T, E> {
        match self.requested() {
            Some(signal) => Err(Interrupted { signal, t: None }.into()),
            None => r,
        }
    }
}

/// The run was stopped by its [`StopFlag`]; the outputs hold every epoch up to `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interrupted {
    /// The signal that asked for the stop (SIGINT, SIGTERM), None for a plain request.
    pub signal: Option<i32>,
    /// The last output epoch written (GNSS time scale), None before the first.
    pub t: Option<f64>,
}

impl Interrupted {
    /// Exit status: 128 + signal (130 for SIGINT, 143 for SIGTERM); 1 without a signal.
    pub fn exit_status(&self) -> u8 {
        self.signal.map_or(1, |s| (128 + s).clamp(0, 255) as u8)
    }
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = match self.signal {
            Some(2) => "SIGINT".to_string(),
            Some(15) => "SIGTERM".to_string(),
            Some(s) => format!("signal {s}"),
            None => "request".to_string(),
        };
        match self.t {
            Some(t) => write!(
                f,
                "interrupted by {name}: every output file holds the epochs up to t = {t:.3}; summary.json is marked \"interrupted\""
            ),
            None => write!(
                f,
                "interrupted by {name} before the first output epoch; summary.json is marked \"interrupted\""
            ),
        }
    }
}

impl std::error::Error for Interrupted {}
