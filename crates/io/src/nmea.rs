//! NMEA 0183 reader (docs/FORMATS.md "NMEA 0183"): GGA, RMC, VTG, GST, GSA, HDT and
//! THS from any talker (`GP`, `GN`, `GL`, `GA`, `GB`, ...), into GNSS fixes and
//! heading records.
//!
//! - Every sentence must carry its checksum `*HH` (XOR of the bytes between `$` and
//!   `*`). A sentence with a wrong or missing checksum, or one that does not parse,
//!   is rejected: counted, and named with its line number in a warning (the first
//!   [`MAX_LISTED`]). More rejected than accepted sentences is an error.
//! - Sentences are grouped into epochs by their UTC time of day (GGA, RMC, GST);
//!   sentences without a time (VTG, GSA, HDT, THS) belong to the epoch of the last
//!   timed sentence before them.
//! - The date comes from RMC; epochs before the first RMC take the configured
//!   `date` (or the first RMC's date, a day earlier if their time of day is later).
//!   A time of day that goes back without a new RMC date is the next day.
//! - UTC -> GPS time: + GPS-UTC leap seconds of the epoch's GPS week
//!   (`navfuse_core::time::leap_seconds`).
//! - A fix is an epoch with a GGA of quality 1-5 (0 = no fix, 6 = dead reckoning, 7 =
//!   manual input, 8 = simulator: counted and skipped). Lines without `$` or `!`
//!   (a preamble, binary messages of a mixed log) are counted and skipped. Height = GGA altitude (above the geoid) + geoid separation = the
//!   ellipsoidal height GnssFix holds.
//! - Velocity (horizontal only): RMC speed and course (status A), else VTG. The
//!   vertical velocity is unknown: it is given as 0 with a std of
//!   [`VERTICAL_VEL_STD_MPS`]; the horizontal std is [`HORIZONTAL_VEL_STD_MPS`] (NMEA
//!   carries none: a documented guess).
//! - Position std: GST (lat, lon, alt 1-sigma), else the configured
//!   `position_std_m`, else [`HDOP_UERE_M`] x HDOP horizontally and 2x that
//!   vertically (VDOP from GSA when present): a guess, with a warning.
//! - Heading: HDT, or THS with mode `A` (autonomous); other THS modes are skipped.

use crate::error::InputError;
use crate::fmt::LineReader;
use crate::time::{days_from_civil, SECONDS_PER_WEEK};
use nalgebra::Vector3;
use navfuse_core::{GnssFix, HeadingObs};
use std::path::Path;

/// Options of an NMEA source (`[gnss] format = "nmea"`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NmeaOptions {
    /// UTC date (year, month, day) of the first epoch when the file has no RMC.
    pub date: Option<(i64, u32, u32)>,
    /// Position std N E D \[m\] for epochs without GST (before the HDOP guess).
    pub position_std_m: Option<[f64; 3]>,
}

/// Position std per unit of HDOP when neither GST nor a configured std is there \[m\]
/// (a typical single-frequency code UERE; a guess).
pub const HDOP_UERE_M: f64 = 2.5;
/// HDOP assumed when GGA leaves it empty (navfuse's own export does).
pub const DEFAULT_HDOP: f64 = 2.0;
/// Horizontal velocity std given to RMC/VTG velocities \[m/s\] (NMEA has none).
pub const HORIZONTAL_VEL_STD_MPS: f64 = 0.5;
/// Vertical velocity std \[m/s\]: NMEA gives no vertical velocity; 0 +- this.
pub const VERTICAL_VEL_STD_MPS: f64 = 5.0;
/// Rejected sentences named one by one in the warnings; the rest are counted.
pub const MAX_LISTED: usize = 10;
/// Heading std given to HDT/THS records \[deg\] (`heading.std_deg` overrides).
pub const HEADING_STD_DEG: f64 = 0.5;

/// What an NMEA file gave.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NmeaData {
    /// Fixes, time strictly increasing, GPS seconds of `gps_week` (continuing past a
    /// week).
    pub fixes: Vec<GnssFix>,
    /// Heading records (HDT, THS mode A), same time scale.
    pub heading: Vec<HeadingObs>,
    /// GPS week of the first epoch.
    pub gps_week: Option<u32>,
    /// Sentences accepted.
    pub sentences: usize,
    /// Sentences rejected (bad checksum, unparsable).
    pub rejected: usize,
    /// Epochs with GGA quality 0 (no fix), or 6, 7, 8 (dead reckoning, manual
    /// input, simulation: no GNSS measurement).
    pub no_fix: usize,
    /// Lines without a sentence (no `$` or `!`), skipped.
    pub non_nmea_lines: usize,
    /// Epochs without GGA (no height): no fix made.
    pub without_gga: usize,
    /// Fixes whose std is the HDOP guess.
    pub hdop_std: usize,
    /// Sentences of other types, ignored.
    pub ignored: usize,
    pub warnings: Vec<String>,
}

#[derive(Clone, Copy, Debug, Default)]
struct Gga {
    lat: f64,
    lon: f64,
    h: f64,
    quality: u8,
    hdop: Option<f64>,
}

#[derive(Clone, Debug, Default)]
struct Epoch {
    /// UTC seconds of day.
    tod: f64,
    /// UTC date as days since 1970-01-01, from this epoch's RMC.
    day: Option<i64>,
    gga: Option<Gga>,
    /// Horizontal velocity (north, east) [m/s] from RMC.
    rmc_vel: Option<(f64, f64)>,
    vtg_vel: Option<(f64, f64)>,
    gst: Option<[f64; 3]>,
    vdop: Option<f64>,
    heading_deg: Option<f64>,
    line: usize,
}

/// Read an NMEA file; see the module documentation.
pub fn read_nmea(path: &Path, opt: &NmeaOptions) -> Result<NmeaData, InputError> {
    let mut lines = LineReader::open(path)?;
    let mut out = NmeaData::default();
    let mut epochs: Vec<Epoch> = Vec::new();
    let mut cur: Option<Epoch> = None;
    let mut untimed_before_first = 0usize;
    while let Some((ln, text)) = lines.next_line()? {
        let t = trim(text);
        if t.is_empty() || t.first() == Some(&b'#') {
            continue;
        }
        // Not NMEA (a logger's preamble, binary messages of a mixed log): skipped.
        if !t.iter().any(|&c| c == b'$' || c == b'!') {
            out.non_nmea_lines += 1;
            continue;
        }
        match parse_sentence(path, ln, t) {
            Ok(s) => {
                out.sentences += 1;
                if let Some(tod) = s.tod() {
                    let same = cur.as_ref().is_some_and(|e| e.tod == tod);
                    if !same {
                        if let Some(e) = cur.take() {
                            epochs.push(e);
                        }
                        cur = Some(Epoch {
                            tod,
                            line: ln,
                            ..Epoch::default()
                        });
                    }
                }
                match cur.as_mut() {
                    Some(e) => s.apply(e),
                    None => untimed_before_first += 1,
                }
                if matches!(s, Sentence::Other) {
                    out.ignored += 1;
                }
            }
            Err(e) => {
                out.rejected += 1;
                if out.rejected <= MAX_LISTED {
                    out.warnings.push(format!("sentence rejected: {e}"));
                }
            }
        }
    }
    if let Some(e) = cur.take() {
        epochs.push(e);
    }
    if out.rejected > MAX_LISTED {
        out.warnings.push(format!(
            "{}: {} sentences rejected in all ({} listed)",
            path.display(),
            out.rejected,
            MAX_LISTED
        ));
    }
    if untimed_before_first > 0 {
        out.warnings.push(format!(
            "{}: {untimed_before_first} sentences before the first timed sentence (GGA, RMC, GST) skipped",
            path.display()
        ));
    }
    if out.non_nmea_lines > 0 {
        out.warnings.push(format!(
            "{}: {} lines without an NMEA sentence ('$' or '!') skipped",
            path.display(),
            out.non_nmea_lines
        ));
    }
    if out.sentences == 0 && out.rejected == 0 && out.non_nmea_lines > 0 {
        return Err(InputError::new(
            path,
            format!(
                "no NMEA sentence in {} lines (none has '$'): expected an NMEA 0183 log",
                out.non_nmea_lines
            ),
        ));
    }
    if out.rejected > out.sentences {
        return Err(InputError::new(
            path,
            format!(
                "{} of {} NMEA sentences rejected (bad checksum or format): expected an NMEA 0183 log",
                out.rejected,
                out.rejected + out.sentences
            ),
        ));
    }
    resolve_days(path, &mut epochs, opt)?;
    let std_cfg = opt.position_std_m.map(Vector3::from);
    let mut week0: Option<i64> = None;
    let mut prev_t: Option<f64> = None;
    for e in &epochs {
        let day = e.day.unwrap_or(0);
        // UTC seconds since the GPS epoch, then + leap seconds.
        let utc_s = (day - days_from_civil(1980, 1, 6)) as f64 * 86_400.0 + e.tod;
        let week_utc = (utc_s / SECONDS_PER_WEEK).floor();
        if week_utc < 0.0 {
            return Err(InputError::at_line(
                path,
                e.line,
                "expected a date after the GPS epoch 1980-01-06",
            ));
        }
        let leap = navfuse_core::time::leap_seconds_at_utc(utc_s);
        let gps_s = utc_s + leap;
        let w0 = *week0.get_or_insert((gps_s / SECONDS_PER_WEEK).floor() as i64);
        let t = gps_s - w0 as f64 * SECONDS_PER_WEEK;
        if prev_t.is_some_and(|p| t <= p) {
            return Err(InputError::at_line(
                path,
                e.line,
                format!(
                    "epoch time goes back or repeats: {t} s after {} s of the GPS week (an NMEA log of one receiver, in time order, expected)",
                    prev_t.unwrap_or(0.0)
                ),
            ));
        }
        prev_t = Some(t);
        if let Some(h) = e.heading_deg {
            out.heading.push(HeadingObs {
                t,
                heading_rad: h.to_radians(),
                std_rad: HEADING_STD_DEG.to_radians(),
            });
        }
        let Some(g) = e.gga else {
            out.without_gga += 1;
            continue;
        };
        if matches!(g.quality, 0 | 6..=8) {
            out.no_fix += 1;
            continue;
        }
        let std_ned = match (e.gst, std_cfg) {
            (Some(s), _) => Vector3::new(s[0], s[1], s[2]),
            (None, Some(s)) => s,
            (None, None) => {
                out.hdop_std += 1;
                let hd = g.hdop.unwrap_or(DEFAULT_HDOP);
                let vd = e.vdop.unwrap_or(2.0 * hd);
                Vector3::new(HDOP_UERE_M * hd, HDOP_UERE_M * hd, HDOP_UERE_M * vd)
            }
        };
        let vel = e.rmc_vel.or(e.vtg_vel);
        out.fixes.push(GnssFix {
            t,
            lla: Vector3::new(g.lat.to_radians(), g.lon.to_radians(), g.h),
            std_ned,
            vel_ned: vel.map(|(n, e)| Vector3::new(n, e, 0.0)),
            vel_std_ned: vel.map(|_| {
                Vector3::new(
                    HORIZONTAL_VEL_STD_MPS,
                    HORIZONTAL_VEL_STD_MPS,
                    VERTICAL_VEL_STD_MPS,
                )
            }),
        });
    }
    out.gps_week = week0.map(|w| w as u32);
    if out.hdop_std > 0 {
        out.warnings.push(format!(
            "{}: {} fixes have no GST and no gnss.position_std_m: their std is a guess, {HDOP_UERE_M} m x HDOP (HDOP {DEFAULT_HDOP} where GGA gives none)",
            path.display(),
            out.hdop_std
        ));
    }
    if out.no_fix > 0 {
        out.warnings.push(format!(
            "{}: {} epochs with GGA quality 0 (no fix) or 6-8 (dead reckoning, manual, simulator) skipped",
            path.display(),
            out.no_fix
        ));
    }
    Ok(out)
}

/// Give every epoch a date (days since 1970); see the module documentation.
fn resolve_days(path: &Path, epochs: &mut [Epoch], opt: &NmeaOptions) -> Result<(), InputError> {
    let first_dated = epochs.iter().position(|e| e.day.is_some());
    let start_day = match (opt.date, first_dated) {
        (Some((y, m, d)), _) => days_from_civil(y, m, d),
        (None, Some(k)) => {
            // Walk back from the first RMC date: a later time of day is the day before.
            let mut day = epochs[k].day.unwrap_or(0);
            let mut tod = epochs[k].tod;
            for e in epochs[..k].iter().rev() {
                if e.tod > tod {
                    day -= 1;
                }
                tod = e.tod;
            }
            day
        }
        (None, None) if epochs.is_empty() => return Ok(()),
        (None, None) => {
            return Err(InputError::new(
                path,
                "no RMC sentence gives the date: set date = \"YYYY-MM-DD\" (the UTC date of the first epoch) in the section that names this file (gnss.date or heading.date)",
            )
            .with_field("date"))
        }
    };
    let mut day = start_day;
    let mut prev_tod: Option<f64> = None;
    for e in epochs.iter_mut() {
        match e.day {
            Some(d) => day = d,
            None => {
                if prev_tod.is_some_and(|p| e.tod < p) {
                    day += 1;
                }
                e.day = Some(day);
            }
        }
        prev_tod = Some(e.tod);
    }
    Ok(())
}

fn trim(b: &[u8]) -> &[u8] {
    let s = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    let e = b
        .iter()
        .rposition(|c| !c.is_ascii_whitespace())
        .map_or(s, |i| i + 1);
    b.get(s..e.max(s)).unwrap_or(&[])
}

enum Sentence {
    Gga(f64, Gga),
    /// time of day, day number, horizontal velocity (if status A and given).
    Rmc(f64, Option<i64>, Option<(f64, f64)>),
    Vtg(Option<(f64, f64)>),
    Gst(f64, [f64; 3]),
    Gsa(Option<f64>),
    Heading(f64),
    /// THS in a mode other than A: skipped.
    NoHeading,
    Other,
}

impl Sentence {
    fn tod(&self) -> Option<f64> {
        match self {
            Sentence::Gga(t, _) | Sentence::Rmc(t, _, _) | Sentence::Gst(t, _) => Some(*t),
            _ => None,
        }
    }

    fn apply(&self, e: &mut Epoch) {
        match self {
            Sentence::Gga(_, g) => e.gga = Some(*g),
            Sentence::Rmc(_, d, v) => {
                if d.is_some() {
                    e.day = *d;
                }
                if v.is_some() {
                    e.rmc_vel = *v;
                }
            }
            Sentence::Vtg(v) => {
                if v.is_some() {
                    e.vtg_vel = *v;
                }
            }
            Sentence::Gst(_, s) => e.gst = Some(*s),
            Sentence::Gsa(v) => e.vdop = v.or(e.vdop),
            Sentence::Heading(h) => e.heading_deg = Some(*h),
            Sentence::NoHeading | Sentence::Other => {}
        }
    }
}

/// A sentence's fields, for errors naming the sentence and field.
struct Fields<'a> {
    path: &'a Path,
    ln: usize,
    kind: &'a str,
    f: Vec<&'a str>,
}

impl<'a> Fields<'a> {
    fn err(&self, k: usize, name: &str, expected: &str) -> InputError {
        let found = self.f.get(k).copied().unwrap_or("");
        InputError::at_field(
            self.path,
            self.ln,
            format!("{} {name}", self.kind),
            format!(
                "expected {expected}, found \"{}\"",
                crate::error::shorten(found.as_bytes())
            ),
        )
    }

    fn s(&self, k: usize) -> &'a str {
        self.f.get(k).copied().unwrap_or("")
    }

    /// An optional number (empty = None).
    fn opt(&self, k: usize, name: &str) -> Result<Option<f64>, InputError> {
        let s = self.s(k);
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(self.err(k, name, "a number")),
        }
    }

    fn num(&self, k: usize, name: &str) -> Result<f64, InputError> {
        self.opt(k, name)?
            .ok_or_else(|| self.err(k, name, "a number"))
    }

    /// `hhmmss.ss` -> seconds of day.
    fn time(&self, k: usize) -> Result<f64, InputError> {
        let s = self.s(k);
        let b = s.as_bytes();
        let bad = || self.err(k, "time", "a UTC time hhmmss.ss");
        if b.len() < 6 || !b.iter().take(6).all(u8::is_ascii_digit) {
            return Err(bad());
        }
        let two = |i: usize| f64::from((b[i] - b'0') * 10 + (b[i + 1] - b'0'));
        let (h, m) = (two(0), two(2));
        let sec: f64 = s.get(4..).and_then(|x| x.parse().ok()).ok_or_else(bad)?;
        if h > 23.0 || m > 59.0 || !(0.0..61.0).contains(&sec) {
            return Err(bad());
        }
        Ok(h * 3600.0 + m * 60.0 + sec)
    }

    /// `ddmm.mmmm,N` / `dddmm.mmmm,E` -> degrees.
    fn angle(&self, k: usize, lon: bool) -> Result<f64, InputError> {
        let name = if lon { "longitude" } else { "latitude" };
        let s = self.s(k);
        let deg_digits = if lon { 3 } else { 2 };
        let bad = || {
            self.err(
                k,
                name,
                if lon {
                    "a longitude dddmm.mmmm"
                } else {
                    "a latitude ddmm.mmmm"
                },
            )
        };
        let (d, m) = match (s.get(..deg_digits), s.get(deg_digits..)) {
            (Some(d), Some(m)) if d.bytes().all(|c| c.is_ascii_digit()) && !m.is_empty() => (d, m),
            _ => return Err(bad()),
        };
        let d: f64 = d.parse().map_err(|_| bad())?;
        let m: f64 = m.parse().map_err(|_| bad())?;
        if !(0.0..60.0).contains(&m) || !m.is_finite() {
            return Err(bad());
        }
        let v = d + m / 60.0;
        let (pos, neg, max) = if lon {
            ("E", "W", 180.0)
        } else {
            ("N", "S", 90.0)
        };
        if v > max {
            return Err(bad());
        }
        match self.s(k + 1) {
            h if h == pos => Ok(v),
            h if h == neg => Ok(-v),
            _ => Err(self.err(k + 1, "hemisphere", if lon { "E or W" } else { "N or S" })),
        }
    }

    fn at_least(&self, n: usize) -> Result<(), InputError> {
        if self.f.len() < n {
            return Err(InputError::at_line(
                self.path,
                self.ln,
                format!(
                    "{}: expected at least {n} fields, found {}",
                    self.kind,
                    self.f.len()
                ),
            ));
        }
        Ok(())
    }
}

/// Verify the checksum and parse one sentence.
fn parse_sentence(path: &Path, ln: usize, t: &[u8]) -> Result<Sentence, InputError> {
    let at = |m: String| InputError::at_line(path, ln, m);
    let Some(start) = t.iter().position(|&c| c == b'$' || c == b'!') else {
        return Err(at("expected an NMEA sentence starting with '$'".into()));
    };
    let t = t.get(start + 1..).unwrap_or(&[]);
    let Some(star) = t.iter().rposition(|&c| c == b'*') else {
        return Err(at(
            "expected a checksum '*HH' at the end of the sentence".into()
        ));
    };
    let body = t.get(..star).unwrap_or(&[]);
    let cs_text = t.get(star + 1..).unwrap_or(&[]);
    let given = std::str::from_utf8(cs_text)
        .ok()
        .filter(|s| s.len() == 2)
        .and_then(|s| u8::from_str_radix(s, 16).ok());
    let Some(given) = given else {
        return Err(at(format!(
            "expected a checksum of 2 hex digits after '*', found \"{}\"",
            crate::error::shorten(cs_text)
        )));
    };
    let computed = body.iter().fold(0u8, |a, b| a ^ b);
    if given != computed {
        return Err(at(format!(
            "checksum mismatch: the sentence says {given:02X}, its bytes give {computed:02X}"
        )));
    }
    let Ok(body) = std::str::from_utf8(body) else {
        return Err(at("expected ASCII text in the sentence".into()));
    };
    let f: Vec<&str> = body.split(',').collect();
    let addr = f.first().copied().unwrap_or("");
    if addr.len() != 5 || !addr.bytes().all(|c| c.is_ascii_alphanumeric()) {
        return Ok(Sentence::Other);
    }
    let kind = addr.get(2..).unwrap_or("");
    let fl = Fields { path, ln, kind, f };
    match kind {
        "GGA" => {
            fl.at_least(10)?;
            let tod = fl.time(1)?;
            let q = fl.s(6);
            let quality = q
                .parse::<u8>()
                .ok()
                .filter(|q| *q <= 9)
                .ok_or_else(|| fl.err(6, "quality", "a fix quality 0..9"))?;
            if quality == 0 {
                return Ok(Sentence::Gga(tod, Gga::default()));
            }
            let lat = fl.angle(2, false)?;
            let lon = fl.angle(4, true)?;
            let hdop = fl.opt(8, "HDOP")?;
            if hdop.is_some_and(|h| h <= 0.0) {
                return Err(fl.err(8, "HDOP", "a positive HDOP"));
            }
            let alt = fl.num(9, "altitude")?;
            // Geoid separation (field 11); empty = 0 (the altitude is then taken as
            // ellipsoidal, as navfuse's export writes it).
            let sep = if fl.f.len() > 11 {
                fl.opt(11, "geoid separation")?.unwrap_or(0.0)
            } else {
                0.0
            };
            Ok(Sentence::Gga(
                tod,
                Gga {
                    lat,
                    lon,
                    h: alt + sep,
                    quality,
                    hdop: hdop.filter(|h| *h > 0.0),
                },
            ))
        }
        "RMC" => {
            fl.at_least(10)?;
            let tod = fl.time(1)?;
            let status = fl.s(2);
            let date = fl.s(9);
            let day = if date.is_empty() {
                None
            } else {
                let b = date.as_bytes();
                if b.len() != 6 || !b.iter().all(u8::is_ascii_digit) {
                    return Err(fl.err(9, "date", "a date ddmmyy"));
                }
                let two = |i: usize| u32::from((b[i] - b'0') * 10 + (b[i + 1] - b'0'));
                let (d, m, yy) = (two(0), two(2), two(4));
                let y = if yy < 80 { 2000 + yy } else { 1900 + yy };
                if !(1..=12).contains(&m)
                    || d == 0
                    || d > crate::time::days_in_month(i64::from(y), m)
                {
                    return Err(fl.err(9, "date", "a valid date ddmmyy"));
                }
                Some(days_from_civil(i64::from(y), m, d))
            };
            let vel = if status == "A" {
                speed_course(&fl, 7, 8, 1852.0 / 3600.0)?
            } else {
                None
            };
            Ok(Sentence::Rmc(tod, day, vel))
        }
        "VTG" => {
            // Course true (1), T, magnetic (3), M, speed knots (5), N, km/h (7), K.
            fl.at_least(8)?;
            let kmh = speed_course(&fl, 7, 1, 1000.0 / 3600.0)?;
            let vel = match kmh {
                Some(v) => Some(v),
                None => speed_course(&fl, 5, 1, 1852.0 / 3600.0)?,
            };
            Ok(Sentence::Vtg(vel))
        }
        "GST" => {
            // time, rms, semi-major, semi-minor, orientation, sigma lat, lon, alt.
            fl.at_least(9)?;
            let tod = fl.time(1)?;
            let mut s = [0.0; 3];
            for (k, (slot, name)) in s
                .iter_mut()
                .zip(["lat sigma", "lon sigma", "alt sigma"])
                .enumerate()
            {
                let v = fl.num(6 + k, name)?;
                if v <= 0.0 {
                    return Err(fl.err(6 + k, name, "a positive std [m]"));
                }
                *slot = v;
            }
            Ok(Sentence::Gst(tod, s))
        }
        "GSA" => {
            // mode, fix type, 12 PRNs, PDOP, HDOP, VDOP.
            fl.at_least(18)?;
            let vdop = fl.opt(17, "VDOP")?;
            Ok(Sentence::Gsa(vdop.filter(|v| *v > 0.0)))
        }
        "HDT" | "THS" => {
            fl.at_least(3)?;
            if kind == "THS" && fl.s(2) != "A" {
                return Ok(Sentence::NoHeading);
            }
            let Some(h) = fl.opt(1, "heading")? else {
                return Ok(Sentence::NoHeading);
            };
            if !(0.0..360.0).contains(&h) {
                return Err(fl.err(1, "heading", "a heading in [0, 360) deg"));
            }
            Ok(Sentence::Heading(h))
        }
        _ => Ok(Sentence::Other),
    }
}

/// Speed (field `ks`, times `to_mps`) and course over ground (field `kc`, deg from
/// true north) -> (north, east) [m/s]; None when the speed is empty, or the course is
/// empty with a non-zero speed.
fn speed_course(
    fl: &Fields<'_>,
    ks: usize,
    kc: usize,
    to_mps: f64,
) -> Result<Option<(f64, f64)>, InputError> {
    let Some(speed) = fl.opt(ks, "speed")? else {
        return Ok(None);
    };
    if speed < 0.0 {
        return Err(fl.err(ks, "speed", "a speed >= 0"));
    }
    let course = fl.opt(kc, "course")?;
    if course.is_some_and(|c| !(-360.0..=360.0).contains(&c)) {
        return Err(fl.err(kc, "course", "a course in [0, 360] deg"));
    }
    let v = speed * to_mps;
    Ok(match course {
        Some(c) => Some((v * c.to_radians().cos(), v * c.to_radians().sin())),
        None if v == 0.0 => Some((0.0, 0.0)),
        None => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("navfuse-nmea-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn s(body: &str) -> String {
        crate::export::nmea_sentence(body)
    }

    /// The textbook GGA (48°07.038'N 11°31.000'E, 545.4 m + 46.9 m geoid) with an
    /// RMC giving 1994-03-23 and 022.4 kn at 084.4°.
    #[test]
    fn hand_written_sample() {
        let text = [
            s("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"),
            s("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),
            s("GPGST,123519,1.0,2.0,1.0,0.0,1.5,1.2,3.1"),
            s("GPHDT,274.07,T"),
            s("GNGGA,123520,4807.038,S,01131.000,W,0,00,,,M,,M,,"),
        ]
        .concat();
        let p = tmp("hand.nmea", &text);
        let d = read_nmea(&p, &NmeaOptions::default()).unwrap();
        assert_eq!(d.fixes.len(), 1);
        assert_eq!(d.no_fix, 1);
        let f = &d.fixes[0];
        assert!((f.lla.x.to_degrees() - (48.0 + 7.038 / 60.0)).abs() < 1e-12);
        assert!((f.lla.y.to_degrees() - (11.0 + 31.0 / 60.0)).abs() < 1e-12);
        assert!(
            (f.lla.z - 592.3).abs() < 1e-9,
            "altitude + geoid separation"
        );
        assert_eq!(f.std_ned, Vector3::new(1.5, 1.2, 3.1));
        // 1994-03-23 is a Wednesday of GPS week 741; GPS-UTC was 9 s then.
        assert_eq!(d.gps_week, Some(741));
        let sow = 3.0 * 86400.0 + 12.0 * 3600.0 + 35.0 * 60.0 + 19.0 + 9.0;
        assert!((f.t - sow).abs() < 1e-9, "{}", f.t);
        let v = f.vel_ned.unwrap();
        let mps = 22.4 * 1852.0 / 3600.0;
        assert!((v.x.hypot(v.y) - mps).abs() < 1e-12);
        assert!((v.y.atan2(v.x).to_degrees() - 84.4).abs() < 1e-9);
        assert_eq!(d.heading.len(), 1);
        assert!((d.heading[0].heading_rad.to_degrees() - 274.07).abs() < 1e-12);
    }

    #[test]
    fn checksums_and_line_numbers() {
        let good = s("GPGGA,000001,0100.000,N,00100.000,E,1,08,1.0,10.0,M,0.0,M,,");
        let mut text = String::new();
        text.push_str(&s("GPRMC,000000,A,0100.000,N,00100.000,E,0.0,,010125,,,A"));
        text.push_str(&good);
        text.push_str("$GPGGA,000002,0100.000,N,00100.000,E,1,08,1.0,10.0,M,0.0,M,,*00\r\n");
        text.push_str("$GPGGA,000003,0100.000,N,00100.000,E,1,08,1.0,10.0,M,0.0,M,,\r\n");
        text.push_str(&s(
            "GPGGA,000004,01x0.000,N,00100.000,E,1,08,1.0,10.0,M,0.0,M,,",
        ));
        text.push_str(&s(
            "GPGGA,000005,0100.000,N,00100.000,E,1,08,1.0,10.0,M,0.0,M,,",
        ));
        text.push_str(&s(
            "GPGGA,000006,0100.000,N,00100.000,E,1,08,1.0,10.0,M,0.0,M,,",
        ));
        let p = tmp("bad.nmea", &text);
        let d = read_nmea(&p, &NmeaOptions::default()).unwrap();
        assert_eq!(d.rejected, 3);
        assert_eq!(d.fixes.len(), 3);
        let w = d.warnings.join("\n");
        assert!(w.contains("bad.nmea:3: checksum mismatch"), "{w}");
        assert!(w.contains("bad.nmea:4: expected a checksum"), "{w}");
        assert!(w.contains("bad.nmea:5: field 'GGA latitude'"), "{w}");
        assert!(w.contains("guess"), "{w}");
        // Mostly bad: an error.
        let keep: Vec<&str> = text.split_inclusive('\n').take(5).collect();
        let p = tmp("worse.nmea", &keep.concat().replace(&good, ""));
        let e = read_nmea(&p, &NmeaOptions::default()).unwrap_err();
        assert!(
            e.to_string().contains("3 of 4 NMEA sentences rejected"),
            "{e}"
        );
    }

    #[test]
    fn date_from_config_and_midnight() {
        let text = [
            s("GNGGA,235959.5,0100.000,N,00100.000,E,4,08,1.0,10.0,M,0.0,M,,"),
            s("GNVTG,90.0,T,,M,1.0,N,1.852,K,A"),
            s("GNGGA,000000.5,0100.000,N,00100.000,E,4,08,1.0,10.0,M,0.0,M,,"),
        ]
        .concat();
        let p = tmp("nodate.nmea", &text);
        let e = read_nmea(&p, &NmeaOptions::default()).unwrap_err();
        assert!(e.to_string().contains("gnss.date"), "{e}");
        let o = NmeaOptions {
            date: Some((2025, 7, 5)),
            position_std_m: Some([1.0, 1.0, 2.0]),
        };
        let d = read_nmea(&p, &o).unwrap();
        // 2025-07-05 is a Saturday: the next epoch is in the next GPS week.
        assert_eq!(d.fixes.len(), 2);
        assert!((d.fixes[1].t - d.fixes[0].t - 1.0).abs() < 1e-9);
        assert_eq!(d.fixes[0].std_ned, Vector3::new(1.0, 1.0, 2.0));
        let v = d.fixes[0].vel_ned.unwrap();
        assert!((v.y - 1852.0 / 3600.0 * 1.0).abs() < 1e-9 && v.x.abs() < 1e-12);
        assert!(d.fixes[1].vel_ned.is_none());
    }
}
