//! `navfuse eval`: score a solution file against a reference file.

use anyhow::{bail, Context, Result};
use nalgebra::Vector3;
use navfuse_app::score::{errors_csv as errors_csv_text, report_json, score, ScoreOptions};
use navfuse_core::eval::{EvalReport, Stat};
use navfuse_core::outage::OutageSchedule;
use navfuse_io::trajectory::{detect_format, read_trajectory, TrajFormat, Trajectory};
use std::path::Path;

/// The two files and how to read them.
pub struct EvalInputs<'a> {
    pub solution: &'a Path,
    pub truth: &'a Path,
    /// `--solution-format`, `--truth-format`: `auto` (by content) or a format name.
    pub solution_format: &'a str,
    pub truth_format: &'a str,
    /// `--quality`, for a `.pos` truth (a `.pos` solution keeps every epoch).
    pub quality: &'a str,
}

/// Read one side, its format detected by content unless `format` names it.
fn load(path: &Path, format: &str, option: &str, quality: &[u8]) -> Result<Trajectory> {
    let format = match TrajFormat::parse(format).map_err(|e| anyhow::anyhow!("{option}: {e}"))? {
        Some(f) => f,
        None => detect_format(path)
            .with_context(|| format!("cannot tell the file's format ({option} names it)"))?,
    };
    let t = read_trajectory(path, Some(format), quality)?;
    for w in &t.warnings {
        eprintln!("navfuse: warning: {w}");
    }
    Ok(t)
}

/// The reference trajectory in `path`, its format by content unless `format`
/// (`--truth-format`) names it; `quality`: the RTKLIB .pos qualities kept.
pub fn load_reference(path: &Path, format: &str, quality: &[u8]) -> Result<Trajectory> {
    load(path, format, "--truth-format", quality)
}

/// `--quality Q,...`.
pub fn parse_quality(quality: &str) -> Result<Vec<u8>> {
    quality
        .split(',')
        .map(|q| q.trim().parse::<u8>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--quality '{quality}': expected comma-separated integers"))
}

pub fn parse_vec3(s: &str) -> Result<Vector3<f64>> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--lever-arm '{s}': expected three numbers X,Y,Z in metres"))?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        bail!("--lever-arm '{s}': expected three finite numbers X,Y,Z in metres");
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

pub fn main(
    inputs: &EvalInputs<'_>,
    gaps: Option<String>,
    lever_arm: Option<String>,
    window: Option<String>,
    errors_csv: Option<&Path>,
    json_out: bool,
) -> Result<()> {
    let (solution, truth) = (inputs.solution, inputs.truth);
    let quality = parse_quality(inputs.quality)?;
    let sol = load(solution, inputs.solution_format, "--solution-format", &[])?;
    let reference = load_reference(truth, inputs.truth_format, &quality)?;
    let window = match window {
        Some(w) => Some(
            w.split_once(':')
                .and_then(|(a, b)| {
                    Some((a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?))
                })
                .with_context(|| format!("--window '{w}': expected START:END in seconds"))?,
        ),
        None => None,
    };
    let opts = ScoreOptions {
        gaps: gaps
            .as_deref()
            .map(OutageSchedule::parse)
            .transpose()
            .map_err(|e| anyhow::anyhow!("--gaps: {e}"))?,
        lever_arm_b: lever_arm.as_deref().map(parse_vec3).transpose()?,
        lever_arm_name: "--lever-arm",
        window,
        keep_epochs: errors_csv.is_some(),
    };
    let rep = score(
        &sol,
        &solution.display().to_string(),
        reference,
        &truth.display().to_string(),
        &opts,
    )?;
    if let Some(p) = errors_csv {
        std::fs::write(p, errors_csv_text(&rep))
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    if json_out {
        println!("{}", serde_json::to_string_pretty(&report_json(&rep))?);
    } else {
        print!("{}", to_text(&rep));
    }
    Ok(())
}

pub fn to_text(r: &EvalReport) -> String {
    let d = 180.0 / std::f64::consts::PI;
    let mut s = format!(
        "epochs scored: {} (skipped {}), t {:.3} .. {:.3}\n{:<22}{:>12}{:>12}{:>12}\n",
        r.epochs, r.skipped, r.t_first, r.t_last, "error", "rms", "max", "mean"
    );
    let mut row = |name: &str, st: &Stat, k: f64| {
        s.push_str(&format!(
            "{:<22}{:>12.4}{:>12.4}{:>12.4}\n",
            name,
            st.rms * k,
            st.max * k,
            st.mean * k
        ));
    };
    row("north [m]", &r.north, 1.0);
    row("east [m]", &r.east, 1.0);
    row("down [m]", &r.down, 1.0);
    row("horizontal [m]", &r.horizontal, 1.0);
    row("vertical [m]", &r.vertical, 1.0);
    row("3d [m]", &r.pos_3d, 1.0);
    if let Some([a, c]) = &r.along_cross {
        row("along-track [m]", a, 1.0);
        row("cross-track [m]", c, 1.0);
    }
    if let Some(v) = &r.vel {
        row("vel north [m/s]", &v[0], 1.0);
        row("vel east [m/s]", &v[1], 1.0);
        row("vel down [m/s]", &v[2], 1.0);
        row("vel 3d [m/s]", &v[3], 1.0);
    }
    if let Some(a) = &r.att {
        row("roll [deg]", &a[0], d);
        row("pitch [deg]", &a[1], d);
        row("yaw [deg]", &a[2], d);
    }
    if let Some(t) = &r.att_total {
        row("attitude total [deg]", t, d);
    }
    let (h, p) = (&r.horizontal_pct, &r.pos_3d_pct);
    s.push_str(&format!(
        "percentiles [m]      P50 (CEP)      P68   P95 (R95)      P99\nhorizontal    {:>12.4}{:>9.4}{:>12.4}{:>9.4}\n3d            {:>12.4}{:>9.4}{:>12.4}{:>9.4}\n",
        h[0], h[1], h[2], h[3], p[0], p[1], p[2], p[3]
    ));
    // Attitude columns only when attitude was scored (not against a reference
    // without attitude, where they would read 0).
    let att = r.att.is_some();
    if !r.gaps.is_empty() {
        s.push_str(&format!(
            "outages: {}\n{:>14}{:>14}{:>8}{:>10}{:>10}{:>10}{}\n",
            r.gaps.len(),
            "start",
            "end",
            "epochs",
            "hor [m]",
            "ver [m]",
            "3d [m]",
            if att { " yaw [deg]" } else { "" }
        ));
        for g in &r.gaps {
            s.push_str(&format!(
                "{:>14.3}{:>14.3}{:>8}{:>10.3}{:>10.3}{:>10.3}",
                g.start, g.end, g.epochs, g.max_horizontal, g.max_vertical, g.max_3d,
            ));
            if att {
                s.push_str(&format!("{:>10.4}", g.max_yaw * d));
            }
            s.push('\n');
        }
    }
    if let Some(g) = &r.gap_rms {
        s.push_str(&format!(
            "RMS of per-outage maxima: horizontal {:.4} m, vertical {:.4} m, 3d {:.4} m",
            g[0], g[1], g[2]
        ));
        if att {
            s.push_str(&format!(
                ", roll {:.4} deg, pitch {:.4} deg, yaw {:.4} deg",
                g[3] * d,
                g[4] * d,
                g[5] * d
            ));
        }
        s.push('\n');
    }
    s
}
