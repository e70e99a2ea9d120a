//! The RINEX 3.04 GPS L1 C/A observation writer and its header data.

use super::SatObs;
use crate::rinex_nav::{header, utc_now_stamp};
use nalgebra::Vector3;
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

impl<W: Write> RinexObsWriter<W> {
    /// Write the header and return the writer.
    pub fn new(mut w: W, h: &ObsHeader) -> io::Result<Self> {
        header(
            &mut w,
            &format!(
                "{:9.2}{:11}{:<20}{:<20}",
                3.04, "", "OBSERVATION DATA", "G: GPS"
            ),
            "RINEX VERSION / TYPE",
        )?;
        header(
            &mut w,
            &format!(
                "{:<20}{:<20}{:<20}",
                a20(&h.program),
                "",
                h.date.clone().unwrap_or_else(utc_now_stamp)
            ),
            "PGM / RUN BY / DATE",
        )?;
        header(&mut w, &h.marker_name, "MARKER NAME")?;
        header(&mut w, "", "OBSERVER / AGENCY")?;
        header(
            &mut w,
            &format!(
                "{:<20}{:<20}{:<20}",
                a20(&h.receiver[0]),
                a20(&h.receiver[1]),
                a20(&h.receiver[2])
            ),
            "REC # / TYPE / VERS",
        )?;
        header(
            &mut w,
            &format!("{:<20}{:<20}", a20(&h.antenna[0]), a20(&h.antenna[1])),
            "ANT # / TYPE",
        )?;
        let p = h.approx_pos_ecef_m;
        header(
            &mut w,
            &format!("{:14.4}{:14.4}{:14.4}", p.x, p.y, p.z),
            "APPROX POSITION XYZ",
        )?;
        let d = h.antenna_delta_hen_m;
        header(
            &mut w,
            &format!("{:14.4}{:14.4}{:14.4}", d.x, d.y, d.z),
            "ANTENNA: DELTA H/E/N",
        )?;
        let mut types = format!("G  {:3}", OBS_TYPES.len());
        for t in OBS_TYPES {
            types.push(' ');
            types.push_str(t);
        }
        header(&mut w, &types, "SYS / # / OBS TYPES")?;
        header(&mut w, "DBHZ", "SIGNAL STRENGTH UNIT")?;
        if let Some(i) = h.interval_s {
            header(&mut w, &format!("{i:10.3}"), "INTERVAL")?;
        }
        let c = h.first_obs.to_calendar();
        header(
            &mut w,
            &format!(
                "{:6}{:6}{:6}{:6}{:6}{:13.7}     GPS",
                c.year, c.month, c.day, c.hour, c.minute, c.second
            ),
            "TIME OF FIRST OBS",
        )?;
        header(&mut w, "G L1C  0.00000", "SYS / PHASE SHIFT")?;
        header(&mut w, "", "END OF HEADER")?;
        Ok(RinexObsWriter { w })
    }

    /// Write one epoch (flag 0) with its satellites.
    pub fn write_epoch(&mut self, t: GpsTime, sats: &[SatObs]) -> io::Result<()> {
        if sats.len() > 999 {
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
            self.w,
            "> {:04} {:02} {:02} {:02} {:02}{:11.7}  0{:3}",
            c.year,
            c.month,
            c.day,
            c.hour,
            c.minute,
            c.second,
            sats.len()
        )?;
        for s in sats {
            let mut line = format!("G{:02}", s.prn);
            let ssi = s.cn0_dbhz.map_or(0, ssi_from_cn0);
            let vals = [s.pseudorange_m, s.carrier_cycles, s.doppler_hz, s.cn0_dbhz];
            for (k, v) in vals.iter().enumerate() {
                match v {
                    Some(v) => {
                        line.push_str(&f14_3(*v)?);
                        let lli = if k == 1 && s.lli != 0 {
                            (b'0' + (s.lli & 7)) as char
                        } else {
                            ' '
                        };
                        line.push(lli);
                        line.push(if ssi > 0 { (b'0' + ssi) as char } else { ' ' });
                    }
                    None => line.push_str(&" ".repeat(16)),
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
