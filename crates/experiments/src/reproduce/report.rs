//! The result tables: mean [min, max] over seeds beside the paper's figures, and the
//! improvements `(base - variant) / base` (the formula of seed 002 eq. 18; each
//! experiment says what it means for its figures), as text or JSON.

use serde_json::{json, Value};

pub(crate) use navfuse_io::table::MAX_WIDTH;
use navfuse_io::table::{wrap_text, TextTable};

use super::metrics::metric_label;
use super::{Experiment, Results, Variant};

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

/// Improvement of the mean, `(base - new) / base` (seed 002 eq. 18), and its per-seed
/// range.
pub(crate) fn improvement(r: &Results, metric: &str, base: &str, new: &str) -> (f64, f64, f64) {
    let b = values(r, base, metric);
    let n = values(r, new, metric);
    let (mb, _, _) = spread(&b);
    let (mn, _, _) = spread(&n);
    let per: Vec<f64> = b.iter().zip(&n).map(|(b, n)| (b - n) / b).collect();
    let (_, lo, hi) = spread(&per);
    ((mb - mn) / mb, lo, hi)
}

/// Resamples of [`bootstrap_interval`].
const BOOTSTRAP_RESAMPLES: usize = 2000;

/// 95 % percentile bootstrap interval of the improvement of the means over seeds: the
/// seeds drawn with replacement (base and variant of a seed kept together),
/// `(mean(base) - mean(variant)) / mean(base)` of each resample, its 2.5 and 97.5
/// percentiles (Efron & Tibshirani 1993, ch. 13). A fixed generator (SplitMix64), so
/// the same results give the same interval. None for fewer than 2 seeds.
pub(crate) fn bootstrap_interval(base: &[f64], variant: &[f64]) -> Option<(f64, f64)> {
    let n = base.len().min(variant.len());
    if n < 2 {
        return None;
    }
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        // SplitMix64 (Steele, Lea & Flood 2014).
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut imps: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| {
            let (mut sb, mut sv) = (0.0, 0.0);
            for _ in 0..n {
                let k = (next() % n as u64) as usize;
                sb += base[k];
                sv += variant[k];
            }
            (sb - sv) / sb
        })
        .filter(|x| x.is_finite())
        .collect();
    if imps.is_empty() {
        return None;
    }
    imps.sort_by(f64::total_cmp);
    let at = |q: f64| imps[((q * (imps.len() - 1) as f64).round() as usize).min(imps.len() - 1)];
    Some((at(0.025), at(0.975)))
}

/// The bootstrap interval of an improvement row.
pub(crate) fn improvement_interval(
    r: &Results,
    metric: &str,
    base: &str,
    new: &str,
) -> Option<(f64, f64)> {
    bootstrap_interval(&values(r, base, metric), &values(r, new, metric))
}

/// A value for the text tables: 3 decimals below 100, fewer above (the JSON keeps
/// every digit).
pub(crate) fn num(x: f64) -> String {
    match x.abs() {
        a if a < 100.0 => format!("{x:.3}"),
        a if a < 1000.0 => format!("{x:.2}"),
        _ => format!("{x:.1}"),
    }
}

/// "mean [min, max]" over seeds; the mean alone for one seed; "n/a" for none.
fn spread_cell(xs: &[f64]) -> String {
    if xs.is_empty() {
        return "n/a".into();
    }
    let (mean, lo, hi) = spread(xs);
    if xs.len() == 1 {
        num(mean)
    } else {
        format!("{} [{}, {}]", num(mean), num(lo), num(hi))
    }
}

/// The legend of the metric columns: "header: what it is", consecutive columns with
/// the same explanation on one line ("0 s [m] .. 500 s [m]: ...").
pub(crate) fn legend(metrics: &[&str]) -> String {
    let labels: Vec<(String, String)> = metrics.iter().map(|m| metric_label(m)).collect();
    let mut s = String::new();
    let mut k = 0;
    while k < labels.len() {
        let mut j = k;
        while j + 1 < labels.len() && labels[j + 1].1 == labels[k].1 {
            j += 1;
        }
        let name = if j > k {
            format!("{} .. {}", labels[k].0, labels[j].0)
        } else {
            labels[k].0.clone()
        };
        s.push_str(&format!("  {name}: {}\n", labels[k].1));
        k = j + 1;
    }
    s
}

/// The results table: a row per variant (mean [min, max] over seeds), under it the
/// paper's figures for that variant; a column per metric; wrapped to MAX_WIDTH.
fn results_table(ex: &Experiment, r: &Results) -> TextTable {
    let mut header = vec!["variant".to_string()];
    header.extend(ex.metrics.iter().map(|m| metric_label(m).0));
    let mut t = TextTable::new(header);
    for v in &ex.variants {
        let mut row = vec![v.name.to_string()];
        row.extend(
            ex.metrics
                .iter()
                .map(|m| spread_cell(&values(r, v.name, m))),
        );
        t.row(row);
        let paper: Vec<String> = ex
            .metrics
            .iter()
            .map(|m| {
                ex.paper
                    .iter()
                    .find(|p| p.metric == *m && p.variant == v.name)
                    .map_or(String::new(), |p| p.value.to_string())
            })
            .collect();
        if paper.iter().any(|c| !c.is_empty()) {
            let mut row = vec!["  paper".to_string()];
            row.extend(paper);
            t.row(row);
        }
    }
    t
}

/// The improvements (the claims first), ours beside the paper's claim.
fn improvement_table(ex: &Experiment, r: &Results) -> TextTable {
    let mut t = TextTable::new([
        "metric",
        "base -> variant",
        "ours [%]",
        "95 % CI [%]",
        "per seed [%]",
        "claim [%]",
        "claim",
    ])
    .left_aligned(&[1, 6]);
    for (metric, base, new) in improvement_rows(ex) {
        let (imp, lo, hi) = improvement(r, metric, base, new);
        let ci = improvement_interval(r, metric, base, new);
        let claim = ex
            .claims
            .iter()
            .find(|c| c.0 == metric && c.1 == base && c.2 == new);
        t.row([
            metric_label(metric).0,
            format!("{base} -> {new}"),
            format!("{:.1}", imp * 100.0),
            ci.map_or("-".to_string(), |(a, b)| {
                format!("{:.1} .. {:.1}", a * 100.0, b * 100.0)
            }),
            format!("{:.1} .. {:.1}", lo * 100.0, hi * 100.0),
            claim.map_or(String::new(), |c| format!(">= {:.0}", c.3 * 100.0)),
            claim.map_or(String::new(), |c| {
                if imp >= c.3 { "met" } else { "NOT met" }.to_string()
            }),
        ]);
    }
    t
}

/// The variants, a line each: name and what it adds, wrapped to MAX_WIDTH.
pub(crate) fn variant_list<'a>(variants: impl Iterator<Item = &'a Variant> + Clone) -> String {
    let names = variants.clone().map(|v| v.name.len()).max().unwrap_or(0);
    let mut s = String::new();
    for v in variants {
        let first = format!("  {:<names$} ", v.name);
        s.push_str(&wrap_text(
            v.label,
            MAX_WIDTH,
            &first,
            &" ".repeat(names + 3),
        ));
    }
    s
}

pub(crate) fn to_text(ex: &Experiment, r: &Results) -> String {
    let mut s = wrap_text(ex.title, MAX_WIDTH, "", "  ");
    s.push_str(&wrap_text(
        &format!(
            "scenario {}, seeds {:?}; each cell: mean [min, max] over the seeds (one seed: its value)",
            ex.scenario_name, r.seeds
        ),
        MAX_WIDTH,
        "",
        "  ",
    ));
    s.push('\n');
    s.push_str(&variant_list(ex.variants.iter()));
    s.push('\n');
    s.push_str(&results_table(ex, r).render_wrapped(MAX_WIDTH));
    s.push_str("\ncolumns:\n");
    s.push_str(&legend(ex.metrics));
    s.push_str("  paper: the paper's figure (SYSTEM.md §7), where it reports one\n");
    s.push_str("\nimprovement of each variant over the base, ours beside the paper's claim:\n");
    s.push_str(&improvement_table(ex, r).render_wrapped(MAX_WIDTH));
    s.push_str(&wrap_text(
        &format!("improvement = (base - variant) / base {}", ex.improvement),
        MAX_WIDTH,
        "  ",
        "    ",
    ));
    s.push_str(&wrap_text(
        &format!(
            "95 % CI: percentile bootstrap of that improvement over the seeds ({BOOTSTRAP_RESAMPLES} \
             resamples; '-' for one seed); per seed: the range of the seeds' own improvements; \
             claim: met when ours reaches the claimed figure"
        ),
        MAX_WIDTH,
        "  ",
        "    ",
    ));
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
            let ci = improvement_interval(r, m, b, n);
            json!({"metric": m, "base": b, "variant": n, "claimed": c, "measured": imp,
                   "ci95_lo": ci.map(|c| c.0), "ci95_hi": ci.map(|c| c.1),
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

#[cfg(test)]
mod tests {
    use super::super::metrics::Metrics;
    use super::super::papers::experiment;
    use super::*;
    use navfuse_io::table::max_line_width;

    /// Wide values (thousands, three decimals, over several seeds) on every metric of
    /// every variant.
    fn results(ex: &Experiment, seeds: usize) -> Results {
        Results {
            seeds: (1..=seeds as u64).collect(),
            per_variant: ex
                .variants
                .iter()
                .map(|v| {
                    let ms = (0..seeds)
                        .map(|s| Metrics {
                            values: ex
                                .metrics
                                .iter()
                                .map(|m| (*m, 1234.5678 + s as f64))
                                .collect(),
                        })
                        .collect();
                    (v.name, ms)
                })
                .collect(),
        }
    }

    #[test]
    fn tables_fit_in_100_columns_with_columns_apart() {
        for id in [
            "seed000",
            "seed001",
            "seed001_outages",
            "seed002",
            "seed004",
        ] {
            let ex = experiment(id).unwrap();
            for seeds in [1, 4] {
                let s = to_text(&ex, &results(&ex, seeds));
                assert!(max_line_width(&s) <= MAX_WIDTH, "{id}:\n{s}");
                // Values never run together: a value is followed by a space, a
                // bracket or the line end.
                assert!(!s.contains(".61234") && !s.contains("]1234"), "{id}:\n{s}");
                // Every metric has its column and a legend line.
                for m in ex.metrics {
                    assert!(s.contains(&metric_label(m).0), "{id} {m}");
                }
                assert!(s.contains("improvement = (base - variant) / base"));
            }
        }
    }

    #[test]
    fn each_experiment_names_its_own_improvement_source() {
        let footer = |id: &str| experiment(id).unwrap().improvement;
        assert!(footer("seed002").contains("seed 002 eq. 18"));
        assert!(footer("seed000").contains("seed 000"));
        assert!(footer("seed001").contains("seed 001"));
        assert!(footer("seed001_outages").contains("outages included"));
        assert!(footer("seed004").contains("seed 004"));
    }
}
