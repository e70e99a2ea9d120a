//! `[imu]`: the IMU input (input::ImuSource), with `[imu.csv]` in imu_csv.rs.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::imu_csv::{self, TCsv};
use super::imu_files::{self, TImuFiles};
use super::paths::{file_key, PathWriter};
use super::validate::{finite, positive, v3};
use crate::input::{GapPolicy, ImuFormat, ImuSource, RtklibExplorerImuOptions};

/// `imu.format`. A raw type: `ImuFormat`'s variants carry `[imu.csv]` and
/// `imu.tag_file`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub(super) enum TImuFormat {
    #[serde(rename = "kf-gins")]
    KfGins,
    #[serde(rename = "csv")]
    Csv,
    #[serde(rename = "rtklibexplorer")]
    RtklibExplorer,
    #[serde(rename = "ulog")]
    Ulog,
    #[serde(rename = "ubx")]
    Ubx,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TImu {
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub(super) file: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) files: Option<TImuFiles>,
    pub(super) format: TImuFormat,
    pub(super) rate_hz: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) sensor_to_body_rpy_deg: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_offset_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) tag_file: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gap_policy: Option<TGapPolicy>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) max_bridge_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) csv: Option<TCsv>,
    /// `imu.format = "ulog"`: the topic instance (multi_id) of sensor_combined.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) ulog_instance: Option<u8>,
}

/// `imu.gap_policy`. A raw type: `GapPolicy::Bridge` carries `imu.max_bridge_s`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub(super) enum TGapPolicy {
    #[serde(rename = "bridge")]
    Bridge,
    #[serde(rename = "nominal")]
    Nominal,
}

pub(super) fn convert(m: &TImu, base: &Path) -> KResult<ImuSource> {
    let path = match &m.files {
        Some(_) if !m.file.is_empty() => {
            return Err(kerr(
                "imu.files",
                "expected imu.file (one file) or imu.files (several), not both",
            ))
        }
        Some(_) if m.format != TImuFormat::Csv => {
            return Err(kerr("imu.files", "applies only to imu.format = \"csv\""))
        }
        Some(f) => file_key(base, "imu.files.time", &f.time)?,
        None => file_key(base, "imu.file", &m.file)?,
    };
    let rate_hz = positive("imu.rate_hz", m.rate_hz)?;
    let sensor_to_body_rpy_deg = match &m.sensor_to_body_rpy_deg {
        Some(v) => v3("imu.sensor_to_body_rpy_deg", v)?,
        None => [0.0; 3],
    };
    let time_offset_s = finite("imu.time_offset_s", m.time_offset_s.unwrap_or(0.0))?;
    let max_bridge_s = m
        .max_bridge_s
        .map(|x| positive("imu.max_bridge_s", x))
        .transpose()?;
    let gap_policy = match m.gap_policy.unwrap_or(TGapPolicy::Bridge) {
        TGapPolicy::Bridge => GapPolicy::Bridge {
            max_s: max_bridge_s,
        },
        TGapPolicy::Nominal if max_bridge_s.is_some() => {
            return Err(kerr(
                "imu.max_bridge_s",
                "applies only to imu.gap_policy = \"bridge\"",
            ))
        }
        TGapPolicy::Nominal => GapPolicy::Nominal,
    };
    if m.format != TImuFormat::Csv && m.csv.is_some() {
        return Err(kerr(
            "imu.csv",
            "[imu.csv] applies only to imu.format = \"csv\"",
        ));
    }
    if m.format != TImuFormat::RtklibExplorer && m.tag_file.is_some() {
        return Err(kerr(
            "imu.tag_file",
            "applies only to imu.format = \"rtklibexplorer\"",
        ));
    }
    if m.format != TImuFormat::Ulog && m.ulog_instance.is_some() {
        return Err(kerr(
            "imu.ulog_instance",
            "applies only to imu.format = \"ulog\"",
        ));
    }
    let format = match m.format {
        TImuFormat::KfGins => ImuFormat::KfGins,
        TImuFormat::Ubx => ImuFormat::Ubx,
        TImuFormat::Ulog => ImuFormat::Ulog {
            multi_id: m.ulog_instance.unwrap_or(0),
        },
        TImuFormat::Csv => {
            let c = m.csv.as_ref().ok_or_else(|| {
                kerr(
                    "imu.csv",
                    "an [imu.csv] table (time_col, gyro_cols, accel_cols, ...) is required when \
                     imu.format = \"csv\"",
                )
            })?;
            match &m.files {
                Some(f) => ImuFormat::CsvFiles(Box::new(imu_files::convert(f, c, base)?)),
                None => ImuFormat::Csv(imu_csv::convert(c)?),
            }
        }
        TImuFormat::RtklibExplorer => {
            let tag_path = match &m.tag_file {
                Some(t) => file_key(base, "imu.tag_file", t)?,
                None => {
                    let mut s = path.clone().into_os_string();
                    s.push(".tag");
                    PathBuf::from(s)
                }
            };
            ImuFormat::RtklibExplorer(RtklibExplorerImuOptions { tag_path })
        }
    };
    Ok(ImuSource {
        path,
        format,
        rate_hz,
        sensor_to_body_rpy_deg,
        time_offset_s,
        gap_policy,
    })
}

pub(super) fn to_toml(m: &ImuSource, w: &PathWriter) -> TImu {
    let mut files = None;
    let (format, tag_file, csv) = match &m.format {
        ImuFormat::CsvFiles(f) => {
            let (fl, c) = imu_files::to_toml(f, w);
            files = Some(fl);
            (TImuFormat::Csv, None, Some(c))
        }
        ImuFormat::KfGins => (TImuFormat::KfGins, None, None),
        ImuFormat::Ulog { .. } => (TImuFormat::Ulog, None, None),
        ImuFormat::Ubx => (TImuFormat::Ubx, None, None),
        ImuFormat::RtklibExplorer(o) => {
            (TImuFormat::RtklibExplorer, Some(w.path(&o.tag_path)), None)
        }
        ImuFormat::Csv(o) => (TImuFormat::Csv, None, Some(imu_csv::to_toml(o))),
    };
    TImu {
        file: if files.is_some() {
            String::new()
        } else {
            w.path(&m.path)
        },
        files,
        format,
        rate_hz: m.rate_hz,
        sensor_to_body_rpy_deg: Some(m.sensor_to_body_rpy_deg.to_vec()),
        time_offset_s: Some(m.time_offset_s),
        tag_file,
        gap_policy: Some(match m.gap_policy {
            GapPolicy::Bridge { .. } => TGapPolicy::Bridge,
            GapPolicy::Nominal => TGapPolicy::Nominal,
        }),
        max_bridge_s: match m.gap_policy {
            GapPolicy::Bridge { max_s } => max_s,
            GapPolicy::Nominal => None,
        },
        csv,
        ulog_instance: match m.format {
            ImuFormat::Ulog { multi_id } => Some(multi_id),
            _ => None,
        },
    }
}
