//! Trajectories to score (`navfuse eval`), in any of the four formats navfuse reads
//! positions from, recognised by their content (not by the file name): KF-GINS `.nav`
//! (11 columns), navfuse's own `solution.csv` / `smoothed.csv` (its header row), an
//! RTKLIB `.pos` (`%` header, 15 or 24 columns, a date or GPS week first) and the
//! KF-GINS GNSS text file (7 or 13 columns). See docs/FORMATS.md "Trajectories to
//! score".
//!
//! What each carries: `.nav` and CSV position, velocity and attitude (the IMU centre);
//! `.pos` position, and velocity in its 24-column form; KF-GINS GNSS position, and
//! velocity in its 13-column form (the antenna). The points say so (`v_n`, `rpy`
//! None), and the evaluator scores velocity and attitude only where both sides have
//! them.

use crate::error::{shorten, InputError};
use crate::fmt::{field, is_comment_line, parse_f64, split_fields, LineReader};
use crate::gnss::read_gnss;
use crate::input::{GnssFormat, GnssSource};
use crate::nav::{is_csv_nav_header, read_nav, read_solution_csv};
use navfuse_core::attitude::euler_from_q_bn;
use navfuse_core::eval::TrajPoint;
use navfuse_core::time::SECONDS_PER_WEEK;
use navfuse_core::{GnssFix, NavState};
use std::path::Path;

/// A trajectory file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrajFormat {
    /// KF-GINS `.nav`: week, t, lat lon h, vN vE vD, roll pitch yaw.
    Nav,
    /// navfuse `solution.csv` / `smoothed.csv`.
    Csv,
    /// RTKLIB solution file (lat/lon/height, GPST).
    Pos,
    /// KF-GINS GNSS text: t, lat lon h, std N E D [, vel N E D, vel std N E D].
    KfGinsGnss,
    /// PX4 ULog: EKF2's estimate (ulog/mod.rs `ekf2_track`), told by its magic.
    Ulog,
}

/// What the detection looks for, for its error messages.
const EXPECTED: &str = "expected 11 (KF-GINS .nav), 7 or 13 (KF-GINS GNSS), a navfuse CSV \
header (gps_week,t_s,lat_deg,...) or an RTKLIB .pos (% header; 15 or 24 columns)";

impl TrajFormat {
    pub const ALL: [TrajFormat; 5] = [
        TrajFormat::Nav,
        TrajFormat::Csv,
        TrajFormat::Pos,
        TrajFormat::KfGinsGnss,
        TrajFormat::Ulog,
    ];

    /// The name of `--solution-format` / `--truth-format`.
    pub fn name(self) -> &'static str {
        match self {
            TrajFormat::Nav => "nav",
            TrajFormat::Csv => "csv",
            TrajFormat::Pos => "pos",
            TrajFormat::KfGinsGnss => "kfgins-gnss",
            TrajFormat::Ulog => "ulog",
        }
    }

    /// For people: `KF-GINS .nav`, ...
    pub fn describe(self) -> &'static str {
        match self {
            TrajFormat::Nav => "KF-GINS .nav",
            TrajFormat::Csv => "navfuse CSV",
            TrajFormat::Pos => "RTKLIB .pos",
            TrajFormat::KfGinsGnss => "KF-GINS GNSS text",
            TrajFormat::Ulog => "PX4 ULog (EKF2)",
        }
    }

    /// `auto` gives None (detect); an unknown name is an error listing the names.
    pub fn parse(s: &str) -> Result<Option<TrajFormat>, String> {
        let s = s.trim().to_ascii_lowercase();
        if s == "auto" {
            return Ok(None);
        }
        Self::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .map(Some)
            .ok_or_else(|| {
                format!("unknown format {s:?}: expected auto, nav, csv, pos, kfgins-gnss or ulog")
            })
    }
}

/// An RTKLIB column-name line (`%  GPST  latitude(deg) ...`, or the ECEF and baseline
/// forms, which the `.pos` reader then refuses with the reason).
fn is_pos_column_header(text: &[u8]) -> bool {
    let s = String::from_utf8_lossy(text);
    s.contains("latitude(") || s.contains("x-ecef(") || s.contains("e-baseline(")
}

/// The format of `path`, from its first lines: the first data line's column count,
/// the navfuse CSV header, RTKLIB's `%` header. Errors name the file and line and
/// say what was expected.
pub fn detect_format(path: &Path) -> Result<TrajFormat, InputError> {
    if crate::ulog::is_ulog(path) {
        return Ok(TrajFormat::Ulog);
    }
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(32);
    let mut percent_header = false;
    while let Some((ln, text)) = lines.next_line()? {
        split_fields(text, &mut fields);
        if is_comment_line(text, &fields) {
            if fields
                .first()
                .is_some_and(|&(s, _)| text.get(s) == Some(&b'%'))
            {
                if is_pos_column_header(text) {
                    return Ok(TrajFormat::Pos);
                }
                percent_header = true;
            }
            continue;
        }
        if is_csv_nav_header(text) {
            return Ok(TrajFormat::Csv);
        }
        let first = field(text, &fields, 0);
        let is_date = first.contains(&b'/');
        if parse_f64(first).is_none() && !is_date {
            return Err(InputError::at_line(
                path,
                ln,
                format!(
                    "found \"{}\", not a number or a known header; {EXPECTED}",
                    shorten(text)
                ),
            ));
        }
        let n = fields.len();
        return match n {
            11 if !is_date => Ok(TrajFormat::Nav),
            7 | 13 if !is_date => Ok(TrajFormat::KfGinsGnss),
            // RTKLIB writes a `%` header, then a date (or GPS week) and 15 or 24
            // columns; other counts are left to its reader to explain.
            _ if percent_header || is_date || n == 15 || n == 24 => Ok(TrajFormat::Pos),
            _ => Err(InputError::at_line(
                path,
                ln,
                format!("{n} columns; {EXPECTED}"),
            )),
        };
    }
    if percent_header {
        // A `.pos` with its header and no epoch.
        return Ok(TrajFormat::Pos);
    }
    Err(InputError::new(path, format!("no data line; {EXPECTED}")))
}

/// A trajectory with its GPS week (0 = unknown, times are seconds of week).
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    pub format: TrajFormat,
    pub week: u32,
    pub points: Vec<TrajPoint>,
    /// Findings that did not stop the read (a damaged last line dropped).
    pub warnings: Vec<String>,
}

/// Rows of (GPS week, state) as points with velocity and attitude, and the week
/// they count from (the first row's; 0 without rows).
pub fn points_of_rows(rows: Vec<(u32, NavState)>) -> (u32, Vec<TrajPoint>) {
    let week = rows.first().map_or(0, |r| r.0);
    let points = rows
        .into_iter()
        .map(|(w, s)| TrajPoint {
            t: s.t + (w as f64 - week as f64) * SECONDS_PER_WEEK,
            lla: s.lla,
            v_n: Some(s.v_n),
            rpy: Some(euler_from_q_bn(&s.q_bn)),
        })
        .collect();
    (week, points)
}

/// GNSS fixes as points: position, velocity when the fix has it, no attitude.
pub fn points_of_fixes(fixes: &[GnssFix]) -> Vec<TrajPoint> {
    fixes
        .iter()
        .map(|f| TrajPoint {
            t: f.t,
            lla: f.lla,
            v_n: f.vel_ned,
            rpy: None,
        })
        .collect()
}

fn of_rows(format: TrajFormat, rows: Vec<(u32, NavState)>) -> Trajectory {
    let (week, points) = points_of_rows(rows);
    Trajectory {
        format,
        week,
        points,
        warnings: Vec::new(),
    }
}

/// Read `path` as `format` (`None`: [`detect_format`]). `pos_quality`: the Q values an
/// RTKLIB `.pos` keeps (empty: all).
pub fn read_trajectory(
    path: &Path,
    format: Option<TrajFormat>,
    pos_quality: &[u8],
) -> Result<Trajectory, InputError> {
    let format = match format {
        Some(f) => f,
        None => detect_format(path)?,
    };
    let gnss = match format {
        TrajFormat::Nav => return Ok(of_rows(format, read_nav(path)?)),
        TrajFormat::Csv => return Ok(of_rows(format, read_solution_csv(path)?)),
        TrajFormat::Pos => GnssFormat::RtklibPos {
            quality: pos_quality.to_vec(),
        },
        TrajFormat::KfGinsGnss => GnssFormat::KfGins,
        TrajFormat::Ulog => {
            let mut warnings = Vec::new();
            let u = crate::ulog::open(path, &mut warnings)?;
            let (points, map, w) = crate::ulog::ekf2_track(path, &u)?;
            warnings.extend(w);
            return Ok(Trajectory {
                format,
                week: map.week.unwrap_or(0),
                points,
                warnings,
            });
        }
    };
    let g = read_gnss(&GnssSource {
        path: path.to_path_buf(),
        format: gnss,
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })?;
    Ok(Trajectory {
        format,
        week: g.gps_week.unwrap_or(0),
        points: points_of_fixes(&g.fixes),
        warnings: g.warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn tmp(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("navfuse-traj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    const NAV: &str = "0 456300.0 30.4 114.4 20.0 0.1 0.2 0.3 1.0 2.0 185.0\n\
                       0 456300.1 30.4 114.4 20.0 0.1 0.2 0.3 1.0 2.0 185.0\n";
    const CSV: &str = "gps_week,t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg,std_pn_m,gnss_integrity\n\
                       2374,456300.0,30.4,114.4,20.0,0.1,0.2,0.3,1.0,2.0,185.0,,0\n\
                       2374,456300.1,30.4,114.4,20.0,0.1,0.2,0.3,1.0,2.0,185.0,0.1,\n";
    const POS: &str = "% program   : somebody\n\
%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n\
2025/07/08 19:34:18.499 40.0966268 -105.1474483 1601.474 1 21 0.01 0.01 0.01 0 0 0 0 0\n";
    const POS_WEEK: &str =
        "2374 456300.0 40.0966268 -105.1474483 1601.474 1 21 0.01 0.01 0.01 0 0 0 0 0\n";
    const GNSS7: &str = "456250.000 30.44 114.47 21.096 0.010 0.009 0.019\n";
    const GNSS13: &str =
        "456250.000 30.44 114.47 21.096 0.010 0.009 0.019 1.0 2.0 0.1 0.02 0.02 0.03\n";

    #[test]
    fn each_format_is_detected_by_content() {
        for (name, text, want) in [
            ("a.txt", NAV, TrajFormat::Nav),
            ("a.nav", CSV, TrajFormat::Csv),
            ("a.csv", POS, TrajFormat::Pos),
            ("a.dat", POS_WEEK, TrajFormat::Pos),
            ("a.pos", GNSS7, TrajFormat::KfGinsGnss),
            ("b.nav", GNSS13, TrajFormat::KfGinsGnss),
            ("hdr.pos", "% program : x\n%\n", TrajFormat::Pos),
            ("c.nav", &format!("# a comment\n\n{NAV}"), TrajFormat::Nav),
            ("bom.txt", &format!("\u{feff}{CSV}"), TrajFormat::Csv),
            ("crlf.txt", &CSV.replace('\n', "\r\n"), TrajFormat::Csv),
        ] {
            let p = tmp(name, text);
            assert_eq!(detect_format(&p).unwrap(), want, "{name}");
        }
    }

    #[test]
    fn what_each_format_carries() {
        let nav = read_trajectory(&tmp("n.txt", NAV), None, &[]).unwrap();
        assert_eq!(nav.points.len(), 2);
        assert!(nav.points[0].rpy.is_some() && nav.points[0].v_n.is_some());
        let csv = read_trajectory(&tmp("c.txt", CSV), None, &[]).unwrap();
        let bom = read_trajectory(&tmp("bom.csv", &format!("\u{feff}{CSV}")), None, &[]);
        assert_eq!(bom.unwrap().points, csv.points);
        assert_eq!((csv.week, csv.points.len()), (2374, 2));
        // The same values as the .nav (the week aside).
        assert_eq!(csv.points[1].lla, nav.points[1].lla);
        assert_eq!(csv.points[1].rpy, nav.points[1].rpy);
        let pos = read_trajectory(&tmp("p.txt", POS), None, &[]).unwrap();
        assert_eq!(pos.week, 2374);
        assert!(pos.points[0].rpy.is_none() && pos.points[0].v_n.is_none());
        let g7 = read_trajectory(&tmp("g7.pos", GNSS7), None, &[]).unwrap();
        assert_eq!((g7.format, g7.week), (TrajFormat::KfGinsGnss, 0));
        assert!(g7.points[0].rpy.is_none() && g7.points[0].v_n.is_none());
        let g13 = read_trajectory(&tmp("g13.txt", GNSS13), None, &[]).unwrap();
        assert!(g13.points[0].rpy.is_none() && g13.points[0].v_n.is_some());
        // An override reads the file as told (and its reader explains a mismatch).
        let e = read_trajectory(&tmp("n2.txt", NAV), Some(TrajFormat::KfGinsGnss), &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("n2.txt:1") && e.contains("7 or 13"), "{e}");
    }

    #[test]
    fn detection_errors_name_file_line_and_formats() {
        let p = tmp("five.txt", "# x\n1 2 3 4 5\n");
        let e = detect_format(&p).unwrap_err().to_string();
        assert!(e.contains("five.txt:2: 5 columns; expected 11 (KF-GINS .nav), 7 or 13 (KF-GINS GNSS), a navfuse CSV header"), "{e}");
        assert!(e.contains("RTKLIB .pos"), "{e}");
        let p = tmp("sep.csv", "gps_week,gps_sow,d_north_m\n2374,1,2\n");
        let e = detect_format(&p).unwrap_err().to_string();
        assert!(e.contains("sep.csv:1: found \"gps_week,gps_sow,d_north_m\", not a number or a known header; expected 11"), "{e}");
        let p = tmp("empty.txt", "\n# nothing\n");
        let e = detect_format(&p).unwrap_err().to_string();
        assert!(e.contains("empty.txt: no data line; expected 11"), "{e}");
        let e = detect_format(Path::new("/nonexistent/none.nav"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("none.nav: cannot open"), "{e}");
        // The CSV reader wants its header.
        let e = read_solution_csv(&tmp("nohdr.csv", NAV))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("nohdr.csv:1: expected the navfuse CSV header"),
            "{e}"
        );
        assert_eq!(TrajFormat::parse("auto"), Ok(None));
        assert_eq!(
            TrajFormat::parse("KFGINS-GNSS"),
            Ok(Some(TrajFormat::KfGinsGnss))
        );
        assert!(TrajFormat::parse("kml")
            .unwrap_err()
            .contains("kfgins-gnss"));
    }
}
