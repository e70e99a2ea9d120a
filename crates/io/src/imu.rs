//! Streaming IMU readers: KF-GINS text, generic CSV, rtklibexplorer raw log.
//!
//! Every format becomes a stream of [`ImuSample`]s: angle and velocity increments in
//! the body frame over (t - dt, t], with `t` in seconds of the GPS week of the first
//! sample (continuing past 604800 if the data cross a week; seconds-of-week inputs keep
//! their tags). See docs/FORMATS.md.
//!
//! Common rules, all formats:
//! - `time_offset_s` is added to every tag;
//! - a sample with the same tag as the previous one is dropped and counted
//!   ([`ImuReport::duplicates`]); a tag smaller than the previous one is an error;
//! - dt = t_k - t_{k-1}; the first sample gets dt = 1 / rate_hz; after a gap > 0.1 s
//!   it depends on [`GapPolicy`]: `Bridge` (default) keeps the real interval and holds
//!   the sample over it (rates: w_k * dt; increments, taken to cover one nominal
//!   interval: scaled by interval * rate_hz), a gap above `max_s` is an error;
//!   `Nominal` uses dt = 1 / rate_hz and the increment as read (the KF-GINS rule);
//!   intervals longer than 1.5 / rate_hz are listed in [`ImuReport::gaps`], bridged
//!   gaps also in a warning;
//! - rates become increments: instantaneous rates by the trapezoid
//!   (w_{k-1} + w_k) / 2 * dt over the interval ending at t_k (the first sample only
//!   seeds w_{k-1}; after a gap > 0.1 s, w_k * dt), interval-mean rates as w_k * dt;
//! - every value must stay finite after unit scaling;
//! - a damaged last line without line end (a log cut mid-write) is dropped with a
//!   warning
//!   ([`ImuReport::warnings`]); damage elsewhere is an error;
//! - increments are rotated to the body frame: v_body = Rz(yaw) Ry(pitch) Rx(roll)
//!   v_sensor with `sensor_to_body_rpy_deg`.

use crate::error::InputError;
use crate::fmt::{
    field, is_comment_line, parse_f64, parse_first_n, parse_i64, split_fields, LineReader,
};
use crate::input::{
    AccelUnit, CsvImuOptions, GapPolicy, GyroUnit, ImuFormat, ImuQuantity, ImuSource, RateSampling,
    TimeScale, TimeUnit,
};
use crate::time::{gpst_unix_to_week_sow, GPS_EPOCH_UNIX, SECONDS_PER_WEEK_I64};
use crate::timetag::read_timetag;
use nalgebra::{Matrix3, Vector3};
use navfuse_core::attitude::c_bn_from_euler;
use navfuse_core::ImuSample;
use std::fmt;
use std::path::{Path, PathBuf};

/// Standard gravity [m/s²], the unit `g` of accelerometer columns.
pub const STANDARD_GRAVITY: f64 = 9.80665;
/// How many duplicate time tags are kept for the report.
pub const MAX_DUPLICATE_TIMES: usize = 5;
/// Intervals longer than this use dt = 1 / rate_hz (KF-GINS).
pub const MAX_DT_S: f64 = 0.1;

/// What happened while reading an IMU file. Complete once the reader is exhausted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImuReport {
    /// The file.
    pub path: PathBuf,
    /// Lines read (all lines, including headers and blank lines).
    pub lines: usize,
    /// Samples returned.
    pub samples: usize,
    /// Header lines (`skip_lines`), blank lines and `#` / `%` comment lines.
    pub skipped_lines: usize,
    /// Truncated first / last lines skipped (rtklibexplorer logs).
    pub truncated_lines: usize,
    /// Samples dropped because their time tag equals the previous one.
    pub duplicates: usize,
    /// The first few (at most [`MAX_DUPLICATE_TIMES`]) duplicate time tags [s].
    pub duplicate_times: Vec<f64>,
    /// Intervals (t_{k-1}, t_k) longer than 1.5 / rate_hz [s].
    pub gaps: Vec<(f64, f64)>,
    /// Nominal sample interval 1 / rate_hz [s].
    pub nominal_dt: f64,
    /// Time tag of the first sample read (after the offset) [s].
    pub first_t: Option<f64>,
    /// Time tag of the last sample read [s].
    pub last_t: Option<f64>,
    /// What was done with intervals longer than [`MAX_DT_S`].
    pub gap_policy: GapPolicy,
    /// Findings that did not stop the read: a damaged last line dropped, gaps bridged.
    pub warnings: Vec<String>,
}

impl fmt::Display for ImuReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} lines, {} samples",
            self.path.display(),
            self.lines,
            self.samples
        )?;
        if let (Some(a), Some(b)) = (self.first_t, self.last_t) {
            write!(f, " from t = {a:.3} to {b:.3} s ({:.3} s)", b - a)?;
        }
        if self.skipped_lines > 0 {
            write!(
                f,
                "; {} header/blank/comment lines skipped",
                self.skipped_lines
            )?;
        }
        if self.truncated_lines > 0 {
            write!(
                f,
                "; {} truncated first/last lines skipped",
                self.truncated_lines
            )?;
        }
        if self.duplicates > 0 {
            write!(
                f,
                "; {} samples with a repeated time tag dropped (first at",
                self.duplicates
            )?;
            for (k, t) in self.duplicate_times.iter().enumerate() {
                write!(f, "{}{t:.3}", if k == 0 { " " } else { ", " })?;
            }
            if self.duplicates > self.duplicate_times.len() {
                f.write_str(", ...")?;
            }
            f.write_str(" s)")?;
        } else {
            f.write_str("; no duplicate time tags")?;
        }
        if self.gaps.is_empty() {
            write!(
                f,
                "; no gaps longer than {:.1} ms",
                1500.0 * self.nominal_dt
            )?;
        } else {
            let longest = self.gaps.iter().copied().fold((0.0, 0.0), |acc, g| {
                if g.1 - g.0 > acc.1 - acc.0 {
                    g
                } else {
                    acc
                }
            });
            let over = self.gaps.iter().filter(|g| g.1 - g.0 > MAX_DT_S).count();
            write!(
                f,
                "; {} gaps longer than {:.1} ms (nominal {:.1} ms), longest {:.3} s from \
                 t = {:.3}",
                self.gaps.len(),
                1500.0 * self.nominal_dt,
                1000.0 * self.nominal_dt,
                longest.1 - longest.0,
                longest.0
            )?;
            if over > 0 {
                match self.gap_policy {
                    GapPolicy::Nominal => {
                        write!(f, "; {over} longer than {MAX_DT_S} s use dt = 1/rate")?
                    }
                    GapPolicy::Bridge { .. } => write!(
                        f,
                        "; {over} longer than {MAX_DT_S} s bridged with dt = the real interval"
                    )?,
                }
            }
        }
        f.write_str(".")?;
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        Ok(())
    }
}

/// How many bridged gaps a warning lists.
const MAX_LISTED_GAPS: usize = 5;

impl ImuReport {
    /// The warning listing the gaps bridged (longer than [`MAX_DT_S`]), if any.
    fn bridged_gaps_warning(&self) -> Option<String> {
        let long: Vec<&(f64, f64)> = self.gaps.iter().filter(|g| g.1 - g.0 > MAX_DT_S).collect();
        if long.is_empty() || self.gap_policy == GapPolicy::Nominal {
            return None;
        }
        let mut w = format!(
            "{}: {} gaps longer than {MAX_DT_S} s bridged by dead reckoning over their real \
             length (imu.gap_policy = \"bridge\"):",
            self.path.display(),
            long.len()
        );
        for (k, g) in long.iter().take(MAX_LISTED_GAPS).enumerate() {
            let sep = if k == 0 { " " } else { ", " };
            w.push_str(&format!("{sep}{:.3} s from t = {:.3}", g.1 - g.0, g.0));
        }
        if long.len() > MAX_LISTED_GAPS {
            w.push_str(", ...");
        }
        Some(w)
    }
}

/// Where the week of a GPST-as-Unix time column starts, in the column's units.
#[derive(Clone, Copy, Debug)]
struct TimeBase {
    units_i: i64,
    units_f: f64,
}

struct CsvKind {
    opts: CsvImuOptions,
    min_cols: usize,
    what: String,
    time_factor: f64,
    units_per_s: i64,
    base: Option<TimeBase>,
    gyro_factor: f64,
    accel_factor: f64,
}

struct RtkKind {
    first_line: usize,
    last_line: usize,
    c0: f64,
    sow0: f64,
    s_per_count: f64,
}

enum Kind {
    KfGins,
    Csv(Box<CsvKind>),
    Rtk(RtkKind),
}

/// One raw sample: time [s] (offset applied), gyro and accel in SI per-unit values
/// (rad/s and m/s² for rates; rad and m/s for increments), sensor frame.
type Raw = (f64, Vector3<f64>, Vector3<f64>);

/// Streaming IMU reader; see the module documentation. Yields `Err` once and then
/// stops at the first bad line.
pub struct ImuReader {
    lines: LineReader,
    path: PathBuf,
    kind: Kind,
    nominal_dt: f64,
    offset: f64,
    rot: Option<Matrix3<f64>>,
    quantity: ImuQuantity,
    sampling: RateSampling,
    gps_week: Option<u32>,
    prev_t: Option<f64>,
    prev_rate: Option<(Vector3<f64>, Vector3<f64>)>,
    gap_policy: GapPolicy,
    fields: Vec<(usize, usize)>,
    report: ImuReport,
    done: bool,
}

/// Open an IMU source; checks the source description and, for rtklibexplorer logs,
/// reads the tag file and pre-scans the counters.
pub fn open_imu(src: &ImuSource) -> Result<ImuReader, InputError> {
    let path = src.path.as_path();
    if !src.time_offset_s.is_finite() {
        return Err(InputError::new(
            path,
            format!("time_offset_s must be finite, found {}", src.time_offset_s),
        )
        .with_field("time_offset_s"));
    }
    if src.sensor_to_body_rpy_deg.iter().any(|a| !a.is_finite()) {
        return Err(InputError::new(
            path,
            format!(
                "sensor_to_body_rpy_deg must be finite, found {:?}",
                src.sensor_to_body_rpy_deg
            ),
        )
        .with_field("sensor_to_body_rpy_deg"));
    }
    let rpy = Vector3::from(src.sensor_to_body_rpy_deg).map(f64::to_radians);
    let rot = if rpy.iter().all(|&a| a == 0.0) {
        None
    } else {
        Some(c_bn_from_euler(&rpy))
    };
    let rate_hz = crate::error::check_scale("rate_hz", src.rate_hz, src.rate_hz)
        .map_err(|m| InputError::new(path, m).with_field("rate_hz"))?;
    if let GapPolicy::Bridge { max_s: Some(m) } = src.gap_policy {
        crate::error::check_scale("max_bridge_s", m, m)
            .map_err(|m| InputError::new(path, m).with_field("max_bridge_s"))?;
    }
    let lines = LineReader::open(path)?;
    let nominal_dt = 1.0 / rate_hz;
    let mut gps_week = None;
    let (kind, quantity, sampling) = match &src.format {
        ImuFormat::KfGins => (Kind::KfGins, ImuQuantity::Increment, RateSampling::Instant),
        ImuFormat::Csv(o) => {
            let mut k = csv_kind(o);
            if o.time_scale == TimeScale::GpstUnix {
                if let Some((week, base)) = csv_time_base(path, &k, src.time_offset_s)? {
                    gps_week = Some(week);
                    k.base = Some(base);
                }
            }
            (Kind::Csv(Box::new(k)), o.quantity, o.rate_sampling)
        }
        ImuFormat::RtklibExplorer(o) => {
            let tag = read_timetag(&o.tag_path)?;
            let scan = rtk_prescan(path)?;
            let span = scan.c_last - scan.c0;
            if span <= 0.0 {
                return Err(InputError::new(
                    path,
                    format!(
                        "the counter does not advance (first {} at line {}, last {} at line \
                         {}): cannot map it to the tag file's time span",
                        scan.c0, scan.c0_line, scan.c_last, scan.c_last_line
                    ),
                ));
            }
            gps_week = Some(tag.start_week);
            let kind = Kind::Rtk(RtkKind {
                first_line: scan.first_line,
                last_line: scan.last_line,
                c0: scan.c0,
                sow0: tag.start_sow,
                s_per_count: f64::from(tag.last_tick_ms) * 1e-3 / span,
            });
            (kind, ImuQuantity::Rate, RateSampling::Instant)
        }
    };
    Ok(ImuReader {
        lines,
        path: path.to_path_buf(),
        kind,
        nominal_dt,
        offset: src.time_offset_s,
        rot,
        quantity,
        sampling,
        gps_week,
        prev_t: None,
        prev_rate: None,
        gap_policy: src.gap_policy,
        fields: Vec::with_capacity(16),
        report: ImuReport {
            path: path.to_path_buf(),
            nominal_dt,
            gap_policy: src.gap_policy,
            ..ImuReport::default()
        },
        done: false,
    })
}

impl ImuReader {
    /// GPS week that `t` counts from; None for seconds-of-week inputs (KF-GINS, CSV with
    /// `GpsSecondsOfWeek`) and for an empty GPST-Unix CSV file.
    pub fn gps_week(&self) -> Option<u32> {
        self.gps_week
    }

    /// What happened so far (complete once the iterator has returned None).
    pub fn report(&self) -> &ImuReport {
        &self.report
    }

    /// Read lines until one gives a sample, the file ends or an error occurs. An error
    /// on the last line drops it with a warning.
    fn read_sample(&mut self) -> Result<Option<ImuSample>, InputError> {
        loop {
            let Some((ln, line)) = self.lines.next_line()? else {
                self.finish();
                return Ok(None);
            };
            self.report.lines += 1;
            let raw = match &self.kind {
                Kind::KfGins => parse_kfgins(&self.path, ln, line, &mut self.fields, self.offset),
                Kind::Csv(k) => parse_csv(&self.path, ln, line, &mut self.fields, k, self.offset),
                Kind::Rtk(k) => {
                    match parse_rtk(&self.path, ln, line, &mut self.fields, k, self.offset) {
                        Ok(RtkLine::Sample(r)) => Ok(Some(r)),
                        Ok(RtkLine::Truncated) => {
                            self.report.truncated_lines += 1;
                            continue;
                        }
                        Ok(RtkLine::Blank) => Ok(None),
                        Err(e) => Err(e),
                    }
                }
            };
            let r = match raw {
                Ok(Some((t, g, a))) => self.process(ln, t, g, a),
                Ok(None) => {
                    self.report.skipped_lines += 1;
                    continue;
                }
                Err(e) => Err(e),
            };
            match r {
                Ok(Some(s)) => return Ok(Some(s)),
                Ok(None) => {}
                Err(e) if e.line == Some(ln) && self.lines.cut_last_line() => {
                    self.report.truncated_lines += 1;
                    self.report.warnings.push(e.last_line_warning());
                    self.finish();
                    return Ok(None);
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// End of the file: the gap warning.
    fn finish(&mut self) {
        if let Some(w) = self.report.bridged_gaps_warning() {
            self.report.warnings.push(w);
        }
    }

    /// Time checks, dt, rate integration and rotation for one raw sample.
    fn process(
        &mut self,
        ln: usize,
        t: f64,
        g: Vector3<f64>,
        a: Vector3<f64>,
    ) -> Result<Option<ImuSample>, InputError> {
        if !t.is_finite() {
            return Err(InputError::at_field(
                &self.path,
                ln,
                "time",
                format!("time tag {t} s after the offset: expected a finite time"),
            ));
        }
        // Increments scale with the interval they are held over (bridged gaps).
        let mut hold = 1.0;
        let (dt, after_gap) = match self.prev_t {
            Some(pt) => {
                if t == pt {
                    self.report.duplicates += 1;
                    if self.report.duplicate_times.len() < MAX_DUPLICATE_TIMES {
                        self.report.duplicate_times.push(t);
                    }
                    return Ok(None);
                }
                if t < pt {
                    return Err(InputError::backwards(&self.path, ln, t, pt));
                }
                let interval = t - pt;
                if interval > 1.5 * self.nominal_dt {
                    self.report.gaps.push((pt, t));
                }
                if interval > MAX_DT_S {
                    match self.gap_policy {
                        GapPolicy::Nominal => (self.nominal_dt, true),
                        GapPolicy::Bridge { max_s } => {
                            if let Some(m) =
                                max_s.filter(|m| interval > *m || !interval.is_finite())
                            {
                                return Err(InputError::at_field(
                                    &self.path,
                                    ln,
                                    "time",
                                    format!(
                                        "gap of {interval} s from t = {pt} to {t} is longer \
                                         than imu.max_bridge_s = {m} s: split the run at the \
                                         gap, or raise imu.max_bridge_s"
                                    ),
                                ));
                            }
                            if !(interval * interval).is_finite() {
                                return Err(InputError::at_field(
                                    &self.path,
                                    ln,
                                    "time",
                                    format!("gap of {interval} s from t = {pt} to {t} is too long to bridge"),
                                ));
                            }
                            hold = interval / self.nominal_dt;
                            (interval, true)
                        }
                    }
                } else {
                    (interval, false)
                }
            }
            None => {
                self.report.first_t = Some(t);
                (self.nominal_dt, true)
            }
        };
        let first = self.prev_t.is_none();
        self.prev_t = Some(t);
        self.report.last_t = Some(t);
        let (mut dtheta, mut dvel) = match (self.quantity, self.sampling) {
            (ImuQuantity::Increment, _) => (g * hold, a * hold),
            (ImuQuantity::Rate, RateSampling::IntervalMean) => (g * dt, a * dt),
            (ImuQuantity::Rate, RateSampling::Instant) => {
                let prev = self.prev_rate.replace((g, a));
                match prev {
                    _ if first => return Ok(None),
                    Some((pg, pa)) if !after_gap => ((pg + g) * (0.5 * dt), (pa + a) * (0.5 * dt)),
                    _ => (g * dt, a * dt),
                }
            }
        };
        if let Some(r) = &self.rot {
            dtheta = r * dtheta;
            dvel = r * dvel;
        }
        if let Some(v) = dtheta.iter().chain(dvel.iter()).find(|v| !v.is_finite()) {
            return Err(InputError::at_line(
                &self.path,
                ln,
                format!("the increment over dt = {dt} s is {v}: expected finite values"),
            ));
        }
        self.report.samples += 1;
        Ok(Some(ImuSample {
            t,
            dt,
            dtheta,
            dvel,
        }))
    }
}

impl Iterator for ImuReader {
    type Item = Result<ImuSample, InputError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.read_sample() {
            Ok(Some(s)) => Some(Ok(s)),
            Ok(None) => {
                self.done = true;
                None
            }
            Err(e) => {
                self.done = true;
                Some(Err(e))
            }
        }
    }
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

fn parse_kfgins(
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

fn csv_kind(o: &CsvImuOptions) -> CsvKind {
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
fn csv_time_base(
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

fn parse_csv(
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

struct RtkScan {
    first_line: usize,
    last_line: usize,
    c0: f64,
    c0_line: usize,
    c_last: f64,
    c_last_line: usize,
}

/// First and last non-blank lines, and the first and last counter values of 7-column
/// lines.
fn rtk_prescan(path: &Path) -> Result<RtkScan, InputError> {
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

enum RtkLine {
    Sample(Raw),
    Truncated,
    Blank,
}

fn parse_rtk(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::RtklibExplorerImuOptions;

    fn tmp(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("navfuse-imu-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn csv_opts(quantity: ImuQuantity, sampling: RateSampling) -> CsvImuOptions {
        CsvImuOptions {
            skip_lines: 1,
            time_col: 0,
            gyro_cols: [1, 2, 3],
            accel_cols: [4, 5, 6],
            time_unit: TimeUnit::Seconds,
            time_scale: TimeScale::GpsSecondsOfWeek,
            quantity,
            rate_sampling: sampling,
            gyro_unit: GyroUnit::Rad,
            accel_unit: AccelUnit::Metre,
        }
    }

    fn src(path: PathBuf, format: ImuFormat, rate: f64) -> ImuSource {
        ImuSource {
            path,
            format,
            rate_hz: rate,
            sensor_to_body_rpy_deg: [0.0; 3],
            time_offset_s: 0.0,
            gap_policy: GapPolicy::Nominal,
        }
    }

    /// A rate growing linearly in time, w(t) = c0 + c1 t, sampled instantaneously at
    /// uneven tags, must integrate exactly with the trapezoid over each (t_{k-1}, t_k],
    /// with no half-interval shift.
    #[test]
    fn instant_rates_integrate_linear_rate_exactly() {
        let tags = [100.0, 100.01, 100.018, 100.029, 100.04, 100.05];
        let w = |t: f64| 0.3 + 2.0 * (t - 100.0);
        let mut text = String::from("t,gx,gy,gz,ax,ay,az\n");
        for &t in &tags {
            text += &format!(
                "{t},{},{},{},{},{},{}\n",
                w(t),
                -w(t),
                0.0,
                9.0 * w(t),
                0.0,
                1.0
            );
        }
        let p = tmp("linear.csv", &text);
        let s = src(
            p,
            ImuFormat::Csv(csv_opts(ImuQuantity::Rate, RateSampling::Instant)),
            100.0,
        );
        let out: Vec<ImuSample> = open_imu(&s).unwrap().map(|r| r.unwrap()).collect();
        assert_eq!(out.len(), tags.len() - 1, "first sample only seeds");
        for (k, smp) in out.iter().enumerate() {
            let (t0, t1) = (tags[k], tags[k + 1]);
            // Exact integral of w over (t0, t1].
            let exact = 0.3 * (t1 - t0) + ((t1 - 100.0).powi(2) - (t0 - 100.0).powi(2));
            assert_eq!(smp.t, t1);
            assert!((smp.dt - (t1 - t0)).abs() < 1e-12);
            assert!((smp.dtheta.x - exact).abs() < 1e-12, "{k}");
            assert!((smp.dtheta.y + exact).abs() < 1e-12);
            assert!((smp.dvel.x - 9.0 * exact).abs() < 1e-12);
            assert!((smp.dvel.z - (t1 - t0)).abs() < 1e-12);
        }
    }

    #[test]
    fn interval_mean_and_units() {
        let text = "# header\n1.000,10,0,0,0,0,1\n1.010,10,0,0,0,0,1\n";
        let p = tmp("mean.csv", text);
        let mut o = csv_opts(ImuQuantity::Rate, RateSampling::IntervalMean);
        o.gyro_unit = GyroUnit::Deg;
        o.accel_unit = AccelUnit::G;
        let out: Vec<ImuSample> = open_imu(&src(p, ImuFormat::Csv(o), 100.0))
            .unwrap()
            .map(|r| r.unwrap())
            .collect();
        assert_eq!(out.len(), 2);
        for s in &out {
            assert!((s.dt - 0.01).abs() < 1e-12);
            assert!((s.dtheta.x - 10f64.to_radians() * 0.01).abs() < 1e-15);
            assert!((s.dvel.z - STANDARD_GRAVITY * 0.01).abs() < 1e-15);
        }
    }

    #[test]
    fn rotation_gaps_and_dt_rule() {
        // KF-GINS increments; roll 180 deg flips y and z.
        let text = "10.00 0.1 0.2 0.3 1 2 3\n10.01 0.1 0.2 0.3 1 2 3\n10.03 0.1 0.2 0.3 1 2 3\n\
                    10.50 0.1 0.2 0.3 1 2 3\n10.50 9 9 9 9 9 9\n10.51 0.1 0.2 0.3 1 2 3\n";
        let p = tmp("kf.txt", text);
        let mut s = src(p, ImuFormat::KfGins, 100.0);
        s.sensor_to_body_rpy_deg = [180.0, 0.0, 0.0];
        s.time_offset_s = 0.5;
        let mut r = open_imu(&s).unwrap();
        assert_eq!(r.gps_week(), None);
        let out: Vec<ImuSample> = r.by_ref().map(|x| x.unwrap()).collect();
        let dts: Vec<f64> = out.iter().map(|s| s.dt).collect();
        let want = [0.01, 0.01, 0.02, 0.01, 0.01];
        assert_eq!(out.len(), want.len());
        for (a, b) in dts.iter().zip(want) {
            assert!((a - b).abs() < 1e-9, "{dts:?}");
        }
        assert!((out[0].t - 10.5).abs() < 1e-12);
        assert!((out[0].dtheta - Vector3::new(0.1, -0.2, -0.3)).norm() < 1e-12);
        assert!((out[0].dvel - Vector3::new(1.0, -2.0, -3.0)).norm() < 1e-12);
        let rep = r.report();
        assert_eq!(rep.duplicates, 1);
        assert_eq!(rep.gaps.len(), 2);
        assert_eq!(rep.samples, 5);
        assert_eq!(rep.lines, 6);
        let msg = rep.to_string();
        assert!(
            msg.contains("1 samples with a repeated time tag dropped"),
            "{msg}"
        );
    }

    #[test]
    fn gpst_unix_csv_time_and_week() {
        // Week 2374 starts at Unix-GPST 315964800 + 2374*604800; put samples 1 ms
        // before the end of the week and across it, in nanoseconds.
        let base = (315_964_800i64 + 2374 * 604_800) * 1_000_000_000;
        let end = base + 604_800 * 1_000_000_000;
        let mut text = String::from("h\n");
        for k in -2i64..3 {
            let t = end + k * 5_000_000; // 200 Hz
            text += &format!("{t} 0 0 0 0 0 0\n");
        }
        let p = tmp("ns.csv", &text);
        let mut o = csv_opts(ImuQuantity::Increment, RateSampling::Instant);
        o.time_unit = TimeUnit::Nanoseconds;
        o.time_scale = TimeScale::GpstUnix;
        let mut r = open_imu(&src(p, ImuFormat::Csv(o), 200.0)).unwrap();
        assert_eq!(r.gps_week(), Some(2374));
        let ts: Vec<f64> = r.by_ref().map(|s| s.unwrap().t).collect();
        assert_eq!(
            ts,
            vec![604_799.99, 604_799.995, 604_800.0, 604_800.005, 604_800.01]
        );
    }

    #[test]
    fn rtk_truncated_lines_and_mapping() {
        let dir = std::env::temp_dir().join(format!("navfuse-imu-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = "1.0,0.0,0.0,0.0,0.0,100\n\
                   0,0,1,0,0,0,1000\n0,0,1,0,0,0,1010\n0,0,1,0,0,0,1010\n0,0,1,0,0,0,1020\n\
                   0,0,1,0,0,0\n";
        let p = tmp("rtk.csv", csv);
        // Tag: start at week 2374 sow 1000.5, last tick 40 ms (the counter spans 20).
        let mut tag = vec![0u8; 60];
        tag[..7].copy_from_slice(b"TIMETAG");
        tag.extend_from_slice(&0u32.to_le_bytes());
        let whole = (315_964_800i64 + 2374 * 604_800 + 1000) as u32;
        tag.extend_from_slice(&whole.to_le_bytes());
        tag.extend_from_slice(&0.5f64.to_le_bytes());
        for t in [0u32, 40] {
            tag.extend_from_slice(&t.to_le_bytes());
            tag.extend_from_slice(&0u32.to_le_bytes());
        }
        let tp = dir.join("rtk.csv.tag");
        std::fs::write(&tp, tag).unwrap();
        let fmt = ImuFormat::RtklibExplorer(RtklibExplorerImuOptions { tag_path: tp });
        let mut r = open_imu(&src(p.clone(), fmt.clone(), 100.0)).unwrap();
        assert_eq!(r.gps_week(), Some(2374));
        let out: Vec<ImuSample> = r.by_ref().map(|x| x.unwrap()).collect();
        assert_eq!(out.len(), 2);
        assert!((out[0].t - 1000.52).abs() < 1e-9);
        assert!((out[1].t - 1000.54).abs() < 1e-9);
        assert!((out[1].dvel.z - STANDARD_GRAVITY * 0.02).abs() < 1e-12);
        assert_eq!(r.report().truncated_lines, 2);
        assert_eq!(r.report().duplicates, 1);

        // A short line in the middle is an error naming the line.
        let csv = "0,0,1,0,0,0,1000\n0,0,1,0,0,1010\n0,0,1,0,0,0,1020\n";
        std::fs::write(&p, csv).unwrap();
        let errs: Vec<_> = open_imu(&src(p, fmt, 100.0)).unwrap().collect();
        let e = errs.last().unwrap().as_ref().unwrap_err().to_string();
        assert!(e.contains("rtk.csv:2: expected 7 columns"), "{e}");
    }
}
