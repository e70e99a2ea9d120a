//! Scoring one run against the truth: RMSE of position and attitude, the closed
//! loop's end error (seed 004), the 3D error at seed 000 Table 4's epochs.

use navfuse_core::eval::{EvalReport, TrajPoint};

/// Accuracy of one run: RMSE of position N, E, D, 3D [m] and attitude roll, pitch,
/// yaw, 3D [deg], and for closed-loop experiments the final errors.
#[derive(Clone, Debug, Default)]
pub(crate) struct Metrics {
    pub(crate) values: Vec<(&'static str, f64)>,
}

impl Metrics {
    pub(crate) fn get(&self, k: &str) -> Option<f64> {
        self.values.iter().find(|(n, _)| *n == k).map(|(_, v)| *v)
    }
}

pub(crate) const METRICS: [&str; 8] = [
    "rmse_n_m",
    "rmse_e_m",
    "rmse_d_m",
    "rmse_3d_m",
    "rmse_roll_deg",
    "rmse_pitch_deg",
    "rmse_yaw_deg",
    "rmse_att3d_deg",
];

/// A metric's column header (short, with its unit) and its legend line.
pub(crate) fn metric_label(key: &str) -> (String, String) {
    let fixed = |h: &str, l: &str| (h.to_string(), l.to_string());
    match key {
        "rmse_n_m" => fixed("N [m]", "RMSE of the north position error"),
        "rmse_e_m" => fixed("E [m]", "RMSE of the east position error"),
        "rmse_d_m" => fixed("D [m]", "RMSE of the down position error"),
        "rmse_3d_m" => fixed("3D [m]", "RMSE of the 3D position error"),
        "rmse_roll_deg" => fixed("roll [deg]", "RMSE of the roll error"),
        "rmse_pitch_deg" => fixed("pitch [deg]", "RMSE of the pitch error"),
        "rmse_yaw_deg" => fixed("yaw [deg]", "RMSE of the yaw (heading) error"),
        "rmse_att3d_deg" => fixed(
            "att [deg]",
            "attitude RMSE, sqrt(roll² + pitch² + yaw²) of the three RMSEs",
        ),
        "end_error_m" => fixed(
            "end [m]",
            "horizontal error at the end of the loop (back at the start)",
        ),
        "end_error_pct_distance" => fixed("end [%]", "end error in % of the distance driven"),
        "error_6min_m" => fixed("6 min [m]", "horizontal error 6 min after the start"),
        "mean_3d_m" => fixed(
            "mean [m]",
            "mean 3D position error over every whole second of the run",
        ),
        other => match TABLE4_METRICS.iter().position(|m| *m == other) {
            Some(k) => (
                format!("{:.0} s [m]", TABLE4_TIMES_S[k]),
                "3D position error at that time after the start (seed 000 Table 4 epochs)"
                    .to_string(),
            ),
            None => (other.to_string(), String::new()),
        },
    }
}

/// Seed 004: error at the end of the closed loop (return to start), in metres and in
/// % of the distance driven, and the error 6 min after the start.
pub(crate) const CLOSED_LOOP_METRICS: [&str; 5] = [
    "end_error_m",
    "end_error_pct_distance",
    "error_6min_m",
    "rmse_3d_m",
    "rmse_yaw_deg",
];

/// Horizontal error [m] of the solution at time `t` (nearest solution epoch at or
/// before t) against the truth at the same epoch.
pub(crate) fn horizontal_error_at(sol: &[TrajPoint], truth: &[TrajPoint], t: f64) -> Option<f64> {
    let i = sol.partition_point(|p| p.t <= t + 1e-6).checked_sub(1)?;
    let s = &sol[i];
    let j = truth.partition_point(|p| p.t < s.t - 1e-6);
    let r = truth.get(j).filter(|r| (r.t - s.t).abs() < 1e-3)?;
    let d = navfuse_core::earth::lla_diff_ned(&s.lla, &r.lla);
    Some(d.x.hypot(d.y))
}

pub(crate) fn closed_loop_metrics(
    m: &mut Metrics,
    sol: &[TrajPoint],
    truth: &[TrajPoint],
    distance_m: f64,
) {
    let (Some(first), Some(last)) = (sol.first(), sol.last()) else {
        return;
    };
    if let Some(e) = horizontal_error_at(sol, truth, last.t) {
        m.values.push(("end_error_m", e));
        m.values
            .push(("end_error_pct_distance", 100.0 * e / distance_m));
    }
    if let Some(e) = horizontal_error_at(sol, truth, first.t + 360.0) {
        m.values.push(("error_6min_m", e));
    }
}

pub(crate) fn metrics_of(rep: &EvalReport) -> Metrics {
    let att = rep.att.unwrap_or_default();
    let d = |s: &navfuse_core::eval::Stat| s.rms.to_degrees();
    let a3 = (d(&att[0]).powi(2) + d(&att[1]).powi(2) + d(&att[2]).powi(2)).sqrt();
    Metrics {
        values: vec![
            ("rmse_n_m", rep.north.rms),
            ("rmse_e_m", rep.east.rms),
            ("rmse_d_m", rep.down.rms),
            ("rmse_3d_m", rep.pos_3d.rms),
            ("rmse_roll_deg", d(&att[0])),
            ("rmse_pitch_deg", d(&att[1])),
            ("rmse_yaw_deg", d(&att[2])),
            ("rmse_att3d_deg", a3),
        ],
    }
}

/// Seed 000 Table 4's epochs [s after the start].
pub(crate) const TABLE4_TIMES_S: [f64; 11] = [
    0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 100.0, 200.0, 300.0, 400.0, 500.0,
];
/// Seed 000: 3D position error at the Table 4 epochs and its mean over the run.
pub(crate) const TABLE4_METRICS: [&str; 12] = [
    "err_3d_0s_m",
    "err_3d_10s_m",
    "err_3d_20s_m",
    "err_3d_30s_m",
    "err_3d_40s_m",
    "err_3d_50s_m",
    "err_3d_100s_m",
    "err_3d_200s_m",
    "err_3d_300s_m",
    "err_3d_400s_m",
    "err_3d_500s_m",
    "mean_3d_m",
];

/// 3D error [m] of the solution epoch nearest to `t` (within 0.6 s) against the truth
/// at that epoch.
pub(crate) fn error_3d_at(sol: &[TrajPoint], truth: &[TrajPoint], t: f64) -> Option<f64> {
    let i = sol.partition_point(|p| p.t < t);
    let s = [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter_map(|k| sol.get(k))
        .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
        .filter(|s| (s.t - t).abs() <= 0.6)?;
    // GNSS fixes are valid at the true time (tag - receiver clock): a few us off.
    let j = truth.partition_point(|p| p.t < s.t);
    let r = [j.checked_sub(1), Some(j)]
        .into_iter()
        .flatten()
        .filter_map(|k| truth.get(k))
        .find(|r| (r.t - s.t).abs() < 1e-3)?;
    Some(navfuse_core::earth::lla_diff_ned(&s.lla, &r.lla).norm())
}

/// Table 4 metrics: the 3D error at each Table 4 epoch, and the mean 3D error over
/// every whole second of the run.
pub(crate) fn table4_metrics(m: &mut Metrics, sol: &[TrajPoint], truth: &[TrajPoint]) {
    let Some(t0) = truth.first().map(|p| p.t) else {
        return;
    };
    for (k, dt) in TABLE4_TIMES_S.iter().enumerate() {
        if let Some(e) = error_3d_at(sol, truth, t0 + dt) {
            m.values.push((TABLE4_METRICS[k], e));
        }
    }
    let end = truth.last().map_or(t0, |p| p.t);
    let errs: Vec<f64> = (0..=((end - t0).floor() as usize))
        .filter_map(|k| error_3d_at(sol, truth, t0 + k as f64))
        .collect();
    if !errs.is_empty() {
        m.values
            .push(("mean_3d_m", errs.iter().sum::<f64>() / errs.len() as f64));
    }
}
