//! Line parsers of the IMU formats (KF-GINS text, CSV, rtklibexplorer logs), the
//! CSV column layout and GPST-as-Unix week base, and the rtklibexplorer pre-scan.

use super::{Raw, STANDARD_GRAVITY};
use crate::error::InputError;
use crate::fmt::{
    field, is_comment_line, parse_f64, parse_first_n, parse_i64, split_fields, LineReader,
};
use crate::input::{AccelUnit, CsvImuOptions, GyroUnit, TimeUnit};
use crate::time::{gpst_unix_to_week_sow, GPS_EPOCH_UNIX, SECONDS_PER_WEEK_I64};
use nalgebra::Vector3;
use std::path::Path;

/// Where the week of a GPST-as-Unix time column starts, in the column's units.
#[derive(Clone, Copy, Debug)]
pub(super) struct TimeBase {
    units_i: i64,
    units_f: f64,
}

pub(super) struct CsvKind {
    opts: CsvImuOptions,
    min_cols: usize,
    what: String,
    time_factor: f64,
    units_per_s: i64,
    pub(super) base: Option<TimeBase>,
    gyro_factor: f64,
    accel_factor: f64,
}

pub(super) struct RtkKind {
    pub(super) first_line: usize,
    pub(super) last_line: usize,
    pub(super) c0: f64,
    pub(super) sow0: f64,
    pub(super) s_per_count: f64,
}

pub(super) enum Kind {
    KfGins,
    Csv(Box<CsvKind>),
    Rtk(RtkKind),
    /// PX4 ULog: the samples read up front (ulog/mod.rs), interval-mean rates.
    Ulog(std::vec::IntoIter<Raw>),
}

/// A finite number from field `k`.
#[inline]
fn num(
    path: &Path,
    ln: usize,
    line: &[u8],
    fields: &[(usize, usize)],
    k: usize,
    name: &str,
) -> Result<f64, InputError> {
    let text = field(line, fields, k);
    match parse_f64(text) {
        Some(v) if v.is_finite() => Ok(v),
        Some(v) => Err(InputError::not_finite(path, ln, name, v)),
        None => Err(InputError::not_a_number(path, ln, name, text)),
    }
}

fn vec3(
    path: &Path,
    ln: usize,
    line: &[u8],
    fields: &[(usize, usize)],
    cols: [usize; 3],
    names: [&str; 3],
    factor: f64,
) -> Result<Vector3<f64>, InputError> {
    let one = |k: usize| -> Result<f64, InputError> {
        let v = num(path, ln, line, fields, cols[k], names[k])?;
        InputError::scaled(path, ln, names[k], v, v * factor)
    };
    Ok(Vector3::new(one(0)?, one(1)?, one(2)?))
}

pub(super) fn parse_kfgins(
    path: &Path,
    ln: usize,
    line: &[u8],
    fields: &mut Vec<(usize, usize)>,
    offset: f64,
) -> Result<Option<Raw>, InputError> {
    // One-pass fast path for plain numbers; the general path below handles the rest
    // (comments, other number forms) and gives the precise error.
    if let Some([t, gx, gy, gz, ax, ay, az]) = parse_first_n::<7>(line) {
        return Ok(Some((
            t + offset,
            Vector3::new(gx, gy, gz),
            Vector3::new(ax, ay, az),
        )));
    }
    split_fields(line, fields);
    if is_comment_line(line, fields) {
        return Ok(None);
    }
    if fields.len() < 7 {
        return Err(InputError::columns(
            path,
            ln,
            7,
            "t, dtheta x y z, dvel x y z",
            fields.len(),
        ));
    }
    let t = num(path, ln, line, fields, 0, "t")?;
    let g = vec3(
        path,
        ln,
        line,
        fields,
        [1, 2, 3],
        ["dtheta_x", "dtheta_y", "dtheta_z"],
        1.0,
    )?;
    let a = vec3(
        path,
        ln,
        line,
        fields,
        [4, 5, 6],
        ["dvel_x", "dvel_y", "dvel_z"],
        1.0,
    )?;
    Ok(Some((t + offset, g, a)))
}

pub(super) fn csv_kind(o: &CsvImuOptions) -> CsvKind {
    let (time_factor, units_per_s) = match o.time_unit {
        TimeUnit::Seconds => (1.0, 1),
        TimeUnit::Milliseconds => (1e-3, 1_000),
        TimeUnit::Microseconds => (1e-6, 1_000_000),
        TimeUnit::Nanoseconds => (1e-9, 1_000_000_000),
    };
    let gyro_factor = match o.gyro_unit {
        GyroUnit::Rad => 1.0,
        GyroUnit::Deg => std::f64::consts::PI / 180.0,
    };
    let accel_factor = match o.accel_unit {
        AccelUnit::Metre => 1.0,
        AccelUnit::G => STANDARD_GRAVITY,
    };
    let min_cols = 1 + o
        .gyro_cols
        .iter()
        .chain(o.accel_cols.iter())
        .copied()
        .fold(o.time_col, usize::max);
    let what = format!(
        "0-based: time in column {}, gyro in {} {} {}, accel in {} {} {}",
        o.time_col,
        o.gyro_cols[0],
        o.gyro_cols[1],
        o.gyro_cols[2],
        o.accel_cols[0],
        o.accel_cols[1],
        o.accel_cols[2]
    );
    CsvKind {
        opts: o.clone(),
        min_cols,
        what,
        time_factor,
        units_per_s,
        base: None,
        gyro_factor,
        accel_factor,
    }
}

/// For GPST-Unix CSV files: the GPS week of the first sample and where it starts in
/// the time column's units. None for a file without data lines.
pub(super) fn csv_time_base(
    path: &Path,
    k: &CsvKind,
    offset: f64,
) -> Result<Option<(u32, TimeBase)>, InputError> {
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::new();
    while let Some((ln, line)) = lines.next_line()? {
        if ln <= k.opts.skip_lines {
            continue;
        }
        split_fields(line, &mut fields);
        if is_comment_line(line, &fields) {
            continue;
        }
        if fields.len() < k.min_cols {
            return Err(InputError::columns(
                path,
                ln,
                format!("at least {}", k.min_cols),
                &k.what,
                fields.len(),
            ));
        }
        let v = num(path, ln, line, &fields, k.opts.time_col, "time")?;
        let unix_s = v * k.time_factor + offset;
        let (week, _) = gpst_unix_to_week_sow(unix_s).ok_or_else(|| {
            InputError::at_field(
                path,
                ln,
                "time",
                format!(
                    "expected GPST as Unix seconds after the GPS epoch (315964800 s), found \
                     {unix_s} s"
                ),
            )
        })?;
        let base_s = GPS_EPOCH_UNIX + i64::from(week) * SECONDS_PER_WEEK_I64;
        let units_i = base_s.saturating_mul(k.units_per_s);
        return Ok(Some((
            week,
            TimeBase {
                units_i,
                units_f: units_i as f64,
            },
        )));
    }
    Ok(None)
}

pub(super) fn parse_csv(
    path: &Path,
    ln: usize,
    line: &[u8],
    fields: &mut Vec<(usize, usize)>,
    k: &CsvKind,
    offset: f64,
) -> Result<Option<Raw>, InputError> {
    if ln <= k.opts.skip_lines {
        return Ok(None);
    }
    split_fields(line, fields);
    if is_comment_line(line, fields) {
        return Ok(None);
    }
    if fields.len() < k.min_cols {
        return Err(InputError::columns(
            path,
            ln,
            format!("at least {}", k.min_cols),
            &k.what,
            fields.len(),
        ));
    }
    let text = field(line, fields, k.opts.time_col);
    let t = match k.base {
        Some(base) => match parse_i64(text).and_then(|i| i.checked_sub(base.units_i)) {
            Some(d) => d as f64 * k.time_factor,
            None => {
                let v = num(path, ln, line, fields, k.opts.time_col, "time")?;
                (v - base.units_f) * k.time_factor
            }
        },
        None => num(path, ln, line, fields, k.opts.time_col, "time")? * k.time_factor,
    };
    let g = vec3(
        path,
        ln,
        line,
        fields,
        k.opts.gyro_cols,
        ["gyro_x", "gyro_y", "gyro_z"],
        k.gyro_factor,
    )?;
    let a = vec3(
        path,
        ln,
        line,
        fields,
        k.opts.accel_cols,
        ["accel_x", "accel_y", "accel_z"],
        k.accel_factor,
    )?;
    Ok(Some((t + offset, g, a)))
}

pub(super) struct RtkScan {
    pub(super) first_line: usize,
    pub(super) last_line: usize,
    pub(super) c0: f64,
    pub(super) c0_line: usize,
    pub(super) c_last: f64,
    pub(super) c_last_line: usize,
}

/// First and last non-blank lines, and the first and last counter values of 7-column
/// lines.
pub(super) fn rtk_prescan(path: &Path) -> Result<RtkScan, InputError> {
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::new();
    let mut first_line = 0;
    let mut last_line = 0;
    let mut first_c: Option<(f64, usize)> = None;
    let mut last_c: Option<(f64, usize)> = None;
    while let Some((ln, line)) = lines.next_line()? {
        split_fields(line, &mut fields);
        if fields.is_empty() {
            continue;
        }
        if first_line == 0 {
            first_line = ln;
        }
        last_line = ln;
        if fields.len() == 7 {
            if let Some(c) = parse_f64(field(line, &fields, 6)).filter(|c| c.is_finite()) {
                if first_c.is_none() {
                    first_c = Some((c, ln));
                }
                last_c = Some((c, ln));
            }
        }
    }
    match (first_c, last_c) {
        (Some((c0, c0_line)), Some((c_last, c_last_line))) => Ok(RtkScan {
            first_line,
            last_line,
            c0,
            c0_line,
            c_last,
            c_last_line,
        }),
        _ => Err(InputError::new(
            path,
            "expected lines of 7 columns (ax ay az [g], gx gy gz [deg/s], counter [ms]), \
             found none",
        )),
    }
}

pub(super) enum RtkLine {
    Sample(Raw),
    Truncated,
    Blank,
}

pub(super) fn parse_rtk(
    path: &Path,
    ln: usize,
    line: &[u8],
    fields: &mut Vec<(usize, usize)>,
    k: &RtkKind,
    offset: f64,
) -> Result<RtkLine, InputError> {
    split_fields(line, fields);
    if fields.is_empty() {
        return Ok(RtkLine::Blank);
    }
    if fields.len() != 7 {
        if fields.len() < 7 && (ln == k.first_line || ln == k.last_line) {
            return Ok(RtkLine::Truncated);
        }
        return Err(InputError::columns(
            path,
            ln,
            7,
            "ax ay az [g], gx gy gz [deg/s], counter [ms]; only the first or last line may \
             be truncated",
            fields.len(),
        ));
    }
    let a = vec3(
        path,
        ln,
        line,
        fields,
        [0, 1, 2],
        ["ax", "ay", "az"],
        STANDARD_GRAVITY,
    )?;
    let g = vec3(
        path,
        ln,
        line,
        fields,
        [3, 4, 5],
        ["gx", "gy", "gz"],
        std::f64::consts::PI / 180.0,
    )?;
    let c = num(path, ln, line, fields, 6, "counter")?;
    let t = k.sow0 + (c - k.c0) * k.s_per_count + offset;
    Ok(RtkLine::Sample((t, g, a)))
}
