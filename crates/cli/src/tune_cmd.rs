//! `navfuse tune CONFIG --out DIR`: the noise model estimated from the run's own data
//! (`navfuse_app::tune`), written as a tuned configuration with the estimation's
//! report, then the tuned configuration's run.

use anyhow::{Context, Result};
use navfuse_app::tune::{tune_config, TuneOptions};
use navfuse_app::{config, FileSink, RunOptions, StopFlag};
use std::path::PathBuf;

pub struct TuneArgs {
    pub config: PathBuf,
    pub out: PathBuf,
    pub options: TuneOptions,
    /// Run the tuned configuration into `out`.
    pub run: bool,
    pub quiet: bool,
}

pub fn main(a: &TuneArgs) -> Result<()> {
    let is_yaml = a
        .config
        .extension()
        .is_some_and(|e| e == "yaml" || e == "yml");
    let cfg = if is_yaml {
        config::load_kfgins_yaml(&a.config)
    } else {
        config::load(&a.config)
    }?;
    for w in &cfg.warnings {
        eprintln!("navfuse: warning: {w}");
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create the output directory {}", a.out.display()))?;
    let stop = StopFlag::new();
    crate::run_cmd::install_signal_handlers(&stop)
        .context("cannot install the SIGINT/SIGTERM handlers")?;
    let opts = RunOptions {
        progress: false,
        warn: !a.quiet,
        stop: Some(stop.clone()),
        ..Default::default()
    };
    if !a.quiet {
        eprintln!(
            "navfuse tune: estimating the noise model of {} (up to {} passes)",
            a.config.display(),
            a.options.max_iterations
        );
    }
    let mut cfg = cfg;
    cfg.tuning = navfuse_app::config::TuningSpec {
        enabled: true,
        iterations: a.options.max_iterations,
        from_data: a.options.from_data,
        fix_error_model: a.options.fix_error_model,
    };
    let t = tune_config(&cfg, &opts)?;
    let toml_path = a.out.join("tuned.toml");
    let header = format!(
        "# Written by `navfuse tune {}`: the noise model estimated from the data (tuning.txt).\n",
        a.config.display()
    );
    std::fs::write(&toml_path, header + &t.config.to_toml_string())
        .with_context(|| format!("cannot write {}", toml_path.display()))?;
    std::fs::write(a.out.join("tuning.txt"), &t.text)
        .with_context(|| format!("cannot write {}", a.out.join("tuning.txt").display()))?;
    std::fs::write(
        a.out.join("tuning.json"),
        serde_json::to_string_pretty(&t.result.to_json())? + "\n",
    )
    .with_context(|| format!("cannot write {}", a.out.join("tuning.json").display()))?;
    let table = t.result.table();
    println!("{table}");
    if !a.quiet {
        eprintln!(
            "navfuse tune: wrote {}, {}, {}",
            toml_path.display(),
            a.out.join("tuning.json").display(),
            a.out.join("tuning.txt").display()
        );
    }
    if a.run {
        let opts = RunOptions {
            progress: !a.quiet,
            warn: !a.quiet,
            stop: Some(stop),
            ..Default::default()
        };
        let job = navfuse_app::run(t.config, &mut FileSink::create(&a.out)?, &opts)?;
        if !a.quiet {
            eprintln!("{}", job.summary_line());
        }
        if let Some(u) = job.unreliable() {
            return Err(anyhow::Error::new(u));
        }
    }
    Ok(())
}
