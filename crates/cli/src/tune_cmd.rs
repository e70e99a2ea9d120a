//! `navfuse tune CONFIG --out DIR`: the noise model estimated from the run's own data
//! (`navfuse_app::tune`), written as a tuned configuration with the estimation's
//! report, then the tuned configuration's run.

use anyhow::{Context, Result};
use navfuse_app::tune::{copy_noise_model, tune, TuneOptions};
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
    let r = tune(cfg.clone(), &a.options, &opts)?;
    // The input with the estimates in it (its inputs, time offset and outages as given).
    let mut tuned = cfg;
    copy_noise_model(&r.tuned.nav, &mut tuned.nav);
    tuned.defaulted.retain(|k| !k.starts_with("imu_noise."));
    let toml_path = a.out.join("tuned.toml");
    let header = format!(
        "# Written by `navfuse tune {}`: the noise model estimated from the data (tuning.txt).\n",
        a.config.display()
    );
    std::fs::write(&toml_path, header + &tuned.to_toml_string())
        .with_context(|| format!("cannot write {}", toml_path.display()))?;
    let table = r.table();
    let diff = config_diff(&cfg_text(&a.config)?, &tuned.to_toml_string());
    std::fs::write(a.out.join("tuning.txt"), format!("{table}\n{diff}"))
        .with_context(|| format!("cannot write {}", a.out.join("tuning.txt").display()))?;
    std::fs::write(
        a.out.join("tuning.json"),
        serde_json::to_string_pretty(&r.to_json())? + "\n",
    )
    .with_context(|| format!("cannot write {}", a.out.join("tuning.json").display()))?;
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
        let job = navfuse_app::run(tuned, &mut FileSink::create(&a.out)?, &opts)?;
        if !a.quiet {
            eprintln!("{}", job.summary_line());
        }
        if let Some(u) = job.unreliable() {
            return Err(anyhow::Error::new(u));
        }
    }
    Ok(())
}

/// The configuration as the tuned one is written (every key), for the difference.
fn cfg_text(path: &std::path::Path) -> Result<String> {
    let is_yaml = path.extension().is_some_and(|e| e == "yaml" || e == "yml");
    let c = if is_yaml {
        config::load_kfgins_yaml(path)
    } else {
        config::load(path)
    }?;
    Ok(c.to_toml_string())
}

/// The lines of `after` that differ from `before` (both written by `to_toml_string`,
/// so in the same order), as `- old` / `+ new` under their section.
fn config_diff(before: &str, after: &str) -> String {
    let mut out =
        String::from("Difference from the input configuration (every key written out):\n");
    let mut section = "";
    let b: Vec<&str> = before.lines().collect();
    let a: Vec<&str> = after.lines().collect();
    let mut any = false;
    for (i, line) in a.iter().enumerate() {
        if line.starts_with('[') {
            section = line;
        }
        let old = b.get(i).copied().unwrap_or("");
        if old != *line {
            if !any || !out.ends_with(&format!("{section}\n")) {
                out.push_str(&format!("{section}\n"));
            }
            out.push_str(&format!("- {old}\n+ {line}\n"));
            any = true;
        }
    }
    if !any {
        out.push_str("(none)\n");
    }
    out
}
