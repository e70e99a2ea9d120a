//! Scoring a trajectory against a reference, as `navfuse eval` does: both on one GPS
//! week, the reference cut to a window, outage gaps, a lever arm, then
//! `navfuse_core::eval::evaluate`; the report as `navfuse eval --json` prints it and
//! the per-epoch table of `--errors`. Used by the CLI, `navfuse batch` and Python.

use crate::error::Error;
use nalgebra::Vector3;
use navfuse_core::eval::{evaluate, EvalOptions, EvalReport, Stat};
use navfuse_core::outage::OutageSchedule;
use navfuse_core::time::SECONDS_PER_WEEK as WEEK_S;
use navfuse_io::trajectory::Trajectory;
use serde_json::{json, Value};

/// How to score (the options of `navfuse eval`).
#[derive(Clone, Debug, Default)]
pub struct ScoreOptions {
    /// `--gaps`: outage windows for the per-outage maxima.
    pub gaps: Option<OutageSchedule>,
    /// `--lever-arm`: the body-frame point the reference tracks \[m\].
    pub lever_arm_b: Option<Vector3<f64>>,
    /// What the caller calls the lever arm, for the message when the solution has no
    /// attitude (`--lever-arm`, `lever_arm`; empty: "a lever arm").
    pub lever_arm_name: &'static str,
    /// `--window START:END`: reference epochs kept (seconds of the solution's week).
    pub window: Option<(f64, f64)>,
    /// Keep every scored epoch's errors (`--errors`).
    pub keep_epochs: bool,
}

/// Score `solution` against `reference` (names: for messages). Errors when either is
/// empty, when a lever arm is asked for without attitude, and when no reference epoch
/// falls inside the solution's span.
pub fn score(
    solution: &Trajectory,
    solution_name: &str,
    mut reference: Trajectory,
    reference_name: &str,
    opts: &ScoreOptions,
) -> Result<EvalReport, Error> {
    let (Some(first), Some(last)) = (solution.points.first(), solution.points.last()) else {
        return Err(Error::Other(format!("{solution_name}: no solution epochs")));
    };
    if reference.points.is_empty() {
        return Err(Error::Other(format!(
            "{reference_name}: no reference epochs"
        )));
    }
    // Same week reference for both (a week of 0 means seconds of week only).
    if solution.week != 0 && reference.week != 0 && solution.week != reference.week {
        let shift = (f64::from(reference.week) - f64::from(solution.week)) * WEEK_S;
        reference.points.iter_mut().for_each(|p| p.t += shift);
    }
    if let Some((a, b)) = opts.window {
        reference.points.retain(|p| p.t >= a && p.t <= b);
    }
    let (t0, t1) = (first.t, last.t);
    let eval_opts = EvalOptions {
        gaps: opts
            .gaps
            .as_ref()
            .map_or_else(Vec::new, |g| g.windows_in(t0, t1)),
        lever_arm_b: opts.lever_arm_b,
        keep_epochs: opts.keep_epochs,
        ..Default::default()
    };
    if eval_opts.lever_arm_b.is_some() && solution.points.iter().any(|p| p.rpy.is_none()) {
        return Err(Error::Other(format!(
            "{} needs attitude in the solution, and {solution_name} ({}) has none",
            if opts.lever_arm_name.is_empty() {
                "a lever arm"
            } else {
                opts.lever_arm_name
            },
            solution.format.describe()
        )));
    }
    let rep = evaluate(&solution.points, &reference.points, &eval_opts);
    if rep.epochs == 0 {
        return Err(Error::Other(format!(
            "no reference epoch of {reference_name} falls inside the solution's time span {t0:.3} .. {t1:.3} (check the time tags and weeks)"
        )));
    }
    Ok(rep)
}

/// Header of [`errors_csv`].
pub const ERRORS_HEADER: &str = "t_s,d_north_m,d_east_m,d_down_m,horizontal_m,along_m,cross_m,d_vn_mps,d_ve_mps,d_vd_mps,d_roll_deg,d_pitch_deg,d_yaw_deg,d_att_deg";

/// One scored epoch's errors in [`ERRORS_HEADER`] order, in its units (None where a
/// side lacks velocity or attitude, or the track is too slow for along/cross).
pub fn epoch_errors(e: &navfuse_core::eval::EpochError) -> [Option<f64>; 14] {
    let v = e.vel_ned;
    let a = e.att.map(|a| a.map(f64::to_degrees));
    [
        Some(e.t),
        Some(e.pos_ned.x),
        Some(e.pos_ned.y),
        Some(e.pos_ned.z),
        Some(e.horizontal),
        e.along_cross.map(|a| a.0),
        e.along_cross.map(|a| a.1),
        v.map(|v| v.x),
        v.map(|v| v.y),
        v.map(|v| v.z),
        a.map(|a| a.x),
        a.map(|a| a.y),
        a.map(|a| a.z),
        a.map(|a| a.norm()),
    ]
}

/// The `--errors` table: one line per scored epoch, 6 decimals, empty fields where
/// [`epoch_errors`] has none.
pub fn errors_csv(r: &EvalReport) -> String {
    let mut t = String::from(ERRORS_HEADER);
    t.push('\n');
    for e in &r.per_epoch {
        let fields: Vec<String> = epoch_errors(e)
            .iter()
            .map(|v| v.map_or(String::new(), |x| format!("{x:.6}")))
            .collect();
        t.push_str(&fields.join(","));
        t.push('\n');
    }
    t
}

fn stat_json(s: &Stat, scale: f64) -> Value {
    json!({ "rms": s.rms * scale, "max": s.max * scale, "mean": s.mean * scale })
}

/// The report as `navfuse eval --json` prints it.
pub fn report_json(r: &EvalReport) -> Value {
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
