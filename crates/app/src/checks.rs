//! The run's checks, around the plausibility functions (plausibility.rs): the
//! configuration and inputs before the run, the IMU window at the start of the data,
//! and the result after it. [`check`] records findings and turns their errors into
//! [`Error::Refused`].

use crate::error::Error;
use crate::plausibility::{self, Finding, Span};
use crate::summary::JobResult;
use nalgebra::Vector3;
use navfuse_core::config::{AttitudeInit, NhcMode};
use navfuse_core::earth::gravity_normal;
use navfuse_io::config::RunConfig;
use navfuse_io::imu::open_imu;
use navfuse_io::input::{AccelUnit, GyroUnit, ImuFormat};

/// Record the findings of a check (printing warnings and unreliable findings when
/// `warn`); its errors stop the run with their messages.
pub(crate) fn check(job: &mut JobResult, warn: bool, found: Vec<Finding>) -> Result<(), Error> {
    let mut errors = Vec::new();
    for f in found {
        if f.is_error() {
            errors.push(f.message.clone());
        } else if warn {
            eprintln!("navfuse: {f}");
        }
        job.findings.push(f);
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(Error::Refused(errors.join("; ")))
    }
}

/// Configuration and input checks before the run: lever arms, the time-offset prior,
/// the spoofing reference, an empty GNSS input, a start after the GNSS data.
pub(crate) fn before_run(
    cfg: &RunConfig,
    gnss_epochs: usize,
    gnss_skipped: usize,
    last_gnss_t: Option<f64>,
) -> Vec<Finding> {
    let mut found = plausibility::lever_arm("[gnss] lever_arm_m", &cfg.nav.gnss.lever_arm_b);
    found.extend(plausibility::lever_arm(
        "[vehicle] lever_arm_m",
        &cfg.nav.vehicle.lever_arm_b,
    ));
    if let Some(to) = cfg.nav.filter.time_offset {
        found.extend(plausibility::time_offset_prior(to.std_s));
    }
    found.extend(plausibility::spoofing_reference(
        cfg.nav.integrity.enabled,
        cfg.nav.odometer.enabled,
        cfg.nav.nhc.mode != NhcMode::Off,
    ));
    if let Some(g) = &cfg.gnss {
        found.extend(plausibility::gnss_not_empty(
            &g.path.display().to_string(),
            gnss_epochs,
            gnss_skipped,
        ));
        if let Some(t) = last_gnss_t {
            let what = format!("the GNSS file {}", g.path.display());
            found.extend(plausibility::start_before_end(cfg.nav.start_time, t, &what));
        }
    }
    found
}

/// What the run's result is checked against afterwards.
pub(crate) struct AfterRun<'a> {
    /// The IMU file's span (its last time from the reader's report).
    pub imu: Span,
    pub gnss: Option<&'a Span>,
    /// GNSS epoch times (fixes, or raw epochs with tight coupling).
    pub gnss_times: &'a [f64],
}

/// After the run: results the program can tell are meaningless, and suspicious fits.
pub(crate) fn after_run(cfg: &RunConfig, job: &JobResult, a: &AfterRun) -> Vec<Finding> {
    let (first_t, imu_last) = (a.imu.first, a.imu.last);
    let mut found = Vec::new();
    if let Some(g) = a.gnss {
        found.extend(plausibility::time_overlap(&a.imu, g));
    }
    if job.summary.imu_samples == 0 && found.is_empty() {
        let what = format!("the IMU file {}", cfg.imu.path.display());
        found.extend(plausibility::start_before_end(
            cfg.nav.start_time,
            imu_last,
            &what,
        ));
        if found.is_empty() {
            found.push(Finding::error(format!(
                "no IMU sample was navigated (IMU t {first_t:.3} .. {imu_last:.3}): the alignment found no start ([initial.alignment], [time] start)"
            )));
        }
    }
    if job.summary.imu_samples > 0 {
        let in_span = a
            .gnss_times
            .iter()
            .filter(|&&t| t >= first_t && t <= imu_last)
            .count();
        found.extend(plausibility::gnss_usage(&plausibility::GnssUse {
            in_span,
            used: job.summary.gnss_used,
            rejected: job.summary.gnss_rejected,
            in_outages: job.summary.gnss_in_outage,
            before_start: job.summary.gnss_before_start,
        }));
    }
    if let Some(f) = &job.time_offset {
        found.extend(plausibility::time_offset_fit(f.tau0, f.rate));
    }
    if let (Some(g), Some(&imu_last)) = (a.gnss, Some(&a.imu.last)) {
        if job.summary.imu_samples > 0 {
            found.extend(plausibility::imu_ends_early(
                imu_last,
                g.first,
                g.last,
                cfg.nav.end_time,
            ));
        }
    }
    for (source, stats) in &job.summary.innovation_stats {
        let nis = job.summary.aiding_nis.get(source);
        found.extend(plausibility::innovation_consistency(
            &plausibility::SourceInnovations {
                source,
                nis_per_row: nis.map(|(sum, rows)| sum / (*rows).max(1) as f64),
                applied: job.summary.aiding_used.get(source).copied().unwrap_or(0),
                stats,
                // The fix-error states are on the position only.
                correlated_model: *source == "gnss_position" && cfg.nav.gnss.fix_error.correlated(),
            },
        ));
    }
    let land = cfg.nav.nhc.mode != NhcMode::Off || cfg.nav.odometer.enabled;
    for e in &job.summary.events {
        if let navfuse_core::Event::Aligned {
            rpy_deg, method, ..
        } = e
        {
            found.extend(plausibility::aligned_tilt(*rpy_deg, land));
            found.extend(plausibility::aligned_yaw_unknown(method));
        }
    }
    found
}

/// The IMU window at the start of the data against gravity, Earth rate and the
/// configured bias bounds; `fix_lla` (the first GNSS fix) gives the local gravity when
/// the configuration has no initial position.
pub(crate) fn imu_window(cfg: &RunConfig, fix_lla: Option<Vector3<f64>>) -> Vec<Finding> {
    let (len, static_start) = match cfg.nav.initial.attitude {
        AttitudeInit::LevelAndGnssCourse { level_window_s, .. }
        | AttitudeInit::StaticGyrocompass { level_window_s } => (level_window_s, true),
        AttitudeInit::Auto { level_window_s, .. } => (level_window_s, false),
        _ => (plausibility::DEFAULT_IMU_WINDOW_S, false),
    };
    let Ok(reader) = open_imu(&cfg.imu) else {
        return Vec::new();
    };
    let start = cfg.nav.start_time;
    let mut samples = Vec::new();
    let mut t0 = None;
    for s in reader {
        // Reading errors are reported by the run itself.
        let Ok(s) = s else { break };
        if s.t < start {
            continue;
        }
        let t0 = *t0.get_or_insert(s.t);
        if s.t > t0 + len {
            break;
        }
        samples.push(s);
    }
    let Some(w) = plausibility::imu_window(&samples) else {
        return Vec::new();
    };
    // Several CSV files have the units of one.
    let joined;
    let format = match &cfg.imu.format {
        ImuFormat::CsvFiles(f) => {
            joined = ImuFormat::Csv(f.csv.clone());
            &joined
        }
        f => f,
    };
    let units = match format {
        ImuFormat::Csv(o) => plausibility::ImuUnits {
            accel_scale: match o.accel_unit {
                AccelUnit::G => navfuse_io::imu::STANDARD_GRAVITY,
                AccelUnit::Metre => 1.0,
            },
            gyro_scale: match o.gyro_unit {
                GyroUnit::Deg => 1f64.to_radians(),
                GyroUnit::Rad => 1.0,
            },
            csv: true,
        },
        ImuFormat::KfGins | ImuFormat::Ulog { .. } | ImuFormat::Ubx => plausibility::ImuUnits {
            accel_scale: 1.0,
            gyro_scale: 1.0,
            csv: false,
        },
        ImuFormat::RtklibExplorer(_) | ImuFormat::CsvFiles(_) => plausibility::ImuUnits {
            accel_scale: navfuse_io::imu::STANDARD_GRAVITY,
            gyro_scale: 1f64.to_radians(),
            csv: false,
        },
    };
    let lla = cfg.nav.initial.lla.or(fix_lla);
    let gravity = lla.map_or(navfuse_io::imu::STANDARD_GRAVITY, |p| {
        gravity_normal(p.x, p.z)
    });
    let init = &cfg.nav.initial;
    let bias_bound = init.imu_errors.gyro_bias.norm() + 3.0 * init.imu_errors_std.gyro_bias.norm();
    plausibility::imu_magnitudes(&w, &units, gravity, bias_bound, static_start)
}

/// After smoothing: a separation report flagging many epochs means the filter's
/// covariance does not cover its errors (a warning, the solutions are kept).
pub(crate) fn after_smoothing(cfg: &RunConfig, rep: &crate::SmootherReport) -> Vec<Finding> {
    let rows = rep.separation_rows.max(1) as f64;
    let share = rep.separation_flagged as f64 / rows;
    if rep.separation_rows >= 10 && share > 0.2 {
        let k = cfg.smoother.separation_sigma;
        vec![Finding::warning(format!(
            "smoothing: {} of {} separation rows ({:.0} %) differ by more than {k} sigma (largest {:.0} sigma): the filter's covariance does not cover its errors (see separation.csv); check the other warnings, then the [imu_noise] values",
            rep.separation_flagged,
            rep.separation_rows,
            100.0 * share,
            rep.separation_max_ratio
        ))]
    } else {
        Vec::new()
    }
}
