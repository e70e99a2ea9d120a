//! The RINEX observation writers and their header data: [`RinexObsWriter`] (RINEX
//! 3.04, GPS L1 C/A) and [`RinexMultiObsWriter`] (RINEX 3.05 mixed, any system and
//! signal, from [`MultiObsEpoch`]s).

use super::{MultiObsEpoch, SatObs};
use crate::rinex_nav::{header, utc_now_stamp};
use nalgebra::Vector3;
use navfuse_core::sat::System;
use navfuse_gnss::signal::ObsCode;
use navfuse_gnss::GpsTime;
use std::io::{self, Write};

/// Observation file header data written by [`RinexObsWriter`].
#[derive(Clone, Debug, PartialEq)]
pub struct ObsHeader {
    pub marker_name: String,
    /// `APPROX POSITION XYZ` \[m\].
    pub approx_pos_ecef_m: Vector3<f64>,
    /// `ANTENNA: DELTA H/E/N` (height, east, north) \[m\].
    pub antenna_delta_hen_m: Vector3<f64>,
    /// `INTERVAL` \[s\]; None leaves the record out.
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

/// The header records of a RINEX 3 observation file: `version`, `system` (the
/// `RINEX VERSION / TYPE` system field), the observation types and the phase-shift
/// signals of each system, GLONASS slots and channels.
fn write_header(
    w: &mut impl Write,
    h: &ObsHeader,
    version: f64,
    system: &str,
    types: &[(char, Vec<String>)],
    glonass_channels: &[(u8, i8)],
) -> io::Result<()> {
    header(
        w,
        &format!(
            "{:9.2}{:11}{:<20}{:<20}",
            version, "", "OBSERVATION DATA", system
        ),
        "RINEX VERSION / TYPE",
    )?;
    header(
        w,
        &format!(
            "{:<20}{:<20}{:<20}",
            a20(&h.program),
            "",
            h.date.clone().unwrap_or_else(utc_now_stamp)
        ),
        "PGM / RUN BY / DATE",
    )?;
    header(w, &h.marker_name, "MARKER NAME")?;
    header(w, "", "OBSERVER / AGENCY")?;
    header(
        w,
        &format!(
            "{:<20}{:<20}{:<20}",
            a20(&h.receiver[0]),
            a20(&h.receiver[1]),
            a20(&h.receiver[2])
        ),
        "REC # / TYPE / VERS",
    )?;
    header(
        w,
        &format!("{:<20}{:<20}", a20(&h.antenna[0]), a20(&h.antenna[1])),
        "ANT # / TYPE",
    )?;
    let p = h.approx_pos_ecef_m;
    header(
        w,
        &format!("{:14.4}{:14.4}{:14.4}", p.x, p.y, p.z),
        "APPROX POSITION XYZ",
    )?;
    let d = h.antenna_delta_hen_m;
    header(
        w,
        &format!("{:14.4}{:14.4}{:14.4}", d.x, d.y, d.z),
        "ANTENNA: DELTA H/E/N",
    )?;
    for (sys, list) in types {
        // 13 types per line, continuation lines blank in columns 1-6 (§5.2.12).
        for (k, chunk) in list.chunks(13).enumerate() {
            let mut line = if k == 0 {
                format!("{sys}  {:3}", list.len())
            } else {
                " ".repeat(6)
            };
            for t in chunk {
                line.push(' ');
                line.push_str(t);
            }
            header(w, &line, "SYS / # / OBS TYPES")?;
        }
    }
    header(w, "DBHZ", "SIGNAL STRENGTH UNIT")?;
    if let Some(i) = h.interval_s {
        header(w, &format!("{i:10.3}"), "INTERVAL")?;
    }
    let c = h.first_obs.to_calendar();
    header(
        w,
        &format!(
            "{:6}{:6}{:6}{:6}{:6}{:13.7}     GPS",
            c.year, c.month, c.day, c.hour, c.minute, c.second
        ),
        "TIME OF FIRST OBS",
    )?;
    if !glonass_channels.is_empty() {
        // 8 slots per line (§5.2.14).
        for (k, chunk) in glonass_channels.chunks(8).enumerate() {
            let mut line = if k == 0 {
                format!("{:3} ", glonass_channels.len())
            } else {
                " ".repeat(4)
            };
            for (slot, ch) in chunk {
                line.push_str(&format!("R{slot:02} {ch:2} "));
            }
            header(w, &line, "GLONASS SLOT / FRQ #")?;
        }
    }
    // The phase of each system's first carrier type, no shift applied.
    for (sys, list) in types {
        if let Some(l) = list.iter().find(|t| t.starts_with('L')) {
            header(w, &format!("{sys} {l}  0.00000"), "SYS / PHASE SHIFT")?;
        }
    }
    header(w, "", "END OF HEADER")
}

/// An epoch line `> yyyy mm dd hh mm ss.sssssss  0nnn` (flag 0).
fn write_epoch_line(w: &mut impl Write, t: GpsTime, n: usize) -> io::Result<()> {
    if n > 999 {
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
        w,
        "> {:04} {:02} {:02} {:02} {:02}{:11.7}  0{:3}",
        c.year, c.month, c.day, c.hour, c.minute, c.second, n
    )
}

/// One observation field: F14.3 value, LLI and SSI characters (blank = absent), or
/// 16 blanks without a value.
fn push_field(
    line: &mut String,
    v: Option<f64>,
    lli: Option<u8>,
    ssi: Option<u8>,
) -> io::Result<()> {
    let digit = |d: Option<u8>| d.map_or(' ', |d| (b'0' + d.min(9)) as char);
    match v {
        Some(v) => {
            line.push_str(&f14_3(v)?);
            line.push(digit(lli));
            line.push(digit(ssi));
        }
        None => line.push_str(&" ".repeat(16)),
    }
    Ok(())
}

impl<W: Write> RinexObsWriter<W> {
    /// Write the header and return the writer.
    pub fn new(mut w: W, h: &ObsHeader) -> io::Result<Self> {
        let types = [('G', OBS_TYPES.iter().map(|t| t.to_string()).collect())];
        write_header(&mut w, h, 3.04, "G: GPS", &types, &[])?;
        Ok(RinexObsWriter { w })
    }

    /// Write one epoch (flag 0) with its satellites.
    pub fn write_epoch(&mut self, t: GpsTime, sats: &[SatObs]) -> io::Result<()> {
        write_epoch_line(&mut self.w, t, sats.len())?;
        for s in sats {
            let mut line = format!("G{:02}", s.prn);
            let ssi = s.cn0_dbhz.map_or(0, ssi_from_cn0);
            let ssi = (ssi > 0).then_some(ssi);
            let vals = [s.pseudorange_m, s.carrier_cycles, s.doppler_hz, s.cn0_dbhz];
            for (k, v) in vals.iter().enumerate() {
                let lli = (k == 1 && s.lli != 0).then_some(s.lli & 7);
                push_field(&mut line, *v, lli, ssi)?;
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

/// Writes a mixed RINEX 3.05 observation file (`M: Mixed` when more than one system,
/// else the system's letter and name): one `SYS / # / OBS TYPES` list per system, each
/// satellite's observations in its system's order (blank where absent), LLI and SSI
/// digits as given (None = blank).
pub struct RinexMultiObsWriter<W: Write> {
    w: W,
    types: Vec<(System, Vec<ObsCode>)>,
}

impl<W: Write> RinexMultiObsWriter<W> {
    /// Write the header for `types` (system and its codes, in the header's order) and
    /// GLONASS `glonass_channels` (slot, channel), and return the writer.
    pub fn new(
        mut w: W,
        h: &ObsHeader,
        types: &[(System, Vec<ObsCode>)],
        glonass_channels: &[(u8, i8)],
    ) -> io::Result<Self> {
        let sys = match types {
            [(s, _)] => format!("{}: {}", s.letter(), s.name()),
            _ => "M: Mixed".to_string(),
        };
        let lists: Vec<(char, Vec<String>)> = types
            .iter()
            .map(|(s, l)| (s.letter(), l.iter().map(|c| c.to_string()).collect()))
            .collect();
        write_header(&mut w, h, 3.05, &sys, &lists, glonass_channels)?;
        Ok(RinexMultiObsWriter {
            w,
            types: types.to_vec(),
        })
    }

    /// Write one epoch (its time and satellites; flag 0; the receiver clock offset is
    /// not written). A satellite of a system not in the header is an error.
    pub fn write_epoch(&mut self, ep: &MultiObsEpoch) -> io::Result<()> {
        write_epoch_line(&mut self.w, ep.t, ep.sats.len())?;
        for s in &ep.sats {
            let Some((_, codes)) = self.types.iter().find(|(sys, _)| *sys == s.sat.system) else {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("{}: system not in the header", s.sat),
                ));
            };
            let mut line = s.sat.to_string();
            for c in codes {
                match s.get(*c) {
                    Some(v) => push_field(&mut line, v.value, v.lli, v.ssi)?,
                    None => push_field(&mut line, None, None, None)?,
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
