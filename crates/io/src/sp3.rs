//! IGS SP3-c and SP3-d precise orbit files (docs/FORMATS.md "SP3"): read into
//! `navfuse_gnss::precise::PreciseProducts`, and written (from any orbit source, e.g.
//! broadcast ephemerides sampled on a grid).
//!
//! Layout (SP3-d, Hilla 2016, §2-§3; SP3-c the same with at most 85 satellites):
//! line 1 `#dP` + start epoch + number of epochs; line 2 `##` + GPS week, seconds of
//! week, epoch interval; `+ ` lines: satellite count and identifiers (17 per line
//! from column 10); `%c` line: file type and time system (columns 10-12); `*  `
//! epoch lines; `P` records: satellite, x y z \[km\] (columns 5-46), clock \[us\]
//! (columns 47-60; 999999.999999 = none); `V` records: velocity [dm/s] and clock rate
//! [1e-4 us/s]; `EOF`.

use crate::error::InputError;
use nalgebra::Vector3;
use navfuse_core::sat::SatId;
use navfuse_core::time::{leap_seconds, GpsTime, GpstCalendar};
use navfuse_gnss::precise::PreciseProducts;
use std::io::Write;
use std::path::Path;

/// The "no value" of SP3's position and clock fields.
const BAD_CLOCK_US: f64 = 999_999.0;

/// One SP3 file's header and samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Sp3File {
    /// 'c' or 'd'.
    pub version: char,
    /// The time system of the epochs (`GPS`, `GAL`, `BDT`, `UTC`, `TAI`, `GLO`, `QZS`);
    /// the samples below are converted to GPST.
    pub time_system: String,
    /// Nominal epoch interval \[s\].
    pub interval_s: f64,
    /// Coordinate system and agency (line 1).
    pub coordinate_system: String,
    pub agency: String,
    /// Satellites of the header.
    pub satellites: Vec<SatId>,
    /// (GPST, satellite, ECEF position \[m\], clock \[s\] when given).
    pub samples: Vec<(GpsTime, SatId, Vector3<f64>, Option<f64>)>,
}

fn err(path: &Path, line: usize, msg: impl Into<String>) -> InputError {
    InputError::at_line(path, line, msg)
}

fn field(l: &str, a: usize, b: usize) -> &str {
    l.get(a..b.min(l.len())).unwrap_or("").trim()
}

fn num(path: &Path, no: usize, l: &str, a: usize, b: usize, what: &str) -> Result<f64, InputError> {
    let f = field(l, a, b);
    f.parse::<f64>().map_err(|_| {
        err(
            path,
            no,
            format!(
                "columns {}-{} ({what}) = `{f}`: expected a number",
                a + 1,
                b
            ),
        )
    })
}

/// GPST minus the time system's clock \[s\] (UTC and GLONASS with the leap seconds of
/// `week`).
fn to_gpst_offset_s(system: &str, week: i32) -> Option<f64> {
    let leap = leap_seconds(u32::try_from(week).ok());
    match system {
        "GPS" | "GAL" | "QZS" | "IRN" | "" => Some(0.0),
        "BDT" => Some(14.0),
        "TAI" => Some(-19.0),
        "UTC" | "GLO" => Some(leap),
        _ => None,
    }
}

/// Read an SP3-c/d file. Errors name the file, line and columns.
pub fn read_sp3(path: &Path) -> Result<Sp3File, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::open(path, &e))?;
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let (_, l1) = lines
        .next()
        .ok_or_else(|| err(path, 1, "empty file; expected an SP3 header `#cP` or `#dP`"))?;
    let version = l1.chars().nth(1).unwrap_or(' ');
    if !l1.starts_with('#') || !matches!(version, 'c' | 'd') {
        return Err(err(
            path,
            1,
            format!(
                "`{}`: expected an SP3-c or SP3-d header (`#cP`, `#dP`, `#cV`, `#dV`)",
                l1.chars().take(3).collect::<String>()
            ),
        ));
    }
    let coordinate_system = field(l1, 46, 51).to_string();
    let agency = field(l1, 56, 60).to_string();
    let mut interval_s = 0.0;
    let mut time_system = String::from("GPS");
    let mut satellites = Vec::new();
    let mut samples = Vec::new();
    let mut epoch: Option<(GpsTime, f64)> = None;
    let mut sat_count: Option<usize> = None;
    let mut ended = false;
    for (no, l) in lines {
        if ended || l.trim().is_empty() {
            continue;
        }
        if l.starts_with("##") {
            interval_s = num(path, no, l, 24, 38, "epoch interval")?;
        } else if l.starts_with("+ ") && !l.starts_with("++") {
            if sat_count.is_none() {
                sat_count = Some(num(path, no, l, 3, 6, "number of satellites")? as usize);
            }
            let want = sat_count.unwrap_or(0);
            for k in 0..17 {
                let id = field(l, 9 + 3 * k, 12 + 3 * k);
                if satellites.len() >= want || id.is_empty() || id == "0" || id == "00" {
                    continue;
                }
                let sat = SatId::parse(id).ok_or_else(|| {
                    err(
                        path,
                        no,
                        format!(
                            "satellite `{id}` in column {}: expected e.g. G01",
                            10 + 3 * k
                        ),
                    )
                })?;
                satellites.push(sat);
            }
        } else if l.starts_with("%c") && time_system == "GPS" && field(l, 9, 12) != "ccc" {
            let ts = field(l, 9, 12);
            if !ts.is_empty() {
                time_system = ts.to_string();
            }
        } else if l.starts_with('*') {
            let c = GpstCalendar {
                year: num(path, no, l, 3, 7, "year")? as i32,
                month: num(path, no, l, 8, 10, "month")? as u32,
                day: num(path, no, l, 11, 13, "day")? as u32,
                hour: num(path, no, l, 14, 16, "hour")? as u32,
                minute: num(path, no, l, 17, 19, "minute")? as u32,
                second: num(path, no, l, 20, 31, "second")?,
            };
            let t = GpsTime::from_calendar(&c)
                .ok_or_else(|| err(path, no, "epoch: not a valid date and time"))?;
            let off = to_gpst_offset_s(&time_system, t.week).ok_or_else(|| {
                err(path, no, format!("time system `{time_system}` (%c line): expected GPS, GAL, BDT, QZS, UTC, TAI or GLO"))
            })?;
            epoch = Some((t.add_s(off), off));
        } else if l.starts_with('P') {
            let (t, _) = epoch.ok_or_else(|| {
                err(
                    path,
                    no,
                    "a position record before the first epoch line (`*`)",
                )
            })?;
            let id = field(l, 1, 4);
            let sat = SatId::parse(id).ok_or_else(|| {
                err(
                    path,
                    no,
                    format!("satellite `{id}` (columns 2-4): expected e.g. G01"),
                )
            })?;
            let x = num(path, no, l, 4, 18, "x [km]")?;
            let y = num(path, no, l, 18, 32, "y [km]")?;
            let z = num(path, no, l, 32, 46, "z [km]")?;
            if x == 0.0 && y == 0.0 && z == 0.0 {
                continue; // SP3's "no position"
            }
            let clk = if field(l, 46, 60).is_empty() {
                None
            } else {
                let c = num(path, no, l, 46, 60, "clock [us]")?;
                (c.abs() < BAD_CLOCK_US).then_some(c * 1e-6)
            };
            samples.push((t, sat, Vector3::new(x, y, z) * 1e3, clk));
        } else if l.starts_with("EOF") {
            ended = true;
        }
        // `++`, `%f`, `%i`, `/*`, `V`, `EP`, `EV` lines: not needed here.
    }
    if samples.is_empty() {
        return Err(err(path, 1, "no position records (`P` lines)"));
    }
    if interval_s.is_nan() || interval_s <= 0.0 {
        return Err(err(
            path,
            2,
            "epoch interval (line 2, columns 25-38) missing or not positive",
        ));
    }
    Ok(Sp3File {
        version,
        time_system,
        interval_s,
        coordinate_system,
        agency,
        satellites,
        samples,
    })
}

/// Add an SP3 file's samples to `products` (several files: consecutive days).
pub fn add_to_products(f: &Sp3File, products: &mut PreciseProducts) {
    for (t, sat, pos, clk) in &f.samples {
        products.add_orbit(*sat, *t, *pos, *clk);
    }
}

/// `YYYY MM DD HH MM SS.SSSSSSSS` as SP3 writes epochs (columns 4-31 of `*` lines).
fn sp3_epoch(t: &GpsTime) -> String {
    let c = t.to_calendar();
    let (y, mo, d, h, mi) = (c.year, c.month, c.day, c.hour, c.minute);
    format!("{y:4} {mo:2} {d:2} {h:2} {mi:2} {:11.8}", c.second)
}

/// One epoch to write: GPST and (satellite, ECEF position \[m\], clock \[s\]).
pub type Sp3Epoch = (GpsTime, Vec<(SatId, Vector3<f64>, Option<f64>)>);

/// Write an SP3-d file in GPS time: `epochs` of (GPST, [(satellite, ECEF position
/// \[m\], clock \[s\])]); `interval_s` is the nominal spacing.
pub fn write_sp3(
    path: &Path,
    interval_s: f64,
    agency: &str,
    epochs: &[Sp3Epoch],
) -> Result<(), InputError> {
    let mut sats: Vec<SatId> = epochs
        .iter()
        .flat_map(|e| e.1.iter().map(|s| s.0))
        .collect();
    sats.sort();
    sats.dedup();
    let first = epochs
        .first()
        .map(|e| e.0)
        .ok_or_else(|| err(path, 0, "no epochs to write"))?;
    let mut o = String::new();
    o.push_str(&format!(
        "#dP{} {:7} ORBIT IGS20 BCT {agency:>4}\n",
        sp3_epoch(&first),
        epochs.len()
    ));
    let mjd = (first.week as f64 * 7.0 + first.sow / 86_400.0) + 44_244.0;
    o.push_str(&format!(
        "## {:4} {:15.8} {:14.8} {:5} {:15.13}\n",
        first.week,
        first.sow,
        interval_s,
        mjd.floor() as i64,
        mjd.fract()
    ));
    for (k, chunk) in sats.chunks(17).enumerate() {
        let mut line = if k == 0 {
            format!("+  {:3}   ", sats.len())
        } else {
            "+        ".to_string()
        };
        for s in chunk {
            line.push_str(&s.to_string());
        }
        for _ in chunk.len()..17 {
            line.push_str("  0");
        }
        o.push_str(&line);
        o.push('\n');
    }
    o.push_str("%c M  cc GPS ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n");
    o.push_str("/* navfuse: written by navfuse_io::sp3::write_sp3\n");
    for (t, recs) in epochs {
        o.push_str(&format!("*  {}\n", sp3_epoch(t)));
        for (sat, pos, clk) in recs {
            let km = pos / 1e3;
            o.push_str(&format!(
                "P{}{:14.6}{:14.6}{:14.6}{:14.6}\n",
                sat,
                km.x,
                km.y,
                km.z,
                clk.map_or(999_999.999_999, |c| c * 1e6)
            ));
        }
    }
    o.push_str("EOF\n");
    let mut f = std::fs::File::create(path).map_err(|e| InputError::create(path, &e))?;
    f.write_all(o.as_bytes())
        .map_err(|e| InputError::write(path, &e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use navfuse_gnss::constellation::nominal_gps24;

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("navfuse_sp3_{}_{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Broadcast orbits sampled every 15 min for a day, written, read back and
    /// interpolated: the file's 1 mm / 1 ps resolution, and the broadcast orbit to
    /// about a millimetre between the samples.
    #[test]
    fn broadcast_orbits_through_sp3_and_back() {
        let d = tmp("rt");
        let t0 = GpsTime::new(2111, 345_600.0);
        let mut ephs = nominal_gps24(t0);
        for (k, e) in ephs.iter_mut().enumerate() {
            e.af0_s = 1e-5 * (k as f64 - 12.0);
            e.af1_s_per_s = 3e-12;
        }
        let epochs: Vec<_> = (0..=96)
            .map(|k| {
                let t = t0.add_s(900.0 * f64::from(k));
                let recs = ephs
                    .iter()
                    .map(|e| {
                        let s = e.sat_state(t);
                        (SatId::gps(e.prn), s.pos_ecef_m, Some(s.clock_bias_s))
                    })
                    .collect();
                (t, recs)
            })
            .collect();
        let p = d.join("brdc.sp3");
        write_sp3(&p, 900.0, "NAVF", &epochs).unwrap();
        let f = read_sp3(&p).unwrap();
        assert_eq!(f.version, 'd');
        assert_eq!(f.satellites.len(), 24);
        assert_eq!(f.samples.len(), 97 * 24);
        assert_eq!(f.interval_s, 900.0);
        let mut worst = (0.0f64, 0.0f64);
        for ((t, recs), chunk) in epochs.iter().zip(f.samples.chunks(24)) {
            for ((sat, pos, clk), (tt, s2, p2, c2)) in recs.iter().zip(chunk) {
                assert_eq!((t, sat), (tt, s2));
                worst.0 = worst.0.max((pos - p2).norm());
                worst.1 = worst.1.max((clk.unwrap() - c2.unwrap()).abs());
            }
        }
        assert!(
            worst.0 <= 0.87e-3 && worst.1 <= 0.5e-12,
            "read back: {worst:?}"
        );
        let mut prod = PreciseProducts::new(t0, f.interval_s, f.interval_s);
        add_to_products(&f, &mut prod);
        prod.finish();
        let mut interp = 0.0f64;
        for k in 0..1700 {
            let t = t0.add_s(4_500.0 + 45.0 * f64::from(k));
            for e in &ephs {
                let s = prod.state(SatId::gps(e.prn), t).unwrap();
                interp = interp.max((s.pos_ecef_m - e.sat_state(t).pos_ecef_m).norm());
            }
        }
        eprintln!(
            "SP3 round trip {:.6} m / {:.2e} s; interpolated from the file {interp:.6} m",
            worst.0, worst.1
        );
        assert!(interp < 1.5e-3, "{interp} m");
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn errors_name_line_and_columns() {
        let d = tmp("err");
        let p = d.join("bad.sp3");
        std::fs::write(&p, "#aP2020  6 25\n").unwrap();
        assert!(read_sp3(&p)
            .unwrap_err()
            .to_string()
            .contains("SP3-c or SP3-d"));
        std::fs::write(
            &p,
            "#dP2020  6 25  0  0  0.00000000       2 ORBIT IGS20 HLM  IGS\n## 2111 345600.00000000   900.00000000 59025 0.0000000000000\n+    1   G01\n*  2020  6 25  0  0  0.00000000\nPG01  -2830.24566x  15536.390216  21430.061393    123.456789\nEOF\n",
        )
        .unwrap();
        let e = read_sp3(&p).unwrap_err().to_string();
        assert!(e.contains("bad.sp3:5") && e.contains("x [km]"), "{e}");
        std::fs::remove_dir_all(&d).ok();
    }
}
