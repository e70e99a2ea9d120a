//! RINEX observation files, GPS L1 C/A only: pseudorange (m), carrier phase (cycles)
//! with its loss-of-lock indicator, Doppler (Hz) and C/N0 (dB-Hz).
//!
//! Writer: [`RinexObsWriter`] produces a GPS-only RINEX 3.04 file (§5.2 header, §5.3
//! epoch records: F14.3 value, LLI digit, SSI digit per observation; blank fields when
//! absent) with C1C, L1C, D1C, S1C.
//!
//! Readers: [`read_rinex_obs`] takes the version from `RINEX VERSION / TYPE` and reads
//! RINEX 2.10/2.11 (any 2.xx) and 3.0x files of any system mix; [`read_rinex3_obs`]
//! reads 3.0x only. Both give the same [`ObsEpoch`]s for the same content. Other
//! systems' satellites and other observation types are skipped; epochs with flag 0
//! (OK) or 1 (power failure since the previous epoch) are kept, flags 2-5 (events,
//! with the header/comment records they announce) and 6 (cycle-slip records) are
//! skipped.
//!
//! - 3.0x: C1C, L1C, D1C, S1C, found by their position in the GPS `SYS / # / OBS
//!   TYPES` list; one line per satellite (`G05` + 16 columns per observation).
//! - 2.xx: C1, L1, D1, S1, found by their position in `# / TYPES OF OBSERV` (`I6`
//!   count, 9 types per line, continuation lines with a blank count). P1 is never used
//!   for the pseudorange: it is the P(Y) code, which differs from C/A by the P1-C1
//!   code bias, so a file with P1 but no C1 gives no pseudoranges. Epoch line
//!   ` yy mm dd hh mm ss.sssssss  f nnn` + 12 satellites (`A1,I2`; a blank system is
//!   GPS) + receiver clock offset (F12.9, columns 69-80); more than 12 satellites
//!   continue on lines starting with 32 blanks. Two-digit years 80-99 are 1980-1999,
//!   00-79 are 2000-2079. Each satellite has ceil(types / 5) lines of 5 fields
//!   (F14.3, LLI, SSI); trailing blanks may be missing. An event with flag 3 or 4 may
//!   carry a new `# / TYPES OF OBSERV` list, which applies from the next epoch on.
//!   Flag 6 skips the satellite list and one observation record per satellite.
//! - The LLI digit of L1/L1C is kept as written: in 2.xx bit 1 means "opposite
//!   wavelength factor" and bit 2 "under anti-spoofing", in 3.0x bit 1 is a
//!   half-cycle ambiguity and bit 2 BOC tracking; bit 0 (lost lock) is the same. SSI
//!   digits are not read; S1 is taken as dB-Hz (RINEX 2 leaves the unit to the
//!   receiver).
//! - Errors name the file, the line and the field and say what was expected
//!   (`obs.11o:14: field 'G05 C1': expected a number, found "2057x396.770"`); truncated
//!   lines read as blank fields, a truncated record is an error at its epoch line.
//!   Hatanaka-compressed (CRINEX) files are refused with a hint.

use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav::{cols, header, utc_now_stamp};
use nalgebra::Vector3;
use navfuse_gnss::time::GpstCalendar;
use navfuse_gnss::GpsTime;
use std::io::{self, Write};
use std::path::Path;

/// Observation file header data written by [`RinexObsWriter`].
#[derive(Clone, Debug, PartialEq)]
pub struct ObsHeader {
    pub marker_name: String,
    /// `APPROX POSITION XYZ` [m].
    pub approx_pos_ecef_m: Vector3<f64>,
    /// `ANTENNA: DELTA H/E/N` (height, east, north) [m].
    pub antenna_delta_hen_m: Vector3<f64>,
    /// `INTERVAL` [s]; None leaves the record out.
    pub interval_s: Option<f64>,
    /// `TIME OF FIRST OBS` (GPST).
    pub first_obs: GpsTime,
    /// `REC # / TYPE / VERS`: number, type, version.
    pub receiver: [String; 3],
    /// `ANT # / TYPE`: number, type.
    pub antenna: [String; 2],
    /// `PGM / RUN BY / DATE` program name.
    pub program: String,
    /// `PGM / RUN BY / DATE` date (`yyyymmdd hhmmss UTC`); None = now. Give one for
    /// reproducible output.
    pub date: Option<String>,
}

pub use navfuse_gnss::obs::{ObsEpoch, SatObs};

/// The four observation types written, in order.
const OBS_TYPES: [&str; 4] = ["C1C", "L1C", "D1C", "S1C"];

/// Signal strength indicator from C/N0 (RINEX 3.04 §5.7 table: 1 < 12 dBHz, 2 12-17,
/// ..., 8 48-53, 9 >= 54).
pub fn ssi_from_cn0(cn0_dbhz: f64) -> u8 {
    if !cn0_dbhz.is_finite() {
        return 0;
    }
    (cn0_dbhz / 6.0).floor().clamp(1.0, 9.0) as u8
}

/// Writes a GPS L1 C/A RINEX 3.04 observation file.
pub struct RinexObsWriter<W: Write> {
    w: W,
}

fn a20(s: &str) -> String {
    s.chars().take(20).collect()
}

/// `F14.3` or an error if the value does not fit 14 characters.
fn f14_3(v: f64) -> io::Result<String> {
    let s = format!("{v:14.3}");
    if !v.is_finite() || s.len() > 14 {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("observation {v} does not fit RINEX F14.3"),
        ));
    }
    Ok(s)
}

impl<W: Write> RinexObsWriter<W> {
    /// Write the header and return the writer.
    pub fn new(mut w: W, h: &ObsHeader) -> io::Result<Self> {
        header(
            &mut w,
            &format!(
                "{:9.2}{:11}{:<20}{:<20}",
                3.04, "", "OBSERVATION DATA", "G: GPS"
            ),
            "RINEX VERSION / TYPE",
        )?;
        header(
            &mut w,
            &format!(
                "{:<20}{:<20}{:<20}",
                a20(&h.program),
                "",
                h.date.clone().unwrap_or_else(utc_now_stamp)
            ),
            "PGM / RUN BY / DATE",
        )?;
        header(&mut w, &h.marker_name, "MARKER NAME")?;
        header(&mut w, "", "OBSERVER / AGENCY")?;
        header(
            &mut w,
            &format!(
                "{:<20}{:<20}{:<20}",
                a20(&h.receiver[0]),
                a20(&h.receiver[1]),
                a20(&h.receiver[2])
            ),
            "REC # / TYPE / VERS",
        )?;
        header(
            &mut w,
            &format!("{:<20}{:<20}", a20(&h.antenna[0]), a20(&h.antenna[1])),
            "ANT # / TYPE",
        )?;
        let p = h.approx_pos_ecef_m;
        header(
            &mut w,
            &format!("{:14.4}{:14.4}{:14.4}", p.x, p.y, p.z),
            "APPROX POSITION XYZ",
        )?;
        let d = h.antenna_delta_hen_m;
        header(
            &mut w,
            &format!("{:14.4}{:14.4}{:14.4}", d.x, d.y, d.z),
            "ANTENNA: DELTA H/E/N",
        )?;
        let mut types = format!("G  {:3}", OBS_TYPES.len());
        for t in OBS_TYPES {
            types.push(' ');
            types.push_str(t);
        }
        header(&mut w, &types, "SYS / # / OBS TYPES")?;
        header(&mut w, "DBHZ", "SIGNAL STRENGTH UNIT")?;
        if let Some(i) = h.interval_s {
            header(&mut w, &format!("{i:10.3}"), "INTERVAL")?;
        }
        let c = h.first_obs.to_calendar();
        header(
            &mut w,
            &format!(
                "{:6}{:6}{:6}{:6}{:6}{:13.7}     GPS",
                c.year, c.month, c.day, c.hour, c.minute, c.second
            ),
            "TIME OF FIRST OBS",
        )?;
        header(&mut w, "G L1C  0.00000", "SYS / PHASE SHIFT")?;
        header(&mut w, "", "END OF HEADER")?;
        Ok(RinexObsWriter { w })
    }

    /// Write one epoch (flag 0) with its satellites.
    pub fn write_epoch(&mut self, t: GpsTime, sats: &[SatObs]) -> io::Result<()> {
        if sats.len() > 999 {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "more than 999 satellites",
            ));
        }
        let c = t.to_calendar();
        // The seconds field F11.7 must not show 60.0000000: round the time first.
        let t_r = GpsTime::new(t.week, (t.sow * 1e7).round() / 1e7);
        let c = if (c.second * 1e7).round() >= 60e7 {
            t_r.to_calendar()
        } else {
            c
        };
        writeln!(
            self.w,
            "> {:04} {:02} {:02} {:02} {:02}{:11.7}  0{:3}",
            c.year,
            c.month,
            c.day,
            c.hour,
            c.minute,
            c.second,
            sats.len()
        )?;
        for s in sats {
            let mut line = format!("G{:02}", s.prn);
            let ssi = s.cn0_dbhz.map_or(0, ssi_from_cn0);
            let vals = [s.pseudorange_m, s.carrier_cycles, s.doppler_hz, s.cn0_dbhz];
            for (k, v) in vals.iter().enumerate() {
                match v {
                    Some(v) => {
                        line.push_str(&f14_3(*v)?);
                        let lli = if k == 1 && s.lli != 0 {
                            (b'0' + (s.lli & 7)) as char
                        } else {
                            ' '
                        };
                        line.push(lli);
                        line.push(if ssi > 0 { (b'0' + ssi) as char } else { ' ' });
                    }
                    None => line.push_str(&" ".repeat(16)),
                }
            }
            writeln!(self.w, "{}", line.trim_end())?;
        }
        Ok(())
    }

    /// Flush and return the inner writer.
    pub fn finish(mut self) -> io::Result<W> {
        self.w.flush()?;
        Ok(self.w)
    }
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).trim().to_string()
}

fn int_field(
    path: &Path,
    ln: usize,
    name: &str,
    b: &[u8],
    lo: i64,
    hi: i64,
) -> Result<i64, InputError> {
    let t = text(b);
    match t.parse::<i64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        Ok(v) => Err(InputError::at_field(
            path,
            ln,
            name,
            format!("expected {lo}..{hi}, found {v}"),
        )),
        Err(_) => Err(InputError::at_field(
            path,
            ln,
            name,
            format!("expected an integer, found \"{t}\""),
        )),
    }
}

fn f64_field(path: &Path, ln: usize, name: &str, b: &[u8]) -> Result<Option<f64>, InputError> {
    let t = text(b);
    if t.is_empty() {
        return Ok(None);
    }
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(v) => Err(InputError::not_finite(path, ln, name, v)),
        Err(_) => Err(InputError::not_a_number(path, ln, name, t.as_bytes())),
    }
}

/// A required number: a blank field is an error.
fn f64_required(path: &Path, ln: usize, name: &str, b: &[u8]) -> Result<f64, InputError> {
    f64_field(path, ln, name, b)?.ok_or_else(|| {
        InputError::at_field(path, ln, name, "expected a number, found a blank field")
    })
}

/// A loss-of-lock indicator column: blank (0) or a digit 0-7.
fn lli_digit(path: &Path, ln: usize, name: &str, b: &[u8]) -> Result<u8, InputError> {
    match b {
        [b' '] | [] => Ok(0),
        [d @ b'0'..=b'7'] => Ok(d - b'0'),
        other => Err(InputError::at_field(
            path,
            ln,
            name,
            format!(
                "expected a blank or a digit 0-7, found \"{}\"",
                String::from_utf8_lossy(other)
            ),
        )),
    }
}

/// Open an observation file and check its `RINEX VERSION / TYPE` line; returns the
/// reader, the line number and the version.
fn open_obs(path: &Path) -> Result<(LineReader, usize, f64), InputError> {
    let mut rd = LineReader::open(path)?;
    let (ln, first) = match rd.next_line()? {
        Some((ln, l)) => (ln, l.to_vec()),
        None => return Err(InputError::new(path, "empty file: expected a RINEX header")),
    };
    let label = text(cols(&first, 60, 80));
    if label == "CRINEX VERS   / TYPE" || label == "CRINEX VERS / TYPE" {
        return Err(InputError::at_line(
            path,
            ln,
            "Hatanaka-compressed (CRINEX) files are not supported: expand them with CRX2RNX first",
        ));
    }
    if label != "RINEX VERSION / TYPE" {
        return Err(InputError::at_line(
            path,
            ln,
            "expected 'RINEX VERSION / TYPE' in columns 61-80 of the first line",
        ));
    }
    let version = f64_required(path, ln, "RINEX version", cols(&first, 0, 9))?;
    let kind = cols(&first, 20, 21);
    if kind != b"O" {
        return Err(InputError::at_field(
            path,
            ln,
            "file type",
            format!(
                "expected an observation file (type O in column 21), found \"{}\"",
                String::from_utf8_lossy(kind)
            ),
        ));
    }
    Ok((rd, ln, version))
}

fn unsupported(path: &Path, ln: usize, version: f64, supported: &str) -> InputError {
    InputError::at_field(
        path,
        ln,
        "RINEX version",
        format!("version {version} is not supported ({supported})"),
    )
}

/// Read the GPS L1 C/A observations of a RINEX 2.10/2.11 or 3.0x observation file;
/// the version is taken from the `RINEX VERSION / TYPE` line. See the module
/// documentation for what is kept and skipped.
/// Warnings (a damaged last epoch dropped) are left out: see [`read_rinex_obs_report`].
pub fn read_rinex_obs(path: &Path) -> Result<Vec<ObsEpoch>, InputError> {
    read_rinex_obs_report(path).map(|r| r.epochs)
}

/// What an observation file gave.
#[derive(Clone, Debug, PartialEq)]
pub struct RinexObsRead {
    pub epochs: Vec<ObsEpoch>,
    /// Findings that did not stop the read: a damaged last epoch dropped.
    pub warnings: Vec<String>,
}

/// [`read_rinex_obs`] with its warnings. A last epoch cut by the end of the file (a
/// log cut mid-write) is dropped with a warning; damage elsewhere is an error.
pub fn read_rinex_obs_report(path: &Path) -> Result<RinexObsRead, InputError> {
    let (mut rd, ln, version) = open_obs(path)?;
    let body = if version.floor() == 2.0 {
        read_v2_body
    } else if version.floor() == 3.0 {
        read_v3_body
    } else {
        return Err(unsupported(path, ln, version, "2.10, 2.11 and 3.0x are"));
    };
    let mut out = RinexObsRead {
        epochs: Vec::new(),
        warnings: Vec::new(),
    };
    let mut records = false;
    match body(&mut rd, path, &mut out.epochs, &mut records) {
        Ok(()) => {}
        Err(e) if records && rd.cut_last_line() => out.warnings.push(e.last_line_warning()),
        Err(e) => return Err(e),
    }
    for (k, w) in out.epochs.windows(2).enumerate() {
        if w[1].t.diff_s(&w[0].t) < 0.0 {
            return Err(InputError::new(
                path,
                format!(
                    "epoch {} (week {} {} s) goes backwards (previous {} s): expected \
                     non-decreasing epoch times",
                    k + 2,
                    w[1].t.week,
                    w[1].t.sow,
                    w[0].t.sow
                ),
            )
            .with_field("epoch time"));
        }
    }
    Ok(out)
}

/// Read the GPS C1C/L1C/D1C/S1C observations of a RINEX 3.0x observation file. Other
/// versions are refused; [`read_rinex_obs`] also reads RINEX 2.10/2.11.
pub fn read_rinex3_obs(path: &Path) -> Result<Vec<ObsEpoch>, InputError> {
    let (mut rd, ln, version) = open_obs(path)?;
    if version.floor() != 3.0 {
        return Err(unsupported(
            path,
            ln,
            version,
            "3.0x is; read_rinex_obs also reads 2.10/2.11",
        ));
    }
    let mut out = Vec::new();
    read_v3_body(&mut rd, path, &mut out, &mut false)?;
    Ok(out)
}

/// The records after `RINEX VERSION / TYPE` of a RINEX 3.0x file.
fn read_v3_body(
    rd: &mut LineReader,
    path: &Path,
    out: &mut Vec<ObsEpoch>,
    records: &mut bool,
) -> Result<(), InputError> {
    // GPS observation types in header order (continuation lines have a blank system).
    let mut gps_types: Vec<String> = Vec::new();
    let mut current_sys = b' ';
    let mut gps_expected = 0usize;
    loop {
        let (ln, line) = match rd.next_line()? {
            Some(x) => x,
            None => return Err(InputError::new(path, "no 'END OF HEADER' line")),
        };
        let label = text(cols(line, 60, 80));
        if label == "END OF HEADER" {
            break;
        }
        if label == "SYS / # / OBS TYPES" {
            let sys = cols(line, 0, 1).first().copied().unwrap_or(b' ');
            if sys != b' ' {
                current_sys = sys;
                let n = int_field(
                    path,
                    ln,
                    "number of observation types",
                    cols(line, 3, 6),
                    0,
                    999,
                )?;
                if sys == b'G' {
                    gps_expected = n as usize;
                }
            }
            if current_sys == b'G' {
                for k in 0..13 {
                    let t = text(cols(line, 7 + 4 * k, 10 + 4 * k));
                    if !t.is_empty() {
                        gps_types.push(t);
                    }
                }
            }
        }
    }
    if gps_types.len() != gps_expected {
        return Err(InputError::new(
            path,
            format!(
                "SYS / # / OBS TYPES: GPS announces {gps_expected} types, lists {}",
                gps_types.len()
            ),
        )
        .with_field("SYS / # / OBS TYPES"));
    }
    let idx = |name: &str| gps_types.iter().position(|t| t == name);
    let (i_c, i_l, i_d, i_s) = (idx("C1C"), idx("L1C"), idx("D1C"), idx("S1C"));

    *records = true;
    while let Some((ln, l)) = rd.next_line()? {
        let line = l.to_vec();
        if text(&line).is_empty() {
            continue;
        }
        if line.first() != Some(&b'>') {
            return Err(InputError::at_line(
                path,
                ln,
                format!(
                    "expected an epoch line starting with '>', found \"{}\"",
                    crate::error::shorten(&line)
                ),
            ));
        }
        let flag = int_field(path, ln, "epoch flag", cols(&line, 31, 32), 0, 6)? as u8;
        let n = int_field(
            path,
            ln,
            "number of satellites",
            cols(&line, 32, 35),
            0,
            999,
        )? as usize;
        if flag >= 2 {
            // Events (2-5: n header/comment lines follow) and cycle-slip records (6).
            for _ in 0..n {
                if rd.next_line()?.is_none() {
                    return Err(InputError::at_line(
                        path,
                        ln,
                        "epoch truncated: end of file",
                    ));
                }
            }
            continue;
        }
        let cal = GpstCalendar {
            year: int_field(path, ln, "year", cols(&line, 2, 6), 1980, 2200)? as i32,
            month: int_field(path, ln, "month", cols(&line, 7, 9), 1, 12)? as u32,
            day: int_field(path, ln, "day", cols(&line, 10, 12), 1, 31)? as u32,
            hour: int_field(path, ln, "hour", cols(&line, 13, 15), 0, 23)? as u32,
            minute: int_field(path, ln, "minute", cols(&line, 16, 18), 0, 59)? as u32,
            second: f64_field(path, ln, "second", cols(&line, 18, 29))?.unwrap_or(f64::NAN),
        };
        let t = GpsTime::from_calendar(&cal)
            .ok_or_else(|| InputError::at_field(path, ln, "epoch", "invalid date or time"))?;
        let clk = f64_field(path, ln, "receiver clock offset", cols(&line, 41, 56))?;
        let mut sats = Vec::new();
        for _ in 0..n {
            let (sln, sl) = match rd.next_line()? {
                Some(x) => x,
                None => {
                    return Err(InputError::at_line(
                        path,
                        ln,
                        "epoch truncated: end of file",
                    ))
                }
            };
            if sl.first() != Some(&b'G') {
                continue;
            }
            let prn = int_field(path, sln, "PRN", cols(sl, 1, 3), 1, 63)? as u8;
            let get = |k: Option<usize>, name: &str| -> Result<Option<f64>, InputError> {
                match k {
                    Some(k) => f64_field(path, sln, name, cols(sl, 3 + 16 * k, 17 + 16 * k)),
                    None => Ok(None),
                }
            };
            let lli = match i_l {
                Some(k) => lli_digit(path, sln, "L1C LLI", cols(sl, 17 + 16 * k, 18 + 16 * k))?,
                None => 0,
            };
            sats.push(SatObs {
                prn,
                pseudorange_m: get(i_c, "C1C")?,
                carrier_cycles: get(i_l, "L1C")?,
                doppler_hz: get(i_d, "D1C")?,
                cn0_dbhz: get(i_s, "S1C")?,
                lli,
            });
        }
        out.push(ObsEpoch {
            t,
            flag,
            rx_clock_offset_s: clk,
            sats,
        });
    }
    Ok(())
}

/// Header label of the RINEX 2 observation type list.
const V2_TYPES_LABEL: &str = "# / TYPES OF OBSERV";

/// A RINEX 2 `# / TYPES OF OBSERV` list being read: `I6,9(4X,A2)`, continuation
/// lines `6X,9(4X,A2)`.
#[derive(Default)]
struct V2Types {
    /// Types in order.
    list: Vec<String>,
    /// The announced number (None before the first record).
    expected: Option<usize>,
    /// Line of the last record read.
    last_ln: usize,
}

impl V2Types {
    /// Add one `# / TYPES OF OBSERV` record.
    fn push_record(&mut self, path: &Path, ln: usize, line: &[u8]) -> Result<(), InputError> {
        let count = cols(line, 0, 6);
        if !text(count).is_empty() {
            // A new list: the previous one (if any) must be complete.
            self.check(path)?;
            let n = int_field(path, ln, V2_TYPES_LABEL, count, 1, 999)? as usize;
            self.list.clear();
            self.expected = Some(n);
        } else if self.expected.is_none() {
            return Err(InputError::at_field(
                path,
                ln,
                V2_TYPES_LABEL,
                "expected the number of observation types in columns 1-6 \
                 (a continuation line must follow a line giving it)",
            ));
        }
        self.last_ln = ln;
        for k in 0..9 {
            let t = text(cols(line, 6 + 6 * k, 12 + 6 * k));
            if !t.is_empty() {
                self.list.push(t);
            }
        }
        Ok(())
    }

    /// The announced number of types must equal the number listed.
    fn check(&self, path: &Path) -> Result<(), InputError> {
        match self.expected {
            Some(n) if n != self.list.len() => Err(InputError::at_field(
                path,
                self.last_ln,
                V2_TYPES_LABEL,
                format!(
                    "the number of types ({n}, columns 1-6) does not match the types listed \
                     ({}: {})",
                    self.list.len(),
                    self.list.join(" ")
                ),
            )),
            _ => Ok(()),
        }
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.list.iter().position(|t| t == name)
    }
}

/// Where the four GPS L1 C/A observables are in a RINEX 2 record.
struct V2Layout {
    /// Lines per satellite: 5 observations per line.
    lines_per_sat: usize,
    /// Type index of C1, L1, D1, S1.
    idx: [Option<usize>; 4],
}

const V2_NAMES: [&str; 4] = ["C1", "L1", "D1", "S1"];

impl V2Layout {
    fn new(types: &V2Types) -> Self {
        V2Layout {
            lines_per_sat: types.list.len().div_ceil(5),
            idx: V2_NAMES.map(|n| types.index(n)),
        }
    }
}

/// One satellite of a RINEX 2 epoch: its text (`G05`) and its GPS PRN (None for other
/// systems).
struct V2Sat {
    id: String,
    gps_prn: Option<u8>,
}

/// Parse satellite `k` (0-based) of `n` in an epoch line or continuation line:
/// `A1,I2` at columns 33 + 3 (k mod 12).
fn v2_sat(path: &Path, ln: usize, line: &[u8], k: usize, n: usize) -> Result<V2Sat, InputError> {
    let a = 32 + 3 * (k % 12);
    let id = cols(line, a, a + 3);
    let field = "satellite list";
    if text(id).is_empty() {
        return Err(InputError::at_field(
            path,
            ln,
            field,
            format!(
                "expected satellite {} of {n} in columns {}-{}, found a blank",
                k + 1,
                a + 1,
                a + 3
            ),
        ));
    }
    let sys = id.first().copied().unwrap_or(b' ');
    let num = cols(id, 1, 3);
    let num_ok = num.len() == 2 && num.iter().any(u8::is_ascii_digit);
    let prn = if num_ok {
        text(num).parse::<u8>().ok()
    } else {
        None
    };
    let (Some(prn), true) = (prn, sys == b' ' || sys.is_ascii_uppercase()) else {
        return Err(InputError::at_field(
            path,
            ln,
            field,
            format!(
                "satellite {} of {n} (columns {}-{}): expected a system letter (blank = GPS) \
                 and a 2-digit number, found \"{}\"",
                k + 1,
                a + 1,
                a + 3,
                String::from_utf8_lossy(id)
            ),
        ));
    };
    if sys == b' ' || sys == b'G' {
        if !(1..=63).contains(&prn) {
            return Err(InputError::at_field(
                path,
                ln,
                field,
                format!(
                    "satellite {} of {n}: expected a GPS PRN 1..63, found {prn}",
                    k + 1
                ),
            ));
        }
        Ok(V2Sat {
            id: format!("G{prn:02}"),
            gps_prn: Some(prn),
        })
    } else {
        Ok(V2Sat {
            id: String::from_utf8_lossy(id).into_owned(),
            gps_prn: None,
        })
    }
}

/// Read the satellite list of a RINEX 2 epoch line (number `ln`) and its continuation
/// lines (32 blanks, then up to 12 more satellites).
fn v2_sat_list(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    line: &[u8],
    n: usize,
) -> Result<Vec<V2Sat>, InputError> {
    let mut sats = Vec::with_capacity(n);
    for k in 0..n.min(12) {
        sats.push(v2_sat(path, ln, line, k, n)?);
    }
    let mut k = 12;
    while k < n {
        let (cln, cl) = rd.next_line()?.ok_or_else(|| {
            InputError::at_line(
                path,
                ln,
                format!(
                    "epoch truncated: {n} satellites need {} satellite list lines, \
                     the file ends",
                    n.div_ceil(12)
                ),
            )
        })?;
        if !text(cols(cl, 0, 32)).is_empty() {
            return Err(InputError::at_line(
                path,
                cln,
                format!(
                    "expected a continuation of the satellite list of line {ln} \
                     (32 blanks, then satellites {}-{}), found \"{}\"",
                    k + 1,
                    n.min(k + 12),
                    crate::error::shorten(cl)
                ),
            ));
        }
        while k < n.min((k / 12 + 1) * 12) {
            sats.push(v2_sat(path, cln, cl, k, n)?);
            k += 1;
        }
    }
    Ok(sats)
}

/// Skip `count` lines that belong to the record starting at line `ln`.
fn skip_lines(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    count: usize,
    what: &str,
) -> Result<(), InputError> {
    for k in 0..count {
        if rd.next_line()?.is_none() {
            return Err(InputError::at_line(
                path,
                ln,
                format!("epoch truncated: expected {count} {what}, the file ends after {k}"),
            ));
        }
    }
    Ok(())
}

/// The records after `RINEX VERSION / TYPE` of a RINEX 2.10/2.11 file.
fn read_v2_body(
    rd: &mut LineReader,
    path: &Path,
    out: &mut Vec<ObsEpoch>,
    records: &mut bool,
) -> Result<(), InputError> {
    let mut types = V2Types::default();
    loop {
        let (ln, line) = rd
            .next_line()?
            .ok_or_else(|| InputError::new(path, "no 'END OF HEADER' line"))?;
        let label = text(cols(line, 60, 80));
        if label == "END OF HEADER" {
            break;
        }
        if label == V2_TYPES_LABEL {
            types.push_record(path, ln, line)?;
        }
    }
    types.check(path)?;
    if types.expected.is_none() {
        return Err(InputError::new(
            path,
            "expected a '# / TYPES OF OBSERV' header record, found none",
        )
        .with_field(V2_TYPES_LABEL));
    }
    let mut layout = V2Layout::new(&types);

    *records = true;
    while let Some((ln, l)) = rd.next_line()? {
        let line = l.to_vec();
        if text(&line).is_empty() {
            continue;
        }
        let flag = int_field(path, ln, "epoch flag", cols(&line, 28, 29), 0, 6)? as u8;
        if (2..=5).contains(&flag) {
            // Events: the count is that of the special records (header lines) that
            // follow. A new '# / TYPES OF OBSERV' among them replaces the list.
            let n = int_field(path, ln, "number of records", cols(&line, 29, 32), 0, 999)? as usize;
            let mut new_types = V2Types::default();
            for k in 0..n {
                let (rln, r) = rd.next_line()?.ok_or_else(|| {
                    InputError::at_line(
                        path,
                        ln,
                        format!(
                            "event truncated: expected {n} header records, \
                             the file ends after {k}"
                        ),
                    )
                })?;
                if text(cols(r, 60, 80)) == V2_TYPES_LABEL {
                    new_types.push_record(path, rln, r)?;
                }
            }
            if new_types.expected.is_some() {
                new_types.check(path)?;
                types = new_types;
                layout = V2Layout::new(&types);
            }
            continue;
        }
        let n = int_field(
            path,
            ln,
            "number of satellites",
            cols(&line, 29, 32),
            0,
            999,
        )? as usize;
        if flag == 6 {
            // Cycle-slip records: the satellite list, then one observation record
            // per satellite.
            v2_sat_list(rd, path, ln, &line, n)?;
            skip_lines(
                rd,
                path,
                ln,
                n * layout.lines_per_sat,
                "cycle-slip record lines",
            )?;
            continue;
        }
        let yy = int_field(path, ln, "year", cols(&line, 1, 3), 0, 99)? as i32;
        let cal = GpstCalendar {
            // Two-digit years: 80-99 are 1980-1999, 00-79 are 2000-2079.
            year: if yy >= 80 { 1900 + yy } else { 2000 + yy },
            month: int_field(path, ln, "month", cols(&line, 4, 6), 1, 12)? as u32,
            day: int_field(path, ln, "day", cols(&line, 7, 9), 1, 31)? as u32,
            hour: int_field(path, ln, "hour", cols(&line, 10, 12), 0, 23)? as u32,
            minute: int_field(path, ln, "minute", cols(&line, 13, 15), 0, 59)? as u32,
            second: f64_required(path, ln, "second", cols(&line, 15, 26))?,
        };
        let t = GpsTime::from_calendar(&cal).ok_or_else(|| {
            InputError::at_field(
                path,
                ln,
                "epoch",
                format!(
                    "expected a valid GPST date and time, found {:04}-{:02}-{:02} \
                     {:02}:{:02}:{}",
                    cal.year, cal.month, cal.day, cal.hour, cal.minute, cal.second
                ),
            )
        })?;
        let sat_list = v2_sat_list(rd, path, ln, &line, n)?;
        let clk = f64_field(path, ln, "receiver clock offset", cols(&line, 68, 80))?;
        let mut sats = Vec::new();
        for sat in &sat_list {
            let mut vals: [Option<f64>; 4] = [None; 4];
            let mut lli = 0;
            for j in 0..layout.lines_per_sat {
                let (oln, ol) = rd.next_line()?.ok_or_else(|| {
                    InputError::at_line(
                        path,
                        ln,
                        format!(
                            "epoch truncated: expected {} observation lines for each of \
                             {n} satellites, the file ends in those of {}",
                            layout.lines_per_sat, sat.id
                        ),
                    )
                })?;
                if sat.gps_prn.is_none() {
                    continue;
                }
                for (w, name) in V2_NAMES.iter().enumerate() {
                    let Some(i) = layout.idx.get(w).copied().flatten() else {
                        continue;
                    };
                    if i / 5 != j {
                        continue;
                    }
                    let c = 16 * (i % 5);
                    let field = format!("{} {name}", sat.id);
                    if let Some(v) = vals.get_mut(w) {
                        *v = f64_field(path, oln, &field, cols(ol, c, c + 14))?;
                    }
                    if w == 1 {
                        lli = lli_digit(
                            path,
                            oln,
                            &format!("{field} LLI"),
                            cols(ol, c + 14, c + 15),
                        )?;
                    }
                }
            }
            if let Some(prn) = sat.gps_prn {
                let [pseudorange_m, carrier_cycles, doppler_hz, cn0_dbhz] = vals;
                sats.push(SatObs {
                    prn,
                    pseudorange_m,
                    carrier_cycles,
                    doppler_hz,
                    cn0_dbhz,
                    lli,
                });
            }
        }
        out.push(ObsEpoch {
            t,
            flag,
            rx_clock_offset_s: clk,
            sats,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ssi_table() {
        assert_eq!(ssi_from_cn0(5.0), 1);
        assert_eq!(ssi_from_cn0(12.0), 2);
        assert_eq!(ssi_from_cn0(17.9), 2);
        assert_eq!(ssi_from_cn0(18.0), 3);
        assert_eq!(ssi_from_cn0(45.0), 7);
        assert_eq!(ssi_from_cn0(53.9), 8);
        assert_eq!(ssi_from_cn0(54.0), 9);
        assert_eq!(ssi_from_cn0(70.0), 9);
    }
}
