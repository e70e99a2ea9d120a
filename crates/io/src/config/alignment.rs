//! `[initial.alignment]`: how the initial attitude is found from the data
//! (core::config::AttitudeInit other than `Given`).

use navfuse_core::config::{AttitudeInit, DEFAULT_ALIGN_MIN_SPEED_MPS, DEFAULT_LEVEL_WINDOW_S};
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};

/// `initial.alignment.mode`. A raw type: `AttitudeInit`'s variants carry the
/// windows and speeds of other keys.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub(super) enum TAlignMode {
    #[serde(rename = "level_and_course")]
    LevelAndCourse,
    #[serde(rename = "static_gyrocompass")]
    StaticGyrocompass,
    #[serde(rename = "in_motion")]
    InMotion,
    #[serde(rename = "auto")]
    Auto,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TAlignment {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) mode: Option<TAlignMode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) level_window_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) min_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyrocompass: Option<bool>,
}

pub(super) fn convert(al: &TAlignment) -> KResult<AttitudeInit> {
    let mode = al.mode.unwrap_or(TAlignMode::LevelAndCourse);
    let mode_name = match mode {
        TAlignMode::LevelAndCourse => "level_and_course",
        TAlignMode::StaticGyrocompass => "static_gyrocompass",
        TAlignMode::InMotion => "in_motion",
        TAlignMode::Auto => "auto",
    };
    if mode == TAlignMode::InMotion && al.level_window_s.is_some() {
        return Err(kerr(
            "initial.alignment.level_window_s",
            "does not apply to mode = \"in_motion\" (no static levelling window)",
        ));
    }
    if mode == TAlignMode::StaticGyrocompass && al.min_speed_mps.is_some() {
        return Err(kerr(
            "initial.alignment.min_speed_mps",
            "does not apply to mode = \"static_gyrocompass\" (the yaw does not come from a GNSS course)",
        ));
    }
    if mode != TAlignMode::Auto && al.gyrocompass.is_some() {
        return Err(kerr(
            "initial.alignment.gyrocompass",
            format!("applies only to mode = \"auto\", not \"{mode_name}\""),
        ));
    }
    let level_window_s = al.level_window_s.unwrap_or(DEFAULT_LEVEL_WINDOW_S);
    let min_speed_mps = al.min_speed_mps.unwrap_or(DEFAULT_ALIGN_MIN_SPEED_MPS);
    if !(level_window_s > 0.0 && level_window_s.is_finite()) {
        return Err(kerr(
            "initial.alignment.level_window_s",
            format!("must be > 0 s, got {level_window_s}"),
        ));
    }
    if !(min_speed_mps > 0.0 && min_speed_mps.is_finite()) {
        return Err(kerr(
            "initial.alignment.min_speed_mps",
            format!("must be > 0 m/s, got {min_speed_mps}"),
        ));
    }
    Ok(match mode {
        TAlignMode::LevelAndCourse => AttitudeInit::LevelAndGnssCourse {
            level_window_s,
            min_speed_mps,
        },
        TAlignMode::StaticGyrocompass => AttitudeInit::StaticGyrocompass { level_window_s },
        TAlignMode::InMotion => AttitudeInit::InMotion { min_speed_mps },
        TAlignMode::Auto => AttitudeInit::Auto {
            level_window_s,
            min_speed_mps,
            gyrocompass: al.gyrocompass.unwrap_or(false),
        },
    })
}

/// None for an attitude given in the configuration (`initial.attitude_deg`).
pub(super) fn to_toml(a: &AttitudeInit) -> Option<TAlignment> {
    Some(match *a {
        AttitudeInit::Given(_) => return None,
        AttitudeInit::LevelAndGnssCourse {
            level_window_s,
            min_speed_mps,
        } => TAlignment {
            mode: Some(TAlignMode::LevelAndCourse),
            level_window_s: Some(level_window_s),
            min_speed_mps: Some(min_speed_mps),
            gyrocompass: None,
        },
        AttitudeInit::StaticGyrocompass { level_window_s } => TAlignment {
            mode: Some(TAlignMode::StaticGyrocompass),
            level_window_s: Some(level_window_s),
            min_speed_mps: None,
            gyrocompass: None,
        },
        AttitudeInit::InMotion { min_speed_mps } => TAlignment {
            mode: Some(TAlignMode::InMotion),
            level_window_s: None,
            min_speed_mps: Some(min_speed_mps),
            gyrocompass: None,
        },
        AttitudeInit::Auto {
            level_window_s,
            min_speed_mps,
            gyrocompass,
        } => TAlignment {
            mode: Some(TAlignMode::Auto),
            level_window_s: Some(level_window_s),
            min_speed_mps: Some(min_speed_mps),
            gyrocompass: Some(gyrocompass),
        },
    })
}
