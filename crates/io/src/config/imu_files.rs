//! `[imu] files = { time = ..., gyro = ..., accel = ... }`: an IMU in several CSV
//! files (input::CsvImuFiles, imu/join.rs). `[imu.csv]` gives the columns, each in
//! its own file (time_col in the time file, gyro_cols in the gyro file, accel_cols
//! in the accelerometer file), and the units.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::imu_csv::{self, TCsv};
use super::paths::{file_key, PathWriter};
use super::validate::positive;
use crate::input::{CsvImuFiles, CsvImuPart};

/// Default largest time difference of rows joined on time \[s\].
pub const DEFAULT_JOIN_TOLERANCE_S: f64 = 1e-6;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TImuFiles {
    pub(super) time: String,
    pub(super) gyro: String,
    pub(super) accel: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_time_col: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_time_col: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) tolerance_s: Option<f64>,
}

pub(super) fn convert(f: &TImuFiles, c: &TCsv, base: &Path) -> KResult<CsvImuFiles> {
    let csv = imu_csv::convert_units(c)?;
    let part = |key: &str, file: &str, time_col: Option<usize>, cols: [usize; 3]| {
        if let Some(t) = time_col.filter(|t| cols.contains(t)) {
            return Err(kerr(
                key,
                format!("time column {t} is also a data column of that file"),
            ));
        }
        Ok(CsvImuPart {
            path: file_key(base, key, file)?,
            time_col,
            cols,
        })
    };
    Ok(CsvImuFiles {
        time_path: file_key(base, "imu.files.time", &f.time)?,
        time_col: csv.time_col,
        gyro: part("imu.files.gyro", &f.gyro, f.gyro_time_col, csv.gyro_cols)?,
        accel: part(
            "imu.files.accel",
            &f.accel,
            f.accel_time_col,
            csv.accel_cols,
        )?,
        skip_lines: c.skip_lines,
        tolerance_s: positive(
            "imu.files.tolerance_s",
            f.tolerance_s.unwrap_or(DEFAULT_JOIN_TOLERANCE_S),
        )?,
        csv,
    })
}

pub(super) fn to_toml(f: &CsvImuFiles, w: &PathWriter) -> (TImuFiles, TCsv) {
    let mut c = imu_csv::to_toml(&f.csv);
    c.skip_lines = f.skip_lines;
    (
        TImuFiles {
            time: w.path(&f.time_path),
            gyro: w.path(&f.gyro.path),
            accel: w.path(&f.accel.path),
            gyro_time_col: f.gyro.time_col,
            accel_time_col: f.accel.time_col,
            tolerance_s: Some(f.tolerance_s),
        },
        c,
    )
}
