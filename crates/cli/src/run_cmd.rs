//! `navfuse run`: read the inputs a configuration names, run the navigator, write the
//! solution files. The engine (time loop) is `navfuse_core::run`; this file only
//! wires files to it.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use navfuse_core::config::TimeOffsetConfig;
use navfuse_core::outage::OutageSchedule;
use navfuse_core::{GnssFix, GnssRawEpoch, HeadingObs, Navigator, OdometerSample, RunSummary};
use navfuse_io::config::{self, RunConfig};
use navfuse_io::gnss::read_gnss;
use navfuse_io::heading::read_heading;
use navfuse_io::imu::open_imu;
use navfuse_io::input::{Coupling, GnssFormat, GnssSource};
use navfuse_io::nav::{CsvWriter, ImuErrWriter, NavWriter, SolutionRecord, StdWriter};
use navfuse_io::odometer::read_odometer;
use std::io::Write;
use std::path::{Path, PathBuf};
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
    let job = run_job(cfg, &out_dir, !quiet)?;
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
}

impl JobResult {
    /// The run summary as JSON (written to DIR/summary.json).
    pub fn to_json(&self) -> serde_json::Value {
        let s = &self.summary;
        serde_json::json!({
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

/// Run one configuration, writing into `out_dir`.
pub fn run_job(mut cfg: RunConfig, out_dir: &Path, progress: bool) -> Result<JobResult> {
    let t_wall = Instant::now();
    let mut input_notes = Vec::new();
    let mut reader = open_imu(&cfg.imu).map_err(|e| anyhow::anyhow!("{e}"))?;
    let imu_week = reader.gps_week();
    let mut time_offset_pass1 = None;
    let mut raw: Vec<GnssRawEpoch> = Vec::new();
    let (mut fixes, gnss_week): (Vec<GnssFix>, Option<u32>) = match &cfg.gnss {
        Some(
            src @ GnssSource {
                format: GnssFormat::Rinex(r),
                ..
            },
        ) => {
            let g = crate::gnss_input::load_rinex(src, r)?;
            input_notes.extend(g.notes);
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
            let o = read_odometer(src).map_err(|e| anyhow::anyhow!("{e}"))?;
            if o.is_empty() {
                input_notes.push(format!("{}: no odometer samples", src.path.display()));
            }
            o
        }
        _ => Vec::new(),
    };
    let mut heading: Vec<HeadingObs> = match &cfg.heading {
        Some(src) if cfg.nav.heading.baseline_b.is_some() => {
            let h = read_heading(&src.path).map_err(|e| anyhow::anyhow!("{e}"))?;
            if h.is_empty() {
                input_notes.push(format!("{}: no heading records", src.path.display()));
            }
            h
        }
        _ => Vec::new(),
    };
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
    let last_gnss_t = raw.last().map(|e| e.t).or(fixes.last().map(|f| f.t));
    // GNSS epochs offered to the navigator: fixes, or raw epochs (tight coupling).
    let gnss_epochs = fixes.len() + raw.len();
    let measurements = navfuse_core::merge_raw_epochs(
        navfuse_core::merge_measurements(&fixes, &odometer, &heading),
        raw,
    );

    let first = match reader.next() {
        Some(Ok(s)) => s,
        Some(Err(e)) => anyhow::bail!("{e}"),
        None => anyhow::bail!("{}: no IMU samples", cfg.imu.path.display()),
    };
    let first_t = first.t;
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
            let pass1_reader = open_imu(&cfg.imu).map_err(|e| anyhow::anyhow!("{e}"))?;
            let s1 = navfuse_core::run(
                &cfg.nav,
                pass1_reader.map(|r| r.map_err(|e| anyhow::anyhow!("{e}"))),
                &measurements,
                Some(f64::INFINITY),
                |_| Ok(()),
                |_| {},
            )
            .context("time-offset estimation pass")?;
            if let Some((tau_end, sd)) = s1.time_offset {
                let (rate, rate_sd) = s1.time_offset_rate.unwrap_or((to.initial_rate, 0.0));
                let tau0 = tau_end - rate * (s1.last_t - s1.first_t);
                time_offset_pass1 = Some(TimeOffsetFit {
                    tau0,
                    tau0_sd: sd,
                    rate,
                    rate_sd,
                    t0: s1.first_t,
                });
                cfg.nav.filter.time_offset = Some(TimeOffsetConfig {
                    initial_s: tau0,
                    std_s: 0.0,
                    random_walk: 0.0,
                    initial_rate: rate,
                    rate_std: 0.0,
                });
            }
        }
    }

    // Leftovers of an earlier run in the same directory must not sit beside this one's.
    for stale in ["events.log", "summary.json"] {
        let _ = std::fs::remove_file(out_dir.join(stale));
    }
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("cannot create output directory {}", out_dir.display()))?;
    let mut files = vec![out_dir.join("solution.nav")];
    let mut nav_w = NavWriter::create(&files[0]).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut err_w = if cfg.output.imu_err {
        files.push(out_dir.join("imu_err.txt"));
        Some(ImuErrWriter::create(files.last().unwrap()).map_err(|e| anyhow::anyhow!("{e}"))?)
    } else {
        None
    };
    let mut std_w = if cfg.output.std {
        files.push(out_dir.join("std.txt"));
        Some(StdWriter::create(files.last().unwrap()).map_err(|e| anyhow::anyhow!("{e}"))?)
    } else {
        None
    };
    // With the integrity monitor, solution.csv carries its flag column.
    let monitor_on = cfg.nav.integrity.enabled;
    let mut csv_w = if cfg.output.csv || monitor_on {
        files.push(out_dir.join("solution.csv"));
        Some(
            CsvWriter::create(files.last().unwrap(), cfg.output.std, monitor_on)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
        )
    } else {
        None
    };

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
    // as navigating, and the machine has two cores.
    let want_std = std_w.is_some() || (csv_w.is_some() && cfg.output.std);
    let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<SolutionRecord>>(8);
    let writer = std::thread::spawn(move || -> Result<()> {
        let io = |e: navfuse_io::InputError| anyhow::anyhow!("{e}");
        let mut failed = None;
        for batch in rx {
            for rec in &batch {
                let r = (|| {
                    nav_w.write(rec)?;
                    if let Some(w) = err_w.as_mut() {
                        w.write(rec)?;
                    }
                    if let Some(w) = std_w.as_mut() {
                        w.write(rec)?;
                    }
                    if let Some(w) = csv_w.as_mut() {
                        w.write(rec)?;
                    }
                    Ok::<(), navfuse_io::InputError>(())
                })();
                if let Err(e) = r {
                    failed = Some(io(e));
                    break;
                }
            }
            if failed.is_some() {
                break;
            }
        }
        // Whatever happened, keep what was computed: flush every writer.
        for r in [
            nav_w.finish(),
            err_w.map_or(Ok(()), |w| w.finish()),
            std_w.map_or(Ok(()), |w| w.finish()),
            csv_w.map_or(Ok(()), |w| w.finish()),
        ] {
            if let Err(e) = r {
                failed.get_or_insert(io(e));
            }
        }
        failed.map_or(Ok(()), Err)
    });
    const BATCH: usize = 2048;
    let mut batch: Vec<SolutionRecord> = Vec::with_capacity(BATCH);
    let send = |batch: &mut Vec<SolutionRecord>| -> Result<()> {
        let full = std::mem::replace(batch, Vec::with_capacity(BATCH));
        tx.send(full)
            .map_err(|_| anyhow::anyhow!("the output writer stopped"))
    };
    let result = navfuse_core::run(
        &cfg.nav,
        std::iter::once(Ok(first)).chain(
            reader
                .by_ref()
                .map(|r| r.map_err(|e| anyhow::anyhow!("{e}"))),
        ),
        &measurements,
        cfg.output.rate_hz.map(|r| 1.0 / r),
        |n: &Navigator| {
            let nav = *n.nav();
            let (wk, t) = split_week(week, n.time_gnss());
            batch.push(SolutionRecord {
                gps_week: wk,
                nav: navfuse_core::NavState { t, ..nav },
                imu_errors: *n.imu_errors(),
                std: if want_std { Some(n.std21()) } else { None },
                gnss_integrity: monitor_on.then(|| n.integrity_state().flag()),
            });
            if batch.len() == BATCH {
                send(&mut batch)?;
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
    let report = reader.report().to_string();
    // A failed writer (disk full, ...) is the real cause when the run stopped on it.
    written.with_context(|| format!("writing the solution into {}", out_dir.display()))?;
    sent?;
    let summary = result.with_context(|| {
        format!(
            "run stopped; the output up to the failure is in {}",
            out_dir.display()
        )
    })?;
    // Event log: rejected fixes and input findings.
    let ev_path = out_dir.join("events.log");
    let mut ev = std::fs::File::create(&ev_path)
        .with_context(|| format!("cannot create {}", ev_path.display()))?;
    if !report.is_empty() {
        input_notes.push(report);
    }
    for n in &input_notes {
        writeln!(ev, "# input: {n}")?;
    }
    for e in &summary.events {
        writeln!(ev, "{e}")?;
    }
    files.push(ev_path);
    if monitor_on {
        // Integrity transitions as a table (they are also in events.log).
        let p = out_dir.join("integrity.csv");
        let mut w =
            std::fs::File::create(&p).with_context(|| format!("cannot create {}", p.display()))?;
        writeln!(w, "t_s,from,to,detector,statistic,threshold")?;
        let mut spoofed = 0;
        for e in &summary.events {
            if let navfuse_core::engine::Event::Integrity(tr) = e {
                spoofed += usize::from(tr.to == navfuse_core::integrity::IntegrityState::Spoofed);
                writeln!(
                    w,
                    "{:.3},{},{},{},{:.4},{}",
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
                )?;
            }
        }
        files.push(p);
        if progress && spoofed > 0 {
            eprintln!(
                "navfuse: GNSS integrity: declared spoofed {spoofed} time(s) (see integrity.csv)"
            );
        }
    }
    if progress {
        for n in &input_notes {
            eprintln!("navfuse: note: {n}");
        }
        let rej = summary
            .events
            .iter()
            .filter(|e| matches!(e, navfuse_core::engine::Event::Rejected { .. }))
            .count();
        if rej > 0 {
            eprintln!(
                "navfuse: {rej} GNSS/heading measurements rejected by the innovation gate (see events.log)"
            );
        }
    }
    let mut job = JobResult {
        summary,
        wall: t_wall.elapsed(),
        files,
        gnss_fixes: gnss_epochs,
        odometer_samples: odometer.len(),
        heading_records: heading.len(),
        time_offset: time_offset_pass1,
    };
    let sum_path = out_dir.join("summary.json");
    job.files.push(sum_path.clone());
    std::fs::write(
        &sum_path,
        serde_json::to_string_pretty(&job.to_json())? + "\n",
    )
    .with_context(|| format!("cannot write {}", sum_path.display()))?;
    Ok(job)
}

/// Normalise (week, t) so that t is in [0, 604800).
fn split_week(week: u32, t: f64) -> (u32, f64) {
    if (0.0..WEEK_S).contains(&t) {
        return (week, t);
    }
    let k = (t / WEEK_S).floor();
    ((week as i64 + k as i64).max(0) as u32, t - k * WEEK_S)
}
