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

use self::parse::{
    csv_kind, csv_time_base, parse_csv, parse_kfgins, parse_rtk, rtk_prescan, Kind, RtkKind,
    RtkLine,
};
use crate::error::InputError;
use crate::fmt::LineReader;
use crate::input::{GapPolicy, ImuFormat, ImuQuantity, ImuSource, RateSampling, TimeScale};
use crate::timetag::read_timetag;
use nalgebra::{Matrix3, Vector3};
use navfuse_core::attitude::c_bn_from_euler;
use navfuse_core::ImuSample;
use std::path::PathBuf;

mod join;
mod parse;
mod report;
#[cfg(test)]
mod tests;

pub use report::ImuReport;

/// Standard gravity [m/s²], the unit `g` of accelerometer columns.
pub const STANDARD_GRAVITY: f64 = 9.80665;
/// How many duplicate time tags are kept for the report.
pub const MAX_DUPLICATE_TIMES: usize = 5;
/// Intervals longer than this use dt = 1 / rate_hz (KF-GINS).
pub const MAX_DT_S: f64 = 0.1;

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
    let lines = match &src.format {
        ImuFormat::CsvFiles(f) => {
            LineReader::from_reader(path, Box::new(std::io::Cursor::new(join::join(f)?)))
        }
        _ => LineReader::open(path)?,
    };
    let mut ulog_warnings = Vec::new();
    let mut source_note = None;
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
        ImuFormat::CsvFiles(f) => {
            if f.csv.time_scale == TimeScale::GpstUnix {
                return Err(InputError::new(
                    path,
                    "time_scale \"gpst_unix\" is not supported with several IMU files yet: \
                     expected \"gps_sow\"",
                )
                .with_field("time_scale"));
            }
            // The joined layout: t, gyro x y z, accel x y z.
            let o = crate::input::CsvImuOptions {
                skip_lines: 0,
                time_col: 0,
                gyro_cols: [1, 2, 3],
                accel_cols: [4, 5, 6],
                ..f.csv.clone()
            };
            (
                Kind::Csv(Box::new(csv_kind(&o))),
                o.quantity,
                o.rate_sampling,
            )
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
        ImuFormat::Ulog { multi_id } => {
            let u = crate::ulog::open(path, &mut ulog_warnings)?;
            let map = crate::ulog::TimeMap::of(&u);
            gps_week = map.week;
            let mut imu = crate::ulog::imu_rates(path, &u, *multi_id, &map)?;
            imu.samples
                .iter_mut()
                .for_each(|r| r.0 += src.time_offset_s);
            if imu.skipped > 0 {
                ulog_warnings.push(format!(
                    "{}: {}: {} records left out (no accelerometer sample, non-finite values or out of time order)",
                    path.display(),
                    imu.topics,
                    imu.skipped
                ));
            }
            let kind = Kind::Ulog(imu.samples.into_iter());
            (kind, ImuQuantity::Rate, imu.sampling)
        }
        ImuFormat::Ubx => {
            // ESF samples are instantaneous sensor readings: the trapezoid rule.
            let log = crate::ubx::read_ubx(path)?;
            let (mut raw, note) = crate::ubx::aiding::imu_rates(path, &log, &mut ulog_warnings)?;
            ulog_warnings.extend(log.warnings.iter().cloned());
            source_note = Some(note);
            gps_week = log.fix_week.and_then(|w| u32::try_from(w).ok());
            raw.iter_mut().for_each(|r| r.0 += src.time_offset_s);
            // Kind::Ulog: any list of records, "line" numbers counting them.
            (
                Kind::Ulog(raw.into_iter()),
                ImuQuantity::Rate,
                RateSampling::Instant,
            )
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
            warnings: ulog_warnings,
            source_note,
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
        if matches!(self.kind, Kind::Ulog(_)) {
            // ULog records: "line" numbers count records (1-based).
            while let Some((t, g, a)) = match &mut self.kind {
                Kind::Ulog(it) => it.next(),
                _ => None,
            } {
                self.report.lines += 1;
                let ln = self.report.lines;
                if let Some(s) = self.process(ln, t, g, a)? {
                    return Ok(Some(s));
                }
            }
            self.finish();
            return Ok(None);
        }
        loop {
            let Some((ln, line)) = self.lines.next_line()? else {
                self.finish();
                return Ok(None);
            };
            self.report.lines += 1;
            let raw = match &self.kind {
                Kind::KfGins => parse_kfgins(&self.path, ln, line, &mut self.fields, self.offset),
                Kind::Csv(k) => parse_csv(&self.path, ln, line, &mut self.fields, k, self.offset),
                Kind::Ulog(_) => Ok(None),
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
