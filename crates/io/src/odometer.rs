//! Odometer readers (docs/FORMATS.md "Odometer"): vehicle speed from a wheel encoder
//! or CAN bus, as speeds or cumulative pulse counts, turned into
//! [`OdometerSample`]s (forward speed of the vehicle reference point, before the
//! scale-factor correction, and the interval it is the mean of).
//!
//! Three formats, all whitespace- or comma-separated, `#` / `%` comment lines and
//! blank lines allowed:
//!
//! - `speed`: `t speed_mps`;
//! - `pulses`: `t cumulative_pulses` (speed = meters_per_pulse dN / dt);
//! - `navfuse`: the simulator's odometer.txt, `t cumulative_pulses pulses_in_interval
//!   speed`, read like `pulses` from the cumulative count;
//! - `navfuse_speed`: the same file read from its speed column (the mean since the
//!   previous record, with the simulated speed noise), like `speed` with
//!   `speed_is_mean`.
//!
//! Times are on the IMU time scale, in the seconds-of-week convention of the IMU
//! file; they must increase strictly. The whole file is validated; the first bad
//! record stops the read with an [`InputError`] naming file, line and field. A file
//! without records (or a pulse file with one record) gives an empty list.

use crate::error::InputError;
use crate::fmt::{after_record, field, parse_f64, split_fields, LineReader};
use crate::input::{OdometerFormat, OdometerSource};
use navfuse_core::OdometerSample;

/// Read an odometer file; see the module documentation. A damaged last line is an
/// error here; [`read_odometer_report`] drops it with a warning.
pub fn read_odometer(src: &OdometerSource) -> Result<Vec<OdometerSample>, InputError> {
    read(src, None)
}

/// [`read_odometer`], with a last line cut mid-write (no line end) dropped and a
/// warning naming file and line pushed to `warnings`.
pub fn read_odometer_report(
    src: &OdometerSource,
    warnings: &mut Vec<String>,
) -> Result<Vec<OdometerSample>, InputError> {
    read(src, Some(warnings))
}

fn read(
    src: &OdometerSource,
    mut warnings: Option<&mut Vec<String>>,
) -> Result<Vec<OdometerSample>, InputError> {
    let path = src.path.as_path();
    if let OdometerFormat::Ubx(how) = src.format {
        let log = crate::ubx::read_ubx(path)?;
        let mut w = log.warnings.clone();
        let out = crate::ubx::aiding::odometer(path, &log, how, &mut w)?;
        if let Some(ws) = warnings {
            ws.extend(w);
        }
        return Ok(out);
    }
    let (ncols, what) = match src.format {
        OdometerFormat::Speed { .. } => (2, "t, speed [m/s]"),
        OdometerFormat::Pulses { .. } => (2, "t, cumulative pulses"),
        OdometerFormat::Navfuse { .. } | OdometerFormat::NavfuseSpeed => (
            4,
            "t, cumulative pulses, pulses in the interval, speed [m/s]",
        ),
        OdometerFormat::Ubx(_) => (2, "not reached: read above"),
    };
    let meters_per_pulse = match src.format {
        OdometerFormat::Speed { .. } | OdometerFormat::NavfuseSpeed | OdometerFormat::Ubx(_) => {
            None
        }
        OdometerFormat::Pulses { meters_per_pulse }
        | OdometerFormat::Navfuse { meters_per_pulse } => {
            let k =
                crate::error::check_scale("meters_per_pulse", meters_per_pulse, meters_per_pulse)
                    .map_err(|m| InputError::new(path, m).with_field("meters_per_pulse"))?;
            Some(k)
        }
    };

    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(8);
    let mut out = Vec::new();
    // previous record: time, cumulative pulses (pulse formats)
    let mut prev: Option<(f64, f64)> = None;
    let mut header = crate::fmt::SkipLines::new(src.skip_lines);
    while let Some((ln, text)) = lines.next_line()? {
        let mut record = || -> Result<(), InputError> {
            split_fields(text, &mut fields);
            if header.skip(ln, text, &fields) {
                return Ok(());
            }
            if fields.len() != ncols {
                return Err(InputError::columns(path, ln, ncols, what, fields.len()));
            }
            let num = |k: usize, name: &str| -> Result<f64, InputError> {
                let s = field(text, &fields, k);
                match parse_f64(s) {
                    Some(v) if v.is_finite() => Ok(v),
                    Some(v) => Err(InputError::not_finite(path, ln, name, v)),
                    None => Err(InputError::not_a_number(path, ln, name, s)),
                }
            };
            let t = num(0, "t")?;
            InputError::check_time_order(path, ln, t, prev.map(|p| p.0))?;
            if let Some((tp, _)) = prev {
                if !(t - tp).is_finite() {
                    return Err(InputError::at_field(
                        path,
                        ln,
                        "time",
                        format!("time {t} is too far from the previous record ({tp})"),
                    ));
                }
            }
            let speed_format = match src.format {
                OdometerFormat::Speed { speed_is_mean } => Some((1, speed_is_mean)),
                OdometerFormat::NavfuseSpeed => {
                    num(1, "pulses")?;
                    num(2, "pulses_in_interval")?;
                    Some((3, true))
                }
                _ => None,
            };
            match (src.format, speed_format) {
                (_, Some((column, speed_is_mean))) => {
                    let speed = num(column, "speed")?;
                    match (speed_is_mean, prev) {
                        (false, _) => out.push(OdometerSample {
                            t,
                            speed_mps: speed,
                            interval_s: 0.0,
                        }),
                        (true, Some((tp, _))) => out.push(OdometerSample {
                            t,
                            speed_mps: speed,
                            interval_s: t - tp,
                        }),
                        // a mean since an unknown time: it only starts the intervals
                        (true, None) => {}
                    }
                    prev = Some((t, 0.0));
                }
                (OdometerFormat::Pulses { .. } | OdometerFormat::Navfuse { .. }, _) => {
                    let pulses = num(1, "pulses")?;
                    if let OdometerFormat::Navfuse { .. } = src.format {
                        let n = num(2, "pulses_in_interval")?;
                        if n < 0.0 {
                            return Err(InputError::at_field(
                                path,
                                ln,
                                "pulses_in_interval",
                                format!("expected a pulse count >= 0, found {n}"),
                            ));
                        }
                        num(3, "speed")?;
                    }
                    if let Some((tp, np)) = prev {
                        if pulses < np {
                            return Err(InputError::at_field(
                                path,
                                ln,
                                "pulses",
                                format!(
                                "cumulative pulse count {pulses} goes backwards (previous {np}): \
                                 expected a non-decreasing count"
                            ),
                            ));
                        }
                        let dt = t - tp;
                        let k = meters_per_pulse.unwrap_or(0.0);
                        let speed = k * (pulses - np) / dt;
                        if !speed.is_finite() {
                            return Err(InputError::at_field(
                                path,
                                ln,
                                "pulses",
                                format!(
                                    "{} pulses in {dt} s give a speed of {speed} m/s: expected a \
                                 finite speed",
                                    pulses - np
                                ),
                            ));
                        }
                        out.push(OdometerSample {
                            t,
                            speed_mps: speed,
                            interval_s: dt,
                        });
                    }
                    prev = Some((t, pulses));
                }
                // UBX is read above; the speed formats are the first arm.
                _ => {}
            }
            Ok(())
        };
        let r = record();
        if !after_record(r, ln, &mut lines, &mut warnings)? {
            break;
        }
    }
    Ok(out)
}
