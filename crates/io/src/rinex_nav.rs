//! RINEX navigation files: broadcast ephemerides of every system.
//!
//! Reads RINEX 2.10/2.11 GPS navigation files (type `N`), RINEX 3.0x navigation
//! files (GPS-only or mixed) and RINEX 4.00. GPS records (RINEX 3.04 Table A6, 2.11
//! Table A4) go to `gps`; Galileo, BeiDou, GLONASS and QZSS records to their lists
//! (`rinex_nav_gnss`; GLONASS has 3 orbit lines before 3.05, 4 from 3.05 and in 4.00);
//! SBAS and NavIC records, RINEX 4 CNAV/CNV1-3 messages, STO and EOP records are
//! skipped and counted (`skipped`). Header: ION ALPHA / ION BETA (v2), IONOSPHERIC
//! CORR GPSA/GPSB, QZSA/QZSB, BDSA/BDSB, GAL (v3), LEAP SECONDS; RINEX 4 `> ION`
//! records when the header has none. Numbers may use `D` or `E` exponents. RINEX
//! 4.01 and later are refused (they add messages this reader does not know).
//! Writes RINEX 3.04 GPS navigation files (fixed-width D19.12 fields), mixed
//! (`M: MIXED`) when Galileo, BeiDou or GLONASS records are given (Tables A8, A14,
//! A10).

use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav_gnss as other;
use navfuse_gnss::ephemeris::beidou::BDT_WEEK0_IN_GPS_WEEKS;
use navfuse_gnss::ephemeris::kepler::KeplerOrbit;
use navfuse_gnss::ephemeris::Ephemeris;
use navfuse_gnss::time::{GpstCalendar, HALF_WEEK_S, SECONDS_PER_WEEK};
use navfuse_gnss::{
    BeiDouEphemeris, EphemerisStore, GalileoEphemeris, GlonassEphemeris, GpsEphemeris, GpsTime,
};
use std::io::{self, Write};
use std::path::Path;

/// What a RINEX navigation file gave.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RinexNav {
    /// GPS ephemerides, in file order.
    pub gps: Vec<GpsEphemeris>,
    /// Klobuchar alpha0-3 [s, s/sc, s/sc^2, s/sc^3].
    pub iono_alpha: Option<[f64; 4]>,
    /// Klobuchar beta0-3 [s, s/sc, s/sc^2, s/sc^3].
    pub iono_beta: Option<[f64; 4]>,
    /// GPS-UTC leap seconds from the header.
    pub leap_seconds: Option<i32>,
    /// Records not in `gps` (other systems, RINEX 4 non-LNAV messages, STO/EOP/ION
    /// records), whether read into the lists below or skipped (`skipped` says which).
    pub skipped_records: usize,
    /// QZSS LNAV ephemerides (`prn` is the J number), in file order.
    pub qzss: Vec<GpsEphemeris>,
    /// Galileo I/NAV and F/NAV ephemerides.
    pub galileo: Vec<GalileoEphemeris>,
    /// BeiDou D1/D2 ephemerides (times BDT).
    pub beidou: Vec<BeiDouEphemeris>,
    /// GLONASS ephemerides (tb in GPST).
    pub glonass: Vec<GlonassEphemeris>,
    /// Ionosphere coefficients of other systems (header or RINEX 4 ION records).
    pub iono: OtherIono,
    /// What was skipped, by kind.
    pub skipped: SkippedCounts,
    /// Findings that did not stop the read: a damaged last record dropped.
    pub warnings: Vec<String>,
}

/// Klobuchar sets of QZSS and BeiDou, NeQuick-G of Galileo.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct OtherIono {
    /// QZSS alpha, beta (IS-QZSS-PNT §5.1.2.1.4, the GPS model).
    pub qzss_klobuchar: Option<([f64; 4], [f64; 4])>,
    /// BeiDou alpha, beta (SIS ICD B1I 3.0 §5.3.3.3).
    pub beidou_klobuchar: Option<([f64; 4], [f64; 4])>,
    /// Galileo a_i0 \[sfu\], a_i1 [sfu/deg], a_i2 [sfu/deg^2] (OS SIS ICD 2.1 §5.1.6).
    pub galileo_nequick: Option<[f64; 3]>,
}

/// Records read but not kept, by kind.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SkippedCounts {
    /// SBAS records (orbits not used here).
    pub sbas: usize,
    /// NavIC records.
    pub navic: usize,
    /// RINEX 4 ephemeris messages other than LNAV/INAV/FNAV/D1/D2/FDMA (CNAV, CNV1-3).
    pub other_messages: usize,
    /// RINEX 4 system time offsets (STO) and Earth orientation (EOP) records.
    pub sto_eop: usize,
    /// RINEX 4 ION records whose coefficients were not kept (already in the header,
    /// or of another kind).
    pub ion: usize,
}

impl RinexNav {
    /// Every ephemeris read, for all systems, as one store.
    pub fn store(&self) -> EphemerisStore {
        let mut s = EphemerisStore::new(self.gps.iter().cloned().map(Ephemeris::Gps));
        self.qzss
            .iter()
            .for_each(|e| s.push(Ephemeris::Qzss(e.clone())));
        self.galileo
            .iter()
            .for_each(|e| s.push(Ephemeris::Galileo(e.clone())));
        self.beidou
            .iter()
            .for_each(|e| s.push(Ephemeris::BeiDou(e.clone())));
        self.glonass
            .iter()
            .for_each(|e| s.push(Ephemeris::Glonass(e.clone())));
        s
    }
}

/// Header label columns (RINEX 3.04 §5.1: label in columns 61-80).
const LABEL_COL: usize = 60;

/// "Transmission time unknown" value (RINEX 3.04 Table A6 note: 0.9999e9).
const TT_UNKNOWN: f64 = 0.9999e9;

/// Names of the 28 broadcast-orbit fields, 4 per line (RINEX 3.04 Table A6).
pub(crate) const ORBIT_FIELDS: [&str; 28] = [
    "IODE",
    "Crs",
    "Delta n",
    "M0",
    "Cuc",
    "e",
    "Cus",
    "sqrt(A)",
    "Toe",
    "Cic",
    "OMEGA0",
    "Cis",
    "i0",
    "Crc",
    "omega",
    "OMEGA DOT",
    "IDOT",
    "Codes on L2",
    "GPS Week",
    "L2 P flag",
    "SV accuracy",
    "SV health",
    "TGD",
    "IODC",
    "Transmission time",
    "Fit interval",
    "spare",
    "spare",
];

/// Physical bounds of the orbit fields (index into [`ORBIT_FIELDS`], largest |value|,
/// unit), far above real GPS values: angles within a turn or two, rates below
/// 1e-6 rad/s (real: ~1e-8), harmonic terms below 1e-2 rad / 1e4 m (real: ~1e-5 /
/// ~400), TGD below 1e-3 s. Beyond them the orbit is meaningless (or NaN).
const ORBIT_LIMITS: [(usize, f64, &str); 14] = [
    (1, 1e4, "m"),
    (2, 1e-6, "rad/s"),
    (3, 2.0 * TWO_PI, "rad"),
    (4, 1e-2, "rad"),
    (6, 1e-2, "rad"),
    (9, 1e-2, "rad"),
    (10, 2.0 * TWO_PI, "rad"),
    (11, 1e-2, "rad"),
    (12, TWO_PI, "rad"),
    (13, 1e4, "m"),
    (14, 2.0 * TWO_PI, "rad"),
    (15, 1e-6, "rad/s"),
    (16, 1e-6, "rad/s"),
    (22, 1e-3, "s"),
];
const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// The text of columns [a, b) of a line (clamped to its length).
pub(crate) fn cols(line: &[u8], a: usize, b: usize) -> &[u8] {
    let b = b.min(line.len());
    if a >= b {
        &[]
    } else {
        line.get(a..b).unwrap_or(&[])
    }
}

fn trim(s: &[u8]) -> &[u8] {
    let start = s
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(s.len());
    let end = s
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(start, |e| e + 1);
    s.get(start..end).unwrap_or(&[])
}

/// Parse a Fortran number (`D`/`d` exponents allowed); Ok(None) for a blank field.
pub(crate) fn parse_num(
    path: &Path,
    ln: usize,
    name: &str,
    text: &[u8],
) -> Result<Option<f64>, InputError> {
    let t = trim(text);
    if t.is_empty() {
        return Ok(None);
    }
    let s: String = t
        .iter()
        .map(|&b| {
            if b == b'D' || b == b'd' {
                'E'
            } else {
                b as char
            }
        })
        .collect();
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(v) => Err(InputError::not_finite(path, ln, name, v)),
        Err(_) => Err(InputError::not_a_number(path, ln, name, t)),
    }
}

pub(crate) fn required(path: &Path, ln: usize, name: &str, text: &[u8]) -> Result<f64, InputError> {
    parse_num(path, ln, name, text)?.ok_or_else(|| {
        InputError::at_field(path, ln, name, "expected a number, found a blank field")
    })
}

pub(crate) fn int_in(
    path: &Path,
    ln: usize,
    name: &str,
    text: &[u8],
    lo: i64,
    hi: i64,
) -> Result<i64, InputError> {
    let t = trim(text);
    let v = std::str::from_utf8(t)
        .ok()
        .and_then(|s| s.parse::<i64>().ok());
    match v {
        Some(v) if (lo..=hi).contains(&v) => Ok(v),
        Some(v) => Err(InputError::at_field(
            path,
            ln,
            name,
            format!("expected {lo}..{hi}, found {v}"),
        )),
        None => Err(InputError::at_field(
            path,
            ln,
            name,
            format!(
                "expected an integer, found \"{}\"",
                String::from_utf8_lossy(t)
            ),
        )),
    }
}

/// A float field that must hold a whole number in lo..=hi.
pub(crate) fn whole_in(
    path: &Path,
    ln: usize,
    name: &str,
    v: f64,
    lo: f64,
    hi: f64,
) -> Result<f64, InputError> {
    if v.fract() != 0.0 || v < lo || v > hi {
        return Err(InputError::at_field(
            path,
            ln,
            name,
            format!("expected a whole number in {lo}..{hi}, found {v}"),
        ));
    }
    Ok(v)
}

/// N header coefficients of width 12 from column `start` (RINEX 3.05 §5.2
/// `IONOSPHERIC CORR`: A4,1X,4D12.4; v2 `ION ALPHA`: 2X,4D12.4).
fn coeffs<const N: usize>(
    path: &Path,
    ln: usize,
    line: &[u8],
    name: &str,
    start: usize,
) -> Result<[f64; N], InputError> {
    let mut c = [0.0; N];
    for (k, v) in c.iter_mut().enumerate() {
        *v = required(
            path,
            ln,
            name,
            cols(line, start + 12 * k, start + 12 + 12 * k),
        )?;
    }
    Ok(c)
}

fn header_label(line: &[u8]) -> &[u8] {
    trim(cols(line, LABEL_COL, 80))
}

/// Read a RINEX 2.10/2.11 or 3.0x navigation file; see the module documentation.
pub fn read_rinex_nav(path: &Path) -> Result<RinexNav, InputError> {
    let mut rd = LineReader::open(path)?;
    let mut nav = RinexNav::default();
    // Header.
    let (ln, first) = match rd.next_line()? {
        Some((ln, l)) => (ln, l.to_vec()),
        None => return Err(InputError::new(path, "empty file: expected a RINEX header")),
    };
    if header_label(&first) != b"RINEX VERSION / TYPE" {
        return Err(InputError::at_line(
            path,
            ln,
            "expected 'RINEX VERSION / TYPE' in columns 61-80 of the first line",
        ));
    }
    let version = required(path, ln, "RINEX version", cols(&first, 0, 9))?;
    let type_char = cols(&first, 20, 21).first().copied().unwrap_or(b' ');
    let major = version.floor() as i64;
    match major {
        2 if type_char == b'N' => {}
        2 => {
            return Err(InputError::at_field(
                path,
                ln,
                "file type",
                format!(
                    "expected a GPS navigation file (type N), found type '{}'",
                    type_char as char
                ),
            ))
        }
        3 if type_char == b'N' => {}
        // RINEX 4.00 (4.01+ add messages this reader does not know: refused).
        4 if type_char == b'N' && version == 4.0 => {}
        3 | 4 if version == 4.0 || major == 3 => {
            return Err(InputError::at_field(
                path,
                ln,
                "file type",
                format!(
                    "expected a navigation file (type N), found '{}'",
                    type_char as char
                ),
            ))
        }
        _ => {
            return Err(InputError::at_field(
                path,
                ln,
                "RINEX version",
                format!("version {version} is not supported (2.10, 2.11, 3.0x and 4.00 are)"),
            ))
        }
    }
    let v3 = major >= 3;
    let v4 = major == 4;
    loop {
        let (ln, line) = match rd.next_line()? {
            Some(x) => x,
            None => return Err(InputError::new(path, "no 'END OF HEADER' line")),
        };
        let label = header_label(line);
        match label {
            b"END OF HEADER" => break,
            b"ION ALPHA" | b"ION BETA" => {
                let c = coeffs::<4>(path, ln, line, "ION ALPHA/BETA", 2)?;
                if label == b"ION ALPHA" {
                    nav.iono_alpha = Some(c);
                } else {
                    nav.iono_beta = Some(c);
                }
            }
            b"IONOSPHERIC CORR" => {
                let kind = cols(line, 0, 4);
                let name = "IONOSPHERIC CORR";
                if kind == b"GAL " {
                    nav.iono.galileo_nequick = Some(coeffs::<3>(path, ln, line, name, 5)?);
                } else if matches!(kind, b"QZSA" | b"QZSB" | b"BDSA" | b"BDSB") {
                    let c = coeffs::<4>(path, ln, line, name, 5)?;
                    let slot = if kind.starts_with(b"QZ") {
                        &mut nav.iono.qzss_klobuchar
                    } else {
                        &mut nav.iono.beidou_klobuchar
                    };
                    let pair = slot.get_or_insert(([0.0; 4], [0.0; 4]));
                    if kind[3] == b'A' {
                        pair.0 = c;
                    } else {
                        pair.1 = c;
                    }
                } else if kind == b"GPSA" || kind == b"GPSB" {
                    let c = coeffs::<4>(path, ln, line, name, 5)?;
                    if kind == b"GPSA" {
                        nav.iono_alpha = Some(c);
                    } else {
                        nav.iono_beta = Some(c);
                    }
                }
            }
            b"LEAP SECONDS" => {
                nav.leap_seconds =
                    Some(int_in(path, ln, "LEAP SECONDS", cols(line, 0, 6), -100, 1000)? as i32);
            }
            _ => {}
        }
    }
    // Records. A last record cut by the end of the file is dropped with a warning.
    let res = if v4 {
        read_records_v4(&mut rd, path, &mut nav)
    } else {
        // RINEX 3.05 added a fourth GLONASS orbit line (status flags, L1/L2 delay
        // difference, URAI, health flags; 3.05 Table A10).
        let glo_orbit_lines = if version >= 3.05 - 1e-9 { 4 } else { 3 };
        read_records(&mut rd, path, v3, glo_orbit_lines, &mut nav)
    };
    match res {
        Ok(()) => {}
        Err(e) if rd.cut_last_line() => nav.warnings.push(e.last_line_warning()),
        Err(e) => return Err(e),
    }
    Ok(nav)
}

fn read_records(
    rd: &mut LineReader,
    path: &Path,
    v3: bool,
    glo_orbit_lines: usize,
    nav: &mut RinexNav,
) -> Result<(), InputError> {
    while let Some((ln, l)) = rd.next_line()? {
        let line = l.to_vec();
        if trim(&line).is_empty() {
            continue;
        }
        if v3 {
            let sys = line.first().copied().unwrap_or(b' ');
            let lines = match sys {
                b'G' => 8,
                b'R' => 1 + glo_orbit_lines,
                b'S' => 4,
                b'E' | b'C' | b'J' | b'I' => 8,
                _ => {
                    return Err(InputError::at_field(
                        path,
                        ln,
                        "satellite system",
                        format!(
                            "expected G, R, E, C, J, I or S in column 1, found \"{}\"",
                            crate::error::shorten(cols(&line, 0, 3))
                        ),
                    ))
                }
            };
            if sys != b'G' {
                nav.skipped_records += 1;
                read_other(rd, path, ln, &line, sys, lines, glo_orbit_lines, nav)?;
                continue;
            }
        }
        let eph = read_gps_record(rd, path, ln, &line, v3)?;
        nav.gps.push(eph);
    }
    Ok(())
}

/// A record of another system than GPS (first line read): kept, or its remaining
/// lines skipped and counted. `glo_lines`: GLONASS orbit lines (3 in 3.05, 4 in 4.00).
#[allow(clippy::too_many_arguments)]
fn read_other(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    line: &[u8],
    sys: u8,
    lines: usize,
    glo_lines: usize,
    nav: &mut RinexNav,
) -> Result<(), InputError> {
    match sys {
        b'E' => nav.galileo.push(other::galileo(rd, path, ln, line)?),
        b'C' => nav.beidou.push(other::beidou(rd, path, ln, line)?),
        b'R' => nav.glonass.push(other::glonass(
            rd,
            path,
            ln,
            line,
            glo_lines,
            nav.leap_seconds,
        )?),
        b'J' => nav.qzss.push(read_gps_record(rd, path, ln, line, true)?),
        _ => {
            skip_lines(rd, path, ln, sys, lines)?;
            if sys == b'S' {
                nav.skipped.sbas += 1;
            } else {
                nav.skipped.navic += 1;
            }
        }
    }
    Ok(())
}

fn skip_lines(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    sys: u8,
    lines: usize,
) -> Result<(), InputError> {
    for _ in 1..lines {
        if rd.next_line()?.is_none() {
            return Err(InputError::at_line(
                path,
                ln,
                format!(
                    "record truncated: a '{}' record has {lines} lines",
                    sys as char
                ),
            ));
        }
    }
    Ok(())
}

/// RINEX 4.00 records: a `> TYPE SAT MESSAGE` line (4.00 §4, Table A1), then the
/// record. LNAV (GPS, QZSS), INAV/FNAV, D1/D2 and FDMA are read; other ephemeris
/// messages, STO and EOP are skipped and counted; ION gives Klobuchar / NeQuick-G
/// coefficients when the header had none.
fn read_records_v4(rd: &mut LineReader, path: &Path, nav: &mut RinexNav) -> Result<(), InputError> {
    while let Some((ln, l)) = rd.next_line()? {
        let head = l.to_vec();
        if trim(&head).is_empty() {
            continue;
        }
        if head.first() != Some(&b'>') {
            return Err(InputError::at_field(
                path,
                ln,
                "record type",
                format!(
                    "expected a '> EPH', '> STO', '> EOP' or '> ION' line, found \"{}\"",
                    crate::error::shorten(cols(&head, 0, 20))
                ),
            ));
        }
        let kind = trim(cols(&head, 2, 5)).to_vec();
        let sys = cols(&head, 6, 7).first().copied().unwrap_or(b' ');
        let msg = trim(cols(&head, 10, 15)).to_vec();
        let Some(lines) = other::v4_record_lines(&kind, sys, &msg) else {
            return Err(InputError::at_field(
                path,
                ln,
                "record type",
                format!(
                    "unknown record \"{}\" (RINEX 4.00 Table A1)",
                    crate::error::shorten(trim(&head))
                ),
            ));
        };
        nav.skipped_records += usize::from(!(kind == b"EPH" && sys == b'G' && msg == b"LNAV"));
        match kind.as_slice() {
            b"EPH" => {
                let (n, first) = match rd.next_line()? {
                    Some((n, f)) => (n, f.to_vec()),
                    None => {
                        return Err(InputError::at_line(
                            path,
                            ln,
                            "record missing after its '>' line",
                        ))
                    }
                };
                let known = matches!(
                    (sys, msg.as_slice()),
                    (b'G' | b'J', b"LNAV") | (b'E', _) | (b'C', b"D1" | b"D2") | (b'R', _)
                );
                if sys == b'G' && known {
                    nav.gps.push(read_gps_record(rd, path, n, &first, true)?);
                } else if known {
                    read_other(rd, path, n, &first, sys, lines, 4, nav)?;
                } else {
                    skip_lines(rd, path, n, sys, lines)?;
                    if sys == b'S' {
                        nav.skipped.sbas += 1;
                    } else if sys == b'I' {
                        nav.skipped.navic += 1;
                    } else {
                        nav.skipped.other_messages += 1;
                    }
                }
            }
            b"ION" => {
                let v = other::ion_numbers(rd, path, ln, lines)?;
                let kl = || {
                    let a = [v[0], v[1], v[2], v[3]];
                    let b = [v[4], v[5], v[6], v[7]];
                    (a, b)
                };
                let slot_free = match (sys, msg.as_slice()) {
                    (b'G', b"LNAV") if nav.iono_alpha.is_none() => {
                        let (a, b) = kl();
                        nav.iono_alpha = Some(a);
                        nav.iono_beta = Some(b);
                        true
                    }
                    (b'J', b"LNAV") if nav.iono.qzss_klobuchar.is_none() => {
                        nav.iono.qzss_klobuchar = Some(kl());
                        true
                    }
                    (b'C', b"D1D2") if nav.iono.beidou_klobuchar.is_none() => {
                        nav.iono.beidou_klobuchar = Some(kl());
                        true
                    }
                    (b'E', b"IFNV") if nav.iono.galileo_nequick.is_none() => {
                        nav.iono.galileo_nequick = Some([v[0], v[1], v[2]]);
                        true
                    }
                    _ => false,
                };
                nav.skipped.ion += usize::from(!slot_free);
            }
            _ => {
                for _ in 0..lines {
                    if rd.next_line()?.is_none() {
                        return Err(InputError::at_line(path, ln, "record truncated"));
                    }
                }
                nav.skipped.sto_eop += 1;
            }
        }
    }
    Ok(())
}

/// Parse one GPS record whose first line (number `ln`) has been read.
fn read_gps_record(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    line: &[u8],
    v3: bool,
) -> Result<GpsEphemeris, InputError> {
    // First line: PRN, toc, af0, af1, af2 (3.04 Table A6; 2.11 Table A4).
    let (prn, cal, clk0) = if v3 {
        let prn = int_in(path, ln, "PRN", cols(line, 1, 3), 1, 63)?;
        let year = int_in(path, ln, "toc year", cols(line, 4, 8), 1980, 2200)?;
        let cal = (
            year,
            int_in(path, ln, "toc month", cols(line, 9, 11), 1, 12)?,
            int_in(path, ln, "toc day", cols(line, 12, 14), 1, 31)?,
            int_in(path, ln, "toc hour", cols(line, 15, 17), 0, 23)?,
            int_in(path, ln, "toc minute", cols(line, 18, 20), 0, 59)?,
            int_in(path, ln, "toc second", cols(line, 21, 23), 0, 60)? as f64,
        );
        (prn, cal, 23)
    } else {
        let prn = int_in(path, ln, "PRN", cols(line, 0, 2), 1, 63)?;
        let yy = int_in(path, ln, "toc year", cols(line, 3, 5), 0, 99)?;
        let year = if yy < 80 { 2000 + yy } else { 1900 + yy };
        let sec = required(path, ln, "toc second", cols(line, 17, 22))?;
        let cal = (
            year,
            int_in(path, ln, "toc month", cols(line, 6, 8), 1, 12)?,
            int_in(path, ln, "toc day", cols(line, 9, 11), 1, 31)?,
            int_in(path, ln, "toc hour", cols(line, 12, 14), 0, 23)?,
            int_in(path, ln, "toc minute", cols(line, 15, 17), 0, 59)?,
            sec,
        );
        (prn, cal, 22)
    };
    let toc = GpsTime::from_calendar(&GpstCalendar {
        year: cal.0 as i32,
        month: cal.1 as u32,
        day: cal.2 as u32,
        hour: cal.3 as u32,
        minute: cal.4 as u32,
        second: cal.5,
    })
    .ok_or_else(|| InputError::at_field(path, ln, "toc", "invalid calendar date or time"))?;
    let af0 = required(path, ln, "af0", cols(line, clk0, clk0 + 19))?;
    let af1 = required(path, ln, "af1", cols(line, clk0 + 19, clk0 + 38))?;
    let af2 = required(path, ln, "af2", cols(line, clk0 + 38, clk0 + 57))?;
    // Seven broadcast-orbit lines of four fields.
    let off = if v3 { 4 } else { 3 };
    let mut f = [0.0f64; 28];
    let mut present = [false; 28];
    let mut lines = [0usize; 7];
    for (k, line_no) in lines.iter_mut().enumerate() {
        let (n, l) = match rd.next_line()? {
            Some(x) => x,
            None => {
                return Err(InputError::at_line(
                    path,
                    ln,
                    format!("GPS record truncated: expected 8 lines, found {}", k + 1),
                ))
            }
        };
        *line_no = n;
        for j in 0..4 {
            let idx = 4 * k + j;
            let name = ORBIT_FIELDS[idx];
            let text = cols(l, off + 19 * j, off + 19 * (j + 1));
            if let Some(v) = parse_num(path, n, name, text)? {
                f[idx] = v;
                present[idx] = true;
            }
        }
    }
    // Lines 1-5 (except codes on L2 and L2 P flag) are required.
    for idx in 0..20 {
        if !present[idx] && idx != 17 && idx != 19 {
            return Err(InputError::at_field(
                path,
                lines[idx / 4],
                ORBIT_FIELDS[idx],
                "expected a number, found a blank field",
            ));
        }
    }
    let line_of = |idx: usize| lines[idx / 4];
    let iode = whole_in(path, line_of(0), "IODE", f[0], 0.0, 1023.0)? as u16;
    let e = f[5];
    if !(0.0..1.0).contains(&e) {
        return Err(InputError::at_field(
            path,
            line_of(5),
            "e",
            format!("expected 0 <= e < 1, found {e}"),
        ));
    }
    if !(f[7] > 1_000.0 && f[7] < 10_000.0) {
        return Err(InputError::at_field(
            path,
            line_of(7),
            "sqrt(A)",
            format!("expected 1000..10000 sqrt(m), found {}", f[7]),
        ));
    }
    if !(0.0..SECONDS_PER_WEEK).contains(&f[8]) {
        return Err(InputError::at_field(
            path,
            line_of(8),
            "Toe",
            format!("expected 0 <= toe < 604800 s, found {}", f[8]),
        ));
    }
    for (idx, lim, unit) in ORBIT_LIMITS {
        let v = f[idx];
        if v.abs() > lim {
            return Err(InputError::at_field(
                path,
                line_of(idx),
                ORBIT_FIELDS[idx],
                format!("expected |value| <= {lim} {unit} (a broadcast orbit), found {v}"),
            ));
        }
    }
    for (name, v, lim) in [("af0", af0, 1.0), ("af1", af1, 1e-3), ("af2", af2, 1e-3)] {
        if v.abs() > lim {
            return Err(InputError::at_field(
                path,
                ln,
                name,
                format!("expected |value| <= {lim} (a satellite clock), found {v}"),
            ));
        }
    }
    let mut week = whole_in(path, line_of(18), "GPS Week", f[18], 0.0, 1e5)? as i32;
    // A week given modulo 1024 is moved next to toc's week.
    if (toc.week - week).abs() > 512 {
        week += 1024 * ((toc.week - week) as f64 / 1024.0).round() as i32;
    }
    let toe = GpsTime::new(week, f[8]);
    let health = whole_in(
        path,
        line_of(21),
        "SV health",
        f[21],
        0.0,
        f64::from(u32::MAX),
    )? as u32;
    let iodc = whole_in(path, line_of(23), "IODC", f[23], 0.0, 1023.0)? as u16;
    let transmission_time = if present[24] && f[24] < TT_UNKNOWN * 0.999 {
        // Seconds of the toe week; moved to within half a week of toe.
        Some(within_half_week(GpsTime::new(week, f[24]), toe))
    } else {
        None
    };
    // Fit interval in hours (3.04 Table A6); 0 or a 0/1 flag value means 4 h.
    let fit_interval_h = if f[25] >= 4.0 { f[25] } else { 4.0 };
    let eph = GpsEphemeris {
        toc,
        af0_s: af0,
        af1_s_per_s: af1,
        af2_s_per_s2: af2,
        iode,
        codes_l2: f[17],
        l2p_flag: f[19],
        sv_accuracy_m: f[20],
        health,
        tgd_s: f[22],
        iodc,
        transmission_time,
        fit_interval_h,
        ..GpsEphemeris::zeroed(prn as u8, toe)
    };
    Ok(eph.with_orbit(&kepler_from_fields(&f)))
}

/// The Keplerian elements from orbit fields 1-16 of the common RINEX layout
/// (GPS Table A6, Galileo A8, QZSS A12, BeiDou A14: Crs, Delta n, M0, Cuc, e, Cus,
/// sqrt(A), toe, Cic, Omega0, Cis, i0, Crc, omega, Omega dot, IDOT).
pub(crate) fn kepler_from_fields(f: &[f64]) -> KeplerOrbit {
    KeplerOrbit {
        crs_m: f[1],
        delta_n_rad_per_s: f[2],
        m0_rad: f[3],
        cuc_rad: f[4],
        e: f[5],
        cus_rad: f[6],
        sqrt_a_sqrt_m: f[7],
        toe_sow_s: f[8],
        cic_rad: f[9],
        omega0_rad: f[10],
        cis_rad: f[11],
        i0_rad: f[12],
        crc_m: f[13],
        omega_rad: f[14],
        omega_dot_rad_per_s: f[15],
        idot_rad_per_s: f[16],
    }
}

/// A number as a Fortran-style `D19.12` field written with `E` (RINEX 3.04 §6.7 allows
/// either letter): sign or blank, `d.dddddddddddd`, `E+ee`. Exactly 19 characters.
fn d19(v: f64) -> io::Result<String> {
    fixed_exp(v, 12, 19)
}

fn fixed_exp(v: f64, decimals: usize, width: usize) -> io::Result<String> {
    if !v.is_finite() || v.abs() >= 1e99 {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("value {v} does not fit a RINEX exponent field"),
        ));
    }
    let a = v.abs();
    let s = if a < 1e-99 {
        format!("{:.*E}", decimals, 0.0)
    } else {
        format!("{:.*E}", decimals, a)
    };
    let (mant, exp) = s.split_once('E').unwrap_or((&s, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let sign = if v < 0.0 && a >= 1e-99 { '-' } else { ' ' };
    let body = format!(
        "{sign}{mant}E{}{:02}",
        if exp < 0 { '-' } else { '+' },
        exp.abs()
    );
    Ok(format!("{body:>width$}"))
}

/// One header line: content in columns 1-60 (cut to 60), label from column 61
/// (RINEX 3.04 §5.1).
pub(crate) fn header(w: &mut impl Write, content: &str, label: &str) -> io::Result<()> {
    let c: String = content.chars().take(60).collect();
    writeln!(w, "{c:<60}{label}")
}

/// Current UTC date for `PGM / RUN BY / DATE` as `yyyymmdd hhmmss UTC`.
pub(crate) fn utc_now_stamp() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (y, m, d) = crate::time::civil_from_days(secs.div_euclid(86_400));
    let sod = secs.rem_euclid(86_400);
    format!(
        "{y:04}{m:02}{d:02} {:02}{:02}{:02} UTC",
        sod / 3600,
        (sod % 3600) / 60,
        sod % 60
    )
}

/// Write a RINEX 3.04 GPS navigation file (header + one 8-line record per ephemeris).
/// `program` goes into `PGM / RUN BY / DATE` (at most 20 characters kept), with the
/// current UTC date.
pub fn write_rinex3_nav(w: &mut impl Write, nav: &RinexNav, program: &str) -> io::Result<()> {
    write_rinex3_nav_dated(w, nav, program, &utc_now_stamp())
}

/// [`write_rinex3_nav`] with a given `PGM / RUN BY / DATE` date (`yyyymmdd hhmmss UTC`),
/// for reproducible output.
pub fn write_rinex3_nav_dated(
    w: &mut impl Write,
    nav: &RinexNav,
    program: &str,
    date: &str,
) -> io::Result<()> {
    let mixed = !(nav.galileo.is_empty() && nav.beidou.is_empty() && nav.glonass.is_empty());
    header(
        w,
        &format!(
            "{:9.2}{:11}{:<20}{:<20}",
            3.04,
            "",
            "N: GNSS NAV DATA",
            if mixed { "M: MIXED" } else { "G: GPS" }
        ),
        "RINEX VERSION / TYPE",
    )?;
    let pgm: String = program.chars().take(20).collect();
    header(
        w,
        &format!("{pgm:<20}{:<20}{:<20}", "", date),
        "PGM / RUN BY / DATE",
    )?;
    for (kind, c) in [("GPSA", nav.iono_alpha), ("GPSB", nav.iono_beta)] {
        if let Some(c) = c {
            let mut s = format!("{kind} ");
            for v in c {
                s.push_str(&fixed_exp(v, 4, 12)?);
            }
            header(w, &s, "IONOSPHERIC CORR")?;
        }
    }
    if let Some(ls) = nav.leap_seconds {
        header(w, &format!("{ls:6}"), "LEAP SECONDS")?;
    }
    header(w, "", "END OF HEADER")?;
    for e in &nav.gps {
        let af = [e.af0_s, e.af1_s_per_s, e.af2_s_per_s2];
        write_first_line(w, 'G', e.prn, e.toc, af)?;
        let tt = tt_of_week(e.transmission_time, e.toe.week);
        let k = kepler_rows(f64::from(e.iode), &e.orbit(), e.toe.sow);
        let rows: [&[f64]; 7] = [
            &k[0],
            &k[1],
            &k[2],
            &k[3],
            &[
                e.idot_rad_per_s,
                e.codes_l2,
                f64::from(e.toe.week),
                e.l2p_flag,
            ],
            &[
                e.sv_accuracy_m,
                f64::from(e.health),
                e.tgd_s,
                f64::from(e.iodc),
            ],
            &[tt, e.fit_interval_h],
        ];
        write_orbit_lines(w, &rows)?;
    }
    // Galileo (RINEX 3.04 Table A8): GST calendar = GPST.
    for e in &nav.galileo {
        let af = [e.af0_s, e.af1_s_per_s, e.af2_s_per_s2];
        write_first_line(w, 'E', e.prn, e.toc, af)?;
        let tt = tt_of_week(e.transmission_time, e.toe.week);
        let k = kepler_rows(f64::from(e.iodnav), &e.orbit, e.toe.sow);
        let rows: [&[f64]; 7] = [
            &k[0],
            &k[1],
            &k[2],
            &k[3],
            &[
                e.orbit.idot_rad_per_s,
                f64::from(e.data_sources),
                f64::from(e.toe.week),
                0.0,
            ],
            &[
                e.sisa_m,
                f64::from(e.health),
                e.bgd_e1_e5a_s,
                e.bgd_e1_e5b_s,
            ],
            &[tt],
        ];
        write_orbit_lines(w, &rows)?;
    }
    // BeiDou (RINEX 3.04 Table A14): the epoch is a BDT calendar date.
    for e in &nav.beidou {
        let af = [e.af0_s, e.af1_s_per_s, e.af2_s_per_s2];
        let toc_cal = GpsTime::new(e.toc.week + BDT_WEEK0_IN_GPS_WEEKS, e.toc.sow);
        write_first_line(w, 'C', e.prn, toc_cal, af)?;
        let tt = tt_of_week(e.transmission_time, e.toe.week);
        let k = kepler_rows(f64::from(e.aode), &e.orbit, e.toe.sow);
        let rows: [&[f64]; 7] = [
            &k[0],
            &k[1],
            &k[2],
            &k[3],
            &[e.orbit.idot_rad_per_s, 0.0, f64::from(e.toe.week), 0.0],
            &[e.sv_accuracy_m, f64::from(e.sat_h1), e.tgd1_s, e.tgd2_s],
            &[tt, f64::from(e.aodc)],
        ];
        write_orbit_lines(w, &rows)?;
    }
    // GLONASS (RINEX 3.04 Table A10, 3 orbit lines): the epoch is UTC = GPST - the
    // header's LEAP SECONDS (18 when absent); km, km/s, km/s^2.
    let leap = f64::from(nav.leap_seconds.unwrap_or(18));
    for e in &nav.glonass {
        let clock = [-e.tau_n_s, e.gamma_n, e.frame_time_s];
        write_first_line(w, 'R', e.slot, e.tb.add_s(-leap), clock)?;
        let (p, v, a) = (e.pos_m * 1e-3, e.vel_mps * 1e-3, e.acc_mps2 * 1e-3);
        let rows: [&[f64]; 3] = [
            &[p.x, v.x, a.x, f64::from(e.health)],
            &[p.y, v.y, a.y, f64::from(e.freq_channel)],
            &[p.z, v.z, a.z, e.age_days],
        ];
        write_orbit_lines(w, &rows)?;
    }
    Ok(())
}

/// A record's first line: system letter, PRN, the epoch `t` as a calendar date
/// (whole seconds) and the three clock terms.
fn write_first_line(
    w: &mut impl Write,
    sys: char,
    prn: u8,
    t: GpsTime,
    af: [f64; 3],
) -> io::Result<()> {
    let c = t.to_calendar();
    let sec = c.second.round() as u32;
    write!(
        w,
        "{sys}{:02} {:04} {:02} {:02} {:02} {:02} {:02}",
        prn,
        c.year,
        c.month,
        c.day,
        c.hour,
        c.minute,
        sec.min(59)
    )?;
    writeln!(w, "{}{}{}", d19(af[0])?, d19(af[1])?, d19(af[2])?)
}

/// Broadcast-orbit lines 1-4 of the Keplerian layout (GPS, Galileo, BeiDou, QZSS):
/// issue of data, Crs, Delta n, M0 / Cuc, e, Cus, sqrt(A) / toe, Cic, Omega0, Cis /
/// i0, Crc, omega, Omega_dot.
fn kepler_rows(iod: f64, o: &KeplerOrbit, toe_sow: f64) -> [[f64; 4]; 4] {
    [
        [iod, o.crs_m, o.delta_n_rad_per_s, o.m0_rad],
        [o.cuc_rad, o.e, o.cus_rad, o.sqrt_a_sqrt_m],
        [toe_sow, o.cic_rad, o.omega0_rad, o.cis_rad],
        [o.i0_rad, o.crc_m, o.omega_rad, o.omega_dot_rad_per_s],
    ]
}

/// Transmission time as seconds of week `week` (0.9999e9 = unknown).
fn tt_of_week(t: Option<GpsTime>, week: i32) -> f64 {
    match t {
        Some(t) => t.diff_s(&GpsTime::new(week, 0.0)),
        None => TT_UNKNOWN,
    }
}

/// Broadcast-orbit lines: `4X` then `D19.12` fields.
fn write_orbit_lines(w: &mut impl Write, rows: &[&[f64]]) -> io::Result<()> {
    for row in rows {
        let mut s = String::from("    ");
        for v in row.iter() {
            s.push_str(&d19(*v)?);
        }
        writeln!(w, "{s}")?;
    }
    Ok(())
}

/// `t` moved by whole weeks to within half a week of `near` (a transmission time
/// given as seconds of the toe's week).
pub(crate) fn within_half_week(t: GpsTime, near: GpsTime) -> GpsTime {
    let d = t.diff_s(&near);
    if d > HALF_WEEK_S {
        t.add_s(-SECONDS_PER_WEEK)
    } else if d < -HALF_WEEK_S {
        t.add_s(SECONDS_PER_WEEK)
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d19_is_19_wide() {
        assert_eq!(d19(-3.44484578818e-4).unwrap(), "-3.444845788180E-04");
        assert_eq!(d19(5153.64527702).unwrap(), " 5.153645277020E+03");
        assert_eq!(d19(0.0).unwrap(), " 0.000000000000E+00");
        assert_eq!(fixed_exp(1.1176e-8, 4, 12).unwrap(), "  1.1176E-08");
        assert!(d19(f64::NAN).is_err());
    }
}
