//! RTKLIB TIMETAG files (`*.tag` beside a logged stream), little-endian binary:
//!
//! | bytes | content |
//! |---|---|
//! | 0-59 | ASCII id, NUL padded (`TIMETAG RTKLIB demo5`, `TIMETAG RTKLIB EX` ...) |
//! | 60-63 | u32 tick (ms) at log start |
//! | 64-67 | u32 whole seconds, GPST as Unix time (no leap seconds) of log start |
//! | 68-75 | f64 fraction of a second of the log start |
//! | 76-   | records of (u32 ms since log start, u32 byte offset in the data file) |
//!
//! A trailing partial record (fewer than 8 bytes) is ignored, as RTKLIB does.

use crate::error::InputError;
use crate::time::gpst_unix_parts_to_week_sow;
use std::path::{Path, PathBuf};

const HEADER_LEN: usize = 76;
const RECORD_LEN: usize = 8;

/// What a TIMETAG file says.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeTag {
    pub path: PathBuf,
    /// The ASCII id, NULs and trailing spaces removed.
    pub id: String,
    /// Tick (ms) of the logging computer at log start.
    pub start_tick: u32,
    /// Log start, GPST as Unix seconds: whole part.
    pub start_unix_whole: u32,
    /// Log start: fraction of a second, in [0, 1).
    pub start_unix_frac: f64,
    /// GPS week of the log start.
    pub start_week: u32,
    /// Seconds of that week at the log start.
    pub start_sow: f64,
    /// Number of complete (tick, offset) records.
    pub records: usize,
    /// Tick of the first record [ms since log start].
    pub first_tick_ms: u32,
    /// Tick of the last record [ms since log start].
    pub last_tick_ms: u32,
    /// Byte offset of the last record in the data file.
    pub last_offset: u32,
    /// Bytes after the last complete record (a partial record, ignored).
    pub trailing_bytes: usize,
}

impl TimeTag {
    /// Log start as GPST-as-Unix seconds (f64: about 0.2 microsecond resolution).
    pub fn start_unix(&self) -> f64 {
        f64::from(self.start_unix_whole) + self.start_unix_frac
    }
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
    Some(u32::from_le_bytes(s))
}

fn f64_at(b: &[u8], at: usize) -> Option<f64> {
    let s: [u8; 8] = b.get(at..at + 8)?.try_into().ok()?;
    Some(f64::from_le_bytes(s))
}

/// Read and check a TIMETAG file: the id must start with `TIMETAG`, the start time
/// must be a valid GPST after the GPS epoch with a fraction in [0, 1), there must be at
/// least one record, and record ticks must not decrease.
pub fn read_timetag(path: &Path) -> Result<TimeTag, InputError> {
    let bytes = std::fs::read(path).map_err(|e| InputError::open(path, &e))?;
    if bytes.len() < HEADER_LEN {
        return Err(InputError::new(
            path,
            format!(
                "expected a TIMETAG file of at least {HEADER_LEN} bytes (60-byte id, tick, \
                 start time), found {} bytes",
                bytes.len()
            ),
        ));
    }
    let id_bytes = bytes.get(..60).unwrap_or(&[]);
    if !id_bytes.starts_with(b"TIMETAG") {
        return Err(InputError::new(
            path,
            format!(
                "expected the id \"TIMETAG ...\" at byte 0, found \"{}\"",
                crate::error::shorten(id_bytes.split(|&b| b == 0).next().unwrap_or(&[]))
            ),
        )
        .with_field("id"));
    }
    let id = String::from_utf8_lossy(id_bytes)
        .trim_end_matches(['\0', ' '])
        .to_string();
    let bad_header = || InputError::new(path, "truncated header");
    let start_tick = u32_at(&bytes, 60).ok_or_else(bad_header)?;
    let whole = u32_at(&bytes, 64).ok_or_else(bad_header)?;
    let frac = f64_at(&bytes, 68).ok_or_else(bad_header)?;
    if !(frac.is_finite() && (0.0..1.0).contains(&frac)) {
        return Err(InputError::new(
            path,
            format!("expected a start-time fraction in [0, 1) at byte 68, found {frac}"),
        )
        .with_field("start time"));
    }
    let (start_week, start_sow) =
        gpst_unix_parts_to_week_sow(i64::from(whole), frac).ok_or_else(|| {
            InputError::new(
                path,
                format!(
                    "start time {whole} s (GPST as Unix seconds) is before the GPS epoch \
                     (315964800)"
                ),
            )
            .with_field("start time")
        })?;
    let body = bytes.get(HEADER_LEN..).unwrap_or(&[]);
    let records = body.len() / RECORD_LEN;
    let trailing_bytes = body.len() % RECORD_LEN;
    if records == 0 {
        return Err(InputError::new(
            path,
            "expected at least one (tick, offset) record after the 76-byte header, found none",
        ));
    }
    let mut prev: Option<u32> = None;
    let mut first_tick_ms = 0;
    let mut last_tick_ms = 0;
    let mut last_offset = 0;
    for (k, rec) in body.chunks_exact(RECORD_LEN).enumerate() {
        let tick = u32_at(rec, 0).unwrap_or(0);
        let off = u32_at(rec, 4).unwrap_or(0);
        if let Some(p) = prev {
            if tick < p {
                return Err(InputError::new(
                    path,
                    format!("tick {tick} ms goes backwards (previous {p} ms)"),
                )
                .with_field(format!(
                    "record {} (byte {})",
                    k + 1,
                    HEADER_LEN + k * RECORD_LEN
                )));
            }
        } else {
            first_tick_ms = tick;
        }
        prev = Some(tick);
        last_tick_ms = tick;
        last_offset = off;
    }
    Ok(TimeTag {
        path: path.to_path_buf(),
        id,
        start_tick,
        start_unix_whole: whole,
        start_unix_frac: frac,
        start_week,
        start_sow,
        records,
        first_tick_ms,
        last_tick_ms,
        last_offset,
        trailing_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tag_bytes(id: &[u8], whole: u32, frac: f64, recs: &[(u32, u32)]) -> Vec<u8> {
        let mut b = vec![0u8; 60];
        b[..id.len()].copy_from_slice(id);
        b.extend_from_slice(&7u32.to_le_bytes());
        b.extend_from_slice(&whole.to_le_bytes());
        b.extend_from_slice(&frac.to_le_bytes());
        for &(t, o) in recs {
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&o.to_le_bytes());
        }
        b
    }

    fn write_tmp(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("navfuse-timetag-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn reads_synthetic_tag() {
        // 2025-07-08 19:34:21.854 GPST = week 2374, sow 243261.854.
        let whole = (315_964_800i64 + 2374 * 604_800 + 243_261) as u32;
        let mut b = tag_bytes(
            b"TIMETAG RTKLIB demo5",
            whole,
            0.854,
            &[(0, 0), (10, 37), (548_731, 99)],
        );
        b.extend_from_slice(&[1, 2, 3]);
        let p = write_tmp("ok.tag", &b);
        let t = read_timetag(&p).unwrap();
        assert_eq!(t.id, "TIMETAG RTKLIB demo5");
        assert_eq!(t.start_tick, 7);
        assert_eq!(t.start_week, 2374);
        assert!((t.start_sow - 243_261.854).abs() < 1e-9);
        assert_eq!(t.records, 3);
        assert_eq!(t.last_tick_ms, 548_731);
        assert_eq!(t.trailing_bytes, 3);
    }

    #[test]
    fn rejects_bad_files() {
        let p = write_tmp("short.tag", b"TIMETAG");
        let e = read_timetag(&p).unwrap_err().to_string();
        assert!(
            e.contains("at least 76 bytes") && e.contains("found 7 bytes"),
            "{e}"
        );

        let p = write_tmp(
            "id.tag",
            &tag_bytes(b"HELLO", 1_500_000_000, 0.0, &[(0, 0)]),
        );
        let e = read_timetag(&p).unwrap_err().to_string();
        assert!(e.contains("field 'id'") && e.contains("HELLO"), "{e}");

        let p = write_tmp(
            "frac.tag",
            &tag_bytes(b"TIMETAG", 1_500_000_000, 1.5, &[(0, 0)]),
        );
        let e = read_timetag(&p).unwrap_err().to_string();
        assert!(e.contains("fraction"), "{e}");

        let p = write_tmp("norec.tag", &tag_bytes(b"TIMETAG", 1_500_000_000, 0.0, &[]));
        let e = read_timetag(&p).unwrap_err().to_string();
        assert!(e.contains("at least one"), "{e}");

        let p = write_tmp("early.tag", &tag_bytes(b"TIMETAG", 1000, 0.0, &[(0, 0)]));
        let e = read_timetag(&p).unwrap_err().to_string();
        assert!(e.contains("before the GPS epoch"), "{e}");

        let p = write_tmp(
            "back.tag",
            &tag_bytes(b"TIMETAG", 1_500_000_000, 0.0, &[(5, 0), (4, 0)]),
        );
        let e = read_timetag(&p).unwrap_err().to_string();
        assert!(
            e.contains("record 2") && e.contains("goes backwards"),
            "{e}"
        );

        let e = read_timetag(Path::new("/nonexistent/x.tag"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot open: No such file or directory"), "{e}");
    }
}
