//! RINEX 3.04 observation files, GPS L1 C/A only: C1C (pseudorange, m), L1C (carrier
//! phase, cycles), D1C (Doppler, Hz), S1C (C/N0, dB-Hz).
//!
//! The writer produces a GPS-only RINEX 3.04 file (§5.2 header, §5.3 epoch records:
//! F14.3 value, LLI digit, SSI digit per observation; blank fields when absent). The
//! reader takes RINEX 3.0x files of any system mix: GPS observation types are found
//! by their position in `SYS / # / OBS TYPES`, other systems' satellites are skipped,
//! epochs with flag 0 (OK) or 1 (power failure since the previous epoch) are kept,
//! flags 2-5 (events: their header/comment lines are skipped) and 6 (cycle-slip
//! records) are skipped.

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

/// One satellite's L1 C/A observations at one epoch.
#[derive(Clone, Debug, PartialEq)]
pub struct SatObs {
    pub prn: u8,
    /// C1C [m].
    pub pseudorange_m: Option<f64>,
    /// L1C [cycles].
    pub carrier_cycles: Option<f64>,
    /// D1C [Hz].
    pub doppler_hz: Option<f64>,
    /// S1C [dB-Hz].
    pub cn0_dbhz: Option<f64>,
    /// Loss-of-lock indicator of the carrier phase (RINEX 3.04 §5.3: bit 0 lost lock,
    /// bit 1 half-cycle ambiguity, bit 2 BOC tracking); 0 = OK.
    pub lli: u8,
}

/// One epoch of GPS observations.
#[derive(Clone, Debug, PartialEq)]
pub struct ObsEpoch {
    /// Receiver time tag (GPST).
    pub t: GpsTime,
    /// Epoch flag, 0 or 1.
    pub flag: u8,
    /// Receiver clock offset [s], if the file gives it.
    pub rx_clock_offset_s: Option<f64>,
    /// GPS satellites, in file order.
    pub sats: Vec<SatObs>,
}

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

/// Read the GPS C1C/L1C/D1C/S1C observations of a RINEX 3.0x observation file.
pub fn read_rinex3_obs(path: &Path) -> Result<Vec<ObsEpoch>, InputError> {
    let mut rd = LineReader::open(path)?;
    let (ln, first) = match rd.next_line()? {
        Some((ln, l)) => (ln, l.to_vec()),
        None => return Err(InputError::new(path, "empty file: expected a RINEX header")),
    };
    if text(cols(&first, 60, 80)) != "RINEX VERSION / TYPE" {
        return Err(InputError::at_line(
            path,
            ln,
            "expected 'RINEX VERSION / TYPE' in columns 61-80 of the first line",
        ));
    }
    let version = f64_field(path, ln, "RINEX version", cols(&first, 0, 9))?.unwrap_or(0.0);
    if version.floor() != 3.0 {
        return Err(InputError::at_field(
            path,
            ln,
            "RINEX version",
            format!("version {version} is not supported (3.0x is)"),
        ));
    }
    if cols(&first, 20, 21) != b"O" {
        return Err(InputError::at_field(
            path,
            ln,
            "file type",
            "expected an observation file (type O)",
        ));
    }
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

    let mut out = Vec::new();
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
                Some(k) => match cols(sl, 17 + 16 * k, 18 + 16 * k) {
                    [b' '] | [] => 0,
                    [d @ b'0'..=b'7'] => d - b'0',
                    other => {
                        return Err(InputError::at_field(
                            path,
                            sln,
                            "L1C LLI",
                            format!(
                                "expected a digit 0-7, found \"{}\"",
                                String::from_utf8_lossy(other)
                            ),
                        ))
                    }
                },
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
    Ok(out)
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
