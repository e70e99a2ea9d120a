//! The body of a RINEX 3.0x / 4.0x observation file, every system and signal
//! (RINEX 3.05 §5.2-5.3, RINEX 4.00 §5: the same observation records).

use super::fields::{f64_field, int_field, lli_digit, text};
use super::BodyOut;
use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav::cols;
use navfuse_gnss::obs::{MultiObsEpoch, ObsSignalsHeader, ObsValue, PhaseShift, SatSignals};
use navfuse_gnss::time::GpstCalendar;
use navfuse_gnss::{GpsTime, ObsCode, SatId, System};
use std::path::Path;

const TYPES_LABEL: &str = "SYS / # / OBS TYPES";

/// One system letter from column 1 of a header record.
fn system_at(path: &Path, ln: usize, field: &str, b: u8) -> Result<System, InputError> {
    System::from_letter(b as char)
        .filter(|_| b != b' ')
        .ok_or_else(|| {
            InputError::at_field(
                path,
                ln,
                field,
                format!(
                    "expected a system letter G R E C J S I, found \"{}\"",
                    b as char
                ),
            )
        })
}

/// Read the header after `RINEX VERSION / TYPE`: `SYS / # / OBS TYPES` (`A1,2X,I3,
/// 13(1X,A3)`, continuation lines with a blank system), `GLONASS SLOT / FRQ #` (`I3,1X,
/// 8(A1,I2,1X,I2,1X)`), `SYS / PHASE SHIFT` (`A1,1X,A3,1X,F8.5`; its satellite lists
/// are not kept).
fn read_v3_header(
    rd: &mut LineReader,
    path: &Path,
    version: f64,
) -> Result<ObsSignalsHeader, InputError> {
    let mut h = ObsSignalsHeader {
        version,
        ..Default::default()
    };
    let mut expected: Vec<(System, usize, usize)> = Vec::new();
    loop {
        let (ln, line) = rd
            .next_line()?
            .ok_or_else(|| InputError::new(path, "no 'END OF HEADER' line"))?;
        let label = text(cols(line, 60, 80));
        match label.as_str() {
            "END OF HEADER" => break,
            TYPES_LABEL => {
                let b = cols(line, 0, 1).first().copied().unwrap_or(b' ');
                if b != b' ' {
                    let sys = system_at(path, ln, TYPES_LABEL, b)?;
                    let n = int_field(
                        path,
                        ln,
                        "number of observation types",
                        cols(line, 3, 6),
                        0,
                        999,
                    )?;
                    h.types.retain(|(s, _)| *s != sys);
                    expected.retain(|(s, _, _)| *s != sys);
                    h.types.push((sys, Vec::new()));
                    expected.push((sys, n as usize, ln));
                } else if h.types.is_empty() {
                    return Err(InputError::at_field(
                        path,
                        ln,
                        TYPES_LABEL,
                        "expected a system letter in column 1 (a continuation line must \
                         follow a line giving it)",
                    ));
                }
                let Some((_, list)) = h.types.last_mut() else {
                    continue;
                };
                for k in 0..13 {
                    let t = text(cols(line, 7 + 4 * k, 10 + 4 * k));
                    if t.is_empty() {
                        continue;
                    }
                    let code = ObsCode::parse(&t).ok_or_else(|| {
                        InputError::at_field(
                            path,
                            ln,
                            TYPES_LABEL,
                            format!("expected an observation code like C1C, found \"{t}\""),
                        )
                    })?;
                    list.push(code);
                }
            }
            "GLONASS SLOT / FRQ #" => {
                for k in 0..8 {
                    let a = 4 + 7 * k;
                    let id = text(cols(line, a, a + 3));
                    if id.is_empty() {
                        continue;
                    }
                    let field = "GLONASS SLOT / FRQ #";
                    let sat = SatId::parse(&id).filter(|s| s.system == System::Glonass);
                    let sat = sat.ok_or_else(|| {
                        InputError::at_field(
                            path,
                            ln,
                            field,
                            format!("expected Rnn, found \"{id}\""),
                        )
                    })?;
                    let k = int_field(path, ln, field, cols(line, a + 4, a + 6), -7, 13)? as i8;
                    h.glonass_channels.push((sat.prn, k));
                }
            }
            "SYS / PHASE SHIFT" => {
                let b = cols(line, 0, 1).first().copied().unwrap_or(b' ');
                if b == b' ' {
                    continue; // a continuation line of satellites
                }
                let field = "SYS / PHASE SHIFT";
                let system = system_at(path, ln, field, b)?;
                let t = text(cols(line, 2, 5));
                let code = ObsCode::parse(&t).ok_or_else(|| {
                    InputError::at_field(
                        path,
                        ln,
                        field,
                        format!("expected an observation code, found \"{t}\""),
                    )
                })?;
                let shift_cycles = f64_field(path, ln, field, cols(line, 6, 14))?;
                h.phase_shifts.push(PhaseShift {
                    system,
                    code,
                    shift_cycles,
                });
            }
            _ => {}
        }
    }
    for ((sys, list), (_, n, ln)) in h.types.iter().zip(&expected) {
        if list.len() != *n {
            return Err(InputError::at_field(
                path,
                *ln,
                TYPES_LABEL,
                format!("{} announces {n} types, lists {}", sys.name(), list.len()),
            ));
        }
    }
    Ok(h)
}

/// The records after `RINEX VERSION / TYPE` of a RINEX 3.0x / 4.0x file.
pub(super) fn read_v3_body(
    rd: &mut LineReader,
    path: &Path,
    version: f64,
    out: &mut BodyOut,
) -> Result<(), InputError> {
    out.header = read_v3_header(rd, path, version)?;
    let types = &out.header.types;
    out.records = true;
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
        let mut sats = Vec::with_capacity(n);
        for _ in 0..n {
            let Some((sln, sl)) = rd.next_line()? else {
                return Err(InputError::at_line(
                    path,
                    ln,
                    "epoch truncated: end of file",
                ));
            };
            let id = cols(sl, 0, 3);
            let b = id.first().copied().unwrap_or(b' ');
            let Some(system) = System::from_letter(b as char).filter(|_| b != b' ') else {
                return Err(InputError::at_field(
                    path,
                    sln,
                    "satellite",
                    format!(
                        "expected a satellite like G05 in columns 1-3, found \"{}\"",
                        String::from_utf8_lossy(id)
                    ),
                ));
            };
            let hi = if system == System::Gps { 63 } else { 99 };
            let prn = int_field(path, sln, "PRN", cols(sl, 1, 3), 1, hi)? as u8;
            let sat = SatId::new(system, prn);
            let Some((_, list)) = types.iter().find(|(s, _)| *s == system) else {
                return Err(InputError::at_field(
                    path,
                    sln,
                    "satellite",
                    format!(
                        "{sat}: the header lists no observation types for {}",
                        system.name()
                    ),
                ));
            };
            let mut signals = Vec::with_capacity(list.len());
            for (k, code) in list.iter().enumerate() {
                let c = 3 + 16 * k;
                let ob = cols(sl, c, c + 16);
                if ob.iter().all(|&x| x == b' ') {
                    continue;
                }
                // The line names the satellite (columns 1-3).
                let name = code.to_string();
                let value = f64_field(path, sln, &name, cols(ob, 0, 14))?;
                let lli = flag_digit(path, sln, &name, "LLI", cols(ob, 14, 15))?;
                let ssi = flag_digit(path, sln, &name, "SSI", cols(ob, 15, 16))?;
                signals.push((*code, ObsValue { value, lli, ssi }));
            }
            sats.push(SatSignals { sat, signals });
        }
        out.epochs.push(MultiObsEpoch {
            t,
            flag,
            rx_clock_offset_s: clk,
            sats,
        });
    }
    Ok(())
}

/// An LLI (0-7) or SSI (1-9, 0 allowed) column: None when blank.
pub(super) fn flag_digit(
    path: &Path,
    ln: usize,
    name: &str,
    what: &str,
    b: &[u8],
) -> Result<Option<u8>, InputError> {
    match b {
        [b' '] | [] => Ok(None),
        [d @ b'0'..=b'9'] if what == "SSI" => Ok(Some(d - b'0')),
        _ => lli_digit(path, ln, &format!("{name} {what}"), b).map(Some),
    }
}
