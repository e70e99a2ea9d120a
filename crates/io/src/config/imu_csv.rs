//! `[imu.csv]`: the column layout and units of a CSV IMU file
//! (input::CsvImuOptions).

use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use crate::input::{
    AccelUnit, CsvImuOptions, GyroUnit, ImuQuantity, RateSampling, TimeScale, TimeUnit,
};

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TCsv {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) skip_lines: Option<usize>,
    pub(super) time_col: usize,
    pub(super) gyro_cols: Vec<usize>,
    pub(super) accel_cols: Vec<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_unit: Option<TimeUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_scale: Option<TimeScale>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) quantity: Option<ImuQuantity>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) rate_sampling: Option<RateSampling>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_unit: Option<GyroUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_unit: Option<AccelUnit>,
}

pub(super) fn cols3(key: &str, v: &[usize]) -> KResult<[usize; 3]> {
    if v.len() != 3 {
        return Err(kerr(
            key,
            format!(
                "expected an array of 3 column numbers (0-based), got {} element(s)",
                v.len()
            ),
        ));
    }
    Ok([v[0], v[1], v[2]])
}

pub(super) fn convert(c: &TCsv) -> KResult<CsvImuOptions> {
    let o = convert_units(c)?;
    let (gyro_cols, accel_cols) = (o.gyro_cols, o.accel_cols);
    let mut all = vec![("imu.csv.time_col", c.time_col)];
    all.extend(gyro_cols.iter().map(|&x| ("imu.csv.gyro_cols", x)));
    all.extend(accel_cols.iter().map(|&x| ("imu.csv.accel_cols", x)));
    for (k, (key, col)) in all.iter().enumerate() {
        if let Some((other, _)) = all[..k].iter().find(|(_, c2)| c2 == col) {
            return Err(kerr(
                key,
                format!("column {col} is also used by {other}: expected distinct columns"),
            ));
        }
    }
    Ok(o)
}

/// `[imu.csv]` without the check that the columns are distinct (several files).
pub(super) fn convert_units(c: &TCsv) -> KResult<CsvImuOptions> {
    let gyro_cols = cols3("imu.csv.gyro_cols", &c.gyro_cols)?;
    let accel_cols = cols3("imu.csv.accel_cols", &c.accel_cols)?;
    let d = CsvImuOptions::default();
    Ok(CsvImuOptions {
        skip_lines: c.skip_lines.unwrap_or(d.skip_lines),
        time_col: c.time_col,
        gyro_cols,
        accel_cols,
        time_unit: c.time_unit.unwrap_or(d.time_unit),
        time_scale: c.time_scale.unwrap_or(d.time_scale),
        quantity: c.quantity.unwrap_or(d.quantity),
        rate_sampling: c.rate_sampling.unwrap_or(d.rate_sampling),
        gyro_unit: c.gyro_unit.unwrap_or(d.gyro_unit),
        accel_unit: c.accel_unit.unwrap_or(d.accel_unit),
    })
}

pub(super) fn to_toml(o: &CsvImuOptions) -> TCsv {
    TCsv {
        skip_lines: Some(o.skip_lines),
        time_col: o.time_col,
        gyro_cols: o.gyro_cols.to_vec(),
        accel_cols: o.accel_cols.to_vec(),
        time_unit: Some(o.time_unit),
        time_scale: Some(o.time_scale),
        quantity: Some(o.quantity),
        rate_sampling: Some(o.rate_sampling),
        gyro_unit: Some(o.gyro_unit),
        accel_unit: Some(o.accel_unit),
    }
}
