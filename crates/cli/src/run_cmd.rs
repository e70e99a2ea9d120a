//! `navfuse run`: parse the arguments into a configuration and options, run the
//! pipeline (`navfuse_app::run` into a `FileSink`), print the summary line. The
//! pipeline itself (inputs, checks, time offset, writers, summary) is navfuse_app.

use anyhow::{Context, Result};
use navfuse_app::{config, FileSink, RunOptions, StopFlag};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

pub fn main(
    config: Option<PathBuf>,
    kf_gins: Option<PathBuf>,
    out: Option<PathBuf>,
    outages: Option<String>,
    (smooth, smooth_mode, formats): (bool, Option<String>, Option<String>),
    time_snap_s: Option<f64>,
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
    }?;
    for w in &cfg.warnings {
        eprintln!("navfuse: warning: {w}");
    }
    navfuse_app::RunOverrides {
        outages,
        smooth,
        smooth_mode,
        formats,
        time_snap_s,
    }
    .apply(&mut cfg)?;
    let out_dir = out
        .or_else(|| cfg.kfgins_output_path.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    let stop = StopFlag::new();
    install_signal_handlers(&stop).context("cannot install the SIGINT/SIGTERM handlers")?;
    let opts = RunOptions {
        progress: !quiet,
        warn: true,
        stop: Some(stop),
        ..Default::default()
    };
    let job = navfuse_app::run(cfg, &mut FileSink::create(&out_dir)?, &opts)?;
    if !quiet {
        eprintln!("{}", job.summary_line());
    }
    // Every file is written, but the result is meaningless: say so by the exit status.
    match job.unreliable() {
        Some(u) => Err(anyhow::Error::new(u)),
        None => Ok(()),
    }
}

/// Let SIGINT and SIGTERM stop the run cleanly (`stop` set to the signal; the run ends
/// with `navfuse_app::Interrupted`); a second one ends the process at once with
/// status 128 + signal.
pub(crate) fn install_signal_handlers(stop: &StopFlag) -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let once = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&once))?;
        signal_hook::flag::register(sig, Arc::clone(&once))?;
        signal_hook::flag::register_usize(sig, Arc::clone(stop.atomic()), sig as usize)?;
    }
    Ok(())
}
