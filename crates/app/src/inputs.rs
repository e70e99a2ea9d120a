//! Reading a run's inputs (IMU reader, GNSS fixes or raw epochs, odometer, dual-antenna
//! heading) and putting the GNSS times on the IMU's GPS week.

use crate::checks::check;
use crate::error::Error;
use crate::plausibility::Finding;
use crate::summary::JobResult;
use navfuse_core::{GnssFix, GnssRawEpoch, HeadingObs, OdometerSample};
use navfuse_io::config::RunConfig;
use navfuse_io::gnss::read_gnss;
use navfuse_io::heading::read_heading_report;
use navfuse_io::imu::{open_imu, ImuReader};
use navfuse_io::input::{Coupling, GnssFormat, GnssSource, UbxGnss};
use navfuse_io::odometer::read_odometer_report;

/// Seconds in a GPS week.
pub(crate) use navfuse_core::time::{split_week, SECONDS_PER_WEEK as WEEK_S};

/// A run's inputs, read; GNSS and heading times on the IMU's week.
pub(crate) struct Inputs {
    /// The IMU, not yet read.
    pub reader: ImuReader,
    pub imu_week: Option<u32>,
    pub gnss_week: Option<u32>,
    /// The week output times count from.
    pub week: u32,
    /// GNSS fixes (loose coupling).
    pub fixes: Vec<GnssFix>,
    /// Raw GNSS epochs (tight coupling).
    pub raw: Vec<GnssRawEpoch>,
    /// GNSS epochs left out by the quality filter / decimation.
    pub gnss_skipped: usize,
    pub odometer: Vec<OdometerSample>,
    pub heading: Vec<HeadingObs>,
    /// The other aiding inputs (IMU time scale), as measurements.
    pub other: Vec<navfuse_core::Measurement>,
}

/// Open the IMU and read the other inputs `cfg` names; input notes go to `job.notes`,
/// the readers' warnings to `job.findings` (printed when `warn`).
pub(crate) fn read(cfg: &RunConfig, job: &mut JobResult, warn: bool) -> Result<Inputs, Error> {
    let input_notes = &mut job.notes;
    let reader = open_imu(&cfg.imu)?;
    let imu_week = reader.gps_week();
    let mut raw: Vec<GnssRawEpoch> = Vec::new();
    let mut gnss_skipped = 0;
    // GNSS readers' findings that did not stop the read (a damaged last line
    // dropped); the IMU reader's come with its report after the run.
    let mut reader_warnings: Vec<String> = Vec::new();
    let (mut fixes, gnss_week): (Vec<GnssFix>, Option<u32>) = match &cfg.gnss {
        Some(
            src @ GnssSource {
                format: GnssFormat::Rinex(r) | GnssFormat::Ubx(UbxGnss::Raw(r)),
                ..
            },
        ) => {
            let g = match src.format {
                GnssFormat::Ubx(_) => crate::ubx_input::load_ubx(src, r, &cfg.nav.gnss.systems)?,
                _ => crate::gnss_input::load_rinex(src, r, &cfg.nav.gnss.systems)?,
            };
            input_notes.extend(g.notes);
            reader_warnings.extend(g.warnings);
            match r.coupling {
                Coupling::Loose => (g.fixes, Some(g.gps_week)),
                Coupling::Tight => {
                    raw = g.raw;
                    (Vec::new(), Some(g.gps_week))
                }
            }
        }
        Some(src) => {
            let g = read_gnss(src)?;
            reader_warnings.extend(g.warnings);
            gnss_skipped = g.skipped;
            if g.skipped > 0 {
                input_notes.push(format!(
                    "{}: {} epochs skipped (quality filter / decimation)",
                    src.path.display(),
                    g.skipped
                ));
            }
            (g.fixes, g.gps_week)
        }
        None => (Vec::new(), None),
    };
    // Odometer (IMU time scale) and dual-antenna heading (GNSS time scale).
    let odometer: Vec<OdometerSample> = match &cfg.odometer {
        Some(src) if cfg.nav.odometer.enabled => {
            let o = read_odometer_report(src, &mut reader_warnings)?;
            if o.is_empty() {
                input_notes.push(format!("{}: no odometer samples", src.path.display()));
            }
            o
        }
        _ => Vec::new(),
    };
    // The heading's week: an NMEA log's own (its dates), else the GNSS input's.
    let mut heading_week = gnss_week;
    let mut heading: Vec<HeadingObs> = match &cfg.heading {
        Some(src) if cfg.nav.heading.baseline_b.is_some() => {
            let h = match (&src.nmea, &src.ubx) {
                (None, Some(u)) => {
                    let log = navfuse_io::ubx::read_ubx(&src.path)?;
                    reader_warnings.extend(log.warnings.iter().cloned());
                    // iTOW of the log's own week (RAWX, else the NAV-PVT date).
                    let log_week = log.fix_week.and_then(|w| u32::try_from(w).ok());
                    heading_week = log_week.or(gnss_week);
                    navfuse_io::ubx::aiding::headings(&src.path, &log, *u, &mut reader_warnings)?
                }
                (None, None) => {
                    read_heading_report(&src.path, src.skip_lines, &mut reader_warnings)?
                }
                (Some(o), _) => {
                    let d = navfuse_io::nmea::read_nmea(&src.path, o)?;
                    reader_warnings.extend(d.warnings);
                    heading_week = d.gps_week.or(gnss_week);
                    d.heading
                }
            };
            if h.is_empty() {
                input_notes.push(format!("{}: no heading records", src.path.display()));
            }
            h
        }
        _ => Vec::new(),
    };
    let other = navfuse_io::input::read_aiding_inputs(cfg, &mut reader_warnings)?;
    check(
        job,
        warn,
        reader_warnings.into_iter().map(Finding::warning).collect(),
    )?;
    // Put GNSS times (fixes and heading) on the run's week reference: the IMU's, else
    // the GNSS input's.
    let week_ref = imu_week.or(gnss_week);
    let shift_s = |w: Option<u32>| match (week_ref, w) {
        (Some(r), Some(w)) => (w as f64 - r as f64) * WEEK_S,
        _ => 0.0,
    };
    let shift = shift_s(gnss_week);
    if shift != 0.0 {
        fixes.iter_mut().for_each(|f| f.t += shift);
        for e in raw.iter_mut() {
            e.t += shift;
            if let Some(f) = e.fix.as_mut() {
                f.t += shift;
            }
        }
    }
    let shift = shift_s(heading_week);
    if shift != 0.0 {
        heading.iter_mut().for_each(|h| h.t += shift);
    }
    Ok(Inputs {
        reader,
        imu_week,
        gnss_week,
        week: imu_week.or(gnss_week).unwrap_or(0),
        fixes,
        raw,
        gnss_skipped,
        odometer,
        heading,
        other,
    })
}
