//! GNSS readers: KF-GINS GNSS text and RTKLIB solution files (.pos, lat/lon/height).
//!
//! The whole file is validated (every number finite, lat in [-90, 90], lon in
//! [-360, 360], every position/velocity std > 0, time strictly increasing: an equal
//! time is a duplicate epoch and an error); then epochs are filtered by quality flag
//! (.pos only) and decimated. See docs/FORMATS.md.

use crate::error::InputError;
use crate::fmt::{field, for_each_line, parse_f64, split_fields, LineError, LineReader};
use crate::input::{GnssFormat, GnssSource, UbxGnss};
use crate::time::{calendar_to_week_sow, Calendar, SECONDS_PER_WEEK};
use nalgebra::Vector3;
use navfuse_core::GnssFix;
use std::path::Path;

/// What a GNSS file gave.
#[derive(Clone, Debug, PartialEq)]
pub struct GnssData {
    /// Kept fixes, time strictly increasing. `t` in seconds of `gps_week` (continuing
    /// past 604800 across a week), or the file's seconds of week when the week is
    /// unknown; `time_offset_s` added.
    pub fixes: Vec<GnssFix>,
    /// GPS week of the first epoch (.pos files); None for KF-GINS files.
    pub gps_week: Option<u32>,
    /// Valid epochs left out by the quality filter or by decimation.
    pub skipped: usize,
    /// Findings that did not stop the read (a damaged last line dropped).
    pub warnings: Vec<String>,
}

/// Tolerance of the decimation: an epoch is kept if within 1 ms of a multiple of
/// `decimate_s` [microseconds].
const DECIMATE_TOL_US: i64 = 1000;

/// One parsed and validated epoch, before filtering.
struct Epoch {
    /// File time in seconds of the reference week (no offset).
    t_file: f64,
    quality: Option<u8>,
    fix: GnssFix,
}

/// Read a GNSS source; see the module documentation.
pub fn read_gnss(src: &GnssSource) -> Result<GnssData, InputError> {
    let path = src.path.as_path();
    if !src.time_offset_s.is_finite() {
        return Err(InputError::new(
            path,
            format!("time_offset_s must be finite, found {}", src.time_offset_s),
        )
        .with_field("time_offset_s"));
    }
    let decimate_us = match src.decimate_s {
        None => None,
        Some(d) if (0.002..=1e6).contains(&d) => Some((d * 1e6).round() as i64),
        Some(d) => {
            return Err(InputError::new(
                path,
                format!("decimate_s must be between 0.002 and 1e6 s, found {d}"),
            )
            .with_field("decimate_s"))
        }
    };
    let mut warnings = Vec::new();
    let mut extra_skipped = 0;
    let (epochs, gps_week) = match &src.format {
        GnssFormat::KfGins => (read_kfgins(src, &mut warnings)?, None),
        GnssFormat::RtklibPos { .. } => read_pos(src, &mut warnings)?,
        GnssFormat::Ulog { multi_id } => {
            read_ulog(path, *multi_id, src.time_offset_s, &mut warnings)?
        }
        GnssFormat::Nmea(o) => {
            let d = crate::nmea::read_nmea(path, o)?;
            warnings.extend(d.warnings);
            extra_skipped = d.no_fix;
            (as_epochs(d.fixes, src.time_offset_s), d.gps_week)
        }
        GnssFormat::Csv(o) => {
            let (fixes, week) = crate::gnss_csv::read_csv_gnss(path, o, &mut warnings)?;
            (as_epochs(fixes, src.time_offset_s), week)
        }
        GnssFormat::Rinex(_) | GnssFormat::Ubx(UbxGnss::Raw(_)) => {
            return Err(InputError::new(
                path,
                "RINEX observations are not receiver fixes: they go through the GNSS layer (navfuse run does this)",
            )
            .with_field("format"))
        }
        GnssFormat::Ubx(UbxGnss::Pvt) => read_ubx_pvt(path, src.time_offset_s, &mut warnings)?,
    };
    let quality: &[u8] = match &src.format {
        GnssFormat::RtklibPos { quality } => quality,
        _ => &[],
    };
    let mut fixes = Vec::with_capacity(epochs.len());
    let mut skipped = extra_skipped;
    for e in epochs {
        let q_ok = quality.is_empty() || e.quality.is_some_and(|q| quality.contains(&q));
        let d_ok = match decimate_us {
            None => true,
            Some(d) => {
                let us = (e.t_file * 1e6).round() as i64;
                let r = us.rem_euclid(d);
                r <= DECIMATE_TOL_US || d - r <= DECIMATE_TOL_US
            }
        };
        if q_ok && d_ok {
            fixes.push(e.fix);
        } else {
            skipped += 1;
        }
    }
    Ok(GnssData {
        fixes,
        gps_week,
        skipped,
        warnings,
    })
}

/// Fixes of a reader that returns them whole (file times in `t`) as epochs, with
/// the source's time offset added.
fn as_epochs(fixes: Vec<GnssFix>, offset: f64) -> Vec<Epoch> {
    fixes
        .into_iter()
        .map(|f| Epoch {
            t_file: f.t,
            quality: None,
            fix: GnssFix {
                t: f.t + offset,
                ..f
            },
        })
        .collect()
}

/// The NAV-PVT fixes of a UBX log (crate::ubx), with the log's week.
fn read_ubx_pvt(
    path: &Path,
    offset: f64,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Epoch>, Option<u32>), InputError> {
    let log = crate::ubx::read_ubx(path)?;
    warnings.extend(log.warnings.iter().cloned());
    if log.fixes.is_empty() {
        return Err(InputError::new(
            path,
            format!("no valid NAV-PVT fix ({})", log.summary()),
        ));
    }
    let week = log.fix_week.and_then(|w| u32::try_from(w).ok());
    Ok((as_epochs(log.fixes.clone(), offset), week))
}

/// Field reader bound to one line.
struct Line<'a> {
    path: &'a Path,
    ln: usize,
    text: &'a [u8],
    fields: &'a [(usize, usize)],
}

impl Line<'_> {
    fn num(&self, k: usize, name: &str) -> Result<f64, InputError> {
        let text = field(self.text, self.fields, k);
        match parse_f64(text) {
            Some(v) if v.is_finite() => Ok(v),
            Some(v) => Err(InputError::not_finite(self.path, self.ln, name, v)),
            None => Err(InputError::not_a_number(self.path, self.ln, name, text)),
        }
    }

    fn std(&self, k: usize, name: &str) -> Result<f64, InputError> {
        let v = self.num(k, name)?;
        InputError::scale(self.path, self.ln, name, "std", v, v)
    }

    fn std3(&self, k: usize, names: [&str; 3]) -> Result<Vector3<f64>, InputError> {
        Ok(Vector3::new(
            self.std(k, names[0])?,
            self.std(k + 1, names[1])?,
            self.std(k + 2, names[2])?,
        ))
    }

    /// lat, lon [deg] -> checked, in radians; h [m].
    fn lla(&self, k: usize, names: [&str; 3]) -> Result<Vector3<f64>, InputError> {
        let lat = self.num(k, names[0])?;
        if !(-90.0..=90.0).contains(&lat) {
            return Err(InputError::at_field(
                self.path,
                self.ln,
                names[0],
                format!("expected a latitude in [-90, 90] deg, found {lat}"),
            ));
        }
        let lon = self.num(k + 1, names[1])?;
        if !(-360.0..=360.0).contains(&lon) {
            return Err(InputError::at_field(
                self.path,
                self.ln,
                names[1],
                format!("expected a longitude in [-360, 360] deg, found {lon}"),
            ));
        }
        let h = self.num(k + 2, names[2])?;
        Ok(Vector3::new(lat.to_radians(), lon.to_radians(), h))
    }

    /// Strictly increasing time: equal = duplicate epoch, smaller = backwards.
    fn check_time(&self, t: f64, prev: Option<f64>) -> Result<(), InputError> {
        match prev {
            Some(p) if t == p => Err(InputError::at_field(
                self.path,
                self.ln,
                "time",
                format!("duplicate epoch: time {t} repeats the previous epoch"),
            )),
            Some(p) if t < p => Err(InputError::backwards(self.path, self.ln, t, p)),
            _ => Ok(()),
        }
    }
}

fn read_kfgins(src: &GnssSource, warnings: &mut Vec<String>) -> Result<Vec<Epoch>, InputError> {
    let (path, offset) = (src.path.as_path(), src.time_offset_s);
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(16);
    let mut out = Vec::new();
    let mut prev: Option<f64> = None;
    let mut header = crate::fmt::SkipLines::new(src.skip_lines);
    for_each_line(&mut lines, warnings, |ln, text| {
        split_fields(text, &mut fields);
        if header.skip(ln, text, &fields) {
            return Ok(());
        }
        let l = Line {
            path,
            ln,
            text,
            fields: &fields,
        };
        let n = fields.len();
        if n != 7 && n != 13 {
            return Err(LineError::Data(InputError::columns(
                path,
                ln,
                "7 or 13",
                "t, lat lon h, std N E D [, vel N E D, vel std N E D]",
                n,
            )));
        }
        let t_file = l.num(0, "t")?;
        l.check_time(t_file, prev)?;
        let lla = l.lla(1, ["lat", "lon", "h"])?;
        let std_ned = l.std3(4, ["std_n", "std_e", "std_d"])?;
        let (vel_ned, vel_std_ned) = if n == 13 {
            let v = Vector3::new(l.num(7, "vn")?, l.num(8, "ve")?, l.num(9, "vd")?);
            let s = l.std3(10, ["vel_std_n", "vel_std_e", "vel_std_d"])?;
            (Some(v), Some(s))
        } else {
            (None, None)
        };
        prev = Some(t_file);
        out.push(Epoch {
            t_file,
            quality: None,
            fix: GnssFix {
                t: t_file + offset,
                lla,
                std_ned,
                vel_ned,
                vel_std_ned,
            },
        });
        Ok(())
    })?;
    Ok(out)
}

/// Check a `%` header line of a .pos file for solution forms we cannot read.
fn check_pos_header(path: &Path, ln: usize, text: &[u8]) -> Result<(), InputError> {
    let s = String::from_utf8_lossy(text);
    let first = s
        .trim_start_matches('%')
        .split_whitespace()
        .next()
        .unwrap_or("");
    // The column-name line, e.g. `%  GPST  latitude(deg) longitude(deg) height(m) Q ...`
    // (other header lines, such as `% (lat/lon/height=WGS84/ellipsoidal,...)`, pass).
    let is_column_header =
        s.contains("latitude(") || s.contains("x-ecef(") || s.contains("e-baseline(");
    if !is_column_header {
        return Ok(());
    }
    if s.contains("x-ecef(") || s.contains("e-baseline(") {
        return Err(InputError::at_line(
            path,
            ln,
            "expected a latitude/longitude/height solution, found ECEF or baseline columns \
             (set the RTKLIB solution format to lat/lon/height)",
        ));
    }
    if s.contains("latitude(d'") {
        return Err(InputError::at_line(
            path,
            ln,
            "expected latitude/longitude in degrees, found degrees-minutes-seconds",
        ));
    }
    if first != "GPST" {
        return Err(InputError::at_line(
            path,
            ln,
            format!("expected times in GPST, found \"{first}\" (set RTKLIB time format to GPST)"),
        ));
    }
    Ok(())
}

/// Parse `YYYY/MM/DD` `HH:MM:SS.sss` (GPST) into week and seconds of week.
fn parse_calendar(l: &Line<'_>) -> Result<(u32, f64), InputError> {
    let date = field(l.text, l.fields, 0);
    let time = field(l.text, l.fields, 1);
    let bad_date = || {
        InputError::at_field(
            l.path,
            l.ln,
            "date",
            format!(
                "expected a date YYYY/MM/DD, found \"{}\"",
                crate::error::shorten(date)
            ),
        )
    };
    let bad_time = || {
        InputError::at_field(
            l.path,
            l.ln,
            "time",
            format!(
                "expected a time of day HH:MM:SS.sss, found \"{}\"",
                crate::error::shorten(time)
            ),
        )
    };
    let int = |b: &[u8]| -> Option<i64> { crate::fmt::parse_i64(b).filter(|v| *v >= 0) };
    let mut d = date.split(|&b| b == b'/');
    let (Some(y), Some(mo), Some(dd), None) = (d.next(), d.next(), d.next(), d.next()) else {
        return Err(bad_date());
    };
    let (Some(y), Some(mo), Some(dd)) = (int(y), int(mo), int(dd)) else {
        return Err(bad_date());
    };
    let mut t = time.split(|&b| b == b':');
    let (Some(h), Some(mi), Some(s), None) = (t.next(), t.next(), t.next(), t.next()) else {
        return Err(bad_time());
    };
    let (Some(h), Some(mi), Some(s)) = (int(h), int(mi), parse_f64(s)) else {
        return Err(bad_time());
    };
    let cal = Calendar {
        year: y,
        month: u32::try_from(mo).unwrap_or(0),
        day: u32::try_from(dd).unwrap_or(0),
        hour: u32::try_from(h).unwrap_or(99),
        minute: u32::try_from(mi).unwrap_or(99),
        second: s,
    };
    calendar_to_week_sow(&cal).ok_or_else(|| {
        InputError::at_field(
            l.path,
            l.ln,
            "date",
            format!(
                "expected a valid GPST date and time after 1980/01/06, found \"{} {}\"",
                crate::error::shorten(date),
                crate::error::shorten(time)
            ),
        )
    })
}

/// A PX4 ULog's GPS fixes (ulog/mod.rs), on the log's GPS week (None: boot seconds).
fn read_ulog(
    path: &Path,
    multi_id: u8,
    offset: f64,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Epoch>, Option<u32>), InputError> {
    let u = crate::ulog::open(path, warnings)?;
    let map = crate::ulog::TimeMap::of(&u);
    let (fixes, _) = crate::ulog::gnss_fixes(path, &u, multi_id, &map)?;
    let epochs = fixes
        .into_iter()
        .map(|mut fix| {
            let t_file = fix.t;
            fix.t += offset;
            Epoch {
                t_file,
                quality: None,
                fix,
            }
        })
        .collect();
    Ok((epochs, map.week))
}

fn read_pos(
    src: &GnssSource,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Epoch>, Option<u32>), InputError> {
    let (path, offset) = (src.path.as_path(), src.time_offset_s);
    const WHAT: &str = "date time or week tow, lat lon h, Q ns, sdn sde sdu sdne sdeu sdun, age \
                        ratio [, vn ve vu, sdvn sdve sdvu sdvne sdveu sdvun]";
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(32);
    let mut out = Vec::new();
    let mut prev: Option<f64> = None;
    let mut week0: Option<u32> = None;
    for_each_line(&mut lines, warnings, |ln, text| {
        split_fields(text, &mut fields);
        if src.skip_lines.is_some_and(|n| ln <= n) {
            return Ok(());
        }
        match fields.first() {
            None => return Ok(()),
            Some(&(s, _)) if text.get(s) == Some(&b'%') => {
                return check_pos_header(path, ln, text).map_err(LineError::Fatal);
            }
            _ => {}
        }
        let l = Line {
            path,
            ln,
            text,
            fields: &fields,
        };
        let n = fields.len();
        if n != 15 && n != 24 {
            return Err(LineError::Data(InputError::columns(
                path, ln, "15 or 24", WHAT, n,
            )));
        }
        let (week, sow) = if field(text, &fields, 0).contains(&b'/') {
            parse_calendar(&l)?
        } else {
            let w = l.num(0, "week")?;
            let tow = l.num(1, "tow")?;
            if w < 0.0 || w.fract() != 0.0 || w > 100_000.0 {
                return Err(LineError::Data(InputError::at_field(
                    path,
                    ln,
                    "week",
                    format!("expected a GPS week number, found {w}"),
                )));
            }
            if !(0.0..SECONDS_PER_WEEK + 1.0).contains(&tow) {
                return Err(LineError::Data(InputError::at_field(
                    path,
                    ln,
                    "tow",
                    format!("expected seconds of week in [0, 604800], found {tow}"),
                )));
            }
            (w as u32, tow)
        };
        let w0 = week0.unwrap_or(week);
        let t_file = (i64::from(week) - i64::from(w0)) as f64 * SECONDS_PER_WEEK + sow;
        l.check_time(t_file, prev)?;
        let lla = l.lla(2, ["lat", "lon", "height"])?;
        let q = l.num(5, "Q")?;
        if !(0.0..=255.0).contains(&q) || q.fract() != 0.0 {
            return Err(LineError::Data(InputError::at_field(
                path,
                ln,
                "Q",
                format!(
                    "expected an integer quality flag (1 fix, 2 float, 5 single ...), found {q}"
                ),
            )));
        }
        l.num(6, "ns")?;
        let sd = l.std3(7, ["sdn", "sde", "sdu"])?;
        for (k, name) in [
            (10, "sdne"),
            (11, "sdeu"),
            (12, "sdun"),
            (13, "age"),
            (14, "ratio"),
        ] {
            l.num(k, name)?;
        }
        let (vel_ned, vel_std_ned) = if n == 24 {
            let (vn, ve, vu) = (l.num(15, "vn")?, l.num(16, "ve")?, l.num(17, "vu")?);
            let sv = l.std3(18, ["sdvn", "sdve", "sdvu"])?;
            for (k, name) in [(21, "sdvne"), (22, "sdveu"), (23, "sdvun")] {
                l.num(k, name)?;
            }
            (Some(Vector3::new(vn, ve, -vu)), Some(sv))
        } else {
            (None, None)
        };
        week0 = Some(w0);
        prev = Some(t_file);
        out.push(Epoch {
            t_file,
            quality: Some(q as u8),
            fix: GnssFix {
                t: t_file + offset,
                lla,
                std_ned: sd,
                vel_ned,
                vel_std_ned,
            },
        });
        Ok(())
    })?;
    Ok((out, week0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn tmp(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("navfuse-gnss-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    const POS: &str = "% program   : test\n\
% (lat/lon/height=WGS84/ellipsoidal,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp,ns=# of satellites)\n\
%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio  vn(m/s) ve(m/s) vu(m/s) sdvn sdve sdvu sdvne sdveu sdvun\n\
2025/07/08 19:34:18.499 40.0 -105.0 1601.0 1 21 0.01 0.01 0.02 0 0 0 0 0 1.0 2.0 3.0 0.05 0.05 0.06 0 0 0\n\
2025/07/08 19:34:18.749 40.0 -105.0 1601.0 2 21 0.01 0.01 0.02 0 0 0 0 0 1.0 2.0 3.0 0.05 0.05 0.06 0 0 0\n\
2025/07/08 19:34:18.999 40.0 -105.0 1601.0 1 21 0.01 0.01 0.02 0 0 0 0 0 1.0 2.0 3.0 0.05 0.05 0.06 0 0 0\n\
2025/07/08 19:34:19.249 40.0 -105.0 1601.0 1 21 0.01 0.01 0.02 0 0 0 0 0 1.0 2.0 3.0 0.05 0.05 0.06 0 0 0\n";

    #[test]
    fn pos_quality_decimation_and_velocity() {
        let p = tmp("a.pos", POS);
        let mut src = GnssSource {
            path: p,
            format: GnssFormat::RtklibPos { quality: vec![1] },
            decimate_s: None,
            time_offset_s: 0.0,
            skip_lines: None,
        };
        let d = read_gnss(&src).unwrap();
        assert_eq!(d.gps_week, Some(2374));
        assert_eq!(d.fixes.len(), 3);
        assert_eq!(d.skipped, 1);
        let f = &d.fixes[0];
        assert!((f.t - (2.0 * 86400.0 + 19.0 * 3600.0 + 34.0 * 60.0 + 18.499)).abs() < 1e-9);
        assert_eq!(f.vel_ned, Some(Vector3::new(1.0, 2.0, -3.0)));
        assert_eq!(f.vel_std_ned, Some(Vector3::new(0.05, 0.05, 0.06)));
        assert!((f.lla.x - 40f64.to_radians()).abs() < 1e-15);
        src.decimate_s = Some(1.0);
        let d = read_gnss(&src).unwrap();
        assert_eq!(
            d.fixes.len(),
            1,
            "only 18.999 is within 1 ms of a whole second"
        );
        assert_eq!(d.skipped, 3);
    }

    #[test]
    fn pos_week_tow_and_header_checks() {
        let text = "%  GPST  latitude(deg) longitude(deg) height(m) Q ns sdn sde sdu sdne sdeu sdun age ratio\n\
                    2374 604799.5 40 -105 1600 1 9 0.1 0.1 0.2 0 0 0 0 0\n\
                    2375 0.5 40 -105 1600 1 9 0.1 0.1 0.2 0 0 0 0 0\n";
        let p = tmp("b.pos", text);
        let src = GnssSource {
            path: p,
            format: GnssFormat::RtklibPos { quality: vec![] },
            decimate_s: None,
            time_offset_s: -0.25,
            skip_lines: None,
        };
        let d = read_gnss(&src).unwrap();
        assert_eq!(d.gps_week, Some(2374));
        assert_eq!(d.fixes[1].t, 604_800.25);
        assert_eq!(d.fixes[0].vel_ned, None);

        let p = tmp("c.pos", "%  UTC  latitude(deg) longitude(deg) height(m)\n");
        let e = read_gnss(&GnssSource {
            path: p,
            ..src.clone()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("c.pos:1: expected times in GPST"), "{e}");
        let p = tmp("d.pos", "%  GPST  x-ecef(m) y-ecef(m) z-ecef(m)\n");
        let e = read_gnss(&GnssSource { path: p, ..src })
            .unwrap_err()
            .to_string();
        assert!(e.contains("ECEF"), "{e}");
    }

    #[test]
    fn kfgins_13_columns() {
        let p = tmp("g.txt", "100 30 114 20 0.1 0.1 0.2 1 2 3 0.01 0.01 0.02\n101 30 114 20 0.1 0.1 0.2 1 2 3 0.01 0.01 0.02\n");
        let src = GnssSource {
            path: p,
            format: GnssFormat::KfGins,
            decimate_s: None,
            time_offset_s: 0.0,
            skip_lines: None,
        };
        let d = read_gnss(&src).unwrap();
        assert_eq!(d.gps_week, None);
        assert_eq!(d.fixes.len(), 2);
        assert_eq!(d.fixes[1].vel_ned, Some(Vector3::new(1.0, 2.0, 3.0)));
    }
}
