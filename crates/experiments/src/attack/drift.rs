//! `--attack`: the drift attack on scenarios/seed004_attack.toml, every variant on
//! the same data per seed, and its tables.

use anyhow::{anyhow, Context, Result};
use navfuse_core::eval::{evaluate, EvalOptions};
use navfuse_core::integrity::IntegrityState;
use navfuse_core::outage::Window;
use serde_json::{json, Value};

use super::reaction::{nan_or, reaction, transition_rows};
use super::variants::{attack_window_rel, variants};
use super::{navigate, simulate, AFTER_S, ATTACK_SCENARIO, ATTACK_TEXT};
use crate::reproduce::{spread, variant_list, Variant, MAX_WIDTH};
use crate::scenarios::builtin;
use crate::track::load_nav;
use crate::work::WorkDir;
use navfuse_io::table::{wrap_text, TextTable};

/// The metrics of the attack tables: (key, column header, legend, decimals). Counts
/// have 1 decimal (a mean over seeds). The first [`MONITOR_ROWS`] exist only for
/// variants with a monitor.
pub(super) const ROWS: [(&str, &str, &str, usize); 11] = [
    (
        "alarms_before",
        "alarms",
        "alarms before the attack (transitions out of trusted)",
        1,
    ),
    (
        "spoofed_before",
        "spoofed",
        "declared spoofed before the attack",
        1,
    ),
    (
        "delay_s",
        "delay [s]",
        "detection delay after the attack start",
        1,
    ),
    (
        "spoofed_delay_s",
        "spoof [s]",
        "declared spoofed, this long after the attack start",
        1,
    ),
    (
        "readmitted_during",
        "readmit",
        "GNSS re-admitted during the attack",
        1,
    ),
    (
        "trusted_after_end_s",
        "trust [s]",
        "trusted again, this long after the attack end",
        1,
    ),
    (
        "max_h_attack_m",
        "H attack [m]",
        "max horizontal error during the attack",
        2,
    ),
    (
        "max_3d_attack_m",
        "3D attack [m]",
        "max 3D error during the attack",
        2,
    ),
    (
        "max_h_after_m",
        "H after [m]",
        "max horizontal error in the 60 s after the attack",
        2,
    ),
    (
        "max_3d_after_m",
        "3D after [m]",
        "max 3D error in the 60 s after the attack",
        2,
    ),
    ("rmse_3d_m", "RMSE 3D [m]", "3D RMSE over the run", 2),
];
/// ROWS[..MONITOR_ROWS] are the monitor's figures ("-" without a monitor).
pub(super) const MONITOR_ROWS: usize = 6;

/// One variant on one seed.
#[derive(Clone, Debug)]
pub(super) struct VariantRun {
    pub(super) monitor: bool,
    /// ROWS values; NaN = not applicable / did not happen.
    pub(super) values: Vec<(&'static str, f64)>,
    pub(super) detector: Option<String>,
    /// (t from the start, from, to, detector, statistic, threshold).
    pub(super) transitions: Vec<(f64, String, String, String, f64, f64)>,
}

impl VariantRun {
    fn get(&self, k: &str) -> f64 {
        self.values
            .iter()
            .find(|(n, _)| *n == k)
            .map_or(f64::NAN, |(_, v)| *v)
    }
}

/// Seed 004's attack scenario with this seed: every variant.
pub(super) fn attack_seed(seed: u64, work: &WorkDir, quiet: bool) -> Result<Vec<VariantRun>> {
    let dir = work.path().join(format!("seed004_attack_seed{seed}"));
    let mut sc = builtin(ATTACK_SCENARIO, ATTACK_TEXT)?;
    sc.file.seed = seed;
    simulate(&sc, &dir)?;
    let truth = load_nav(&dir.join("truth.nav"))?.points;
    let t0 = sc.file.start.time_s;
    let (a_rel, b_rel) =
        attack_window_rel(&sc).ok_or_else(|| anyhow!("{ATTACK_SCENARIO}: no spoof event"))?;
    let (a, b) = (t0 + a_rel, t0 + b_rel);
    let mut runs = Vec::new();
    for v in variants() {
        let t_run = std::time::Instant::now();
        let out = dir.join(v.name);
        let run = navigate(&dir, &sc, v.apply, work, &out)
            .with_context(|| format!("seed004 --attack seed {seed}: variant {}", v.name))?;
        let (monitor, trs) = (run.monitor, run.transitions);
        let sol = run.nav.track().points;
        let rep = evaluate(
            &sol,
            &truth,
            &EvalOptions {
                gaps: vec![
                    Window { start: a, end: b },
                    Window {
                        start: b,
                        end: b + AFTER_S,
                    },
                ],
                ..EvalOptions::default()
            },
        );
        let gap = |k: usize| rep.gaps.get(k);
        let r = reaction(&trs, a, b);
        let m = |x: Option<f64>| if monitor { nan_or(x) } else { f64::NAN };
        let c = |x: usize| if monitor { x as f64 } else { f64::NAN };
        let values = vec![
            ("alarms_before", c(r.alarms_before)),
            ("spoofed_before", c(r.spoofed_before)),
            ("delay_s", m(r.delay_s)),
            ("spoofed_delay_s", m(r.spoofed_delay_s)),
            ("readmitted_during", c(r.readmitted_during)),
            ("trusted_after_end_s", m(r.trusted_after_end_s)),
            ("max_h_attack_m", nan_or(gap(0).map(|g| g.max_horizontal))),
            ("max_3d_attack_m", nan_or(gap(0).map(|g| g.max_3d))),
            ("max_h_after_m", nan_or(gap(1).map(|g| g.max_horizontal))),
            ("max_3d_after_m", nan_or(gap(1).map(|g| g.max_3d))),
            ("rmse_3d_m", rep.pos_3d.rms),
        ];
        let run = VariantRun {
            monitor,
            values,
            detector: r.detector.clone(),
            transitions: transition_rows(&trs, t0),
        };
        if !quiet {
            let first_early = trs
                .iter()
                .find(|tr| tr.t < a && tr.from == IntegrityState::Trusted)
                .map(|tr| format!(", first at {:.0} s ({})", tr.t - t0, tr.detector.name()))
                .unwrap_or_default();
            eprintln!(
                "  seed004 --attack seed {seed} {:<17} {}; max H attack {:7.2} m, after {:7.2} m; 3D RMSE {:7.2} m ({:.2} s)",
                v.name,
                if monitor {
                    format!(
                        "alarms before {}{first_early}, detected {}",
                        r.alarms_before,
                        match (&r.delay_s, &r.detector) {
                            (Some(d), Some(det)) => format!("after {d:.0} s by {det}"),
                            _ => "never".into(),
                        }
                    )
                } else {
                    "no monitor".into()
                },
                run.get("max_h_attack_m"),
                run.get("max_h_after_m"),
                run.get("rmse_3d_m"),
                t_run.elapsed().as_secs_f64()
            );
        }
        runs.push(run);
    }
    if !work.keep() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(runs)
}

/// Per variant, per seed.
pub(super) struct AttackResults {
    pub(super) seeds: Vec<u64>,
    pub(super) attack_rel: (f64, f64),
    pub(super) per_variant: Vec<(Variant, Vec<VariantRun>)>,
}

impl AttackResults {
    fn runs(&self, name: &str) -> &[VariantRun] {
        self.per_variant
            .iter()
            .find(|(v, _)| v.name == name)
            .map_or(&[], |(_, r)| r.as_slice())
    }

    fn finite(&self, name: &str, key: &str) -> Vec<f64> {
        self.runs(name)
            .iter()
            .map(|r| r.get(key))
            .filter(|x| x.is_finite())
            .collect()
    }
}

/// "mean [min, max]" of the finite values, "(k/n)" when some are missing, "-" when
/// none is finite.
pub(super) fn cell(xs: &[f64], n: usize, dec: usize) -> String {
    if xs.is_empty() {
        return if n == 0 {
            "-".into()
        } else {
            format!("- (0/{n})")
        };
    }
    let (mean, lo, hi) = spread(xs);
    let mut s = if xs.len() == 1 || lo == hi {
        format!("{mean:.dec$}")
    } else {
        format!("{mean:.dec$} [{lo:.dec$}, {hi:.dec$}]")
    };
    if xs.len() < n {
        s.push_str(&format!(" ({}/{n})", xs.len()));
    }
    s
}

/// The detectors that detected, with counts: "window x3, chi2".
pub(super) fn detectors(runs: &[VariantRun]) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for d in runs.iter().filter_map(|r| r.detector.clone()) {
        match counts.iter_mut().find(|(n, _)| *n == d) {
            Some((_, k)) => *k += 1,
            None => counts.push((d, 1)),
        }
    }
    if counts.is_empty() {
        return "-".into();
    }
    counts
        .iter()
        .map(|(d, k)| {
            if *k > 1 {
                format!("{d} x{k}")
            } else {
                d.clone()
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The paper's statements (SYSTEM.md §7 seed 004 row; §5) and what we measured.
pub(super) fn paper_lines(r: &AttackResults) -> Vec<(&'static str, String)> {
    let n = r.seeds.len();
    let c = |v: &str, k: &str, dec: usize| cell(&r.finite(v, k), n, dec);
    let any = |v: &str, k: &str| {
        r.runs(v)
            .iter()
            .filter(|x| x.get(k).is_finite() && x.get(k) > 0.0)
            .count()
    };
    let detected = |v: &str| r.finite(v, "delay_s").len();
    vec![
        (
            "§7: spoofed segment detected with R = 10 m",
            format!(
                "monitor_R: detected in {}/{n} seeds, after {} s ({}); alarms before the attack {}",
                detected("monitor_R"),
                c("monitor_R", "delay_s", 1),
                detectors(r.runs("monitor_R")),
                c("monitor_R", "alarms_before", 1)
            ),
        ),
        (
            "§7: ... and bridged by INS/odometer",
            format!(
                "max horizontal error during the attack: monitor_R {} m, monitor {} m, dead_reckoning {} m, no_monitor {} m",
                c("monitor_R", "max_h_attack_m", 1),
                c("monitor", "max_h_attack_m", 1),
                c("dead_reckoning", "max_h_attack_m", 1),
                c("no_monitor", "max_h_attack_m", 1)
            ),
        ),
        (
            "§7: after 6 min INS/odometer stays 3.1 m from GNSS (INS alone 72 m)",
            format!(
                "dead_reckoning over the {:.0} s attack: max horizontal {} m",
                r.attack_rel.1 - r.attack_rel.0,
                c("dead_reckoning", "max_h_attack_m", 1)
            ),
        ),
        (
            "§5: with INS alone, drift exceeds R before the attack and gives false alarms",
            format!(
                "ins_only_R: alarms before the attack {} (seeds with any: {}/{n}); detected {}/{n}",
                c("ins_only_R", "alarms_before", 1),
                any("ins_only_R", "alarms_before"),
                detected("ins_only_R")
            ),
        ),
        (
            "§5: with the odometer the reference stays tight",
            format!(
                "monitor_R: alarms before the attack {} (seeds with any: {}/{n})",
                c("monitor_R", "alarms_before", 1),
                any("monitor_R", "alarms_before")
            ),
        ),
        (
            "§5: a chi-square test with the filter's covariance generalises R",
            format!(
                "ins_only_chi2: alarms before {} (seeds with any: {}/{n}), detected {}/{n} after {} s; monitor: alarms before {}, detected after {} s ({})",
                c("ins_only_chi2", "alarms_before", 1),
                any("ins_only_chi2", "alarms_before"),
                detected("ins_only_chi2"),
                c("ins_only_chi2", "delay_s", 1),
                c("monitor", "alarms_before", 1),
                c("monitor", "delay_s", 1),
                detectors(r.runs("monitor"))
            ),
        ),
    ]
}

pub(super) fn attack_text(r: &AttackResults) -> String {
    let n = r.seeds.len();
    let mut s = wrap_text(
        &format!(
            "Seed 004 spoofing: car, IMU500 + odometer + GNSS 1 Hz, two laps of the 3010 m loop; \
             drift attack 2 m/s east from {:.0} s to {:.0} s",
            r.attack_rel.0, r.attack_rel.1
        ),
        MAX_WIDTH,
        "",
        "  ",
    );
    s.push_str(&wrap_text(
        &format!(
            "scenario {ATTACK_SCENARIO}, seeds {:?}; mean [min, max] over seeds, (k/n) = seeds \
             where it happened; alarm = a transition out of trusted",
            r.seeds
        ),
        MAX_WIDTH,
        "",
        "  ",
    ));
    s.push('\n');
    s.push_str(&variant_list(r.per_variant.iter().map(|(v, _)| v)));
    s.push('\n');
    // Two tables, detection then errors, each a row per variant.
    let mut detection: Vec<String> = vec!["variant".into()];
    for (k, (_, header, _, _)) in ROWS[..MONITOR_ROWS].iter().enumerate() {
        detection.push(header.to_string());
        if k == 2 {
            detection.push("detector".into());
        }
    }
    // The detector names are text.
    let mut det = TextTable::new(detection).left_aligned(&[4]);
    let mut err =
        TextTable::new(std::iter::once("variant").chain(ROWS[MONITOR_ROWS..].iter().map(|r| r.1)));
    for (v, runs) in &r.per_variant {
        let monitor = runs.iter().any(|x| x.monitor);
        let value = |key: &str, dec: usize| cell(&r.finite(v.name, key), n, dec);
        let mut row = vec![v.name.to_string()];
        for (k, (key, _, _, dec)) in ROWS[..MONITOR_ROWS].iter().enumerate() {
            row.push(if monitor {
                value(key, *dec)
            } else {
                "-".into()
            });
            if k == 2 {
                row.push(if monitor { detectors(runs) } else { "-".into() });
            }
        }
        det.row(row);
        let mut row = vec![v.name.to_string()];
        row.extend(
            ROWS[MONITOR_ROWS..]
                .iter()
                .map(|(key, _, _, dec)| value(key, *dec)),
        );
        err.row(row);
    }
    s.push_str("detection (- = no monitor):\n");
    s.push_str(&det.render_wrapped(MAX_WIDTH));
    s.push_str("\nerrors:\n");
    s.push_str(&err.render_wrapped(MAX_WIDTH));
    s.push_str("\ncolumns:\n");
    for (k, (_, header, legend, _)) in ROWS.iter().enumerate() {
        s.push_str(&format!("  {header}: {legend}\n"));
        if k == 2 {
            s.push_str("  detector: the detector that raised the alarm (x N: in N seeds)\n");
        }
    }
    s.push_str("\npaper (SYSTEM.md §7 seed 004 row, §5) and ours:\n");
    for (p, ours) in paper_lines(r) {
        s.push_str(&wrap_text(p, MAX_WIDTH, "  ", "    "));
        s.push_str(&wrap_text(&ours, MAX_WIDTH, "      ours: ", "            "));
    }
    s
}

pub(super) fn attack_json(r: &AttackResults) -> Value {
    let variants: Vec<Value> = r
        .per_variant
        .iter()
        .map(|(v, runs)| {
            let mut metrics = serde_json::Map::new();
            for (key, _, _, _) in ROWS {
                let per_seed: Vec<Value> = runs
                    .iter()
                    .map(|x| {
                        let y = x.get(key);
                        if y.is_finite() {
                            json!(y)
                        } else {
                            Value::Null
                        }
                    })
                    .collect();
                let xs = r.finite(v.name, key);
                let (mean, min, max) = if xs.is_empty() {
                    (f64::NAN, f64::NAN, f64::NAN)
                } else {
                    spread(&xs)
                };
                let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
                metrics.insert(
                    key.to_string(),
                    json!({"mean": num(mean), "min": num(min), "max": num(max), "per_seed": per_seed}),
                );
            }
            let per_seed_transitions: Vec<Value> = runs
                .iter()
                .map(|x| {
                    Value::Array(
                        x.transitions
                            .iter()
                            .map(|(t, from, to, d, st, th)| {
                                json!({"t_s": t, "from": from, "to": to, "detector": d,
                                       "statistic": st, "threshold": if th.is_finite() { json!(th) } else { Value::Null }})
                            })
                            .collect(),
                    )
                })
                .collect();
            json!({"name": v.name, "label": v.label, "monitor": runs.iter().any(|x| x.monitor),
                   "detector_per_seed": runs.iter().map(|x| x.detector.clone()).collect::<Vec<_>>(),
                   "metrics": metrics, "transitions_per_seed": per_seed_transitions})
        })
        .collect();
    let paper: Vec<Value> = paper_lines(r)
        .into_iter()
        .map(|(p, o)| json!({"paper": p, "ours": o}))
        .collect();
    json!({"scenario": ATTACK_SCENARIO, "seeds": r.seeds,
           "attack": {"mode": "drift", "velocity_mps": [0.0, 2.0, 0.0],
                      "start_s": r.attack_rel.0, "end_s": r.attack_rel.1},
           "variants": variants, "paper": paper})
}

#[cfg(test)]
mod tests {
    use super::*;
    use navfuse_io::table::max_line_width;

    /// Results as `--seeds n` could give them, without running anything: wide cells
    /// (mean [min, max] (k/n)) on every variant.
    fn results(n: usize) -> AttackResults {
        let per_variant = variants()
            .into_iter()
            .enumerate()
            .map(|(k, v)| {
                let runs = (0..n)
                    .map(|s| VariantRun {
                        monitor: k % 3 != 0,
                        values: ROWS
                            .iter()
                            .map(|(key, ..)| {
                                (*key, if s == 0 { f64::NAN } else { 600.5 + s as f64 })
                            })
                            .collect(),
                        detector: Some("already spoofed".into()),
                        transitions: vec![],
                    })
                    .collect();
                (v, runs)
            })
            .collect();
        AttackResults {
            seeds: (1..=n as u64).collect(),
            attack_rel: (150.0, 450.0),
            per_variant,
        }
    }

    #[test]
    fn attack_tables_fit_in_100_columns() {
        for n in [1, 4] {
            let s = attack_text(&results(n));
            assert!(max_line_width(&s) <= MAX_WIDTH, "{s}");
            // Every metric's header is printed, with its legend line.
            for (_, header, legend, _) in ROWS {
                assert!(s.contains(&format!("  {header}: {legend}")), "{header}");
            }
            // Cells are apart: "600.500" never touches the next value.
            assert!(!s.contains("]6") && !s.contains(")6"), "{s}");
        }
    }
}
