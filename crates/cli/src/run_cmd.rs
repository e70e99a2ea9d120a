//! `navfuse run`: read the inputs a configuration names, run the navigator, write the
//! solution files. The engine (time loop) is `navfuse_core::run`; this file only
//! wires files to it.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use navfuse_core::outage::OutageSchedule;
use navfuse_core::{GnssFix, Navigator, RunSummary};
use navfuse_io::config::{self, RunConfig};
use navfuse_io::gnss::read_gnss;
use navfuse_io::imu::open_imu;
use navfuse_io::nav::{CsvWriter, ImuErrWriter, NavWriter, SolutionRecord, StdWriter};
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

/// What a finished run reports.
pub struct JobResult {
    pub summary: RunSummary,
    pub wall: Duration,
    pub files: Vec<PathBuf>,
    pub gnss_fixes: usize,
    pub input_notes: Vec<String>,
}

impl JobResult {
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
        if let Some((to, sd)) = s.time_offset {
            line.push_str(&format!(
                "; GNSS-IMU time offset {:.4} s (1-sigma {:.4})",
                to, sd
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
    let (mut fixes, gnss_week): (Vec<GnssFix>, Option<u32>) = match &cfg.gnss {
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
    // Put GNSS times on the IMU's week reference.
    if let (Some(wi), Some(wg)) = (imu_week, gnss_week) {
        let shift = (wg as f64 - wi as f64) * WEEK_S;
        if shift != 0.0 {
            fixes.iter_mut().for_each(|f| f.t += shift);
        }
    }
    let week = imu_week.or(gnss_week).unwrap_or(0);

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
    let mut csv_w = if cfg.output.csv {
        files.push(out_dir.join("solution.csv"));
        Some(
            CsvWriter::create(files.last().unwrap(), cfg.output.std)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
        )
    } else {
        None
    };

    let t_end = cfg
        .nav
        .end_time
        .or(fixes.last().map(|f| f.t))
        .unwrap_or(run_start);
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

    let want_std = std_w.is_some() || csv_w.as_ref().is_some_and(|_| cfg.output.std);
    let mut write = |n: &Navigator| -> Result<()> {
        let nav = *n.nav();
        let (wk, t) = split_week(week, nav.t);
        let rec = SolutionRecord {
            gps_week: wk,
            nav: navfuse_core::NavState { t, ..nav },
            imu_errors: *n.imu_errors(),
            std: if want_std { Some(n.std21()) } else { None },
        };
        nav_w.write(&rec).map_err(|e| anyhow::anyhow!("{e}"))?;
        if let Some(w) = err_w.as_mut() {
            w.write(&rec).map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        if let Some(w) = std_w.as_mut() {
            w.write(&rec).map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        if let Some(w) = csv_w.as_mut() {
            w.write(&rec).map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        Ok(())
    };
    let result = navfuse_core::run(
        &cfg.nav,
        std::iter::once(Ok(first)).chain(
            reader
                .by_ref()
                .map(|r| r.map_err(|e| anyhow::anyhow!("{e}"))),
        ),
        &fixes,
        cfg.output.rate_hz.map(|r| 1.0 / r),
        &mut write,
        |t| {
            if let Some(b) = &bar {
                b.set_position(((t - run_start) * 10.0).max(0.0) as u64);
                b.set_message(format!("t = {t:.1}"));
            }
        },
    );
    drop(write);
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    // Whatever happened, keep what was computed: flush every writer first.
    let mut flush_err = None;
    for r in [
        nav_w.finish(),
        err_w.map_or(Ok(()), |w| w.finish()),
        std_w.map_or(Ok(()), |w| w.finish()),
        csv_w.map_or(Ok(()), |w| w.finish()),
    ] {
        if let Err(e) = r {
            flush_err.get_or_insert(anyhow::anyhow!("{e}"));
        }
    }
    let report = reader.report().to_string();
    let summary = result.with_context(|| {
        format!(
            "run stopped; output up to the failure is in {}",
            out_dir.display()
        )
    })?;
    if let Some(e) = flush_err {
        return Err(e);
    }
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
    if progress {
        for n in &input_notes {
            eprintln!("navfuse: note: {n}");
        }
        let rej = summary.events.len();
        if rej > 0 {
            eprintln!(
                "navfuse: {rej} GNSS measurements rejected by the innovation gate (see events.log)"
            );
        }
    }
    Ok(JobResult {
        summary,
        wall: t_wall.elapsed(),
        files,
        gnss_fixes: fixes.len(),
        input_notes,
    })
}

/// Normalise (week, t) so that t is in [0, 604800).
fn split_week(week: u32, t: f64) -> (u32, f64) {
    if (0.0..WEEK_S).contains(&t) {
        return (week, t);
    }
    let k = (t / WEEK_S).floor();
    ((week as i64 + k as i64).max(0) as u32, t - k * WEEK_S)
}
