//! `navfuse report RUN_DIR`: the HTML report of a finished run (navfuse-report).

use crate::eval_cmd::{load_reference, parse_quality, parse_vec3};
use anyhow::{bail, Context, Result};
use navfuse_report::Truth;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `navfuse report` (its --help).
#[derive(clap::Args)]
pub struct ReportArgs {
    /// The output directory of `navfuse run`.
    pub run_dir: PathBuf,
    /// A reference trajectory, as for `navfuse eval`: a KF-GINS .nav, a navfuse
    /// solution.csv, an RTKLIB .pos or a KF-GINS GNSS text file (by content).
    #[arg(long, value_name = "FILE")]
    pub truth: Option<PathBuf>,
    /// The truth's format: auto (by content), nav, csv, pos, kfgins-gnss.
    #[arg(long, value_name = "FORMAT", default_value = "auto")]
    pub truth_format: String,
    /// Body-frame point [m] (F,R,D) to move the solution to before comparing
    /// (the antenna, when the truth is an antenna track).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub lever_arm: Option<String>,
    /// For an RTKLIB .pos truth: the solution qualities to use (default 1 = fix).
    #[arg(long, value_name = "Q,...", default_value = "1")]
    pub quality: String,
    /// The HTML file. Default: RUN_DIR/report.html.
    #[arg(long, value_name = "FILE.html")]
    pub out: Option<PathBuf>,
    /// Also write every figure as a standalone SVG file into DIR.
    #[arg(long, value_name = "DIR")]
    pub svg: Option<PathBuf>,
    /// No summary line.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn main(a: ReportArgs) -> Result<()> {
    let started = Instant::now();
    if !a.run_dir.is_dir() {
        bail!(
            "{}: not a directory; expected the output directory of `navfuse run`",
            a.run_dir.display()
        );
    }
    let truth = match &a.truth {
        Some(p) => {
            let track = load_reference(p, &a.truth_format, &parse_quality(&a.quality)?)?;
            if track.points.is_empty() {
                bail!("{}: no reference epochs", p.display());
            }
            Some(Truth {
                path: p.clone(),
                points: track.points,
                lever_arm_b: a.lever_arm.as_deref().map(parse_vec3).transpose()?,
            })
        }
        None => None,
    };
    let report = navfuse_report::build(&a.run_dir, truth.as_ref())?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| a.run_dir.join("report.html"));
    write(&out, &report.html())?;
    let mut svgs = 0;
    if let Some(dir) = &a.svg {
        svgs = report.write_svgs(dir)?.len();
    }
    if !a.quiet {
        eprintln!(
            "navfuse report: {} ({} figures, {} tables{}) in {:.2} s",
            out.display(),
            report.figures.len(),
            report.tables.len(),
            if svgs > 0 {
                format!(
                    "; {svgs} SVG files in {}",
                    a.svg.as_ref().unwrap().display()
                )
            } else {
                String::new()
            },
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<()> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}
