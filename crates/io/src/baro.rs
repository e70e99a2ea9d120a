//! Barometer reader (docs/FORMATS.md "Barometer"): `t value` records, whitespace- or
//! comma-separated, `#` / `%` comment lines, blank lines and a header line of names
//! allowed. The value is a pressure in Pa or hPa (turned into a pressure altitude
//! with the ISA relation against `reference_pressure_pa`, aiding/baro.rs) or a
//! height in metres (a pressure altitude already, e.g. PX4's `baro_alt_meter`).
//!
//! Times are on the IMU time scale (the barometer is logged with the IMU), in the
//! seconds-of-week convention of the IMU file; they must increase strictly. A sensor
//! delay `delay_s` is removed from each time tag (the reading at t is the pressure at
//! t - delay). The first bad record stops the read with an [`InputError`] naming
//! file, line and field.

use crate::error::InputError;
use crate::fmt::{after_record, field, parse_f64, split_fields, LineReader};
use navfuse_core::aiding::baro::{pressure_altitude_m, BaroSample};
use std::path::PathBuf;

/// What the value column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BaroQuantity {
    PressurePa,
    PressureHpa,
    HeightM,
}

/// What kind of file the barometer input is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BaroFormat {
    /// `t value` text records.
    #[default]
    Text,
    /// PX4 ULog `sensor_baro` / `vehicle_air_data`, topic instance `multi_id`
    /// (docs/FORMATS.md "PX4 ULog"); `quantity` does not apply (pressures in Pa).
    Ulog { multi_id: u8 },
}

/// A barometer input (`\[baro\]`).
#[derive(Clone, Debug, PartialEq)]
pub struct BaroSource {
    pub path: PathBuf,
    pub quantity: BaroQuantity,
    /// Sea-level reference pressure of the pressure altitude \[Pa\] (QNH; the bias
    /// state takes up what it leaves).
    pub reference_pressure_pa: f64,
    /// Sensor delay removed from the time tags \[s\].
    pub delay_s: f64,
    pub format: BaroFormat,
    /// Text files: lines to skip at the top; None: a first line with no number is a
    /// header.
    pub skip_lines: Option<usize>,
}

/// Read a barometer file into pressure altitudes; a last line cut mid-write (no line
/// end) is dropped with a warning pushed to `warnings`.
pub fn read_baro(
    src: &BaroSource,
    warnings: &mut Vec<String>,
) -> Result<Vec<BaroSample>, InputError> {
    let path = src.path.as_path();
    if let BaroFormat::Ulog { multi_id } = src.format {
        let u = crate::ulog::open(path, warnings)?;
        let map = crate::ulog::TimeMap::of(&u);
        let p = crate::ulog::baro_pressures(path, &u, multi_id, &map)?;
        let outside = p
            .iter()
            .filter(|&&(_, p)| !(10_000.0..=120_000.0).contains(&p))
            .count();
        if outside > 0 {
            warnings.push(format!(
                "{}: {outside} of {} barometer pressures outside 10-120 kPa dropped",
                path.display(),
                p.len()
            ));
        }
        return Ok(p
            .into_iter()
            .filter(|&(_, p)| (10_000.0..=120_000.0).contains(&p))
            .map(|(t, p)| BaroSample {
                t: t - src.delay_s,
                height_m: pressure_altitude_m(p, src.reference_pressure_pa),
            })
            .collect());
    }
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(4);
    let mut out: Vec<BaroSample> = Vec::new();
    let mut prev_t: Option<f64> = None;
    let mut seen_record = false;
    let mut warn = Some(warnings);
    let mut header = crate::fmt::SkipLines::new(src.skip_lines);
    while let Some((ln, text)) = lines.next_line()? {
        let mut record = || -> Result<(), InputError> {
            split_fields(text, &mut fields);
            if header.skip(ln, text, &fields) {
                return Ok(());
            }
            // A header line of names before the first record.
            if !seen_record && parse_f64(field(text, &fields, 0)).is_none() {
                return Ok(());
            }
            seen_record = true;
            if fields.len() != 2 {
                return Err(InputError::columns(
                    path,
                    ln,
                    2,
                    "t, pressure or height",
                    fields.len(),
                ));
            }
            let num = |k: usize, name: &str| -> Result<f64, InputError> {
                let s = field(text, &fields, k);
                match parse_f64(s) {
                    Some(v) if v.is_finite() => Ok(v),
                    Some(v) => Err(InputError::not_finite(path, ln, name, v)),
                    None => Err(InputError::not_a_number(path, ln, name, s)),
                }
            };
            let t = num(0, "t")? - src.delay_s;
            InputError::check_time_order(path, ln, t, prev_t)?;
            let v = num(1, "value")?;
            let height_m = match src.quantity {
                // -1 km .. 30 km: a pressure column read as heights is far outside.
                BaroQuantity::HeightM if !(-1000.0..=30_000.0).contains(&v) => {
                    let hint = if (10_000.0..=120_000.0).contains(&v) {
                        " (a pressure in Pa? set quantity = \"pressure_pa\")"
                    } else {
                        ""
                    };
                    return Err(InputError::at_field(
                        path,
                        ln,
                        "value",
                        format!("expected a pressure altitude between -1000 and 30000 m, found {v} m{hint}"),
                    ));
                }
                BaroQuantity::HeightM => v,
                BaroQuantity::PressurePa | BaroQuantity::PressureHpa => {
                    let p = if src.quantity == BaroQuantity::PressureHpa {
                        v * 100.0
                    } else {
                        v
                    };
                    // 10 kPa .. 120 kPa: from above 15 km to below the Dead Sea.
                    if !(10_000.0..=120_000.0).contains(&p) {
                        let hint = if (10.0..=120.0).contains(&p) {
                            " (a pressure in kPa? give Pa or hPa)"
                        } else if (100.0..=1200.0).contains(&p) {
                            " (a pressure in hPa? set quantity = \"pressure_hpa\")"
                        } else {
                            ""
                        };
                        return Err(InputError::at_field(
                            path,
                            ln,
                            "value",
                            format!("expected a pressure between 10000 and 120000 Pa, found {p} Pa{hint}"),
                        ));
                    }
                    pressure_altitude_m(p, src.reference_pressure_pa)
                }
            };
            prev_t = Some(t);
            out.push(BaroSample { t, height_m });
            Ok(())
        };
        let result = record();
        if !after_record(result, ln, &mut lines, &mut warn)? {
            break;
        }
    }
    Ok(out)
}
