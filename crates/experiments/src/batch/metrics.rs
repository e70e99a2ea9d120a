//! The figures of a batch case: the run's GNSS counts, and with a truth the
//! accuracy `navfuse eval` prints (one fixed list, [`METRICS`], in that order).

use navfuse_app::JobResult;
use navfuse_core::eval::EvalReport;

/// Every figure a case can have with what it is, in the order of the rows'
/// `metrics` and of the columns of batch.csv. A figure a case does not have (no
/// truth; no velocity or attitude in the truth; no gaps) is left out of its row.
pub const METRICS: [(&str, &str); 18] = [
    ("gnss_used", "GNSS updates used (summary.json gnss.used)"),
    ("gnss_rejected", "GNSS updates rejected by the gate"),
    ("scored_epochs", "truth epochs scored"),
    ("h_rms_m", "RMS of the horizontal position error [m]"),
    ("h_max_m", "maximum horizontal position error [m]"),
    ("h_p95_m", "P95 of the horizontal position error (R95) [m]"),
    ("v_rms_m", "RMS of the vertical position error [m]"),
    ("v_max_m", "maximum vertical position error [m]"),
    ("rms_3d_m", "RMS of the 3D position error [m]"),
    ("max_3d_m", "maximum 3D position error [m]"),
    ("vel_3d_rms_mps", "RMS of the 3D velocity error [m/s]"),
    ("roll_rms_deg", "RMS of the roll error [deg]"),
    ("pitch_rms_deg", "RMS of the pitch error [deg]"),
    ("yaw_rms_deg", "RMS of the yaw error [deg]"),
    (
        "att_rms_deg",
        "RMS of the attitude error (rotation angle) [deg]",
    ),
    (
        "gap_h_max_rms_m",
        "RMS over the gaps of each gap's maximum horizontal error [m]",
    ),
    ("gap_v_max_rms_m", "the same, vertical [m]"),
    ("gap_3d_max_rms_m", "the same, 3D [m]"),
];

/// The figures of a finished run (`job`), scored when `report` is given, in
/// [`METRICS`] order.
pub(crate) fn figures(job: &JobResult, report: Option<&EvalReport>) -> Vec<(String, f64)> {
    let mut m: Vec<(&str, f64)> = vec![
        ("gnss_used", job.summary.gnss_used as f64),
        ("gnss_rejected", job.summary.gnss_rejected as f64),
    ];
    if let Some(r) = report {
        let deg = f64::to_degrees;
        m.extend([
            ("scored_epochs", r.epochs as f64),
            ("h_rms_m", r.horizontal.rms),
            ("h_max_m", r.horizontal.max),
            ("h_p95_m", r.horizontal_pct[2]),
            ("v_rms_m", r.vertical.rms),
            ("v_max_m", r.vertical.max),
            ("rms_3d_m", r.pos_3d.rms),
            ("max_3d_m", r.pos_3d.max),
        ]);
        if let Some(v) = &r.vel {
            m.push(("vel_3d_rms_mps", v[3].rms));
        }
        if let Some(a) = &r.att {
            m.push(("roll_rms_deg", deg(a[0].rms)));
            m.push(("pitch_rms_deg", deg(a[1].rms)));
            m.push(("yaw_rms_deg", deg(a[2].rms)));
        }
        if let Some(t) = &r.att_total {
            m.push(("att_rms_deg", deg(t.rms)));
        }
        if let Some(g) = &r.gap_rms {
            m.push(("gap_h_max_rms_m", g[0]));
            m.push(("gap_v_max_rms_m", g[1]));
            m.push(("gap_3d_max_rms_m", g[2]));
        }
    }
    debug_assert!(m.windows(2).all(|w| index_of(w[0].0) < index_of(w[1].0)));
    m.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

fn index_of(name: &str) -> Option<usize> {
    METRICS.iter().position(|m| m.0 == name)
}

/// The value of figure `name` in a row's metrics.
pub fn metric(metrics: &[(String, f64)], name: &str) -> Option<f64> {
    metrics.iter().find(|(k, _)| k == name).map(|(_, v)| *v)
}
