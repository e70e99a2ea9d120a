//! Generic GNSS CSV reader (docs/FORMATS.md "CSV GNSS"): declared 0-based columns
//! for the time, the position (latitude/longitude/height or ECEF x/y/z), optional
//! velocity N/E/D and optional std columns; units, time scale and delimiter
//! declared; `skip_lines` header lines, or one non-numeric first line (a header)
//! detected and skipped.
//!
//! Errors name `FILE:LINE: field 'NAME (column C)'`, C the 1-based column as a
//! spreadsheet counts. Times must increase strictly; position std > 0 from the
//! columns or the configured `position_std_m` (one of them is required).

use crate::error::InputError;
use crate::fmt::{field, for_each_line, parse_f64, split_fields, LineError, LineReader};
use crate::input::TimeUnit;
use crate::time::{days_from_civil, SECONDS_PER_WEEK};
use nalgebra::Vector3;
use navfuse_core::GnssFix;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What the time column counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CsvTimeScale {
    /// GPS seconds of week; with `week_col`, the GPS week beside it.
    GpsSow,
    /// GPS time counted from 1970-01-01 without leap seconds (RTKLIB tag files).
    GpstUnix,
    /// Unix time (UTC, leap seconds not counted): + GPS-UTC leap seconds.
    UtcUnix,
    /// ISO 8601 `YYYY-MM-DDTHH:MM:SS[.sss][Z]` (or a space for `T`) in GPST.
    IsoGpst,
    /// ISO 8601 in UTC: + GPS-UTC leap seconds.
    IsoUtc,
}

/// The position columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsvPosition {
    /// Latitude, longitude (`angle_unit`), ellipsoidal height (`height_unit`).
    Lla([usize; 3]),
    /// ECEF x, y, z \[m\] (WGS-84).
    Ecef([usize; 3]),
}

/// Angle unit of latitude and longitude.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AngleUnit {
    Deg,
    Rad,
}

/// Unit of heights (and ECEF coordinates, velocities and stds are always SI).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LengthUnit {
    #[serde(rename = "m")]
    Metre,
    /// International foot, 0.3048 m.
    #[serde(rename = "ft")]
    Foot,
}

/// `[gnss] format = "csv"` with `[gnss.csv]`.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvGnssOptions {
    /// Lines to skip at the top; None: skip the first line if it is not numeric.
    pub skip_lines: Option<usize>,
    /// Field separator; None: spaces, tabs and commas (as every text reader).
    pub delimiter: Option<u8>,
    pub time_col: usize,
    /// GPS week column (with `time_scale = gps_sow`).
    pub week_col: Option<usize>,
    pub time_scale: CsvTimeScale,
    /// Unit of a numeric time column.
    pub time_unit: TimeUnit,
    pub position: CsvPosition,
    pub angle_unit: AngleUnit,
    pub height_unit: LengthUnit,
    /// Velocity north, east, down [m/s].
    pub vel_cols: Option<[usize; 3]>,
    /// Position std north, east, down \[m\].
    pub pos_std_cols: Option<[usize; 3]>,
    /// Velocity std north, east, down [m/s].
    pub vel_std_cols: Option<[usize; 3]>,
    /// Position std for files without std columns \[m\].
    pub position_std_m: Option<[f64; 3]>,
    /// Velocity std for files with velocity but no std columns [m/s].
    pub velocity_std_mps: Option<[f64; 3]>,
}

impl CsvGnssOptions {
    /// `t, lat, lon, h` in GPS seconds of week, degrees and metres, with the header
    /// detected and `position_std_m` to be given.
    pub fn lla(time_col: usize, lla: [usize; 3]) -> Self {
        CsvGnssOptions {
            skip_lines: None,
            delimiter: None,
            time_col,
            week_col: None,
            time_scale: CsvTimeScale::GpsSow,
            time_unit: TimeUnit::Seconds,
            position: CsvPosition::Lla(lla),
            angle_unit: AngleUnit::Deg,
            height_unit: LengthUnit::Metre,
            vel_cols: None,
            pos_std_cols: None,
            vel_std_cols: None,
            position_std_m: None,
            velocity_std_mps: None,
        }
    }

    /// Every declared column with its name.
    pub fn columns(&self) -> Vec<(&'static str, usize)> {
        let mut c = vec![("time", self.time_col)];
        if let Some(w) = self.week_col {
            c.push(("week", w));
        }
        let (names, cols) = match self.position {
            CsvPosition::Lla(p) => (["lat", "lon", "height"], p),
            CsvPosition::Ecef(p) => (["x", "y", "z"], p),
        };
        c.extend(names.into_iter().zip(cols));
        for (names, cols) in [
            (["vn", "ve", "vd"], self.vel_cols),
            (["std_n", "std_e", "std_d"], self.pos_std_cols),
            (["vel_std_n", "vel_std_e", "vel_std_d"], self.vel_std_cols),
        ] {
            if let Some(cols) = cols {
                c.extend(names.into_iter().zip(cols));
            }
        }
        c
    }

    /// Every declared column distinct: Err names the two uses of a column.
    pub fn check_columns(&self) -> Result<(), String> {
        let cols = self.columns();
        for (k, (name, c)) in cols.iter().enumerate() {
            let earlier = cols.get(..k).unwrap_or(&[]);
            if let Some((other, _)) = earlier.iter().find(|(_, c2)| c2 == c) {
                return Err(format!(
                    "column {c} is declared for both {other} and {name}: expected distinct columns"
                ));
            }
        }
        Ok(())
    }
}

fn unit_s(u: TimeUnit) -> f64 {
    match u {
        TimeUnit::Seconds => 1.0,
        TimeUnit::Milliseconds => 1e-3,
        TimeUnit::Microseconds => 1e-6,
        TimeUnit::Nanoseconds => 1e-9,
    }
}

struct Row<'a> {
    path: &'a Path,
    ln: usize,
    text: &'a [u8],
    fields: &'a [(usize, usize)],
}

/// `t` with commas turned into points.
fn decimal_points(t: &[u8]) -> Vec<u8> {
    t.iter()
        .map(|&b| if b == b',' { b'.' } else { b })
        .collect()
}

impl Row<'_> {
    fn name(name: &str, k: usize) -> String {
        format!("{name} (column {})", k + 1)
    }

    fn num(&self, k: usize, name: &str) -> Result<f64, InputError> {
        let t = field(self.text, self.fields, k);
        let n = Self::name(name, k);
        match parse_f64(t) {
            Some(v) if v.is_finite() => Ok(v),
            Some(v) => Err(InputError::not_finite(self.path, self.ln, &n, v)),
            // "30,5": a decimal comma (the field split on another delimiter).
            None if t.contains(&b',') && parse_f64(&decimal_points(t)).is_some() => {
                Err(InputError::at_field(
                    self.path,
                    self.ln,
                    &n,
                    format!(
                        "found \"{}\", a decimal comma: navfuse reads decimal points (convert the file, e.g. sed 's/,/./g' when the delimiter is not a comma)",
                        String::from_utf8_lossy(t)
                    ),
                ))
            }
            None => Err(InputError::not_a_number(self.path, self.ln, &n, t)),
        }
    }

    fn v3(&self, c: [usize; 3], names: [&str; 3]) -> Result<Vector3<f64>, InputError> {
        Ok(Vector3::new(
            self.num(c[0], names[0])?,
            self.num(c[1], names[1])?,
            self.num(c[2], names[2])?,
        ))
    }

    fn std3(&self, c: [usize; 3], names: [&str; 3]) -> Result<Vector3<f64>, InputError> {
        let v = self.v3(c, names)?;
        for k in 0..3 {
            InputError::scale(
                self.path,
                self.ln,
                &Self::name(names[k], c[k]),
                "std",
                v[k],
                v[k],
            )?;
        }
        Ok(v)
    }

    fn err(&self, k: usize, name: &str, msg: String) -> InputError {
        InputError::at_field(self.path, self.ln, Self::name(name, k), msg)
    }
}

/// `YYYY-MM-DD[T ]HH:MM:SS[.sss][Z]` -> seconds since the GPS epoch (same scale).
fn parse_iso(s: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(s).ok()?;
    let s = s.strip_suffix('Z').unwrap_or(s);
    let (date, time) = s.split_once(['T', ' '])?;
    let mut d = date.split('-');
    let y: i64 = d.next()?.parse().ok()?;
    let mo: u32 = d.next()?.parse().ok()?;
    let day: u32 = d.next()?.parse().ok()?;
    if d.next().is_some() {
        return None;
    }
    let mut t = time.split(':');
    let h: u32 = t.next()?.parse().ok()?;
    let mi: u32 = t.next()?.parse().ok()?;
    let sec: f64 = t.next()?.parse().ok()?;
    if t.next().is_some()
        || !(1..=12).contains(&mo)
        || !(1900..=9999).contains(&y)
        || day == 0
        || day > crate::time::days_in_month(y, mo)
        || h > 23
        || mi > 59
        || !(0.0..61.0).contains(&sec)
    {
        return None;
    }
    let days = days_from_civil(y, mo, day) - days_from_civil(1980, 1, 6);
    Some(days as f64 * 86_400.0 + f64::from(h * 3600 + mi * 60) + sec)
}

/// Leap seconds (GPS - UTC) at a UTC time counted in seconds since the GPS epoch.
fn leap_at(utc_since_gps_epoch: f64) -> f64 {
    navfuse_core::time::leap_seconds_at_utc(utc_since_gps_epoch)
}

/// Read a CSV GNSS file: fixes with `t` in GPS seconds of the returned week (None
/// for `gps_sow` without a week column: the file's seconds of week).
pub fn read_csv_gnss(
    path: &Path,
    o: &CsvGnssOptions,
    warnings: &mut Vec<String>,
) -> Result<(Vec<GnssFix>, Option<u32>), InputError> {
    o.check_columns().map_err(|m| InputError::new(path, m))?;
    let cols = o.columns();
    if o.pos_std_cols.is_none() && o.position_std_m.is_none() {
        return Err(InputError::new(
            path,
            "no position std: declare gnss.csv.pos_std_cols or set gnss.position_std_m",
        ));
    }
    if o.vel_cols.is_some() && o.vel_std_cols.is_none() && o.velocity_std_mps.is_none() {
        return Err(InputError::new(
            path,
            "velocity columns without a std: declare gnss.csv.vel_std_cols or set gnss.velocity_std_mps",
        ));
    }
    let min_cols = cols.iter().map(|c| c.1).max().unwrap_or(0) + 1;
    let what = cols
        .iter()
        .map(|(n, c)| format!("{n}={}", c + 1))
        .collect::<Vec<_>>()
        .join(" ");
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(16);
    let mut out = Vec::new();
    let mut prev: Option<f64> = None;
    let mut week0: Option<i64> = None;
    let mut first_data = true;
    let tu = unit_s(o.time_unit);
    for_each_line(&mut lines, warnings, |ln, raw| {
        if o.skip_lines.is_some_and(|n| ln <= n) {
            return Ok(());
        }
        let text: &[u8] = raw;
        match o.delimiter {
            Some(d) => crate::fmt::split_on(text, d, &mut fields),
            None => split_fields(text, &mut fields),
        }
        if crate::fmt::is_comment_line(text, &fields) {
            return Ok(());
        }
        let row = Row {
            path,
            ln,
            text,
            fields: &fields,
        };
        let header = std::mem::replace(&mut first_data, false)
            && o.skip_lines.is_none()
            && parse_f64(field(text, &fields, o.time_col)).is_none()
            && (o.time_scale == CsvTimeScale::GpsSow
                || o.time_scale == CsvTimeScale::GpstUnix
                || o.time_scale == CsvTimeScale::UtcUnix
                || parse_iso(field(text, &fields, o.time_col)).is_none());
        if header {
            return Ok(());
        }
        if fields.len() < min_cols {
            return Err(LineError::Data(InputError::columns(
                path,
                ln,
                format!("at least {min_cols}"),
                &what,
                fields.len(),
            )));
        }
        // GPS seconds since the GPS epoch, or of the week (gps_sow without week).
        let tk = o.time_col;
        let (gps_s, has_week) = match o.time_scale {
            CsvTimeScale::GpsSow => {
                let sow = row.num(tk, "time")? * tu;
                match o.week_col {
                    Some(wc) => {
                        let w = row.num(wc, "week")?;
                        if !(0.0..=100_000.0).contains(&w) || w.fract() != 0.0 {
                            return Err(row
                                .err(wc, "week", format!("expected a GPS week number, found {w}"))
                                .into());
                        }
                        if !(0.0..SECONDS_PER_WEEK + 1.0).contains(&sow) {
                            return Err(row
                                .err(
                                    tk,
                                    "time",
                                    format!("expected GPS seconds of week in [0, 604801) beside week_col, found {sow} (check time_unit)"),
                                )
                                .into());
                        }
                        (w * SECONDS_PER_WEEK + sow, true)
                    }
                    None => (sow, false),
                }
            }
            CsvTimeScale::GpstUnix | CsvTimeScale::UtcUnix => {
                let u = row.num(tk, "time")? * tu - crate::time::GPS_EPOCH_UNIX as f64;
                let g = if o.time_scale == CsvTimeScale::UtcUnix {
                    u + leap_at(u)
                } else {
                    u
                };
                (g, true)
            }
            CsvTimeScale::IsoGpst | CsvTimeScale::IsoUtc => {
                let t = field(text, &fields, tk);
                let Some(s) = parse_iso(t) else {
                    return Err(row
                        .err(
                            tk,
                            "time",
                            format!(
                                "expected an ISO date and time YYYY-MM-DDTHH:MM:SS.sss, found \"{}\"",
                                crate::error::shorten(t)
                            ),
                        )
                        .into());
                };
                let g = if o.time_scale == CsvTimeScale::IsoUtc {
                    s + leap_at(s)
                } else {
                    s
                };
                (g, true)
            }
        };
        if has_week && !(0.0..1e11).contains(&gps_s) {
            return Err(row
                .err(
                    tk,
                    "time",
                    format!(
                        "expected a time after the GPS epoch 1980-01-06, found {gps_s} s from it"
                    ),
                )
                .into());
        }
        let t = if has_week {
            let w0 = *week0.get_or_insert((gps_s / SECONDS_PER_WEEK).floor() as i64);
            gps_s - w0 as f64 * SECONDS_PER_WEEK
        } else {
            gps_s
        };
        if let Err(e) = InputError::check_time_order(path, ln, t, prev) {
            return Err(e.with_field(Row::name("time", tk)).into());
        }
        let lla = match o.position {
            CsvPosition::Lla(c) => {
                let v = row.v3(c, ["lat", "lon", "height"])?;
                let a = match o.angle_unit {
                    AngleUnit::Deg => v.x.abs() <= 90.0 && v.y.abs() <= 360.0,
                    AngleUnit::Rad => {
                        v.x.abs() <= std::f64::consts::FRAC_PI_2
                            && v.y.abs() <= 2.0 * std::f64::consts::PI
                    }
                };
                if !a {
                    return Err(row
                        .err(c[0], "lat", format!("expected latitude/longitude within +-90/+-360 deg ({:?}), found {}, {}", o.angle_unit, v.x, v.y))
                        .into());
                }
                let (lat, lon) = match o.angle_unit {
                    AngleUnit::Deg => (v.x.to_radians(), v.y.to_radians()),
                    AngleUnit::Rad => (v.x, v.y),
                };
                let h = match o.height_unit {
                    LengthUnit::Metre => v.z,
                    LengthUnit::Foot => v.z * 0.3048,
                };
                Vector3::new(lat, lon, h)
            }
            CsvPosition::Ecef(c) => {
                let v = row.v3(c, ["x", "y", "z"])?;
                if !(1e5..1e8).contains(&v.norm()) {
                    return Err(row
                        .err(c[0], "x", format!("expected an ECEF position [m] (|r| from 1e5 to 1e8 m), found |r| = {:.3} m", v.norm()))
                        .into());
                }
                navfuse_core::earth::ecef_to_lla(&v)
            }
        };
        let std_ned = match o.pos_std_cols {
            Some(c) => row.std3(c, ["std_n", "std_e", "std_d"])?,
            None => Vector3::from(o.position_std_m.unwrap_or([1.0; 3])),
        };
        let vel_ned = o
            .vel_cols
            .map(|c| row.v3(c, ["vn", "ve", "vd"]))
            .transpose()?;
        let vel_std_ned = match (vel_ned, o.vel_std_cols, o.velocity_std_mps) {
            (None, _, _) => None,
            (Some(_), Some(c), _) => Some(row.std3(c, ["vel_std_n", "vel_std_e", "vel_std_d"])?),
            (Some(_), None, s) => s.map(Vector3::from),
        };
        prev = Some(t);
        out.push(GnssFix {
            t,
            lla,
            std_ned,
            vel_ned,
            vel_std_ned,
        });
        Ok(())
    })?;
    Ok((out, week0.map(|w| w as u32)))
}
