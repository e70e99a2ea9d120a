//! The batch's tables: batch.csv and batch.json (one row per case, deterministic:
//! no wall times; numbers in Rust's shortest round-trip form, so that they read back
//! bit for bit) and batch_timing.csv (each case's wall time).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use serde_json::{json, Map, Value};

use super::{BatchResult, CaseRow, METRICS};

/// Write `out`/batch.csv, batch.json and batch_timing.csv (`out` created if missing).
pub fn write_tables(out: &Path, r: &BatchResult) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    write(&out.join("batch.csv"), &to_csv(&r.rows))?;
    let json = serde_json::to_string_pretty(&to_json(&r.rows))? + "\n";
    write(&out.join("batch.json"), &json)?;
    write(&out.join("batch_timing.csv"), &timing_csv(r))
}

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// A CSV field: quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// index,name,seed,status,epochs,<METRICS...>,error; empty where a case has no value.
fn to_csv(rows: &[CaseRow]) -> String {
    let mut t = String::from("index,name,seed,status,epochs");
    for (m, _) in METRICS {
        t.push(',');
        t.push_str(m);
    }
    t.push_str(",error\n");
    for r in rows {
        let seed = r.seed.map_or(String::new(), |s| s.to_string());
        let _ = write!(
            t,
            "{},{},{seed},{},{}",
            r.index,
            field(&r.name),
            field(&r.status),
            r.epochs
        );
        for (m, _) in METRICS {
            t.push(',');
            if let Some(v) = r.metric(m) {
                let _ = write!(t, "{v}");
            }
        }
        t.push(',');
        t.push_str(&field(r.error.as_deref().unwrap_or_default()));
        t.push('\n');
    }
    t
}

/// `{"cases", "failed", "metrics": {name: meaning}, "rows": [...]}`; a row's
/// `metrics` has every figure, null where the case has none.
fn to_json(rows: &[CaseRow]) -> Value {
    let legend: Map<String, Value> = METRICS
        .iter()
        .map(|(k, v)| (k.to_string(), json!(v)))
        .collect();
    let rows: Vec<Value> = rows
        .iter()
        .map(|r| {
            let metrics: Map<String, Value> = METRICS
                .iter()
                .map(|(k, _)| (k.to_string(), json!(r.metric(k))))
                .collect();
            json!({
                "index": r.index,
                "name": r.name,
                "seed": r.seed,
                "status": r.status,
                "error": r.error,
                "epochs": r.epochs,
                "metrics": metrics,
            })
        })
        .collect();
    json!({
        "cases": rows.len(),
        "failed": rows.iter().filter(|r| r["status"] != "completed" && r["status"] != "unreliable").count(),
        "unreliable": rows.iter().filter(|r| r["status"] == "unreliable").count(),
        "metrics": legend,
        "rows": rows,
    })
}

/// index,name,wall_s.
fn timing_csv(r: &BatchResult) -> String {
    let mut t = String::from("index,name,wall_s\n");
    for (row, w) in r.rows.iter().zip(&r.wall_s) {
        let _ = writeln!(t, "{},{},{w}", row.index, field(&row.name));
    }
    t
}
