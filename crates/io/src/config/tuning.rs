//! `[tuning]`: estimate the noise model from the run's own data before the run
//! (input::TuningSpec; `navfuse tune` does the same as a command).

use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use crate::input::TuningSpec;

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TTuning {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) enabled: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) iterations: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) from_data: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) fix_error_model: Option<bool>,
}

pub(super) fn convert(t: &TTuning) -> KResult<TuningSpec> {
    let d = TuningSpec::default();
    let iterations = match t.iterations {
        Some(n) if !(1..=100).contains(&n) => {
            return Err(kerr(
                "tuning.iterations",
                format!("expected a number of passes from 1 to 100, got {n}"),
            ))
        }
        Some(n) => n as usize,
        None => d.iterations,
    };
    Ok(TuningSpec {
        // A [tuning] section without `enabled` means: tune.
        enabled: t.enabled.unwrap_or(true),
        iterations,
        from_data: t.from_data.unwrap_or(d.from_data),
        fix_error_model: t.fix_error_model.unwrap_or(d.fix_error_model),
    })
}

pub(super) fn to_toml(s: &TuningSpec) -> Option<TTuning> {
    (*s != TuningSpec::default()).then_some(TTuning {
        enabled: Some(s.enabled),
        iterations: Some(s.iterations as i64),
        from_data: Some(s.from_data),
        fix_error_model: Some(s.fix_error_model),
    })
}
