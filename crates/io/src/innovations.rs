//! `innovations.csv` (docs/FORMATS.md "Innovations"): every update an aiding source
//! tried, with its normalised innovation squared, its gate and how it ended. The HTML
//! report plots it per source.

use crate::error::InputError;
use crate::nav::Out;
use navfuse_core::events::{InnovationRow, UpdateKind};
use std::path::Path;

const HEADER: &str = "t_s,source,rows,y1,y2,y3,nis,gate,outcome\n";

/// Writes `innovations.csv`.
pub struct InnovationWriter {
    out: Out,
}

impl InnovationWriter {
    pub fn create(path: &Path) -> Result<Self, InputError> {
        let mut out = Out::create(path)?;
        out.line.extend_from_slice(HEADER.as_bytes());
        out.put()?;
        Ok(InnovationWriter { out })
    }

    pub fn write(&mut self, r: &InnovationRow) -> Result<(), InputError> {
        use std::io::Write;
        let line = &mut self.out.line;
        let opt = |v: f64| {
            if v.is_finite() {
                format!("{v:.6}")
            } else {
                String::new()
            }
        };
        let _ = writeln!(
            line,
            "{:.4},{},{},{},{},{},{},{},{}",
            r.t,
            r.source,
            r.rows,
            opt(r.innovation[0]),
            opt(r.innovation[1]),
            opt(r.innovation[2]),
            if r.nis.is_finite() {
                format!("{:.4}", r.nis)
            } else {
                String::new()
            },
            r.gate.map_or(String::new(), |g| format!("{g:.4}")),
            r.outcome.name()
        );
        self.out.put()
    }

    /// Flush and close.
    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// One row of `innovations.csv` as read back (the source name owned).
#[derive(Clone, Debug, PartialEq)]
pub struct InnovationRecord {
    pub t: f64,
    pub source: String,
    pub rows: usize,
    pub innovation: [f64; 3],
    pub nis: f64,
    pub gate: Option<f64>,
    pub outcome: UpdateKind,
}

/// Read `innovations.csv`; errors name the line and field.
pub fn read_innovations(path: &Path) -> Result<Vec<InnovationRecord>, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::open(path, &e))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let no = i + 1;
        if no == 1 {
            if line.trim() != HEADER.trim() {
                return Err(InputError::at_line(
                    path,
                    no,
                    format!("header is `{line}`; expected `{}`", HEADER.trim()),
                ));
            }
            continue;
        }
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 9 {
            return Err(InputError::at_line(
                path,
                no,
                format!("{} fields; expected 9 ({})", f.len(), HEADER.trim()),
            ));
        }
        let num = |k: usize, name: &str| -> Result<f64, InputError> {
            if f[k].is_empty() {
                return Ok(f64::NAN);
            }
            f[k].parse::<f64>().map_err(|_| {
                InputError::at_line(
                    path,
                    no,
                    format!("field {name} = `{}` is not a number", f[k]),
                )
            })
        };
        let t = num(0, "t_s")?;
        if !t.is_finite() {
            return Err(InputError::at_line(
                path,
                no,
                "field t_s is empty; expected seconds",
            ));
        }
        let rows = f[2].parse::<usize>().map_err(|_| {
            InputError::at_line(
                path,
                no,
                format!("field rows = `{}`; expected a count", f[2]),
            )
        })?;
        let outcome = match f[8] {
            "applied" => UpdateKind::Applied,
            "rejected" => UpdateKind::Rejected,
            "singular" => UpdateKind::Singular,
            o => {
                return Err(InputError::at_line(
                    path,
                    no,
                    format!("field outcome = `{o}`; expected applied, rejected or singular"),
                ))
            }
        };
        let gate = num(7, "gate")?;
        out.push(InnovationRecord {
            t,
            source: f[1].to_string(),
            rows,
            innovation: [num(3, "y1")?, num(4, "y2")?, num(5, "y3")?],
            nis: num(6, "nis")?,
            gate: gate.is_finite().then_some(gate),
            outcome,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let dir = std::env::temp_dir().join(format!("navfuse_innov_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("innovations.csv");
        let mut w = InnovationWriter::create(&p).unwrap();
        let row = InnovationRow {
            t: 12.5,
            source: "gnss_position",
            rows: 3,
            innovation: [0.25, -1.5, 2.0],
            nis: 4.25,
            gate: Some(11.3449),
            outcome: UpdateKind::Applied,
        };
        w.write(&row).unwrap();
        w.write(&InnovationRow {
            rows: 1,
            innovation: [3.0, f64::NAN, f64::NAN],
            nis: f64::NAN,
            gate: None,
            outcome: UpdateKind::Singular,
            source: "odometer",
            ..row
        })
        .unwrap();
        w.finish().unwrap();
        let r = read_innovations(&p).unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].source, "gnss_position");
        assert_eq!(r[0].innovation, [0.25, -1.5, 2.0]);
        assert_eq!(r[0].gate, Some(11.3449));
        assert!(r[1].nis.is_nan() && r[1].gate.is_none() && r[1].innovation[1].is_nan());
        assert_eq!(r[1].outcome, UpdateKind::Singular);
        let text = std::fs::read_to_string(&p)
            .unwrap()
            .replace("singular", "maybe");
        std::fs::write(&p, text).unwrap();
        let e = read_innovations(&p).unwrap_err().to_string();
        assert!(
            e.contains("innovations.csv:3") && e.contains("outcome"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
