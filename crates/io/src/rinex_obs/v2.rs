//! The body of a RINEX 2.10/2.11 observation file: the `# / TYPES OF OBSERV` list,
//! the satellite lists with continuation lines, and the records.

use super::fields::{f64_field, f64_required, int_field, lli_digit, text};
use super::{ObsEpoch, SatObs};
use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav::cols;
use navfuse_gnss::time::GpstCalendar;
use navfuse_gnss::GpsTime;
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

    fn index(&self, name: &str) -> Option<usize> {
        self.list.iter().position(|t| t == name)
    }
}

/// Where the four GPS L1 C/A observables are in a RINEX 2 record.
pub(super) struct V2Layout {
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
pub(super) struct V2Sat {
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
pub(super) fn read_v2_body(
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
