//! Exports of a solution for the tools users already have (docs/FORMATS.md
//! "Exports"): RTKLIB `.pos` (GPST, readable by `pos2kml` and `rtkplot`), NMEA 0183
//! (GGA, RMC, HDT, UTC), KML, GeoJSON and GPX (maps; UTC in GPX). Each is a
//! [`RecordWriter`], so `navfuse run` writes them beside solution.nav (`\[output\]
//! formats`, `--formats`) and `navfuse export` from a finished run.
//!
//! The map formats and NMEA take the first epoch of each [`MAP_PERIOD_S`] of GPS time
//! (a 200 Hz track is too dense for a map or a serial log); `.pos` takes every epoch.

use crate::error::InputError;
use crate::fmt::push_fixed9;
use crate::nav::{Out, RecordWriter, SolutionRecord};
use crate::time::week_sow_to_calendar;
use navfuse_core::attitude::{euler_from_q_bn, wrap_2pi};
use navfuse_core::time::leap_seconds;
use navfuse_core::SolutionState;
use std::io::Write as _;
use std::path::Path;

/// The map and NMEA exports take one epoch per this interval of GPS time \[s\].
pub const MAP_PERIOD_S: f64 = 0.1;

/// An export format (`\[output\] formats`, `--formats`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ExportFormat {
    Pos,
    Nmea,
    Kml,
    Geojson,
    Gpx,
}

impl ExportFormat {
    pub const ALL: [ExportFormat; 5] = [
        ExportFormat::Pos,
        ExportFormat::Nmea,
        ExportFormat::Kml,
        ExportFormat::Geojson,
        ExportFormat::Gpx,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ExportFormat::Pos => "pos",
            ExportFormat::Nmea => "nmea",
            ExportFormat::Kml => "kml",
            ExportFormat::Geojson => "geojson",
            ExportFormat::Gpx => "gpx",
        }
    }

    /// `STEM.EXT`.
    pub fn file_name(self, stem: &str) -> String {
        format!("{stem}.{}", self.name())
    }

    /// Comma-separated names, e.g. `kml,pos`; an error names the unknown one.
    pub fn parse_list(s: &str) -> Result<Vec<ExportFormat>, String> {
        let mut v = Vec::new();
        for name in s.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            let f = Self::ALL
                .into_iter()
                .find(|f| f.name() == name.to_ascii_lowercase())
                .ok_or_else(|| {
                    format!(
                        "unknown export format {name:?}: expected pos, nmea, kml, geojson or gpx"
                    )
                })?;
            if !v.contains(&f) {
                v.push(f);
            }
        }
        Ok(v)
    }

    /// The writer of this format into `path`.
    pub fn create(self, path: &Path) -> Result<Box<dyn RecordWriter>, InputError> {
        let out = Out::create(path)?;
        let w: Box<dyn RecordWriter> = match self {
            ExportFormat::Pos => Box::new(PosWriter::new(out)?),
            ExportFormat::Nmea => Box::new(NmeaWriter::new(out)),
            ExportFormat::Kml => Box::new(MapWriter::new(out, Map::Kml)?),
            ExportFormat::Geojson => Box::new(MapWriter::new(out, Map::Geojson)?),
            ExportFormat::Gpx => Box::new(MapWriter::new(out, Map::Gpx)?),
        };
        Ok(w)
    }
}

/// A set of export formats (small and `Copy`, for the output layout).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExportSet(u8);

impl ExportSet {
    pub fn of(list: &[ExportFormat]) -> Self {
        ExportSet(
            list.iter()
                .map(|f| 1u8 << ExportFormat::ALL.iter().position(|a| a == f).unwrap_or(0))
                .fold(0, |a, b| a | b),
        )
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub fn iter(self) -> impl Iterator<Item = ExportFormat> {
        ExportFormat::ALL
            .into_iter()
            .enumerate()
            .filter(move |(i, _)| self.0 & (1 << i) != 0)
            .map(|(_, f)| f)
    }
}

fn push_f(line: &mut Vec<u8>, v: f64, decimals: usize) {
    let _ = write!(line, "{v:.decimals$}");
}

/// Decimation of the map and NMEA exports: the first epoch in each [`MAP_PERIOD_S`]
/// interval of GPS time (the rule of `output.rate_hz`, with its 1 µs tolerance), so
/// at most 10 Hz, regular at any IMU rate, and a 10 Hz solution whose time tags jitter
/// within their intervals is kept whole.
#[derive(Default)]
struct Every {
    last: Option<i64>,
}

impl Every {
    fn due(&mut self, r: &SolutionRecord) -> bool {
        let per_week = (navfuse_core::time::SECONDS_PER_WEEK / MAP_PERIOD_S).round() as i64;
        let bin =
            i64::from(r.gps_week) * per_week + ((r.nav.t + 1e-6) / MAP_PERIOD_S).floor() as i64;
        if self.last.is_some_and(|l| bin <= l) {
            return false;
        }
        self.last = Some(bin);
        true
    }
}

/// RTKLIB solution file: GPST date and time, latitude, longitude \[deg\], ellipsoidal
/// height \[m\], Q, ns, sdn sde sdu sdne sdeu sdun \[m\], age, ratio. Q is 5 ("single")
/// for every epoch: RTKLIB has no code for an INS solution.
pub struct PosWriter {
    file: PosFile,
}

impl PosWriter {
    fn new(out: Out) -> Result<Self, InputError> {
        Ok(PosWriter {
            file: PosFile::with_out(
                out,
                "GNSS/INS solution exported as an RTKLIB position file",
                "INS/GNSS integrated (Q = 5 for every epoch)",
                0.0,
            )?,
        })
    }
}

/// One line of an RTKLIB position file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PosLine {
    pub gps_week: u32,
    /// GPS seconds of week.
    pub sow: f64,
    /// Latitude, longitude \[rad\], ellipsoidal height \[m\].
    pub lla: nalgebra::Vector3<f64>,
    /// RTKLIB's quality: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP.
    pub q: u8,
    /// Satellites used.
    pub ns: usize,
    /// sdn, sde, sdu, sdne, sdeu, sdun \[m\] (RTKLIB's signed square roots of the
    /// covariances).
    pub sd_m: [f64; 6],
    pub age_s: f64,
    pub ratio: f64,
}

/// An RTKLIB `.pos` file (llh, GPST, `YYYY/MM/DD HH:MM:SS.ssssss`): its header, then
/// one [`PosLine`] per epoch.
pub struct PosFile {
    out: Out,
}

impl PosFile {
    /// Create `path` with the header: `what` (program line), `mode` (pos mode line),
    /// the elevation mask \[deg\].
    pub fn create(
        path: &Path,
        what: &str,
        mode: &str,
        elev_mask_deg: f64,
    ) -> Result<Self, InputError> {
        Self::with_out(Out::create(path)?, what, mode, elev_mask_deg)
    }

    fn with_out(
        mut out: Out,
        what: &str,
        mode: &str,
        elev_mask_deg: f64,
    ) -> Result<Self, InputError> {
        let _ = write!(
            out.line,
            "% program   : navfuse ({what})\n\
% pos mode  : {mode}\n\
% elev mask : {elev_mask_deg:.1} deg\n\
% ref pos   : none\n\
%\n\
% (lat/lon/height=WGS84/ellipsoidal,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp,ns=# of satellites)\n\
%  GPST                     latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n"
        );
        out.put()?;
        Ok(PosFile { out })
    }

    pub fn write(&mut self, p: &PosLine) -> Result<(), InputError> {
        let line = &mut self.out.line;
        // Microseconds (RTKLIB's own files carry 3 decimals; it reads more).
        let c = week_sow_to_calendar(p.gps_week, p.sow);
        let us = (c.second * 1e6).round().min(59_999_999.0);
        let _ = write!(
            line,
            "{:04}/{:02}/{:02} {:02}:{:02}:{:09.6} ",
            c.year,
            c.month,
            c.day,
            c.hour,
            c.minute,
            us / 1e6
        );
        push_f(line, p.lla.x.to_degrees(), 9);
        line.push(b' ');
        push_f(line, p.lla.y.to_degrees(), 9);
        line.push(b' ');
        push_f(line, p.lla.z, 4);
        let sd = p.sd_m;
        let _ = writeln!(
            line,
            " {:3} {:3} {:8.4} {:8.4} {:8.4} {:8.4} {:8.4} {:8.4} {:6.2} {:6.1}",
            p.q, p.ns, sd[0], sd[1], sd[2], sd[3], sd[4], sd[5], p.age_s, p.ratio
        );
        self.out.put()
    }

    pub fn flush(&mut self) -> Result<(), InputError> {
        self.out.flush()
    }

    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

impl RecordWriter for PosWriter {
    fn write_record(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        let sd = r.std.map_or([0.0; 3], |s| [s[0], s[1], s[2]]);
        self.file.write(&PosLine {
            gps_week: r.gps_week,
            sow: r.nav.t,
            lla: r.nav.lla,
            q: 5,
            ns: 0,
            sd_m: [sd[0], sd[1], sd[2], 0.0, 0.0, 0.0],
            age_s: 0.0,
            ratio: 0.0,
        })
    }
    fn flush(&mut self) -> Result<(), InputError> {
        self.file.flush()
    }
    fn finish_boxed(self: Box<Self>) -> Result<(), InputError> {
        self.file.finish()
    }
}

/// NMEA sentence `$BODY*CS\r\n` with the XOR checksum of BODY.
pub fn nmea_sentence(body: &str) -> String {
    let cs = body.bytes().fold(0u8, |a, b| a ^ b);
    format!("${body}*{cs:02X}\r\n")
}

/// UTC of a GPS time (GPS week, seconds of week) to the nearest `1 / per_s` s: the
/// calendar of its whole second and the fraction in those units. Rounding the time
/// first (not the calendar's float seconds) prints 42.3 s as `42.30`, not `42.29`.
fn utc(r: &SolutionRecord, per_s: i64) -> (crate::time::Calendar, i64) {
    let leap = leap_seconds(Some(r.gps_week));
    let ticks = ((r.nav.t - leap) * per_s as f64).round() as i64;
    let c = week_sow_to_calendar(r.gps_week, ticks.div_euclid(per_s) as f64);
    (c, ticks.rem_euclid(per_s))
}

/// Degrees as NMEA `ddmm.mmmmmm` / `dddmm.mmmmmm` with the hemisphere letter.
fn nmea_angle(deg: f64, lon: bool) -> (String, char) {
    let hemi = match (lon, deg < 0.0) {
        (false, false) => 'N',
        (false, true) => 'S',
        (true, false) => 'E',
        (true, true) => 'W',
    };
    let a = deg.abs();
    let mut d = a.floor();
    let mut m = (a - d) * 60.0;
    if m >= 59.999_999_5 {
        d += 1.0;
        m = 0.0;
    }
    let s = if lon {
        format!("{:03}{:09.6}", d as u32, m)
    } else {
        format!("{:02}{:09.6}", d as u32, m)
    };
    (s, hemi)
}

/// NMEA 0183: GGA (fix quality 1; 6 = dead reckoning while the integrity monitor
/// holds GNSS out), RMC, HDT per epoch (one per [`MAP_PERIOD_S`], see `Every`), UTC from
/// GPS time with the leap seconds of the epoch's week. The GGA altitude field holds
/// the ellipsoidal height with a geoid separation of 0 (no geoid model here).
pub struct NmeaWriter {
    out: Out,
    every: Every,
}

impl NmeaWriter {
    fn new(out: Out) -> Self {
        NmeaWriter {
            out,
            every: Every::default(),
        }
    }
}

impl RecordWriter for NmeaWriter {
    fn write_record(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        if !self.every.due(r) {
            return Ok(());
        }
        let (c, cs) = utc(r, 100);
        let hms = format!("{:02}{:02}{:02}.{cs:02}", c.hour, c.minute, c.second);
        let date = format!("{:02}{:02}{:02}", c.day, c.month, c.year.rem_euclid(100));
        let n = &r.nav;
        let (lat, ns) = nmea_angle(n.lla.x.to_degrees(), false);
        let (lon, ew) = nmea_angle(n.lla.y.to_degrees(), true);
        // 6 = estimated (dead reckoning): GNSS held out or not fused lately.
        let coasting = matches!(
            r.state,
            Some(
                SolutionState::DeadReckoning
                    | SolutionState::Inertial
                    | SolutionState::GnssExcluded
            )
        );
        let q = if coasting || matches!(r.gnss_integrity, Some(2)) {
            6
        } else {
            1
        };
        let gga = format!(
            "GPGGA,{hms},{lat},{ns},{lon},{ew},{q},00,,{:.3},M,0.000,M,,",
            n.lla.z
        );
        let speed_kn = n.v_n.x.hypot(n.v_n.y) * 3600.0 / 1852.0;
        let course = wrap_2pi(n.v_n.y.atan2(n.v_n.x)).to_degrees();
        let rmc =
            format!("GPRMC,{hms},A,{lat},{ns},{lon},{ew},{speed_kn:.3},{course:.2},{date},,,D");
        let yaw = wrap_2pi(euler_from_q_bn(&n.q_bn).z).to_degrees();
        let hdt = format!("GPHDT,{yaw:.3},T");
        for s in [gga, rmc, hdt] {
            self.out
                .line
                .extend_from_slice(nmea_sentence(&s).as_bytes());
        }
        self.out.put()
    }
    fn flush(&mut self) -> Result<(), InputError> {
        self.out.flush()
    }
    fn finish_boxed(self: Box<Self>) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// `lon,lat,h` (degrees with 9 decimals, metres with 3), as KML and GeoJSON order them.
fn push_lon_lat_h(line: &mut Vec<u8>, lon: f64, lat: f64, h: f64) {
    push_fixed9(line, lon);
    line.push(b',');
    push_fixed9(line, lat);
    line.push(b',');
    push_f(line, h, 3);
}

#[derive(Clone, Copy, PartialEq)]
enum Map {
    Kml,
    Geojson,
    Gpx,
}

/// A track as one line (KML `LineString`, GeoJSON `LineString` feature, GPX `trkseg`).
pub struct MapWriter {
    out: Out,
    map: Map,
    every: Every,
    points: usize,
}

impl MapWriter {
    fn new(mut out: Out, map: Map) -> Result<Self, InputError> {
        let head: &[u8] = match map {
            Map::Kml => b"<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>navfuse solution</name>\n<Style id=\"track\"><LineStyle><color>ff00ffff</color><width>2</width></LineStyle></Style>\n<Placemark>\n<name>track</name>\n<styleUrl>#track</styleUrl>\n<LineString>\n<altitudeMode>absolute</altitudeMode>\n<coordinates>\n",
            Map::Geojson => b"{\"type\":\"FeatureCollection\",\"features\":[{\"type\":\"Feature\",\"properties\":{\"name\":\"navfuse solution\",\"height\":\"ellipsoidal [m]\"},\"geometry\":{\"type\":\"LineString\",\"coordinates\":[\n",
            Map::Gpx => b"<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<gpx version=\"1.1\" creator=\"navfuse\" xmlns=\"http://www.topografix.com/GPX/1/1\">\n<trk><name>navfuse solution</name><trkseg>\n",
        };
        out.line.extend_from_slice(head);
        out.put()?;
        Ok(MapWriter {
            out,
            map,
            every: Every::default(),
            points: 0,
        })
    }
}

impl RecordWriter for MapWriter {
    fn write_record(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        if !self.every.due(r) {
            return Ok(());
        }
        let n = &r.nav;
        let (lat, lon, h) = (n.lla.x.to_degrees(), n.lla.y.to_degrees(), n.lla.z);
        let line = &mut self.out.line;
        match self.map {
            Map::Kml => {
                push_lon_lat_h(line, lon, lat, h);
                line.push(b'\n');
            }
            Map::Geojson => {
                if self.points > 0 {
                    line.extend_from_slice(b",\n");
                }
                line.push(b'[');
                push_lon_lat_h(line, lon, lat, h);
                line.push(b']');
            }
            Map::Gpx => {
                let (c, ms) = utc(r, 1000);
                let _ = writeln!(
                    line,
                    "<trkpt lat=\"{lat:.9}\" lon=\"{lon:.9}\"><ele>{h:.3}</ele><time>{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{ms:03}Z</time></trkpt>",
                    c.year, c.month, c.day, c.hour, c.minute, c.second
                );
            }
        }
        self.points += 1;
        self.out.put()
    }
    fn flush(&mut self) -> Result<(), InputError> {
        self.out.flush()
    }
    fn finish_boxed(mut self: Box<Self>) -> Result<(), InputError> {
        let tail: &[u8] = match self.map {
            Map::Kml => b"</coordinates>\n</LineString>\n</Placemark>\n</Document>\n</kml>\n",
            Map::Geojson => b"\n]}}]}\n",
            Map::Gpx => b"</trkseg></trk>\n</gpx>\n",
        };
        self.out.line.extend_from_slice(tail);
        self.out.put()?;
        self.out.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nmea_checksum_and_angles() {
        // A sentence from the NMEA literature with its checksum.
        assert_eq!(
            nmea_sentence("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),
            "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"
        );
        assert_eq!(nmea_angle(48.1173, false), ("4807.038000".into(), 'N'));
        assert_eq!(nmea_angle(-11.5166667, true).1, 'W');
        assert_eq!(nmea_angle(-11.5, true).0, "01130.000000");
        assert!(
            ExportFormat::parse_list("kml, POS,kml").unwrap()
                == vec![ExportFormat::Kml, ExportFormat::Pos]
        );
        assert!(ExportFormat::parse_list("shp").unwrap_err().contains("shp"));
    }

    fn at(t: f64) -> SolutionRecord {
        SolutionRecord {
            gps_week: 2374,
            nav: navfuse_core::NavState {
                t,
                lla: nalgebra::Vector3::zeros(),
                v_n: nalgebra::Vector3::zeros(),
                q_bn: nalgebra::UnitQuaternion::identity(),
            },
            imu_errors: Default::default(),
            std: None,
            gnss_integrity: None,
            state: None,
        }
    }

    #[test]
    fn decimation_is_one_epoch_per_tenth_of_a_second() {
        // 200 Hz: every 20th epoch, 10 Hz exactly (the 0.095 s rule it replaces gave
        // 105 epochs in these 10 s, mostly 0.095 s apart).
        let mut e = Every::default();
        let kept: Vec<usize> = (0..2001)
            .filter(|&k| e.due(&at(243_000.0 + k as f64 * 0.005)))
            .collect();
        assert_eq!(kept.len(), 101);
        assert!(kept.iter().enumerate().all(|(i, &k)| k == 20 * i));
        // A 10 Hz solution with 0-11 ms of jitter inside its intervals: all kept.
        let mut e = Every::default();
        let jitter = [0.002, 0.011, 0.0, 0.009, 0.001, 0.010];
        assert!((0..600).all(|k| e.due(&at(243_000.0 + k as f64 * 0.1 + jitter[k % 6]))));
        // Across the week boundary.
        let mut e = Every::default();
        assert!(e.due(&at(604_799.95)));
        let mut r = at(0.0);
        r.gps_week += 1;
        assert!(e.due(&r) && !e.due(&at(604_799.99)));
    }

    #[test]
    fn utc_rounds_the_time_not_the_calendar() {
        // 243000.3 s GPST is 19:29:42.3 UTC (18 leap seconds in 2025).
        let (c, ms) = utc(&at(243_000.3), 1000);
        assert_eq!((c.hour, c.minute, c.second, ms), (19, 29, 42.0, 300));
        let (c, cs) = utc(&at(243_077.999_9), 100);
        assert_eq!((c.minute, c.second, cs), (31, 0.0, 0));
    }
}
