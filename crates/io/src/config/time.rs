//! `[time]`: the processing interval (NavConfig::start_time / end_time).

use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::validate::finite;

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TTime {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) start: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) end: Option<f64>,
}

impl TTime {
    pub(super) fn is_empty(&self) -> bool {
        self.start.is_none() && self.end.is_none()
    }
}

/// (start, end) [s]; None = the first / last IMU epoch.
pub(super) fn convert(t: &TTime) -> KResult<(Option<f64>, Option<f64>)> {
    let start = t.start.map(|t| finite("time.start", t)).transpose()?;
    let end = t.end.map(|t| finite("time.end", t)).transpose()?;
    if let (Some(s), Some(e)) = (start, end) {
        if e <= s {
            return Err(kerr(
                "time.end",
                format!("expected a time after time.start = {s}, got {e}"),
            ));
        }
    }
    Ok((start, end))
}

/// `start_time` is `f64::NEG_INFINITY` when no start is given.
pub(super) fn to_toml(start_time: f64, end_time: Option<f64>) -> TTime {
    TTime {
        start: start_time.is_finite().then_some(start_time),
        end: end_time,
    }
}
