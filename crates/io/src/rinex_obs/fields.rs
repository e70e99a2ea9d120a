//! Fixed-column field parsers shared by the RINEX 2 and 3 readers, and the
//! `RINEX VERSION / TYPE` check.

use super::crx::CrxDecoder;
use crate::error::InputError;
use crate::fmt::{LineReader, BUF_CAPACITY};
use crate::rinex_nav::cols;
use flate2::bufread::MultiGzDecoder;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

pub(super) fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).trim().to_string()
}

pub(super) fn int_field(
    path: &Path,
    ln: usize,
    name: &str,
    b: &[u8],
    lo: i64,
    hi: i64,
) -> Result<i64, InputError> {
    let t = text(b);
    match t.parse::<i64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        Ok(v) => Err(InputError::at_field(
            path,
            ln,
            name,
            format!("expected {lo}..{hi}, found {v}"),
        )),
        Err(_) => Err(InputError::at_field(
            path,
            ln,
            name,
            format!("expected an integer, found \"{t}\""),
        )),
    }
}

pub(super) fn f64_field(
    path: &Path,
    ln: usize,
    name: &str,
    b: &[u8],
) -> Result<Option<f64>, InputError> {
    let t = text(b);
    if t.is_empty() {
        return Ok(None);
    }
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(v) => Err(InputError::not_finite(path, ln, name, v)),
        Err(_) => Err(InputError::not_a_number(path, ln, name, t.as_bytes())),
    }
}

/// A required number: a blank field is an error.
pub(super) fn f64_required(
    path: &Path,
    ln: usize,
    name: &str,
    b: &[u8],
) -> Result<f64, InputError> {
    f64_field(path, ln, name, b)?.ok_or_else(|| {
        InputError::at_field(path, ln, name, "expected a number, found a blank field")
    })
}

/// A loss-of-lock indicator column: blank (0) or a digit 0-7.
pub(super) fn lli_digit(path: &Path, ln: usize, name: &str, b: &[u8]) -> Result<u8, InputError> {
    match b {
        [b' '] | [] => Ok(0),
        [d @ b'0'..=b'7'] => Ok(d - b'0'),
        other => Err(InputError::at_field(
            path,
            ln,
            name,
            format!(
                "expected a blank or a digit 0-7, found \"{}\"",
                String::from_utf8_lossy(other)
            ),
        )),
    }
}

/// Open an observation file, plain, gzip (`1f 8b` magic, any name) or Compact RINEX
/// 1.0 / 3.0 (first line `CRINEX VERS   / TYPE`, expanded by [`super::crx`]), and
/// check its `RINEX VERSION / TYPE` line; returns the reader, the line number and the
/// version. Line numbers of a Compact RINEX file are those of the expanded RINEX
/// text; its decoding errors name the Compact RINEX line.
pub(super) fn open_obs(path: &Path) -> Result<(LineReader, usize, f64), InputError> {
    let file = File::open(path).map_err(|e| InputError::open(path, &e))?;
    if file.metadata().map(|m| m.is_dir()).unwrap_or(false) {
        return Err(InputError::new(path, "cannot open: is a directory"));
    }
    let mut raw = BufReader::with_capacity(BUF_CAPACITY, file);
    let gz = raw
        .fill_buf()
        .map_err(|e| InputError::read(path, &e))?
        .starts_with(&[0x1f, 0x8b]);
    let mut bytes: Box<dyn BufRead + Send> = if gz {
        Box::new(BufReader::with_capacity(
            BUF_CAPACITY,
            MultiGzDecoder::new(raw),
        ))
    } else {
        Box::new(raw)
    };
    let head = bytes.fill_buf().map_err(|e| InputError::read(path, &e))?;
    let first = head.split(|&c| c == b'\n').next().unwrap_or(&[]);
    if text(cols(first, 60, 80)).starts_with("CRINEX VERS") {
        bytes = Box::new(BufReader::with_capacity(
            BUF_CAPACITY,
            CrxDecoder::new(bytes),
        ));
    }
    let mut rd = LineReader::from_reader(path, bytes);
    let (ln, first) = match rd.next_line()? {
        Some((ln, l)) => (ln, l.to_vec()),
        None => return Err(InputError::new(path, "empty file: expected a RINEX header")),
    };
    let label = text(cols(&first, 60, 80));
    if label != "RINEX VERSION / TYPE" {
        return Err(InputError::at_line(
            path,
            ln,
            "expected 'RINEX VERSION / TYPE' in columns 61-80 of the first line",
        ));
    }
    let version = f64_required(path, ln, "RINEX version", cols(&first, 0, 9))?;
    let kind = cols(&first, 20, 21);
    if kind != b"O" {
        return Err(InputError::at_field(
            path,
            ln,
            "file type",
            format!(
                "expected an observation file (type O in column 21), found \"{}\"",
                String::from_utf8_lossy(kind)
            ),
        ));
    }
    Ok((rd, ln, version))
}

pub(super) fn unsupported(path: &Path, ln: usize, version: f64, supported: &str) -> InputError {
    InputError::at_field(
        path,
        ln,
        "RINEX version",
        format!("version {version} is not supported ({supported})"),
    )
}
