//! The body of a RINEX 3.0x observation file (GPS C1C/L1C/D1C/S1C).

use super::fields::{f64_field, int_field, lli_digit, text};
use super::{ObsEpoch, SatObs};
use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav::cols;
use navfuse_gnss::time::GpstCalendar;
use navfuse_gnss::GpsTime;
use std::path::Path;

/// The records after `RINEX VERSION / TYPE` of a RINEX 3.0x file.
pub(super) fn read_v3_body(
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
