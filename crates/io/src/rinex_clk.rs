//! RINEX clock files (3.00-3.04, and 2.00 with the same records; docs/FORMATS.md
//! "RINEX clock"): the satellite clock records `AS`, read into
//! `navfuse_gnss::precise::PreciseProducts` beside SP3 orbits (their clocks are
//! finer: 30 s or 5 s against SP3's 5 or 15 min). Records are read by fields
//! separated by blanks, which covers RINEX 3.04's wider name column: `AS`, the
//! satellite, year, month, day, hour, minute, second, the number of values, the
//! bias \[s\] (and its sigma). Receiver (`AR`) and other records are counted and
//! skipped.

use crate::error::InputError;
use navfuse_core::sat::SatId;
use navfuse_core::time::{leap_seconds, GpsTime, GpstCalendar};
use navfuse_gnss::precise::PreciseProducts;
use std::path::Path;

/// A clock file's satellite clocks.
#[derive(Clone, Debug, PartialEq)]
pub struct ClockFile {
    /// `TIME SYSTEM ID` (GPS when absent); the samples are in GPST.
    pub time_system: String,
    /// (GPST, satellite, clock bias \[s\]).
    pub samples: Vec<(GpsTime, SatId, f64)>,
    /// Records other than `AS` (receivers, calibrations), skipped.
    pub other_records: usize,
}

/// Read the satellite clocks of a RINEX clock file. Errors name the file, line and
/// field.
pub fn read_rinex_clk(path: &Path) -> Result<ClockFile, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::open(path, &e))?;
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let mut time_system = "GPS".to_string();
    let mut header_ok = false;
    for (no, l) in lines.by_ref() {
        if no == 1 && !l.get(60..).unwrap_or("").contains("RINEX VERSION") {
            return Err(InputError::at_line(
                path,
                1,
                "no `RINEX VERSION / TYPE` label in columns 61-80: expected a RINEX clock file",
            ));
        }
        if no == 1 && l.get(20..21) != Some("C") {
            return Err(InputError::at_line(
                path,
                1,
                format!(
                    "file type `{}` (column 21): expected C (clock data)",
                    l.get(20..21).unwrap_or("")
                ),
            ));
        }
        let label = l.get(60..).unwrap_or("").trim();
        if label == "TIME SYSTEM ID" {
            time_system = l.get(..60).unwrap_or("").trim().to_string();
        }
        if label == "END OF HEADER" {
            header_ok = true;
            break;
        }
    }
    if !header_ok {
        return Err(InputError::at_line(path, 1, "no END OF HEADER line"));
    }
    let mut samples = Vec::new();
    let mut other_records = 0;
    for (no, l) in lines {
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.is_empty() {
            continue;
        }
        if f[0] != "AS" {
            other_records += 1;
            continue;
        }
        let bad = |what: &str| {
            InputError::at_line(
                path,
                no,
                format!("AS record, field {what}: expected `AS SAT YYYY MM DD HH MM SS.SSSSSS N BIAS [SIGMA]`"),
            )
        };
        if f.len() < 10 {
            return Err(bad("count"));
        }
        let sat = SatId::parse(f[1]).ok_or_else(|| bad("satellite"))?;
        let n = |k: usize, what: &str| f[k].parse::<f64>().map_err(|_| bad(what));
        let c = GpstCalendar {
            year: n(2, "year")? as i32,
            month: n(3, "month")? as u32,
            day: n(4, "day")? as u32,
            hour: n(5, "hour")? as u32,
            minute: n(6, "minute")? as u32,
            second: n(7, "second")?,
        };
        let t = GpsTime::from_calendar(&c).ok_or_else(|| bad("date"))?;
        let bias = f[9]
            .replace(['D', 'd'], "E")
            .parse::<f64>()
            .map_err(|_| bad("bias"))?;
        let off = match time_system.as_str() {
            "GPS" | "GAL" | "QZS" | "" => 0.0,
            "BDT" => 14.0,
            "UTC" | "GLO" => leap_seconds(u32::try_from(t.week).ok()),
            "TAI" => -19.0,
            other => {
                return Err(InputError::at_line(
                    path,
                    no,
                    format!(
                        "TIME SYSTEM ID `{other}`: expected GPS, GAL, BDT, QZS, UTC, GLO or TAI"
                    ),
                ))
            }
        };
        samples.push((t.add_s(off), sat, bias));
    }
    if samples.is_empty() {
        return Err(InputError::new(path, "no satellite clock records (`AS`)"));
    }
    Ok(ClockFile {
        time_system,
        samples,
        other_records,
    })
}

/// Use a clock file's clocks in `products` in place of the SP3 ones.
pub fn set_clocks(f: &ClockFile, products: &mut PreciseProducts) {
    products.clear_clocks();
    for (t, sat, bias) in &f.samples {
        products.add_clock(*sat, *t, *bias);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str =
        "     3.00           C                                       RINEX VERSION / TYPE
GPS                                                         TIME SYSTEM ID
                                                            END OF HEADER
";

    #[test]
    fn reads_satellite_clocks_and_names_errors() {
        let d = std::env::temp_dir().join(format!("navfuse_clk_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("a.clk");
        let body = "AR ESBC 2020 06 25 00 00  0.000000  1   -1.0E-08\n\
AS G01  2020 06 25 00 00  0.000000  2   -1.234567890123E-04  1.0E-11\n\
AS G01  2020 06 25 00 00 30.000000  1   -1.234568000000E-04\n\
AS E11       2020 06 25 00 00  0.000000  1    2.5D-05\n";
        std::fs::write(&p, format!("{HEADER}{body}")).unwrap();
        let f = read_rinex_clk(&p).unwrap();
        assert_eq!(f.samples.len(), 3);
        assert_eq!(f.other_records, 1);
        assert_eq!(f.samples[1].1, SatId::gps(1));
        assert!(
            (f.samples[1].0.sow - (345_600.0 + 30.0 - 345_600.0 + f.samples[0].0.sow)).abs() < 1e-9
        );
        assert_eq!(f.samples[2].2, 2.5e-5);
        let mut prod = PreciseProducts::new(f.samples[0].0, 900.0, 30.0);
        set_clocks(&f, &mut prod);
        std::fs::write(
            &p,
            format!("{HEADER}AS G01  2020 06 25 00 00  0.000000  1   abc\n"),
        )
        .unwrap();
        let e = read_rinex_clk(&p).unwrap_err().to_string();
        assert!(e.contains("a.clk:4") && e.contains("bias"), "{e}");
        std::fs::remove_dir_all(&d).ok();
    }
}
