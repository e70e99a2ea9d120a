//! [`JobResult`]: what a finished run reports (the counts, the time-offset fit, the
//! findings, how it ended), as `summary.json` and as `navfuse run`'s summary line.

use crate::plausibility::{self, Finding};
use crate::time_offset::{TimeOffsetFit, TimeOffsetSource};
use navfuse_core::RunSummary;
use std::path::PathBuf;
use std::time::Duration;

/// What a finished run reports.
#[derive(Clone, Debug)]
pub struct JobResult {
    pub summary: RunSummary,
    pub wall: Duration,
    pub files: Vec<PathBuf>,
    /// GNSS epochs read: fixes (loose) or raw epochs (tight).
    pub gnss_fixes: usize,
    /// Odometer samples and heading records read (0 when not configured).
    pub odometer_samples: usize,
    pub heading_records: usize,
    pub time_offset: Option<TimeOffsetFit>,
    /// How the run ended (summary.json): "completed", "unreliable" (ran to its end but
    /// the result is meaningless: the findings say why), "failed" or "interrupted".
    pub status: &'static str,
    /// Why it failed or stopped.
    pub error: Option<String>,
    /// Plausibility warnings and errors (plausibility.rs).
    pub findings: Vec<Finding>,
    /// Input facts (events.log `# input:` lines).
    pub notes: Vec<String>,
    /// The last output epoch written [s, GNSS time scale].
    pub last_output_t: Option<f64>,
    /// Write integrity.csv (the monitor ran).
    pub(crate) integrity_table: bool,
    /// What the smoother did, when it ran.
    pub smoother: Option<crate::SmootherReport>,
}

/// Exit status of `navfuse run` (and `navfuse batch`) when the run went to its end but
/// its result is meaningless (`status` "unreliable" in summary.json).
pub const EXIT_UNRELIABLE: u8 = 3;

/// A run that went to its end with a result the program can tell is meaningless: its
/// files are written, summary.json says `"status": "unreliable"` and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Unreliable {
    /// Why (the unreliable findings).
    pub reasons: Vec<String>,
}

impl std::fmt::Display for Unreliable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the run's result is unreliable (its files are written; summary.json \"unreliable\"): {}",
            self.reasons.join("; ")
        )
    }
}

impl std::error::Error for Unreliable {}

impl JobResult {
    /// Why the result is unreliable, when it is ([`Unreliable`]).
    pub fn unreliable(&self) -> Option<Unreliable> {
        let reasons: Vec<String> = self
            .findings
            .iter()
            .filter(|f| f.is_unreliable())
            .map(|f| f.message.clone())
            .collect();
        (!reasons.is_empty()).then_some(Unreliable { reasons })
    }

    pub(crate) fn empty() -> Self {
        JobResult {
            summary: RunSummary::default(),
            wall: Duration::ZERO,
            files: Vec::new(),
            gnss_fixes: 0,
            odometer_samples: 0,
            heading_records: 0,
            time_offset: None,
            status: "running",
            error: None,
            findings: Vec::new(),
            notes: Vec::new(),
            last_output_t: None,
            integrity_table: false,
            smoother: None,
        }
    }

    /// The run summary as JSON (written to DIR/summary.json).
    pub fn to_json(&self) -> serde_json::Value {
        let s = &self.summary;
        let with = |sev| {
            self.findings
                .iter()
                .filter(|f| f.severity == sev)
                .map(|f| f.message.clone())
                .collect::<Vec<_>>()
        };
        let mut v = serde_json::json!({
            "status": self.status,
            "error": self.error,
            "warnings": with(plausibility::Severity::Warning),
            "errors": with(plausibility::Severity::Error),
            "unreliable": with(plausibility::Severity::Unreliable),
            "last_output_t": self.last_output_t,
            "imu_samples": s.imu_samples,
            "t_first": s.first_t,
            "t_last": s.last_t,
            "wall_s": self.wall.as_secs_f64(),
            "outputs": s.outputs,
            "gnss": {
                "fixes": self.gnss_fixes,
                "used": s.gnss_used,
                "rejected": s.gnss_rejected,
                "in_outages": s.gnss_in_outage,
                "before_start": s.gnss_before_start,
            },
            "time_offset": self.time_offset.as_ref().map(|f| serde_json::json!({
                "offset_s_at_start": f.tau0,
                "offset_sigma_s_at_end": f.tau0_sd,
                "rate_ppm": f.rate * 1e6,
                "rate_sigma_ppm": f.rate_sd * 1e6,
                "t_start": f.t0,
                "source": f.source.name(),
                "search_offset_s": f.search.map(|s| s.0),
                "search_sigma_s": f.search.map(|s| s.1),
                "pass_offset_s_at_start": f.filter.0,
                "pass_rate_ppm": f.filter.1 * 1e6,
                "note": f.note,
            })),
            "odometer_samples": self.odometer_samples,
            "heading_records": self.heading_records,
            "aiding_used": s.aiding_used,
            "aiding_rejected": s.aiding_rejected,
            "innovation_stats": s.innovation_stats.iter().map(|(k, st)| (*k, serde_json::json!({
                "tried": st.tried,
                "extreme_nis": st.extreme,
                "lag1_autocorrelation": (0..3).map(|i| st.autocorrelation(i)).collect::<Vec<_>>(),
                "mean_interval_s": st.mean_pair_dt(),
                "log_likelihood": st.log_likelihood,
            }))).collect::<std::collections::BTreeMap<_, _>>(),
            "nis_per_row": s.aiding_nis.iter().map(|(k, (sum, rows))| (*k, sum / (*rows).max(1) as f64)).collect::<std::collections::BTreeMap<_, _>>(),
            "static_s": s.static_s,
            "adaptive_noise": (!s.adaptive_noise.is_empty()).then(|| s.adaptive_noise.iter().map(|(k, p)| (*k, serde_json::json!({
                "scale": p.scale(),
                "sd": p.sd(),
                "std_factor": p.scale().sqrt(),
                "updates": p.updates,
            }))).collect::<std::collections::BTreeMap<_, _>>()),
            "odometer_scale": s.odometer_scale.map(|(k, sd)| serde_json::json!({
                "k_ppm": k * 1e6,
                "sd_ppm": sd * 1e6,
            })),
            "mounting": s.mounting.map(|(rpy, sd)| serde_json::json!({
                "roll_deg": rpy.x.to_degrees(),
                "pitch_deg": rpy.y.to_degrees(),
                "yaw_deg": rpy.z.to_degrees(),
                "sd_pitch_deg": sd[0].to_degrees(),
                "sd_yaw_deg": sd[1].to_degrees(),
            })),
            "events": s.events.iter().map(|e| e.to_string()).collect::<Vec<_>>(),
            "files": self.files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        });
        if let Some(navfuse_core::Event::Aligned {
            t,
            method,
            rpy_deg,
            reason,
            skipped_s,
        }) = s
            .events
            .iter()
            .find(|e| matches!(e, navfuse_core::Event::Aligned { .. }))
        {
            // Which alignment ran and why (also the events line).
            v["alignment"] = serde_json::json!({
                "t": t,
                "method": method,
                "roll_deg": rpy_deg[0],
                "pitch_deg": rpy_deg[1],
                "yaw_deg": rpy_deg[2],
                "reason": reason,
                "imu_skipped_s": skipped_s,
            });
        }
        if s.gnss_sats_ignored > 0 {
            // Tight coupling: measurements of systems not in `[gnss] systems`.
            v["gnss"]["sats_ignored"] = s.gnss_sats_ignored.into();
        }
        if let Some(sm) = &self.smoother {
            v["smoother"] = sm.to_json();
        }
        if !s.source_states.is_empty() {
            // The sources' own states (e.g. the barometer bias), final value and 1-sigma.
            v["source_states"] = s
                .source_states
                .iter()
                .map(|st| {
                    let e = serde_json::json!({"value": st.value, "sd": st.std});
                    (st.name.to_string(), e)
                })
                .collect::<serde_json::Map<_, _>>()
                .into();
        }
        v
    }

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
        // Aiding other than GNSS position/velocity (counted above): used/rejected.
        let aiding: Vec<String> = s
            .aiding_used
            .keys()
            .chain(s.aiding_rejected.keys())
            .filter(|k| !k.starts_with("gnss_"))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .map(|k| {
                let used = s.aiding_used.get(k).copied().unwrap_or(0);
                match s.aiding_rejected.get(k).copied().unwrap_or(0) {
                    0 => format!("{k} {used}"),
                    r => format!("{k} {used} ({r} rejected)"),
                }
            })
            .collect();
        if !aiding.is_empty() {
            line.push_str(&format!("; aiding {}", aiding.join(", ")));
        }
        if let Some(f) = &self.time_offset {
            let how = match f.source {
                TimeOffsetSource::Filter => "estimated in a first pass",
                TimeOffsetSource::Search => {
                    "from the turn-matching search (the estimation pass disagreed)"
                }
                TimeOffsetSource::Initial => {
                    "the initial value kept (no significant estimate, events.log)"
                }
            };
            line.push_str(&format!(
                "; GNSS-IMU time offset {:.4} s at t {:.1} (1-sigma {:.4}), rate {:.1} ppm (1-sigma {:.1}), {how}; output times are GNSS time",
                f.tau0, f.t0, f.tau0_sd, f.rate * 1e6, f.rate_sd * 1e6
            ));
        }
        let names: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
        if !names.is_empty() {
            line.push_str(&format!("; wrote {}", names.join(", ")));
        }
        line
    }
}
