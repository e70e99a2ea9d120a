//! The body of a RINEX 2.10/2.11 observation file: the `# / TYPES OF OBSERV` list,
//! the satellite lists with continuation lines, and the records.

use super::fields::{f64_field, f64_required, int_field, text};
use super::v3::flag_digit;
use super::BodyOut;
use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav::cols;
use navfuse_gnss::obs::{MultiObsEpoch, ObsValue, SatSignals};
use navfuse_gnss::time::GpstCalendar;
use navfuse_gnss::GpsTime;
use navfuse_gnss::{ObsCode, SatId, System};
use std::path::Path;

/// Header label of the RINEX 2 observation type list.
const V2_TYPES_LABEL: &str = "# / TYPES OF OBSERV";

/// A RINEX 2 `# / TYPES OF OBSERV` list being read: `I6,9(4X,A2)`, continuation
/// lines `6X,9(4X,A2)`.
#[derive(Default)]
pub(super) struct V2Types {
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
}

/// Where the observables are in a RINEX 2 record and their RINEX 3 codes per system.
pub(super) struct V2Layout {
    /// Lines per satellite: 5 observations per line.
    lines_per_sat: usize,
    /// The RINEX 2 type names, in order.
    names: Vec<String>,
}

impl V2Layout {
    fn new(types: &V2Types) -> Self {
        V2Layout {
            lines_per_sat: types.list.len().div_ceil(5),
            names: types.list.clone(),
        }
    }

    /// The RINEX 3 code of each type for `system` (None: not mapped, skipped).
    fn codes(&self, system: System) -> Vec<Option<ObsCode>> {
        let has = |n: &str| self.names.iter().any(|t| t == n);
        self.names
            .iter()
            .map(|t| v2_code(system, t, has("P2")))
            .collect()
    }
}

/// The RINEX 3 code of RINEX 2 type `t` for `system` (docs/FORMATS.md "RINEX 2
/// observation codes"; RINEX 3.05 §5.1 names the signals, RINEX 2.11 §5.1 the types):
/// P1/P2 are GPS W (P(Y), semi-codeless) and GLONASS P; C1/L1/D1/S1 are C/A (C) for
/// GPS, QZSS, SBAS and GLONASS and X for Galileo; GPS C2 is L2C (X) and L2/D2/S2 are
/// W when the file has P2, X otherwise; GLONASS C2 is C, L2/D2/S2 P with P2, C
/// otherwise; band 5 is X (SBAS I), Galileo 6/7/8 X, BeiDou 2/6/7 I.
fn v2_code(system: System, t: &str, has_p2: bool) -> Option<ObsCode> {
    let &[k, b] = t.as_bytes() else { return None };
    let kind = match k {
        b'C' | b'P' => b'C',
        b'L' | b'D' | b'S' => k,
        _ => return None,
    };
    use System::*;
    let attr = match (system, k, b) {
        (Gps | Qzss, b'P', b'1' | b'2') => b'W',
        (Glonass, b'P', b'1' | b'2') => b'P',
        (_, b'P', _) => return None,
        (Gps | Qzss | Sbas | Glonass, _, b'1') => b'C',
        (Galileo, _, b'1' | b'5' | b'6' | b'7' | b'8') => b'X',
        (Gps | Qzss, b'C', b'2') => b'X',
        (Gps | Qzss, _, b'2') => {
            if has_p2 {
                b'W'
            } else {
                b'X'
            }
        }
        (Glonass, b'C', b'2') => b'C',
        (Glonass, _, b'2') => {
            if has_p2 {
                b'P'
            } else {
                b'C'
            }
        }
        (Gps | Qzss, _, b'5') => b'X',
        (Sbas, _, b'5') => b'I',
        (BeiDou, _, b'2' | b'6' | b'7') => b'I',
        _ => return None,
    };
    Some(ObsCode([kind, b, attr]))
}

/// One satellite of a RINEX 2 epoch: its text (`G05`) and its identity (None for a
/// system letter navfuse does not know; its records are skipped).
pub(super) struct V2Sat {
    id: String,
    sat: Option<SatId>,
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
            sat: Some(SatId::gps(prn)),
        })
    } else {
        let sat = System::from_letter(sys as char)
            .filter(|_| prn > 0)
            .map(|s| SatId::new(s, prn));
        Ok(V2Sat {
            id: String::from_utf8_lossy(id).into_owned(),
            sat,
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
        // This line's satellites (the bound fixed before the loop: more than 24
        // satellites take three or more lines).
        let end = n.min((k / 12 + 1) * 12);
        while k < end {
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
pub(super) fn read_v2_body(
    rd: &mut LineReader,
    path: &Path,
    version: f64,
    out: &mut BodyOut,
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
    out.header.version = version;
    out.header.types = System::ALL
        .iter()
        .map(|&s| (s, layout.codes(s).into_iter().flatten().collect::<Vec<_>>()))
        .filter(|(_, c)| !c.is_empty())
        .collect();

    out.records = true;
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
        let mut sats = Vec::with_capacity(sat_list.len());
        for sat in &sat_list {
            let codes = sat.sat.map(|s| layout.codes(s.system)).unwrap_or_default();
            let mut signals = Vec::with_capacity(codes.len());
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
                for i in 5 * j..(5 * j + 5).min(codes.len()) {
                    let Some(code) = codes.get(i).copied().flatten() else {
                        continue;
                    };
                    let c = 16 * (i % 5);
                    let ob = cols(ol, c, c + 16);
                    if ob.iter().all(|&x| x == b' ') {
                        continue;
                    }
                    let field = format!("{} {}", sat.id, layout.names[i]);
                    let value = f64_field(path, oln, &field, cols(ob, 0, 14))?;
                    let lli = flag_digit(path, oln, &field, "LLI", cols(ob, 14, 15))?;
                    let ssi = flag_digit(path, oln, &field, "SSI", cols(ob, 15, 16))?;
                    signals.push((code, ObsValue { value, lli, ssi }));
                }
            }
            if let Some(sat) = sat.sat {
                sats.push(SatSignals { sat, signals });
            }
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
