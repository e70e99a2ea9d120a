//! DGPS correction reader (docs/FORMATS.md "DGPS corrections"): the simulator's
//! dgps.csv, RTCM-style pseudorange corrections, `corrected P = P + prc_m + rrc_mps
//! (t - t_s)`.
//!
//! `#` / `%` comment lines and blank lines are skipped anywhere; the first other line
//! must be the header `t_s,prn,prc_m,rrc_mps,iode`. Records: t_s [GPS s of week, in
//! [0, 604800)],
//! prn (GPS 1-32), prc_m \[m\], rrc_mps [m/s], iode (integer 0-65535; empty or left out
//! means unknown). Times must not decrease, except at a GPS week rollover (a
//! drop of more than half a week): the following times are moved on by 604800 s, so
//! the list keeps one continuous scale (seconds of the first record's week). The
//! first bad record stops the read with an [`InputError`] naming file, line and field.
//!
//! A comment line with `reference station lat LAT deg lon LON deg h H m` (the
//! simulator's first line) gives the station position ([`read_dgps_file`]).

use crate::error::{shorten, InputError};
use crate::fmt::{field, is_comment_line, parse_f64, parse_i64, split_fields, LineReader};
use nalgebra::Vector3;
use navfuse_core::time::SECONDS_PER_WEEK;
use navfuse_gnss::dgps::DgpsCorrection;
use std::path::Path;

/// A DGPS correction file.
#[derive(Clone, Debug, PartialEq)]
pub struct DgpsFile {
    pub corrections: Vec<DgpsCorrection>,
    /// Reference station latitude \[rad\], longitude \[rad\], ellipsoidal height \[m\],
    /// when a comment line gives it.
    pub reference_lla: Option<Vector3<f64>>,
}

/// The required header fields.
pub const DGPS_HEADER: [&str; 5] = ["t_s", "prn", "prc_m", "rrc_mps", "iode"];
const WHAT: &str = "t_s, prn, prc_m, rrc_mps, iode";

/// Read the corrections of a DGPS correction file; see the module documentation.
pub fn read_dgps_corrections(path: &Path) -> Result<Vec<DgpsCorrection>, InputError> {
    read_dgps_file(path).map(|f| f.corrections)
}

/// Read a DGPS correction file with its reference station position.
pub fn read_dgps_file(path: &Path) -> Result<DgpsFile, InputError> {
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(8);
    let mut out: Vec<DgpsCorrection> = Vec::new();
    let mut reference_lla = None;
    let mut header_seen = false;
    // Week rollovers so far [s], previous time as read [s].
    let mut offset_s = 0.0;
    let mut prev_t: Option<f64> = None;
    while let Some((ln, text)) = lines.next_line()? {
        split_fields(text, &mut fields);
        if is_comment_line(text, &fields) {
            if let Some(lla) = reference_station(path, ln, text)? {
                reference_lla = Some(lla);
            }
            continue;
        }
        if !header_seen {
            let names: Vec<&[u8]> = (0..fields.len()).map(|k| field(text, &fields, k)).collect();
            if names.len() != DGPS_HEADER.len()
                || names
                    .iter()
                    .zip(DGPS_HEADER)
                    .any(|(a, b)| *a != b.as_bytes())
            {
                return Err(InputError::at_field(
                    path,
                    ln,
                    "header",
                    format!(
                        "expected the header \"{}\", found \"{}\"",
                        DGPS_HEADER.join(","),
                        shorten(text)
                    ),
                ));
            }
            header_seen = true;
            continue;
        }
        if fields.len() != 4 && fields.len() != 5 {
            return Err(InputError::columns(path, ln, 5, WHAT, fields.len()));
        }
        let num = |k: usize, name: &str| -> Result<f64, InputError> {
            let s = field(text, &fields, k);
            match parse_f64(s) {
                Some(v) if v.is_finite() => Ok(v),
                Some(v) => Err(InputError::not_finite(path, ln, name, v)),
                None => Err(InputError::not_a_number(path, ln, name, s)),
            }
        };
        let int = |k: usize, name: &str, lo: i64, hi: i64| -> Result<i64, InputError> {
            let s = field(text, &fields, k);
            match parse_i64(s) {
                Some(v) if (lo..=hi).contains(&v) => Ok(v),
                _ => Err(InputError::at_field(
                    path,
                    ln,
                    name,
                    format!("expected an integer {lo}-{hi}, found \"{}\"", shorten(s)),
                )),
            }
        };
        let t_read = num(0, "t_s")?;
        if !(0.0..SECONDS_PER_WEEK).contains(&t_read) {
            return Err(InputError::at_field(
                path,
                ln,
                "t_s",
                format!("expected GPS seconds of week in [0, 604800), found {t_read}"),
            ));
        }
        if let Some(tp) = prev_t {
            if t_read < tp - 0.5 * SECONDS_PER_WEEK {
                offset_s += SECONDS_PER_WEEK;
            } else if t_read < tp {
                return Err(InputError::backwards(path, ln, t_read, tp));
            }
        }
        prev_t = Some(t_read);
        let prn = int(1, "prn", 1, 32)?;
        let prc_m = num(2, "prc_m")?;
        let rrc_mps = num(3, "rrc_mps")?;
        let iode = match fields.len() {
            5 => Some(int(4, "iode", 0, i64::from(u16::MAX))?),
            _ => None,
        };
        out.push(DgpsCorrection {
            t_s: t_read + offset_s,
            prn: u8::try_from(prn).unwrap_or_default(),
            prc_m,
            rrc_mps,
            iode: iode.and_then(|v| u16::try_from(v).ok()),
        });
    }
    if !header_seen {
        return Err(InputError::new(
            path,
            format!(
                "no header line: expected \"{}\" before the records",
                DGPS_HEADER.join(",")
            ),
        ));
    }
    Ok(DgpsFile {
        corrections: out,
        reference_lla,
    })
}

/// `reference station lat LAT deg lon LON deg h H m` in a comment line, if there.
fn reference_station(
    path: &Path,
    ln: usize,
    text: &[u8],
) -> Result<Option<Vector3<f64>>, InputError> {
    const KEY: &str = "reference station lat ";
    let text = String::from_utf8_lossy(text);
    let Some(i) = text.find(KEY) else {
        return Ok(None);
    };
    let rest = text.get(i + KEY.len()..).unwrap_or("");
    let w: Vec<&str> = rest
        .split(|ch: char| ch.is_whitespace() || ch == ';')
        .filter(|w| !w.is_empty())
        .take(8)
        .collect();
    let num = |k: usize| {
        w.get(k)
            .and_then(|x| x.parse::<f64>().ok())
            .filter(|v| v.is_finite())
    };
    let units = [(1, "deg"), (2, "lon"), (4, "deg"), (5, "h"), (7, "m")];
    let units_ok = units.iter().all(|&(k, u)| w.get(k) == Some(&u));
    match (num(0), num(3), num(6)) {
        (Some(lat), Some(lon), Some(h)) if units_ok && lat.abs() <= 90.0 => {
            Ok(Some(Vector3::new(lat.to_radians(), lon.to_radians(), h)))
        }
        _ => Err(InputError::at_field(
            path,
            ln,
            "reference station",
            format!(
                "expected \"reference station lat LAT deg lon LON deg h H m\", found \"{}\"",
                shorten(rest.as_bytes())
            ),
        )),
    }
}
