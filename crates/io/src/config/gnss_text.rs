//! `[gnss] format = "nmea"` (`gnss.date`) and `format = "csv"` (`[gnss.csv]`): the
//! options of the NMEA and CSV GNSS readers (nmea.rs, gnss_csv.rs). Both take
//! `gnss.position_std_m` (and CSV `gnss.velocity_std_mps`) as the reader's fallback
//! for epochs without std (GST, std columns), not as an override of every fix.

use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::imu_csv::cols3;
use crate::gnss_csv::{AngleUnit, CsvGnssOptions, CsvPosition, CsvTimeScale, LengthUnit};
use crate::input::TimeUnit;
use crate::nmea::NmeaOptions;

/// `[gnss.csv]` as written.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TGnssCsv {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) skip_lines: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) delimiter: Option<String>,
    pub(super) time_col: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) week_col: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_scale: Option<CsvTimeScale>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) time_unit: Option<TimeUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) lla_cols: Option<Vec<usize>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) ecef_cols: Option<Vec<usize>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) angle_unit: Option<AngleUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) height_unit: Option<LengthUnit>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) vel_cols: Option<Vec<usize>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) pos_std_cols: Option<Vec<usize>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) vel_std_cols: Option<Vec<usize>>,
}

fn opt3(key: &str, v: &Option<Vec<usize>>) -> KResult<Option<[usize; 3]>> {
    v.as_deref().map(|v| cols3(key, v)).transpose()
}

/// `gnss.date = "YYYY-MM-DD"` (`key`: also `heading.date`).
pub(super) fn nmea(
    key: &str,
    date: Option<&str>,
    position_std_m: Option<[f64; 3]>,
) -> KResult<NmeaOptions> {
    let date = date
        .map(|d| {
            let bad = || {
                kerr(
                    key,
                    format!("expected a UTC date \"YYYY-MM-DD\", got {d:?}"),
                )
            };
            let mut p = d.split('-');
            let (Some(y), Some(m), Some(dd), None) = (p.next(), p.next(), p.next(), p.next())
            else {
                return Err(bad());
            };
            let (Ok(y), Ok(m), Ok(dd)) = (y.parse::<i64>(), m.parse::<u32>(), dd.parse::<u32>())
            else {
                return Err(bad());
            };
            if !(1980..=9999).contains(&y)
                || !(1..=12).contains(&m)
                || dd == 0
                || dd > crate::time::days_in_month(y, m)
            {
                return Err(bad());
            }
            Ok((y, m, dd))
        })
        .transpose()?;
    Ok(NmeaOptions {
        date,
        position_std_m,
    })
}

pub(super) fn nmea_date_to_toml(o: &NmeaOptions) -> Option<String> {
    o.date.map(|(y, m, d)| format!("{y:04}-{m:02}-{d:02}"))
}

pub(super) fn csv(
    c: &TGnssCsv,
    position_std_m: Option<[f64; 3]>,
    velocity_std_mps: Option<[f64; 3]>,
) -> KResult<CsvGnssOptions> {
    let position = match (&c.lla_cols, &c.ecef_cols) {
        (Some(l), None) => CsvPosition::Lla(cols3("gnss.csv.lla_cols", l)?),
        (None, Some(e)) => CsvPosition::Ecef(cols3("gnss.csv.ecef_cols", e)?),
        _ => {
            return Err(kerr(
                "gnss.csv.lla_cols",
                "expected exactly one of gnss.csv.lla_cols (lat, lon, height) and gnss.csv.ecef_cols (x, y, z)",
            ))
        }
    };
    let delimiter = match c.delimiter.as_deref() {
        None | Some("auto") => None,
        Some("\\t") | Some("tab") => Some(b'\t'),
        Some(d)
            if d.len() == 1
                && d.is_ascii()
                && !d.bytes().any(|b| b.is_ascii_alphanumeric() || b".-+#%\"".contains(&b)) =>
        {
            d.bytes().next()
        }
        Some(d) => {
            return Err(kerr(
                "gnss.csv.delimiter",
                format!(
                "expected one ASCII character that cannot be part of a number or a comment (\",\", \";\", \"|\", \" \", \"\\t\", ...) or \"auto\", got {d:?}"
            ),
            ))
        }
    };
    let mut o = CsvGnssOptions::lla(c.time_col, [0, 0, 0]);
    o.position = position;
    o.skip_lines = c.skip_lines;
    o.delimiter = delimiter;
    o.week_col = c.week_col;
    o.time_scale = c.time_scale.unwrap_or(CsvTimeScale::GpsSow);
    if o.week_col.is_some() && o.time_scale != CsvTimeScale::GpsSow {
        return Err(kerr(
            "gnss.csv.week_col",
            "applies only to gnss.csv.time_scale = \"gps_sow\"",
        ));
    }
    o.time_unit = c.time_unit.unwrap_or(TimeUnit::Seconds);
    o.angle_unit = c.angle_unit.unwrap_or(AngleUnit::Deg);
    o.height_unit = c.height_unit.unwrap_or(LengthUnit::Metre);
    o.vel_cols = opt3("gnss.csv.vel_cols", &c.vel_cols)?;
    o.pos_std_cols = opt3("gnss.csv.pos_std_cols", &c.pos_std_cols)?;
    o.vel_std_cols = opt3("gnss.csv.vel_std_cols", &c.vel_std_cols)?;
    o.position_std_m = position_std_m;
    o.velocity_std_mps = velocity_std_mps;
    if o.pos_std_cols.is_none() && o.position_std_m.is_none() {
        return Err(kerr(
            "gnss.csv.pos_std_cols",
            "missing: declare the position std columns or set gnss.position_std_m",
        ));
    }
    if o.vel_cols.is_some() && o.vel_std_cols.is_none() && o.velocity_std_mps.is_none() {
        return Err(kerr(
            "gnss.csv.vel_std_cols",
            "missing: declare the velocity std columns or set gnss.velocity_std_mps",
        ));
    }
    o.check_columns().map_err(|m| kerr("gnss.csv", m))?;
    Ok(o)
}

pub(super) fn csv_to_toml(o: &CsvGnssOptions) -> TGnssCsv {
    let (lla_cols, ecef_cols) = match o.position {
        CsvPosition::Lla(c) => (Some(c.to_vec()), None),
        CsvPosition::Ecef(c) => (None, Some(c.to_vec())),
    };
    TGnssCsv {
        skip_lines: o.skip_lines,
        delimiter: o.delimiter.map(|d| (d as char).to_string()),
        time_col: o.time_col,
        week_col: o.week_col,
        time_scale: Some(o.time_scale),
        time_unit: Some(o.time_unit),
        lla_cols,
        ecef_cols,
        angle_unit: Some(o.angle_unit),
        height_unit: Some(o.height_unit),
        vel_cols: o.vel_cols.map(|c| c.to_vec()),
        pos_std_cols: o.pos_std_cols.map(|c| c.to_vec()),
        vel_std_cols: o.vel_std_cols.map(|c| c.to_vec()),
    }
}
