//! RINEX navigation records of GLONASS, Galileo, BeiDou and QZSS (RINEX 3.05
//! Tables A8 Galileo, A10 GLONASS, A12 QZSS, A14 BeiDou; RINEX 4.00 Tables A5-A37:
//! the same fields after a `> EPH` line, GLONASS with a fifth line) and RINEX 4
//! `> ION` records (Klobuchar for GPS/QZSS/BeiDou, NeQuick-G for Galileo).
//! Used by `rinex_nav`; errors name the file, the line and the field.

use crate::error::InputError;
use crate::fmt::LineReader;
use crate::rinex_nav::{
    cols, int_in, kepler_from_fields, parse_num, required, whole_in, ORBIT_FIELDS,
};
use nalgebra::Vector3;
use navfuse_gnss::ephemeris::beidou::BDT_WEEK0_IN_GPS_WEEKS;
use navfuse_gnss::ephemeris::kepler::KeplerOrbit;
use navfuse_gnss::time::{GpstCalendar, SECONDS_PER_WEEK};
use navfuse_gnss::{BeiDouEphemeris, GalileoEphemeris, GlonassEphemeris, GpsTime};
use std::path::Path;

/// Transmission time "unknown" (RINEX 3.05 §8.3: 0.9999e9).
const TT_UNKNOWN: f64 = 0.9999e9;

/// The satellite number and epoch of a RINEX 3/4 record's first line
/// (`A1,I2.2,1X,I4,5(1X,I2.2)`), the epoch as a calendar date in the system's scale.
pub(crate) fn first_line(
    path: &Path,
    ln: usize,
    line: &[u8],
    max_prn: i64,
) -> Result<(u8, GpstCalendar), InputError> {
    let prn = int_in(path, ln, "PRN", cols(line, 1, 3), 1, max_prn)?;
    let cal = GpstCalendar {
        year: int_in(path, ln, "toc year", cols(line, 4, 8), 1980, 2200)? as i32,
        month: int_in(path, ln, "toc month", cols(line, 9, 11), 1, 12)? as u32,
        day: int_in(path, ln, "toc day", cols(line, 12, 14), 1, 31)? as u32,
        hour: int_in(path, ln, "toc hour", cols(line, 15, 17), 0, 23)? as u32,
        minute: int_in(path, ln, "toc minute", cols(line, 18, 20), 0, 59)? as u32,
        second: int_in(path, ln, "toc second", cols(line, 21, 23), 0, 60)? as f64,
    };
    Ok((prn as u8, cal))
}

fn time_of(path: &Path, ln: usize, cal: &GpstCalendar) -> Result<GpsTime, InputError> {
    GpsTime::from_calendar(cal)
        .ok_or_else(|| InputError::at_field(path, ln, "toc", "invalid calendar date or time"))
}

/// The three numbers of a first line after the epoch (clock or GLONASS terms).
fn clock3(path: &Path, ln: usize, line: &[u8], names: [&str; 3]) -> Result<[f64; 3], InputError> {
    let mut c = [0.0; 3];
    for (k, v) in c.iter_mut().enumerate() {
        *v = required(path, ln, names[k], cols(line, 23 + 19 * k, 42 + 19 * k))?;
    }
    Ok(c)
}

/// `n` broadcast-orbit lines of four `D19.12` fields from column 5 (RINEX 3.05
/// Table A8 `4X,4D19.12`): values (blank = None) and their line numbers.
struct Orbit {
    v: Vec<Option<f64>>,
    lines: Vec<usize>,
    names: Names,
}

/// Field names: (field 0, fields 17.. ) around the Keplerian fields 1-16 of the GPS
/// layout (`rinex_nav::ORBIT_FIELDS`), or a whole list (GLONASS).
#[derive(Clone, Copy)]
enum Names {
    Kepler(&'static str, &'static [&'static str]),
    All(&'static [&'static str]),
}

impl Names {
    fn get(self, i: usize) -> &'static str {
        match self {
            Names::Kepler(first, _) if i == 0 => first,
            Names::Kepler(_, _) if i < 17 => ORBIT_FIELDS[i],
            Names::Kepler(_, tail) => tail.get(i - 17).copied().unwrap_or("spare"),
            Names::All(all) => all.get(i).copied().unwrap_or("spare"),
        }
    }
}

impl Orbit {
    fn read(
        rd: &mut LineReader,
        path: &Path,
        ln: usize,
        n: usize,
        what: &str,
        names: Names,
    ) -> Result<Orbit, InputError> {
        let mut o = Orbit {
            v: Vec::with_capacity(4 * n),
            lines: Vec::with_capacity(n),
            names,
        };
        for k in 0..n {
            let (m, l) = rd.next_line()?.ok_or_else(|| {
                InputError::at_line(
                    path,
                    ln,
                    format!(
                        "{what} record truncated: expected {} lines, found {}",
                        n + 1,
                        k + 1
                    ),
                )
            })?;
            o.lines.push(m);
            for j in 0..4 {
                let name = names.get(4 * k + j);
                o.v.push(parse_num(path, m, name, cols(l, 4 + 19 * j, 23 + 19 * j))?);
            }
        }
        Ok(o)
    }
    fn line(&self, i: usize) -> usize {
        self.lines[i / 4]
    }
    fn req(&self, path: &Path, i: usize) -> Result<f64, InputError> {
        self.v[i].ok_or_else(|| {
            InputError::at_field(
                path,
                self.line(i),
                self.names.get(i),
                "expected a number, found a blank field",
            )
        })
    }
    fn opt(&self, i: usize) -> f64 {
        self.v.get(i).copied().flatten().unwrap_or(0.0)
    }
    /// The Keplerian elements in the common layout (fields 1-16 of Tables A8/A12/A14).
    fn kepler(&self, path: &Path) -> Result<KeplerOrbit, InputError> {
        let mut f = [0.0; 17];
        for (i, v) in f.iter_mut().enumerate().skip(1) {
            *v = self.req(path, i)?;
        }
        if !(0.0..1.0).contains(&f[5]) {
            return Err(InputError::at_field(
                path,
                self.line(5),
                "e",
                format!("expected 0 <= e < 1, found {}", f[5]),
            ));
        }
        if !(1_000.0..10_000.0).contains(&f[7]) {
            return Err(InputError::at_field(
                path,
                self.line(7),
                "sqrt(A)",
                format!("expected 1000..10000 sqrt(m), found {}", f[7]),
            ));
        }
        if !(0.0..SECONDS_PER_WEEK).contains(&f[8]) {
            return Err(InputError::at_field(
                path,
                self.line(8),
                "Toe",
                format!("expected 0 <= toe < 604800 s, found {}", f[8]),
            ));
        }
        Ok(kepler_from_fields(&f))
    }
    /// toe from its week field (index `wi`), and the transmission time (index 24,
    /// seconds of that week, moved to within half a week of toe; 0.9999e9 = unknown).
    fn toe_tt(
        &self,
        path: &Path,
        wi: usize,
        toe_s: f64,
    ) -> Result<(GpsTime, Option<GpsTime>), InputError> {
        let week = whole_in(
            path,
            self.line(wi),
            self.names.get(wi),
            self.req(path, wi)?,
            0.0,
            1e5,
        )? as i32;
        let toe = GpsTime::new(week, toe_s);
        let tt = match self.v.get(24).copied().flatten() {
            Some(s) if s < TT_UNKNOWN * 0.999 => Some(crate::rinex_nav::within_half_week(
                GpsTime::new(week, s),
                toe,
            )),
            _ => None,
        };
        Ok((toe, tt))
    }
}

/// Galileo fields 17-27 (RINEX 3.05 Table A8); 0 is IODnav, 1-16 as GPS.
const GAL_TAIL: [&str; 11] = [
    "Data sources",
    "GAL Week",
    "spare",
    "SISA",
    "SV health",
    "BGD E5a/E1",
    "BGD E5b/E1",
    "Transmission time",
    "spare",
    "spare",
    "spare",
];
/// BeiDou fields 17-27 (RINEX 3.05 Table A14); 0 is AODE, 1-16 as GPS.
const BDS_TAIL: [&str; 11] = [
    "spare",
    "BDT Week",
    "spare",
    "SV accuracy",
    "SatH1",
    "TGD1 B1/B3",
    "TGD2 B2/B3",
    "Transmission time",
    "AODC",
    "spare",
    "spare",
];
const GLO_FIELDS: [&str; 16] = [
    "X",
    "X velocity",
    "X acceleration",
    "health",
    "Y",
    "Y velocity",
    "Y acceleration",
    "frequency number",
    "Z",
    "Z velocity",
    "Z acceleration",
    "age of information",
    "status flags",
    "L1/L2 delay",
    "URAI",
    "health flags",
];

/// A Galileo record (RINEX 3.05 Table A8; 4.00 INAV/FNAV): first line read.
pub(crate) fn galileo(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    line: &[u8],
) -> Result<GalileoEphemeris, InputError> {
    let (prn, cal) = first_line(path, ln, line, 36)?;
    let toc = time_of(path, ln, &cal)?;
    let [af0, af1, af2] = clock3(path, ln, line, ["af0", "af1", "af2"])?;
    let o = Orbit::read(
        rd,
        path,
        ln,
        7,
        "Galileo",
        Names::Kepler("IODnav", &GAL_TAIL),
    )?;
    let orbit = o.kepler(path)?;
    let (toe, tt) = o.toe_tt(path, 18, orbit.toe_sow_s)?;
    let src = whole_in(
        path,
        o.line(17),
        "Data sources",
        o.req(path, 17)?,
        0.0,
        65_535.0,
    )? as u32;
    let health = whole_in(
        path,
        o.line(21),
        "SV health",
        o.req(path, 21)?,
        0.0,
        65_535.0,
    )? as u32;
    Ok(GalileoEphemeris {
        prn,
        toc,
        af0_s: af0,
        af1_s_per_s: af1,
        af2_s_per_s2: af2,
        iodnav: whole_in(path, o.line(0), "IODnav", o.req(path, 0)?, 0.0, 1023.0)? as u16,
        orbit,
        toe,
        data_sources: src,
        sisa_m: o.opt(20),
        health,
        bgd_e1_e5a_s: o.opt(22),
        bgd_e1_e5b_s: o.opt(23),
        transmission_time: tt,
    })
}

/// A BeiDou record (RINEX 3.05 Table A14; 4.00 D1/D2): times BDT.
pub(crate) fn beidou(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    line: &[u8],
) -> Result<BeiDouEphemeris, InputError> {
    let (prn, cal) = first_line(path, ln, line, 63)?;
    // The epoch is a BDT calendar date: weeks counted from 2006-01-01 (BDT week 0).
    let toc = time_of(path, ln, &cal)?;
    let toc = GpsTime::new(toc.week - BDT_WEEK0_IN_GPS_WEEKS, toc.sow);
    let [af0, af1, af2] = clock3(path, ln, line, ["af0", "af1", "af2"])?;
    let o = Orbit::read(rd, path, ln, 7, "BeiDou", Names::Kepler("AODE", &BDS_TAIL))?;
    let orbit = o.kepler(path)?;
    let (toe, tt) = o.toe_tt(path, 18, orbit.toe_sow_s)?;
    Ok(BeiDouEphemeris {
        prn,
        toc,
        af0_s: af0,
        af1_s_per_s: af1,
        af2_s_per_s2: af2,
        aode: whole_in(path, o.line(0), "AODE", o.req(path, 0)?, 0.0, 255.0)? as u16,
        aodc: whole_in(path, o.line(25), "AODC", o.opt(25), 0.0, 255.0)? as u16,
        orbit,
        toe,
        sv_accuracy_m: o.opt(20),
        sat_h1: whole_in(path, o.line(21), "SatH1", o.req(path, 21)?, 0.0, 255.0)? as u32,
        tgd1_s: o.opt(22),
        tgd2_s: o.opt(23),
        transmission_time: tt,
    })
}

/// A GLONASS record (RINEX 3.05 Table A10: 3 orbit lines; 4.00 FDMA: 4). The epoch
/// is UTC: GPST = UTC + `leap_s` (the header's LEAP SECONDS, else
/// `navfuse_core::time::leap_seconds`).
pub(crate) fn glonass(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    line: &[u8],
    orbit_lines: usize,
    leap_s: Option<i32>,
) -> Result<GlonassEphemeris, InputError> {
    let (slot, cal) = first_line(path, ln, line, 63)?;
    let utc = time_of(path, ln, &cal)?;
    // The header's GPS-UTC, else the table in navfuse_core::time.
    let leap_s = leap_s.map_or_else(
        || navfuse_gnss::time::leap_seconds(u32::try_from(utc.week).ok()),
        f64::from,
    );
    let [m_tau, gamma, frame] = clock3(path, ln, line, ["-TauN", "+GammaN", "message frame time"])?;
    let o = Orbit::read(
        rd,
        path,
        ln,
        orbit_lines,
        "GLONASS",
        Names::All(&GLO_FIELDS),
    )?;
    let mut v = [0.0; 12];
    for (i, x) in v.iter_mut().enumerate() {
        *x = if i == 11 { o.opt(i) } else { o.req(path, i)? };
    }
    let k = whole_in(path, o.line(7), "frequency number", v[7], -7.0, 13.0)?;
    let health = whole_in(path, o.line(3), "health", v[3], 0.0, 255.0)? as u32;
    let sod = f64::from(cal.hour * 3600 + cal.minute * 60) + cal.second;
    Ok(GlonassEphemeris {
        slot,
        tb: utc.add_s(leap_s),
        tb_utc_sod_s: sod,
        tau_n_s: -m_tau,
        gamma_n: gamma,
        frame_time_s: frame,
        pos_m: Vector3::new(v[0], v[4], v[8]) * 1e3,
        vel_mps: Vector3::new(v[1], v[5], v[9]) * 1e3,
        acc_mps2: Vector3::new(v[2], v[6], v[10]) * 1e3,
        health,
        freq_channel: k as i8,
        age_days: v[11],
    })
}

/// Lines of a RINEX 4.00 record after its `>` line (Table A1 and the message tables),
/// or None for a kind this reader does not know.
pub(crate) fn v4_record_lines(kind: &[u8], sys: u8, msg: &[u8]) -> Option<usize> {
    Some(match (kind, sys, msg) {
        (b"EPH", b'G' | b'J' | b'I', b"LNAV") => 8,
        (b"EPH", b'G' | b'J', b"CNAV") => 9,
        (b"EPH", b'G' | b'J', b"CNV2") => 10,
        (b"EPH", b'E', b"INAV" | b"FNAV") => 8,
        (b"EPH", b'R', b"FDMA") => 5,
        (b"EPH", b'C', b"D1" | b"D2") => 8,
        (b"EPH", b'C', b"CNV1" | b"CNV2") => 10,
        (b"EPH", b'C', b"CNV3") => 9,
        (b"EPH", b'S', b"SBAS") => 4,
        (b"STO", _, _) => 2,
        (b"EOP", _, _) => 3,
        (b"ION", b'E', b"IFNV") => 2,
        (b"ION", b'G' | b'J' | b'C' | b'I', _) => 3,
        _ => return None,
    })
}

/// The Klobuchar (3 lines: epoch + alpha0-2, alpha3 beta0-2, beta3) or NeQuick-G
/// (2 lines: epoch + a_i0-2, flags) coefficients of a RINEX 4.00 `> ION` record
/// (Tables A32, A33, A34): numbers at columns 24, 43, 62 on the first line, 5, 24,
/// 43, 62 on the others.
pub(crate) fn ion_numbers(
    rd: &mut LineReader,
    path: &Path,
    ln: usize,
    n: usize,
) -> Result<Vec<f64>, InputError> {
    let mut out = Vec::new();
    for k in 0..n {
        let (m, l) = rd.next_line()?.ok_or_else(|| {
            InputError::at_line(
                path,
                ln,
                format!("ION record truncated: expected {n} lines"),
            )
        })?;
        let starts: &[usize] = if k == 0 {
            &[23, 42, 61]
        } else {
            &[4, 23, 42, 61]
        };
        for &c in starts {
            out.push(parse_num(path, m, "ION coefficient", cols(l, c, c + 19))?.unwrap_or(0.0));
        }
    }
    Ok(out)
}
