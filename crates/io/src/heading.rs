//! Dual-antenna heading reader (docs/FORMATS.md "Heading"): 3 columns
//! `t heading_deg std_deg`, the azimuth of the antenna baseline (primary to
//! secondary antenna) from true north, clockwise, and its 1-sigma; the simulator's
//! heading.txt.
//!
//! Whitespace- or comma-separated, `#` / `%` comment lines and blank lines allowed.
//! Times are on the GNSS time scale (GPS seconds of week, like the GNSS files) and
//! must increase strictly. Headings are accepted in [0, 360) or (-180, 180] deg
//! (that is, -180 < heading < 360), stds must be > 0 with a finite, non-zero
//! square in radians (1e-150 to 1e150 rad). The first bad record stops the
//! read with an [`InputError`] naming file, line and field. A file without records
//! gives an empty list.

use crate::error::InputError;
use crate::fmt::{after_record, field, parse_f64, split_fields, LineReader};
use navfuse_core::HeadingObs;
use std::path::Path;

const WHAT: &str = "t, heading [deg], std [deg]";

/// Read a heading file; see the module documentation. A damaged last line is an
/// error here; [`read_heading_report`] drops it with a warning.
pub fn read_heading(path: &Path) -> Result<Vec<HeadingObs>, InputError> {
    read(path, None, None)
}

/// [`read_heading`], with a last line cut mid-write (no line end) dropped and a
/// warning naming file and line pushed to `warnings`.
pub fn read_heading_report(
    path: &Path,
    skip_lines: Option<usize>,
    warnings: &mut Vec<String>,
) -> Result<Vec<HeadingObs>, InputError> {
    read(path, skip_lines, Some(warnings))
}

fn read(
    path: &Path,
    skip_lines: Option<usize>,
    mut warnings: Option<&mut Vec<String>>,
) -> Result<Vec<HeadingObs>, InputError> {
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(8);
    let mut out: Vec<HeadingObs> = Vec::new();
    let mut prev: Option<f64> = None;
    let mut header = crate::fmt::SkipLines::new(skip_lines);
    while let Some((ln, text)) = lines.next_line()? {
        let mut record = || -> Result<(), InputError> {
            split_fields(text, &mut fields);
            if header.skip(ln, text, &fields) {
                return Ok(());
            }
            if fields.len() != 3 {
                return Err(InputError::columns(path, ln, 3, WHAT, fields.len()));
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
            InputError::check_time_order(path, ln, t, prev)?;
            prev = Some(t);
            let heading = num(1, "heading")?;
            if !(heading > -180.0 && heading < 360.0) {
                return Err(InputError::at_field(
                    path,
                    ln,
                    "heading",
                    format!("expected a heading in [0, 360) or (-180, 180] deg, found {heading}"),
                ));
            }
            let std = num(2, "std")?;
            let std_rad = InputError::scale(path, ln, "std", "std", std, std.to_radians())?;
            out.push(HeadingObs {
                t,
                heading_rad: heading.to_radians(),
                std_rad,
            });
            Ok(())
        };
        let r = record();
        if !after_record(r, ln, &mut lines, &mut warnings)? {
            break;
        }
    }
    Ok(out)
}
