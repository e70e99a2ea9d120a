//! The result tables: mean [min, max] over seeds beside the paper's figures, and the
//! improvements (seed 002 eq. 18), as text or JSON.

use serde_json::{json, Value};

use super::{Experiment, Results};

/// Mean, min and max over seeds.
pub(crate) fn spread(xs: &[f64]) -> (f64, f64, f64) {
    let mean = xs.iter().sum::<f64>() / xs.len().max(1) as f64;
    let min = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let max = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (mean, min, max)
}

pub(crate) fn values(r: &Results, variant: &str, metric: &str) -> Vec<f64> {
    r.per_variant
        .iter()
        .find(|(n, _)| *n == variant)
        .map(|(_, ms)| ms.iter().filter_map(|m| m.get(metric)).collect())
        .unwrap_or_default()
}

/// Improvement of the mean (seed 002 eq. 18) and its per-seed range.
pub(crate) fn improvement(r: &Results, metric: &str, base: &str, new: &str) -> (f64, f64, f64) {
    let b = values(r, base, metric);
    let n = values(r, new, metric);
    let (mb, _, _) = spread(&b);
    let (mn, _, _) = spread(&n);
    let per: Vec<f64> = b.iter().zip(&n).map(|(b, n)| (b - n) / b).collect();
    let (_, lo, hi) = spread(&per);
    ((mb - mn) / mb, lo, hi)
}

pub(crate) fn to_text(ex: &Experiment, r: &Results) -> String {
    let mut s = format!("{}\n", ex.title);
    s.push_str(&format!(
        "scenario {}, seeds {:?}; RMSE over the whole run, mean [min, max] over seeds\n\n",
        ex.scenario_name, r.seeds
    ));
    for v in &ex.variants {
        s.push_str(&format!("  {:<14} {}\n", v.name, v.label));
    }
    s.push_str(&format!("\n{:<24}", "metric"));
    for v in &ex.variants {
        s.push_str(&format!("{:>26}", v.name));
    }
    s.push_str("   paper\n");
    for &m in ex.metrics {
        s.push_str(&format!("{m:<24}"));
        for v in &ex.variants {
            let xs = values(r, v.name, m);
            let cell = if xs.is_empty() {
                "n/a".to_string()
            } else {
                let (mean, lo, hi) = spread(&xs);
                format!("{mean:.3} [{lo:.3}, {hi:.3}]")
            };
            s.push_str(&format!("{cell:>26}"));
        }
        let paper: Vec<String> = ex
            .paper
            .iter()
            .filter(|p| p.metric == m)
            .map(|p| format!("{} {}", p.variant, p.value))
            .collect();
        s.push_str(&format!("   {}\n", paper.join(", ")));
    }
    s.push_str("\nimprovement (seed 002 eq. 18), ours vs the paper's claim:\n");
    for (metric, base, new) in improvement_rows(ex) {
        let (imp, lo, hi) = improvement(r, metric, base, new);
        let claim = ex
            .claims
            .iter()
            .find(|c| c.0 == metric && c.1 == base && c.2 == new)
            .map(|c| {
                format!(
                    "  claim >= {:.0} %: {}",
                    c.3 * 100.0,
                    if imp >= c.3 { "met" } else { "NOT met" }
                )
            })
            .unwrap_or_default();
        s.push_str(&format!(
            "  {metric:<16} {base} -> {new}: {:6.1} % (per seed {:.1} .. {:.1} %){claim}\n",
            imp * 100.0,
            lo * 100.0,
            hi * 100.0
        ));
    }
    s
}

/// The claims, then every metric for every variant against the first (base) variant.
pub(crate) fn improvement_rows(ex: &Experiment) -> Vec<(&'static str, &'static str, &'static str)> {
    let base = ex.variants[0].name;
    let mut rows: Vec<_> = ex.claims.iter().map(|c| (c.0, c.1, c.2)).collect();
    for v in &ex.variants[1..] {
        for m in [
            "rmse_3d_m",
            "rmse_yaw_deg",
            "rmse_att3d_deg",
            "end_error_m",
            "mean_3d_m",
        ] {
            if ex.metrics.contains(&m) && !rows.contains(&(m, base, v.name)) {
                rows.push((m, base, v.name));
            }
        }
    }
    rows
}

pub(crate) fn to_json(ex: &Experiment, r: &Results) -> Value {
    let variants: Vec<Value> = ex
        .variants
        .iter()
        .map(|v| {
            let mut metrics = serde_json::Map::new();
            for &m in ex.metrics {
                let xs = values(r, v.name, m);
                let (mean, min, max) = spread(&xs);
                metrics.insert(
                    m.to_string(),
                    json!({"mean": mean, "min": min, "max": max, "per_seed": xs}),
                );
            }
            json!({"name": v.name, "label": v.label, "metrics": metrics})
        })
        .collect();
    let claims: Vec<Value> = ex
        .claims
        .iter()
        .map(|(m, b, n, c)| {
            let (imp, lo, hi) = improvement(r, m, b, n);
            json!({"metric": m, "base": b, "variant": n, "claimed": c, "measured": imp,
                   "per_seed_min": lo, "per_seed_max": hi, "met": imp >= *c})
        })
        .collect();
    let paper: Vec<Value> = ex
        .paper
        .iter()
        .map(|p| json!({"metric": p.metric, "variant": p.variant, "value": p.value}))
        .collect();
    json!({"experiment": ex.id, "title": ex.title, "scenario": ex.scenario_name,
           "seeds": r.seeds, "variants": variants, "claims": claims, "paper": paper})
}
