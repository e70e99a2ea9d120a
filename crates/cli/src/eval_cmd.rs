//! `navfuse eval`: score a solution file against a reference file.

use anyhow::{bail, Context, Result};
use nalgebra::Vector3;
use navfuse_core::eval::{evaluate, EvalOptions, EvalReport, Stat};
use navfuse_core::outage::OutageSchedule;
use navfuse_core::time::SECONDS_PER_WEEK as WEEK_S;
use navfuse_io::trajectory::{detect_format, read_trajectory, TrajFormat, Trajectory};
use serde_json::{json, Value};
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
    let mut reference = load_reference(truth, inputs.truth_format, &quality)?;
    if sol.points.is_empty() {
        bail!("{}: no solution epochs", solution.display());
    }
    if reference.points.is_empty() {
        bail!("{}: no reference epochs", truth.display());
    }
    // Same week reference for both (a week of 0 means seconds of week only).
    if sol.week != 0 && reference.week != 0 && sol.week != reference.week {
        let shift = (reference.week as f64 - sol.week as f64) * WEEK_S;
        reference.points.iter_mut().for_each(|p| p.t += shift);
    }
    if let Some(w) = window {
        let (a, b) = w
            .split_once(':')
            .and_then(|(a, b)| Some((a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?)))
            .with_context(|| format!("--window '{w}': expected START:END in seconds"))?;
        reference.points.retain(|p| p.t >= a && p.t <= b);
    }
    let schedule = match &gaps {
        Some(g) => OutageSchedule::parse(g).map_err(|e| anyhow::anyhow!("--gaps: {e}"))?,
        None => OutageSchedule::default(),
    };
    let (t0, t1) = (sol.points[0].t, sol.points[sol.points.len() - 1].t);
    let opts = EvalOptions {
        gaps: schedule.windows_in(t0, t1),
        lever_arm_b: lever_arm.as_deref().map(parse_vec3).transpose()?,
        keep_epochs: errors_csv.is_some(),
        ..Default::default()
    };
    if opts.lever_arm_b.is_some() && sol.points.iter().any(|p| p.rpy.is_none()) {
        bail!(
            "--lever-arm needs attitude in the solution, and {} ({}) has none",
            solution.display(),
            sol.format.describe()
        );
    }
    let rep = evaluate(&sol.points, &reference.points, &opts);
    if rep.epochs == 0 {
        bail!(
            "no reference epoch of {} falls inside the solution's time span {:.3} .. {:.3} (check the time tags and weeks)",
            truth.display(), t0, t1
        );
    }
    if let Some(p) = errors_csv {
        write_errors(p, &rep)?;
    }
    if json_out {
        println!("{}", serde_json::to_string_pretty(&to_json(&rep))?);
    } else {
        print!("{}", to_text(&rep));
    }
    Ok(())
}

/// `--errors FILE.csv`: one line per scored epoch (empty fields where a side lacks
/// velocity or attitude, or the track is too slow for along/cross).
fn write_errors(path: &Path, r: &EvalReport) -> Result<()> {
    use std::fmt::Write as _;
    let mut t = String::from(
        "t_s,d_north_m,d_east_m,d_down_m,horizontal_m,along_m,cross_m,d_vn_mps,d_ve_mps,d_vd_mps,d_roll_deg,d_pitch_deg,d_yaw_deg,d_att_deg\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.6}"));
    for e in &r.per_epoch {
        let _ = write!(
            t,
            "{:.6},{:.6},{:.6},{:.6},{:.6},{},{},",
            e.t,
            e.pos_ned.x,
            e.pos_ned.y,
            e.pos_ned.z,
            e.horizontal,
            opt(e.along_cross.map(|a| a.0)),
            opt(e.along_cross.map(|a| a.1)),
        );
        let v = e.vel_ned;
        let a = e.att.map(|a| a.map(f64::to_degrees));
        let _ = writeln!(
            t,
            "{},{},{},{},{},{},{}",
            opt(v.map(|v| v.x)),
            opt(v.map(|v| v.y)),
            opt(v.map(|v| v.z)),
            opt(a.map(|a| a.x)),
            opt(a.map(|a| a.y)),
            opt(a.map(|a| a.z)),
            opt(a.map(|a| a.norm())),
        );
    }
    std::fs::write(path, t).with_context(|| format!("cannot write {}", path.display()))
}

fn stat_json(s: &Stat, scale: f64) -> Value {
    json!({ "rms": s.rms * scale, "max": s.max * scale, "mean": s.mean * scale })
}

pub fn to_json(r: &EvalReport) -> Value {
    let d = 180.0 / std::f64::consts::PI;
    let mut v = json!({
        "epochs": r.epochs,
        "skipped": r.skipped,
        "t_first": r.t_first,
        "t_last": r.t_last,
        "position_m": {
            "north": stat_json(&r.north, 1.0),
            "east": stat_json(&r.east, 1.0),
            "down": stat_json(&r.down, 1.0),
            "horizontal": stat_json(&r.horizontal, 1.0),
            "vertical": stat_json(&r.vertical, 1.0),
            "3d": stat_json(&r.pos_3d, 1.0),
        },
        "percentiles_m": {
            "horizontal": { "p50": r.horizontal_pct[0], "p68": r.horizontal_pct[1], "p95": r.horizontal_pct[2], "p99": r.horizontal_pct[3] },
            "3d": { "p50": r.pos_3d_pct[0], "p68": r.pos_3d_pct[1], "p95": r.pos_3d_pct[2], "p99": r.pos_3d_pct[3] },
            "cep": r.horizontal_pct[0],
            "r95": r.horizontal_pct[2],
        },
    });
    if let Some([a, c]) = &r.along_cross {
        v["position_m"]["along_track"] = stat_json(a, 1.0);
        v["position_m"]["cross_track"] = stat_json(c, 1.0);
    }
    if let Some(vel) = &r.vel {
        v["velocity_mps"] = json!({
            "north": stat_json(&vel[0], 1.0), "east": stat_json(&vel[1], 1.0),
            "down": stat_json(&vel[2], 1.0), "3d": stat_json(&vel[3], 1.0),
        });
    }
    if let Some(a) = &r.att {
        v["attitude_deg"] = json!({
            "roll": stat_json(&a[0], d), "pitch": stat_json(&a[1], d), "yaw": stat_json(&a[2], d),
            "total": r.att_total.as_ref().map(|t| stat_json(t, d)),
        });
    }
    if !r.gaps.is_empty() {
        v["gaps"] = Value::Array(
            r.gaps
                .iter()
                .map(|g| {
                    let mut j = json!({
                        "start": g.start, "end": g.end, "epochs": g.epochs,
                        "max_horizontal_m": g.max_horizontal, "max_vertical_m": g.max_vertical,
                        "max_3d_m": g.max_3d,
                    });
                    if r.att.is_some() {
                        j["max_roll_deg"] = json!(g.max_roll * d);
                        j["max_pitch_deg"] = json!(g.max_pitch * d);
                        j["max_yaw_deg"] = json!(g.max_yaw * d);
                    }
                    j
                })
                .collect(),
        );
    }
    if let Some(g) = &r.gap_rms {
        v["gap_max_rms"] = json!({ "horizontal_m": g[0], "vertical_m": g[1], "3d_m": g[2] });
        if r.att.is_some() {
            v["gap_max_rms"]["roll_deg"] = json!(g[3] * d);
            v["gap_max_rms"]["pitch_deg"] = json!(g[4] * d);
            v["gap_max_rms"]["yaw_deg"] = json!(g[5] * d);
        }
    }
    v
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
