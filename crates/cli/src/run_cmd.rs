//! `navfuse run`: read the inputs a configuration names, run the navigator, write the
//! solution files. The engine (time loop) is `navfuse_core::run`; this file only
//! wires files to it.

use crate::plausibility::{self, Finding, Span};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::Vector3;
use navfuse_core::config::{AttitudeInit, NhcMode, TimeOffsetConfig};
use navfuse_core::earth::gravity_normal;
use navfuse_core::outage::OutageSchedule;
use navfuse_core::{GnssFix, GnssRawEpoch, HeadingObs, Navigator, OdometerSample, RunSummary};
use navfuse_io::config::{self, RunConfig};
use navfuse_io::gnss::read_gnss;
use navfuse_io::heading::read_heading_report;
use navfuse_io::imu::open_imu;
use navfuse_io::input::{AccelUnit, Coupling, GnssFormat, GnssSource, GyroUnit, ImuFormat};
use navfuse_io::nav::{
    CsvWriter, ImuErrWriter, NavWriter, RecordWriter, SolutionRecord, StdWriter,
};
use navfuse_io::odometer::read_odometer_report;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

const WEEK_S: f64 = 604_800.0;

pub fn main(
    config: Option<PathBuf>,
    kf_gins: Option<PathBuf>,
    out: Option<PathBuf>,
    outages: Option<String>,
    quiet: bool,
) -> Result<()> {
    let path = kf_gins
        .as_ref()
        .or(config.as_ref())
        .context("no configuration given")?;
    let mut cfg = if kf_gins.is_some() {
        config::load_kfgins_yaml(path)
    } else {
        config::load(path)
    }
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    for w in &cfg.warnings {
        eprintln!("navfuse: warning: {w}");
    }
    if let Some(spec) = outages {
        let extra = OutageSchedule::parse(&spec).map_err(|e| anyhow::anyhow!("--outages: {e}"))?;
        cfg.nav.gnss.outages.windows.extend(extra.windows);
        cfg.nav.gnss.outages.periodic.extend(extra.periodic);
    }
    let out_dir = out
        .or_else(|| cfg.kfgins_output_path.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    install_signal_handlers().context("cannot install the SIGINT/SIGTERM handlers")?;
    let job = run_job_opts(cfg, &out_dir, !quiet, true)?;
    if !quiet {
        eprintln!("{}", job.summary_line());
    }
    Ok(())
}

/// The GNSS-IMU time offset line found by the estimation pass.
#[derive(Clone, Copy, Debug)]
pub struct TimeOffsetFit {
    pub tau0: f64,
    pub tau0_sd: f64,
    pub rate: f64,
    pub rate_sd: f64,
    pub t0: f64,
}

/// What a finished run reports.
pub struct JobResult {
    pub summary: RunSummary,
    pub wall: Duration,
    pub files: Vec<PathBuf>,
    /// GNSS epochs read: fixes (loose) or raw epochs (tight).
    pub gnss_fixes: usize,
    /// Odometer samples and heading records read (0 when not configured).
    pub odometer_samples: usize,
    pub heading_records: usize,
    pub time_offset: Option<TimeOffsetFit>,
    /// How the run ended: "completed", "failed" or "interrupted" (summary.json).
    pub status: &'static str,
    /// Why it failed or stopped.
    pub error: Option<String>,
    /// Plausibility warnings and errors (plausibility.rs).
    pub findings: Vec<Finding>,
    /// Input facts (events.log `# input:` lines).
    pub notes: Vec<String>,
    /// The last output epoch written [s, GNSS time scale].
    pub last_output_t: Option<f64>,
    /// Write integrity.csv (the monitor ran).
    integrity_table: bool,
}

impl JobResult {
    fn empty() -> Self {
        JobResult {
            summary: RunSummary::default(),
            wall: Duration::ZERO,
            files: Vec::new(),
            gnss_fixes: 0,
            odometer_samples: 0,
            heading_records: 0,
            time_offset: None,
            status: "running",
            error: None,
            findings: Vec::new(),
            notes: Vec::new(),
            last_output_t: None,
            integrity_table: false,
        }
    }

    /// The run summary as JSON (written to DIR/summary.json).
    pub fn to_json(&self) -> serde_json::Value {
        let s = &self.summary;
        let with = |sev| {
            self.findings
                .iter()
                .filter(|f| f.severity == sev)
                .map(|f| f.message.clone())
                .collect::<Vec<_>>()
        };
        serde_json::json!({
            "status": self.status,
            "error": self.error,
            "warnings": with(plausibility::Severity::Warning),
            "errors": with(plausibility::Severity::Error),
            "last_output_t": self.last_output_t,
            "imu_samples": s.imu_samples,
            "t_first": s.first_t,
            "t_last": s.last_t,
            "wall_s": self.wall.as_secs_f64(),
            "outputs": s.outputs,
            "gnss": {
                "fixes": self.gnss_fixes,
                "used": s.gnss_used,
                "rejected": s.gnss_rejected,
                "in_outages": s.gnss_in_outage,
                "before_start": s.gnss_before_start,
            },
            "time_offset": self.time_offset.map(|f| serde_json::json!({
                "offset_s_at_start": f.tau0,
                "offset_sigma_s_at_end": f.tau0_sd,
                "rate_ppm": f.rate * 1e6,
                "rate_sigma_ppm": f.rate_sd * 1e6,
                "t_start": f.t0,
            })),
            "odometer_samples": self.odometer_samples,
            "heading_records": self.heading_records,
            "aiding_used": s.aiding_used,
            "aiding_rejected": s.aiding_rejected,
            "nis_per_row": s.aiding_nis.iter().map(|(k, (sum, rows))| (*k, sum / (*rows).max(1) as f64)).collect::<std::collections::BTreeMap<_, _>>(),
            "static_s": s.static_s,
            "odometer_scale": s.odometer_scale.map(|(k, sd)| serde_json::json!({
                "k_ppm": k * 1e6,
                "sd_ppm": sd * 1e6,
            })),
            "mounting": s.mounting.map(|(rpy, sd)| serde_json::json!({
                "roll_deg": rpy.x.to_degrees(),
                "pitch_deg": rpy.y.to_degrees(),
                "yaw_deg": rpy.z.to_degrees(),
                "sd_pitch_deg": sd[0].to_degrees(),
                "sd_yaw_deg": sd[1].to_degrees(),
            })),
            "events": s.events.iter().map(|e| e.to_string()).collect::<Vec<_>>(),
            "files": self.files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        })
    }

    pub fn summary_line(&self) -> String {
        let s = &self.summary;
        let span = (s.last_t - s.first_t).max(0.0);
        let speed = if self.wall.as_secs_f64() > 0.0 {
            span / self.wall.as_secs_f64()
        } else {
            0.0
        };
        let mut line = format!(
            "navfuse: {} IMU samples, t {:.3} .. {:.3} ({:.1} s of data) in {:.2} s ({:.0}x real time); GNSS {} of {} used, {} rejected, {} in outages",
            s.imu_samples, s.first_t, s.last_t, span, self.wall.as_secs_f64(), speed,
            s.gnss_used, self.gnss_fixes, s.gnss_rejected, s.gnss_in_outage
        );
        // Aiding other than GNSS position/velocity (counted above): used/rejected.
        let aiding: Vec<String> = s
            .aiding_used
            .keys()
            .chain(s.aiding_rejected.keys())
            .filter(|k| !k.starts_with("gnss_"))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .map(|k| {
                let used = s.aiding_used.get(k).copied().unwrap_or(0);
                match s.aiding_rejected.get(k).copied().unwrap_or(0) {
                    0 => format!("{k} {used}"),
                    r => format!("{k} {used} ({r} rejected)"),
                }
            })
            .collect();
        if !aiding.is_empty() {
            line.push_str(&format!("; aiding {}", aiding.join(", ")));
        }
        if let Some(f) = &self.time_offset {
            line.push_str(&format!(
                "; GNSS-IMU time offset {:.4} s at t {:.1} (1-sigma {:.4}), rate {:.1} ppm (1-sigma {:.1}), estimated in a first pass; output times are GNSS time",
                f.tau0, f.t0, f.tau0_sd, f.rate * 1e6, f.rate_sd * 1e6
            ));
        }
        let names: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
        line.push_str(&format!("; wrote {}", names.join(", ")));
        line
    }
}

/// Run one configuration, writing into `out_dir` (warnings printed when `progress`).
pub fn run_job(cfg: RunConfig, out_dir: &Path, progress: bool) -> Result<JobResult> {
    run_job_opts(cfg, out_dir, progress, progress)
}

/// [`run_job`], printing the plausibility warnings when `warn`. Whatever happens once
/// the output directory exists, `events.log` and `summary.json` are written there
/// and say how the run ended (`status`: completed, failed or interrupted) and why.
pub fn run_job_opts(
    cfg: RunConfig,
    out_dir: &Path,
    progress: bool,
    warn: bool,
) -> Result<JobResult> {
    let t_wall = Instant::now();
    // Leftovers of an earlier run in the same directory must not sit beside this one's.
    for stale in ["events.log", "summary.json", "integrity.csv"] {
        let _ = std::fs::remove_file(out_dir.join(stale));
    }
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("cannot create output directory {}", out_dir.display()))?;
    let sum_path = out_dir.join("summary.json");
    reserve_summary(&sum_path).with_context(|| format!("cannot write {}", sum_path.display()))?;
    let mut job = JobResult::empty();
    let outcome = navigate(cfg, out_dir, progress, warn, &mut job);
    job.wall = t_wall.elapsed();
    job.status = match &outcome {
        Ok(()) => "completed",
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => "interrupted",
        Err(_) => "failed",
    };
    if let Err(e) = &outcome {
        job.error = Some(format!("{e:#}"));
    }
    let reports = write_reports(out_dir, &mut job, progress);
    match (outcome, reports) {
        (Ok(()), Ok(())) => Ok(job),
        (Err(_), Err(e)) if job.status != "interrupted" => Err(anyhow::anyhow!(
            "{}; and then: {e:#}",
            job.error.as_deref().unwrap_or_default()
        )),
        (Err(e), Err(r)) => {
            eprintln!("navfuse: error: {r:#}");
            Err(e)
        }
        (Err(e), Ok(())) => Err(e),
        (Ok(()), Err(e)) => Err(e),
    }
}

/// Record the findings of a check (printing warnings when `warn`); its errors stop
/// the run with their messages.
fn check(job: &mut JobResult, warn: bool, found: Vec<Finding>) -> Result<()> {
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
        Err(anyhow::anyhow!("{}", errors.join("; ")))
    }
}

/// Read, check, navigate, write the solution files; fills `job` as it goes.
fn navigate(
    mut cfg: RunConfig,
    out_dir: &Path,
    progress: bool,
    warn: bool,
    job: &mut JobResult,
) -> Result<()> {
    let input_notes = &mut job.notes;
    let mut reader = open_imu(&cfg.imu).map_err(|e| anyhow::anyhow!("{e}"))?;
    let imu_week = reader.gps_week();
    let mut time_offset_pass1 = None;
    let mut raw: Vec<GnssRawEpoch> = Vec::new();
    let mut gnss_skipped = 0;
    // GNSS readers' findings that did not stop the read (a damaged last line
    // dropped); the IMU reader's come with its report after the run.
    let mut reader_warnings: Vec<String> = Vec::new();
    let (mut fixes, gnss_week): (Vec<GnssFix>, Option<u32>) = match &cfg.gnss {
        Some(
            src @ GnssSource {
                format: GnssFormat::Rinex(r),
                ..
            },
        ) => {
            let g = crate::gnss_input::load_rinex(src, r)?;
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
            let g = read_gnss(src).map_err(|e| anyhow::anyhow!("{e}"))?;
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
            let o = read_odometer_report(src, &mut reader_warnings)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            if o.is_empty() {
                input_notes.push(format!("{}: no odometer samples", src.path.display()));
            }
            o
        }
        _ => Vec::new(),
    };
    let mut heading: Vec<HeadingObs> = match &cfg.heading {
        Some(src) if cfg.nav.heading.baseline_b.is_some() => {
            let h = read_heading_report(&src.path, &mut reader_warnings)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            if h.is_empty() {
                input_notes.push(format!("{}: no heading records", src.path.display()));
            }
            h
        }
        _ => Vec::new(),
    };
    check(
        job,
        warn,
        reader_warnings.into_iter().map(Finding::warning).collect(),
    )?;
    // Put GNSS times (fixes and heading) on the IMU's week reference.
    if let (Some(wi), Some(wg)) = (imu_week, gnss_week) {
        let shift = (wg as f64 - wi as f64) * WEEK_S;
        if shift != 0.0 {
            fixes.iter_mut().for_each(|f| f.t += shift);
            heading.iter_mut().for_each(|h| h.t += shift);
            for e in raw.iter_mut() {
                e.t += shift;
                if let Some(f) = e.fix.as_mut() {
                    f.t += shift;
                }
            }
        }
    }
    let week = imu_week.or(gnss_week).unwrap_or(0);
    // GNSS epoch times (fixes, or raw epochs with tight coupling).
    let gnss_times: Vec<f64> = fixes
        .iter()
        .map(|f| f.t)
        .chain(raw.iter().map(|e| e.t))
        .collect();
    let last_gnss_t = gnss_times.last().copied();
    let gnss_span = match (&cfg.gnss, gnss_times.first(), gnss_times.last()) {
        (Some(g), Some(&first), Some(&last)) => Some(Span {
            file: g.path.display().to_string(),
            first,
            last,
            week: gnss_week,
        }),
        _ => None,
    };
    // GNSS epochs offered to the navigator: fixes, or raw epochs (tight coupling).
    let gnss_epochs = fixes.len() + raw.len();
    job.gnss_fixes = gnss_epochs;
    job.odometer_samples = odometer.len();
    job.heading_records = heading.len();
    // Configuration and input checks before the run.
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
        cfg.nav.nhc.mode != navfuse_core::config::NhcMode::Off,
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
    check(job, warn, found)?;
    let measurements = navfuse_core::merge_raw_epochs(
        navfuse_core::merge_measurements(&fixes, &odometer, &heading),
        raw,
    );

    let first = match reader.next() {
        Some(Ok(s)) => s,
        Some(Err(e)) => anyhow::bail!("{e}"),
        None => anyhow::bail!(
            "{}: no IMU samples: the file is empty or holds only headers/comments (check [imu] file and [imu.csv] skip_lines)",
            cfg.imu.path.display()
        ),
    };
    let first_t = first.t;
    let imu_file = cfg.imu.path.display().to_string();
    let imu_span = |last: f64| Span {
        file: imu_file.clone(),
        first: first_t,
        last,
        week: imu_week,
    };
    if let Some(g) = &gnss_span {
        check(
            job,
            warn,
            plausibility::time_overlap(&imu_span(f64::INFINITY), &g),
        )?;
    }
    let found = imu_window_check(&cfg, fixes.first().map(|f| f.lla))?;
    check(job, warn, found)?;
    let run_start = if cfg.nav.start_time.is_finite() {
        cfg.nav.start_time.max(first_t)
    } else {
        first_t
    };
    cfg.resolve_relative_outages(run_start);

    // GNSS-IMU time offset: pass 1 estimates offset and rate as filter states; pass 2
    // navigates with the resulting line tau(t) = tau0 + rate (t - t0) held fixed, so that
    // solution time tags (on the GNSS time scale) stay monotonic.
    if let Some(to) = cfg.nav.filter.time_offset {
        if to.std_s > 0.0 {
            let fit = time_offset_pass(&cfg, &measurements, to)?;
            if let Some(f) = fit {
                // An implausible fit: would the offset of GPS time against UTC fit?
                if !plausibility::time_offset_fit(f.tau0, f.rate).is_empty() {
                    let leap = plausibility::leap_seconds(gnss_week);
                    for cand in [leap, -leap] {
                        let start = TimeOffsetConfig {
                            initial_s: cand,
                            ..to
                        };
                        if let Some(g) = time_offset_pass(&cfg, &measurements, start)? {
                            let found = plausibility::leap_second_fit(f.tau0, g.tau0, g.rate);
                            if !found.is_empty() {
                                check(job, warn, found)?;
                                break;
                            }
                        }
                    }
                }
                cfg.nav.filter.time_offset = Some(TimeOffsetConfig {
                    initial_s: f.tau0,
                    std_s: 0.0,
                    random_walk: 0.0,
                    initial_rate: f.rate,
                    rate_std: 0.0,
                });
            }
            time_offset_pass1 = fit;
        }
    }
    job.time_offset = time_offset_pass1;

    let files = &mut job.files;
    files.push(out_dir.join("solution.nav"));
    let mut writers: Vec<Box<dyn RecordWriter>> = vec![Box::new(
        NavWriter::create(&files[0]).map_err(|e| anyhow::anyhow!("{e}"))?,
    )];
    if cfg.output.imu_err {
        files.push(out_dir.join("imu_err.txt"));
        let w = ImuErrWriter::create(files.last().unwrap());
        writers.push(Box::new(w.map_err(|e| anyhow::anyhow!("{e}"))?));
    }
    if cfg.output.std {
        files.push(out_dir.join("std.txt"));
        let w = StdWriter::create(files.last().unwrap());
        writers.push(Box::new(w.map_err(|e| anyhow::anyhow!("{e}"))?));
    }
    // With the integrity monitor, solution.csv carries its flag column.
    let monitor_on = cfg.nav.integrity.enabled;
    job.integrity_table = monitor_on;
    if cfg.output.csv || monitor_on {
        files.push(out_dir.join("solution.csv"));
        let w = CsvWriter::create(files.last().unwrap(), cfg.output.std, monitor_on);
        writers.push(Box::new(w.map_err(|e| anyhow::anyhow!("{e}"))?));
    }

    let t_end = cfg.nav.end_time.or(last_gnss_t).unwrap_or(run_start);
    let bar = if progress && t_end > run_start {
        let b = ProgressBar::new(((t_end - run_start) * 10.0) as u64);
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    };

    // Records go to a writer thread in batches: formatting text costs about as much
    // as navigating, and the machine has two cores. Every batch is handed to the
    // files, so that after a crash, a full disk or a signal they end within a batch
    // of each other (or, when the run stops cleanly, at the same epoch).
    let want_std = cfg.output.std;
    let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<SolutionRecord>>(8);
    let writer = std::thread::spawn(move || -> Result<()> {
        let mut failed = None;
        'batches: for batch in rx {
            for rec in &batch {
                for w in writers.iter_mut() {
                    if let Err(e) = w.write_record(rec) {
                        failed = Some(e);
                        break 'batches;
                    }
                }
            }
            for w in writers.iter_mut() {
                if let Err(e) = w.flush() {
                    failed = Some(e);
                    break 'batches;
                }
            }
        }
        // Whatever happened, keep what was computed: flush every writer.
        for w in writers {
            if let Err(e) = w.finish_boxed() {
                failed.get_or_insert(e);
            }
        }
        failed.map_or(Ok(()), |e| Err(anyhow::anyhow!("{e}")))
    });
    const BATCH: usize = 2048;
    let mut batch: Vec<SolutionRecord> = Vec::with_capacity(BATCH);
    let send = |batch: &mut Vec<SolutionRecord>| -> Result<()> {
        let full = std::mem::replace(batch, Vec::with_capacity(BATCH));
        tx.send(full)
            .map_err(|_| anyhow::anyhow!("the output writer stopped"))
    };
    // A signal stops the run at the next output epoch (the records so far are all
    // written), or before the first one at the next IMU sample.
    let started = std::cell::Cell::new(false);
    let mut stopped: Option<RunSummary> = None;
    let mut last_out_t = None;
    let result = navfuse_core::run(
        &cfg.nav,
        std::iter::once(Ok(first)).chain(reader.by_ref().map(|r| {
            let r = r.map_err(|e| anyhow::anyhow!("{e}"));
            if started.get() {
                r
            } else {
                stop_on_signal(r)
            }
        })),
        &measurements,
        cfg.output.rate_hz.map(|r| 1.0 / r),
        |n: &Navigator| {
            started.set(true);
            if let Some(signal) = interrupted() {
                stopped = Some(n.summary().clone());
                return Err(Interrupted {
                    signal,
                    t: last_out_t,
                }
                .into());
            }
            let nav = *n.nav();
            let (wk, t) = split_week(week, n.time_gnss());
            batch.push(SolutionRecord {
                gps_week: wk,
                nav: navfuse_core::NavState { t, ..nav },
                imu_errors: *n.imu_errors(),
                std: if want_std { Some(n.std21()) } else { None },
                gnss_integrity: monitor_on.then(|| n.integrity_state().flag()),
            });
            last_out_t = Some(n.time_gnss());
            if batch.len() == BATCH {
                if let Err(e) = send(&mut batch) {
                    stopped = Some(n.summary().clone());
                    return Err(e);
                }
            }
            Ok(())
        },
        |t| {
            if let Some(b) = &bar {
                b.set_position(((t - run_start) * 10.0).max(0.0) as u64);
                b.set_message(format!("t = {t:.1}"));
            }
        },
    );
    let sent = if batch.is_empty() {
        Ok(())
    } else {
        send(&mut batch)
    };

    drop(tx);
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let written = writer
        .join()
        .map_err(|_| anyhow::anyhow!("the output writer panicked"))?;
    let report = reader.report().clone();
    if !report.to_string().is_empty() {
        job.notes.push(report.to_string());
    }
    if let Some(s) = stopped {
        job.summary = s;
        job.summary.outputs -= 1;
    }
    job.last_output_t = last_out_t;
    // A failed writer (disk full, ...) is the real cause when the run stopped on it.
    written.with_context(|| {
        format!(
            "writing the solution into {} (the files hold whole records up to where writing stopped)",
            out_dir.display()
        )
    })?;
    sent?;
    job.summary = result.map_err(|e| match e.downcast::<Interrupted>() {
        Ok(i) => i.into(),
        Err(e) => e.context(format!(
            "run stopped; the output up to the failure is in {}",
            out_dir.display()
        )),
    })?;
    // After the run: results the program can tell are meaningless, and suspicious fits.
    let imu_last = report.last_t.unwrap_or(first_t);
    let mut found = Vec::new();
    if let Some(g) = &gnss_span {
        found.extend(plausibility::time_overlap(&imu_span(imu_last), &g));
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
        let in_span = gnss_times
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
    if let Some((sum, rows)) = job.summary.aiding_nis.get("gnss_position") {
        found.extend(plausibility::fix_agreement(sum / (*rows).max(1) as f64));
    }
    let land = cfg.nav.nhc.mode != NhcMode::Off || cfg.nav.odometer.enabled;
    for e in &job.summary.events {
        if let navfuse_core::Event::Aligned { rpy_deg, .. } = e {
            found.extend(plausibility::aligned_tilt(*rpy_deg, land));
        }
    }
    check(job, warn, found).with_context(|| {
        format!(
            "the run's result is meaningless (its output is kept in {})",
            out_dir.display()
        )
    })?;
    if progress {
        for n in &job.notes {
            eprintln!("navfuse: note: {n}");
        }
        let rej = job
            .summary
            .events
            .iter()
            .filter(|e| matches!(e, navfuse_core::Event::Rejected { .. }))
            .count();
        if rej > 0 {
            eprintln!(
                "navfuse: {rej} GNSS/heading measurements rejected by the innovation gate (see events.log)"
            );
        }
    }
    Ok(())
}

/// The time-offset estimation pass from the prior `to`: the fitted line, or None when
/// the run had no time-offset state.
fn time_offset_pass(
    cfg: &RunConfig,
    measurements: &[navfuse_core::Measurement],
    to: TimeOffsetConfig,
) -> Result<Option<TimeOffsetFit>> {
    let mut nav = cfg.nav.clone();
    nav.filter.time_offset = Some(to);
    let reader = open_imu(&cfg.imu).map_err(|e| anyhow::anyhow!("{e}"))?;
    let s1 = navfuse_core::run(
        &nav,
        reader.map(|r| stop_on_signal(r.map_err(|e| anyhow::anyhow!("{e}")))),
        measurements,
        Some(f64::INFINITY),
        |_| Ok(()),
        |_| {},
    )
    .context("time-offset estimation pass")?;
    Ok(s1.time_offset.map(|(tau_end, sd)| {
        let (rate, rate_sd) = s1.time_offset_rate.unwrap_or((to.initial_rate, 0.0));
        TimeOffsetFit {
            tau0: tau_end - rate * (s1.last_t - s1.first_t),
            tau0_sd: sd,
            rate,
            rate_sd,
            t0: s1.first_t,
        }
    }))
}

/// The IMU window at the start of the data against gravity, Earth rate and the
/// configured bias bounds; `fix_lla` (the first GNSS fix) gives the local gravity when
/// the configuration has no initial position.
fn imu_window_check(cfg: &RunConfig, fix_lla: Option<Vector3<f64>>) -> Result<Vec<Finding>> {
    let (len, static_start) = match cfg.nav.initial.attitude {
        AttitudeInit::LevelAndGnssCourse { level_window_s, .. }
        | AttitudeInit::StaticGyrocompass { level_window_s } => (level_window_s, true),
        AttitudeInit::Auto { level_window_s, .. } => (level_window_s, false),
        _ => (plausibility::DEFAULT_IMU_WINDOW_S, false),
    };
    let Ok(reader) = open_imu(&cfg.imu) else {
        return Ok(Vec::new());
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
        return Ok(Vec::new());
    };
    let units = match &cfg.imu.format {
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
        ImuFormat::KfGins => plausibility::ImuUnits {
            accel_scale: 1.0,
            gyro_scale: 1.0,
            csv: false,
        },
        ImuFormat::RtklibExplorer(_) => plausibility::ImuUnits {
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
    Ok(plausibility::imu_magnitudes(
        &w,
        &units,
        gravity,
        bias_bound,
        static_start,
    ))
}

/// Write `events.log` (input notes, findings, the run's events, how it ended),
/// `integrity.csv` (with the monitor) and `summary.json`, and list them in `job.files`.
fn write_reports(out_dir: &Path, job: &mut JobResult, progress: bool) -> Result<()> {
    let ev_path = out_dir.join("events.log");
    let mut text = String::new();
    for n in &job.notes {
        text.push_str(&format!("# input: {n}\n"));
    }
    // Errors are in the last line (how the run ended).
    for f in job.findings.iter().filter(|f| !f.is_error()) {
        text.push_str(&format!("# {f}\n"));
    }
    for e in &job.summary.events {
        text.push_str(&format!("{e}\n"));
    }
    if let Some(e) = &job.error {
        text.push_str(&format!("# {}: {e}\n", job.status));
    }
    let ev = std::fs::write(&ev_path, text)
        .with_context(|| format!("cannot write {}", ev_path.display()));
    if ev.is_ok() {
        job.files.push(ev_path);
    }
    if job.integrity_table && job.status != "failed" {
        let p = out_dir.join("integrity.csv");
        let mut t = String::from("t_s,from,to,detector,statistic,threshold\n");
        let mut spoofed = 0;
        for e in &job.summary.events {
            if let navfuse_core::Event::Integrity(tr) = e {
                spoofed += usize::from(tr.to == navfuse_core::integrity::IntegrityState::Spoofed);
                t.push_str(&format!(
                    "{:.3},{},{},{},{:.4},{}\n",
                    tr.t,
                    tr.from.name(),
                    tr.to.name(),
                    tr.detector.name(),
                    tr.statistic,
                    if tr.threshold.is_finite() {
                        format!("{:.4}", tr.threshold)
                    } else {
                        String::new()
                    }
                ));
            }
        }
        std::fs::write(&p, t).with_context(|| format!("cannot write {}", p.display()))?;
        job.files.push(p);
        if progress && spoofed > 0 {
            eprintln!(
                "navfuse: GNSS integrity: declared spoofed {spoofed} time(s) (see integrity.csv)"
            );
        }
    }
    let sum_path = out_dir.join("summary.json");
    job.files.push(sum_path.clone());
    let full = serde_json::to_string_pretty(&job.to_json())? + "\n";
    if let Err(e) = write_reserved(&sum_path, &full) {
        // A full disk: the events list (also in events.log) may be what does not fit.
        let mut short = job.to_json();
        short["events"] = serde_json::json!(["(left out: the disk is full; see events.log)"]);
        write_reserved(&sum_path, &(serde_json::to_string_pretty(&short)? + "\n"))
            .map_err(|_| e)
            .with_context(|| format!("cannot write {}", sum_path.display()))?;
    }
    ev
}

/// Space kept for summary.json from the start of a run, so that a run that fills the
/// disk can still say so.
const SUMMARY_RESERVE: usize = 16 << 10;

/// Write a placeholder summary (`"status": "running"`, padded with blanks to
/// [`SUMMARY_RESERVE`] bytes): found after a crash, it says the run never ended.
fn reserve_summary(path: &Path) -> std::io::Result<()> {
    let mut s = String::from("{\n  \"status\": \"running\"\n}\n");
    s.push_str(&" ".repeat(SUMMARY_RESERVE - s.len() - 1));
    s.push('\n');
    std::fs::write(path, s)
}

/// Overwrite `path` in place with `text` (into the blocks reserved by
/// [`reserve_summary`]), then cut it to that length.
fn write_reserved(path: &Path, text: &str) -> std::io::Result<()> {
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .open(path)?;
    f.write_all(text.as_bytes())?;
    f.set_len(text.len() as u64)?;
    f.sync_data().or(Ok(()))
}

/// The signal that asked the run to stop (SIGINT / SIGTERM), once one has arrived.
static SIGNAL: OnceLock<Arc<AtomicUsize>> = OnceLock::new();

/// Let SIGINT and SIGTERM stop the run cleanly (see [`Interrupted`]); a second one
/// ends the process at once with status 128 + signal.
pub fn install_signal_handlers() -> Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let got = SIGNAL.get_or_init(|| Arc::new(AtomicUsize::new(0)));
    let once = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&once))?;
        signal_hook::flag::register(sig, Arc::clone(&once))?;
        signal_hook::flag::register_usize(sig, Arc::clone(got), sig as usize)?;
    }
    Ok(())
}

fn interrupted() -> Option<i32> {
    let s = SIGNAL.get()?.load(Ordering::SeqCst);
    (s != 0).then_some(s as i32)
}

/// An IMU sample, or the [`Interrupted`] error once a signal has arrived.
fn stop_on_signal<T>(r: Result<T>) -> Result<T> {
    match interrupted() {
        Some(signal) => Err(Interrupted { signal, t: None }.into()),
        None => r,
    }
}

/// The run was stopped by a signal; the outputs hold every epoch up to `t`.
#[derive(Debug)]
pub struct Interrupted {
    pub signal: i32,
    /// The last output epoch written (GNSS time scale), None before the first.
    pub t: Option<f64>,
}

impl Interrupted {
    /// Exit status: 128 + signal (130 for SIGINT, 143 for SIGTERM).
    pub fn exit_status(&self) -> u8 {
        (128 + self.signal).clamp(0, 255) as u8
    }
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = match self.signal {
            2 => "SIGINT".to_string(),
            15 => "SIGTERM".to_string(),
            s => format!("signal {s}"),
        };
        match self.t {
            Some(t) => write!(
                f,
                "interrupted by {name}: every output file holds the epochs up to t = {t:.3}; summary.json is marked \"interrupted\""
            ),
            None => write!(
                f,
                "interrupted by {name} before the first output epoch; summary.json is marked \"interrupted\""
            ),
        }
    }
}

impl std::error::Error for Interrupted {}

/// Normalise (week, t) so that t is in [0, 604800).
fn split_week(week: u32, t: f64) -> (u32, f64) {
    if (0.0..WEEK_S).contains(&t) {
        return (week, t);
    }
    let k = (t / WEEK_S).floor();
    ((week as i64 + k as i64).max(0) as u32, t - k * WEEK_S)
}
