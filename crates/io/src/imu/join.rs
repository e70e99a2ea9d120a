//! An IMU given as several CSV files (`[imu] files`, docs/FORMATS.md "IMU from
//! several CSV files"): a time file and files holding the gyro and accelerometer
//! columns, as simulators and loggers write them. They are joined in memory into the
//! one-file CSV layout `t, gyro x y z, accel x y z` the CSV parser reads.
//!
//! - A part without a time column is joined row by row: its k-th data row belongs to
//!   the time file's k-th data row. More or fewer rows than the time file is an error
//!   naming both files and the line where one of them ends.
//! - A part with a time column is joined on time: its k-th data row must carry the
//!   time file's k-th time within `tolerance_s`, else an error naming both lines
//!   (exact join; no interpolation between rates).
//! - In every file blank and `#` / `%` lines are skipped, and so are the first
//!   `skip_lines` lines, or without it a first line with no number (a header).
//! - The joined text keeps the time file's line numbers: every line of the time file
//!   that is not a data row becomes a comment line, so the CSV parser's errors
//!   (`time goes backwards`, gaps) name the time file's own lines. Values are checked
//!   here (numbers, finite) with their own file and line.

use crate::error::InputError;
use crate::fmt::{field, parse_f64, split_fields, LineReader, SkipLines};
use crate::input::CsvImuFiles;
use std::io::Write;
use std::path::Path;

/// One data row of a part: its line and values.
struct Rows {
    lines: Vec<usize>,
    /// Time (if the part has a time column) then the declared columns, per row.
    values: Vec<Vec<f64>>,
}

/// Read one part: the declared columns of every data row. `names` name the columns.
fn read_part(
    path: &Path,
    skip_lines: Option<usize>,
    cols: &[(usize, &str)],
) -> Result<Rows, InputError> {
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(16);
    let mut skip = SkipLines::new(skip_lines);
    let mut out = Rows {
        lines: Vec::new(),
        values: Vec::new(),
    };
    let need = cols.iter().map(|c| c.0).max().unwrap_or(0) + 1;
    while let Some((ln, text)) = lines.next_line()? {
        split_fields(text, &mut fields);
        if skip.skip(ln, text, &fields) {
            continue;
        }
        if fields.len() < need {
            let what: Vec<&str> = cols.iter().map(|c| c.1).collect();
            return Err(InputError::columns(
                path,
                ln,
                format!("at least {need}"),
                &what.join(", "),
                fields.len(),
            ));
        }
        let mut v = Vec::with_capacity(cols.len());
        for &(k, name) in cols {
            let t = field(text, &fields, k);
            match parse_f64(t) {
                Some(x) if x.is_finite() => v.push(x),
                Some(x) => return Err(InputError::not_finite(path, ln, name, x)),
                None => return Err(InputError::not_a_number(path, ln, name, t)),
            }
        }
        out.lines.push(ln);
        out.values.push(v);
    }
    Ok(out)
}

/// Join the files into the one-file CSV text (see the module documentation).
pub(super) fn join(f: &CsvImuFiles) -> Result<Vec<u8>, InputError> {
    let time = read_part(&f.time_path, f.skip_lines, &[(f.time_col, "time")])?;
    let mut parts: Vec<Rows> = Vec::new();
    for (part, names) in [
        (&f.gyro, ["gyro_x", "gyro_y", "gyro_z"]),
        (&f.accel, ["accel_x", "accel_y", "accel_z"]),
    ] {
        let mut cols: Vec<(usize, &str)> = Vec::new();
        if let Some(tc) = part.time_col {
            cols.push((tc, "time"));
        }
        cols.extend(part.cols.iter().copied().zip(names));
        let mut rows = read_part(&part.path, f.skip_lines, &cols)?;
        let n_t = time.values.len();
        if rows.values.len() != n_t {
            let (short, long, k) = if rows.values.len() < n_t {
                (&part.path, &f.time_path, time.lines[rows.values.len()])
            } else {
                (&f.time_path, &part.path, rows.lines[n_t])
            };
            return Err(InputError::at_line(
                long,
                k,
                format!(
                    "{} has {} data rows and {} has {}: this row has no partner in {} \
                     (rows are joined one to one)",
                    f.time_path.display(),
                    n_t,
                    part.path.display(),
                    rows.values.len(),
                    short.display()
                ),
            ));
        }
        if part.time_col.is_some() {
            for (k, v) in rows.values.iter_mut().enumerate() {
                let t0 = time.values[k][0];
                let t = v.remove(0);
                if (t - t0).abs() > f.tolerance_s {
                    return Err(InputError::at_field(
                        &part.path,
                        rows.lines[k],
                        "time",
                        format!(
                            "expected the time of {}:{} ({t0}) within {} s, found {t}: \
                             the files are joined on equal times",
                            f.time_path.display(),
                            time.lines[k],
                            f.tolerance_s
                        ),
                    ));
                }
            }
        }
        parts.push(rows);
    }
    let mut out = Vec::with_capacity(time.values.len() * 96);
    let mut next_line = 1;
    for (k, &ln) in time.lines.iter().enumerate() {
        while next_line < ln {
            // Keep the time file's line numbers.
            out.extend_from_slice(b"#\n");
            next_line += 1;
        }
        let _ = write!(out, "{:?}", time.values[k][0]);
        for p in &parts {
            for v in &p.values[k] {
                let _ = write!(out, ",{v:?}");
            }
        }
        out.push(b'\n');
        next_line += 1;
    }
    Ok(out)
}
