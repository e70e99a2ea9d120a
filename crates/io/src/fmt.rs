//! Fast text helpers shared by the readers and writers:
//!
//! - [`LineReader`]: buffered line reading into a reused buffer, with line numbers;
//! - [`split_fields`]: field splitting on spaces, tabs and commas;
//! - [`parse_f64`]: decimal parsing with an exact fast path;
//! - [`push_fixed9`] / [`push_kf_field`]: fixed 9-decimal formatting, identical to
//!   `format!("{:.9}", v)`, several times faster.

use crate::error::InputError;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};

/// Capacity of the read and write buffers (1 MiB).
pub(crate) const BUF_CAPACITY: usize = 1 << 20;

/// Longest accepted line (1 MiB, without its line end): longer is an error, so a
/// file without line ends cannot fill the memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Reads a text file line by line into a reused buffer.
pub struct LineReader {
    path: PathBuf,
    reader: Box<dyn BufRead + Send>,
    buf: Vec<u8>,
    line_no: usize,
    /// The line last returned ended with `\n`.
    line_end: bool,
}

impl LineReader {
    /// Open `path`; a missing file gives `cannot open: No such file or directory`.
    pub fn open(path: &Path) -> Result<Self, InputError> {
        let file = File::open(path).map_err(|e| InputError::open(path, &e))?;
        if let Ok(meta) = file.metadata() {
            if meta.is_dir() {
                return Err(InputError::new(path, "cannot open: is a directory"));
            }
        }
        Ok(LineReader::from_reader(
            path,
            Box::new(BufReader::with_capacity(BUF_CAPACITY, file)),
        ))
    }

    /// Lines of any byte stream (a gzip or Compact RINEX decoder), named `path` in
    /// errors.
    pub fn from_reader(path: &Path, reader: Box<dyn BufRead + Send>) -> Self {
        LineReader {
            path: path.to_path_buf(),
            reader,
            buf: Vec::with_capacity(256),
            line_no: 0,
            line_end: true,
        }
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// 1-based number of the line last returned (0 before the first).
    pub fn line_no(&self) -> usize {
        self.line_no
    }

    /// The next line's 1-based number and text without its `\n` / `\r\n`, or None
    /// at the end of the file.
    /// A line longer than [`MAX_LINE_BYTES`] is an error.
    pub fn next_line(&mut self) -> Result<Option<(usize, &[u8])>, InputError> {
        self.buf.clear();
        // Room for the line, `\r\n`, and one byte to detect a longer line.
        let limit = MAX_LINE_BYTES as u64 + 3;
        let n = (&mut self.reader)
            .take(limit)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| InputError::read(&self.path, &e).with_line(self.line_no + 1))?;
        if n == 0 {
            return Ok(None);
        }
        self.line_no += 1;
        self.line_end = self.buf.last() == Some(&b'\n');
        let content = self.buf.len()
            - match self.buf.as_slice() {
                [.., b'\r', b'\n'] => 2,
                [.., b'\n'] => 1,
                _ => 0,
            };
        if content > MAX_LINE_BYTES {
            return Err(InputError::at_line(
                &self.path,
                self.line_no,
                format!(
                    "line longer than {MAX_LINE_BYTES} bytes (1 MiB): expected a text file \
                     with line ends"
                ),
            ));
        }
        let mut end = self.buf.len();
        while end > 0 && matches!(self.buf.get(end - 1), Some(b'\n') | Some(b'\r')) {
            end -= 1;
        }
        Ok(self.buf.get(..end).map(|l| (self.line_no, l)))
    }
}

/// Call `f` on every line. An error on a last line without line end (a log cut
/// mid-write) becomes a warning ([`InputError::last_line_warning`]) pushed to `warnings`, and the
/// line is dropped; an error on any other line is returned.
pub(crate) fn for_each_line<F>(
    lines: &mut LineReader,
    warnings: &mut Vec<String>,
    mut f: F,
) -> Result<(), InputError>
where
    F: FnMut(usize, &[u8]) -> Result<(), LineError>,
{
    while let Some((ln, text)) = lines.next_line()? {
        match f(ln, text) {
            Ok(()) => {}
            Err(LineError::Data(e)) if lines.cut_last_line() => {
                warnings.push(e.last_line_warning());
                break;
            }
            Err(LineError::Data(e) | LineError::Fatal(e)) => return Err(e),
        }
    }
    Ok(())
}

/// What follows one record's result in a reader that tolerates a damaged last line
/// when given `warnings`: `Ok(true)` read on, `Ok(false)` stop (the last line, cut
/// mid-write, dropped with a warning), `Err` the record's error.
pub(crate) fn after_record(
    result: Result<(), InputError>,
    ln: usize,
    lines: &mut LineReader,
    warnings: &mut Option<&mut Vec<String>>,
) -> Result<bool, InputError> {
    match result {
        Ok(()) => Ok(true),
        Err(e) if e.line == Some(ln) && warnings.is_some() && lines.cut_last_line() => {
            if let Some(w) = warnings.as_mut() {
                w.push(e.last_line_warning());
            }
            Ok(false)
        }
        Err(e) => Err(e),
    }
}

/// An error of [`for_each_line`]'s callback: in a data line (dropped with a warning on
/// the last line) or fatal wherever it is (a header).
#[derive(Debug)]
pub(crate) enum LineError {
    Data(InputError),
    Fatal(InputError),
}

impl From<InputError> for LineError {
    fn from(e: InputError) -> Self {
        LineError::Data(e)
    }
}

impl LineReader {
    /// True when the line last returned is the file's last and has no line end: a
    /// line cut mid-write.
    pub fn cut_last_line(&mut self) -> bool {
        !self.line_end
            && self
                .reader
                .fill_buf()
                .map(|b| b.is_empty())
                .unwrap_or(false)
    }
}

/// True for a line that holds nothing but spaces, tabs and commas.
#[inline]
pub fn is_blank(line: &[u8]) -> bool {
    line.iter().all(|&b| is_sep(b))
}

#[inline]
fn is_ws(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b'\r'
}

#[inline]
fn is_sep(b: u8) -> bool {
    is_ws(b) || b == b','
}

/// Split `line` on the one byte `delim` only (a declared CSV delimiter: `;` with
/// decimal commas, `,` with spaces inside fields), each field trimmed of spaces and
/// tabs. A blank line has no fields; a trailing delimiter adds none; `a;;b` has an
/// empty middle field. A space or tab delimiter splits on runs of spaces and tabs
/// (aligned columns), commas kept inside fields.
pub fn split_on(line: &[u8], delim: u8, out: &mut Vec<(usize, usize)>) {
    out.clear();
    if line.iter().all(|&b| is_ws(b)) {
        return;
    }
    if is_ws(delim) {
        let mut i = 0;
        while i < line.len() {
            if is_ws(line[i]) {
                i += 1;
                continue;
            }
            let a = i;
            while i < line.len() && !is_ws(line[i]) {
                i += 1;
            }
            out.push((a, i));
        }
        return;
    }
    let mut start = 0;
    let n = line.len();
    loop {
        let end = line[start..]
            .iter()
            .position(|&b| b == delim)
            .map_or(n, |k| start + k);
        let (mut a, mut b) = (start, end);
        while a < b && is_ws(line[a]) {
            a += 1;
        }
        while b > a && is_ws(line[b - 1]) {
            b -= 1;
        }
        let last = end >= n;
        // A trailing delimiter (nothing but spaces after it) adds no field.
        if !(last && a == b && !out.is_empty()) {
            out.push((a, b));
        }
        if last {
            break;
        }
        start = end + 1;
    }
}

/// Split a line into fields (byte ranges). Runs of spaces and tabs separate fields;
/// a comma (with optional whitespace around it) also separates them, so `a,,b` has an
/// empty middle field. Leading and trailing separators make no fields, except a
/// leading comma, which starts with an empty field.
pub fn split_fields(line: &[u8], out: &mut Vec<(usize, usize)>) {
    out.clear();
    let n = line.len();
    let mut i = 0;
    while i < n && line.get(i).is_some_and(|&b| is_ws(b)) {
        i += 1;
    }
    if i >= n {
        return;
    }
    loop {
        let start = i;
        while i < n && line.get(i).is_some_and(|&b| !is_sep(b)) {
            i += 1;
        }
        out.push((start, i));
        while i < n && line.get(i).is_some_and(|&b| is_ws(b)) {
            i += 1;
        }
        if i >= n {
            break;
        }
        if line.get(i) == Some(&b',') {
            i += 1;
            while i < n && line.get(i).is_some_and(|&b| is_ws(b)) {
                i += 1;
            }
            if i >= n {
                break; // trailing comma
            }
        }
    }
}

/// Field `k` of a split line, or an empty slice.
#[inline]
pub fn field<'a>(line: &'a [u8], fields: &[(usize, usize)], k: usize) -> &'a [u8] {
    fields
        .get(k)
        .and_then(|&(s, e)| line.get(s..e))
        .unwrap_or(&[])
}

const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parse a decimal number. Plain `[-+]digits[.digits]` with at most 19 digits and a
/// mantissa up to 2^53 takes an exact fast path (integer mantissa divided by an exact
/// power of ten: one correctly rounded operation); anything else (exponents, long
/// mantissas, `nan`, `inf`) goes to `str::parse::<f64>`. The result can be NaN or
/// infinite: callers check. None if the text is not a number.
pub fn parse_f64(s: &[u8]) -> Option<f64> {
    match parse_prefix(s) {
        Some((v, len)) if len == s.len() => Some(v),
        _ => std::str::from_utf8(s).ok()?.parse::<f64>().ok(),
    }
}

/// The fast path of [`parse_f64`] on the start of `s`: a plain decimal number that
/// ends at the end of `s` or at a field separator (space, tab, comma, CR). Returns the
/// value and its length, or None (not plain, too long, or followed by other text).
#[inline]
pub(crate) fn parse_prefix(s: &[u8]) -> Option<(f64, usize)> {
    let len = s.len();
    let mut i = 0;
    let neg = match s.first() {
        Some(b'-') => {
            i = 1;
            true
        }
        Some(b'+') => {
            i = 1;
            false
        }
        _ => false,
    };
    // Mantissa digits accumulate with wrapping arithmetic: with at most 19 digits
    // there is no overflow, and longer mantissas are rejected below.
    let mut m: u64 = 0;
    let int_start = i;
    i = take_digits(s, i, &mut m);
    let int_digits = i - int_start;
    let mut frac_digits = 0;
    if i < len && s.get(i) == Some(&b'.') {
        let frac_start = i + 1;
        i = take_digits(s, frac_start, &mut m);
        frac_digits = i - frac_start;
    }
    let total = int_digits + frac_digits;
    if total == 0 || total > 19 || m > (1u64 << 53) {
        return None;
    }
    if let Some(&c) = s.get(i) {
        if !is_sep(c) {
            return None;
        }
    }
    let p = POW10.get(frac_digits)?;
    let v = m as f64 / p;
    Some((if neg { -v } else { v }, i))
}

/// Accumulate the ASCII digits of `s` from index `i` into `m` (wrapping), 8 at a time
/// where possible; returns the index of the first non-digit.
#[inline(always)]
fn take_digits(s: &[u8], mut i: usize, m: &mut u64) -> usize {
    while let Some(chunk) = s.get(i..i + 8) {
        let mut b = [0u8; 8];
        b.copy_from_slice(chunk);
        let w = u64::from_le_bytes(b);
        // All eight bytes are '0'..='9'?
        if (w & 0xF0F0_F0F0_F0F0_F0F0)
            | (((w.wrapping_add(0x0606_0606_0606_0606)) & 0xF0F0_F0F0_F0F0_F0F0) >> 4)
            != 0x3333_3333_3333_3333
        {
            break;
        }
        // Eight digits to a number (first byte most significant), as in simdjson.
        const MASK: u64 = 0x0000_00FF_0000_00FF;
        const MUL1: u64 = 100 + (1_000_000 << 32);
        const MUL2: u64 = 1 + (10_000 << 32);
        let mut v = w - 0x3030_3030_3030_3030;
        v = v.wrapping_mul(10).wrapping_add(v >> 8);
        v = (v & MASK)
            .wrapping_mul(MUL1)
            .wrapping_add(((v >> 16) & MASK).wrapping_mul(MUL2))
            >> 32;
        *m = m.wrapping_mul(100_000_000).wrapping_add(v);
        i += 8;
    }
    while let Some(&c) = s.get(i) {
        let digit = c.wrapping_sub(b'0');
        if digit > 9 {
            break;
        }
        *m = m.wrapping_mul(10).wrapping_add(u64::from(digit));
        i += 1;
    }
    i
}

/// Parse the first `N` fields of a line as plain decimal numbers in one pass, if they
/// all take the fast path and are separated by whitespace and at most one comma.
/// None means "use the general path" (which also produces the precise error).
#[inline]
pub(crate) fn parse_first_n<const N: usize>(line: &[u8]) -> Option<[f64; N]> {
    let mut out = [0.0; N];
    let mut i = skip_ws(line, 0);
    for (k, slot) in out.iter_mut().enumerate() {
        if k > 0 {
            i = skip_ws(line, i);
            if line.get(i) == Some(&b',') {
                i = skip_ws(line, i + 1);
            }
        }
        let (v, len) = parse_prefix(line.get(i..)?)?;
        if len == 0 {
            return None;
        }
        *slot = v;
        i += len;
    }
    Some(out)
}

#[inline(always)]
fn skip_ws(s: &[u8], mut i: usize) -> usize {
    while let Some(&c) = s.get(i) {
        if !is_ws(c) {
            break;
        }
        i += 1;
    }
    i
}

/// Parse a plain integer `[-+]digits` (no dot, no exponent), None otherwise.
pub(crate) fn parse_i64(s: &[u8]) -> Option<i64> {
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, s.get(1..).unwrap_or(&[])),
        Some(b'+') => (false, s.get(1..).unwrap_or(&[])),
        _ => (false, s),
    };
    if digits.is_empty() {
        return None;
    }
    let mut v: i64 = 0;
    for &b in digits {
        if !b.is_ascii_digit() {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(i64::from(b - b'0'))?;
    }
    Some(if neg { -v } else { v })
}

/// True for lines every text reader skips: blank, or starting with `#` or `%`.
#[inline]
pub(crate) fn is_comment_line(line: &[u8], fields: &[(usize, usize)]) -> bool {
    match fields.first() {
        None => true,
        Some(&(s, _)) => matches!(line.get(s), Some(b'#') | Some(b'%')),
    }
}

/// What the plain text readers (KF-GINS GNSS, heading, odometer, barometer, the IMU
/// files) skip: comment and blank lines ([`is_comment_line`]) and a header: the first
/// `skip_lines` lines of the file when given, else the first other line when none of
/// its fields is a number (column names such as `t,speed_mps`). Line numbers are the
/// file's, header or not.
#[derive(Default)]
pub(crate) struct SkipLines {
    data_seen: bool,
    lines: Option<usize>,
}

impl SkipLines {
    /// Skip the first `lines` lines (None: detect a header line).
    pub(crate) fn new(lines: Option<usize>) -> SkipLines {
        SkipLines {
            data_seen: false,
            lines,
        }
    }

    /// True when line `ln` (split into `fields`) is to be skipped.
    pub(crate) fn skip(&mut self, ln: usize, line: &[u8], fields: &[(usize, usize)]) -> bool {
        if is_comment_line(line, fields) {
            return true;
        }
        if let Some(n) = self.lines {
            return ln <= n;
        }
        if std::mem::replace(&mut self.data_seen, true) {
            return false;
        }
        fields
            .iter()
            .all(|&(s, e)| line.get(s..e).and_then(parse_f64).is_none())
    }
}

/// Append `v` with exactly 9 decimals, byte for byte as `format!("{:.9}", v)`.
///
/// Fast path for |v| < 4e6: |v| = m 2^e exactly, so |v| 1e9 = m 1e9 / 2^-e is rounded
/// to the nearest integer exactly in 128-bit integer arithmetic; exact decimal ties,
/// larger values and non-finite values use `write!`.
#[inline]
pub fn push_fixed9(out: &mut Vec<u8>, v: f64) {
    // Digits go straight into the vector (no staging buffer: copying one after byte
    // stores costs a store-forwarding stall); a fixed-size resize then a truncate
    // beat a variable-length copy.
    let start = out.len();
    out.extend_from_slice(&[b' '; 24]);
    let len = out.get_mut(start..).and_then(|b| fixed9_fast(v, b));
    match len {
        Some(len) => out.truncate(start + len),
        None => {
            out.truncate(start);
            let _ = write!(out, "{v:.9}");
        }
    }
}

/// The number a reader gets back from [`push_fixed9`]'s text of `v`: `v` rounded to 9
/// decimals, as the nearest f64 (what a correctly rounding parser returns), without
/// formatting it. navfuse's Python frames hold these values, so that they equal the
/// files (`solution.csv`) exactly.
pub fn fixed9_value(v: f64) -> f64 {
    match round_1e9(v.abs()) {
        // n < 4e15 is exact in f64 and IEEE division rounds correctly: n / 1e9 is the
        // nearest f64 to the decimal n * 10^-9.
        Some(n) => {
            let q = n as f64 / 1e9;
            if v.is_sign_negative() {
                -q
            } else {
                q
            }
        }
        None => format!("{v:.9}").parse().unwrap_or(v),
    }
}

/// Append one field as C `"%-15.9lf "`: 9 decimals, left-justified in 15 characters,
/// then one space (KF-GINS output files).
#[inline]
pub fn push_kf_field(out: &mut Vec<u8>, v: f64) {
    let start = out.len();
    out.extend_from_slice(&[b' '; 24]);
    let len = out.get_mut(start..).and_then(|b| fixed9_fast(v, b));
    match len {
        Some(len) => out.truncate(start + len.max(15) + 1),
        None => {
            out.truncate(start);
            let _ = write!(out, "{v:.9}");
            let width = out.len() - start;
            if width < 15 {
                out.resize(start + 15, b' ');
            }
            out.push(b' ');
        }
    }
}

/// The fast path of [`push_fixed9`]: writes into `buf` (at least 18 bytes) from index
/// 0 and returns the length (at most 18), or None when `write!` must be used.
#[inline(always)]
fn fixed9_fast(v: f64, buf: &mut [u8]) -> Option<usize> {
    let n = round_1e9(v.abs())?;
    // n < 4e15: 7 integer digits and 9 fraction digits. `hi` holds the integer
    // digits and the first fraction digit, `lo` the other 8 fraction digits.
    let hi = (n / 100_000_000) as u32; // <= 4e7
    let lo = (n % 100_000_000) as u32;
    let mut pos = 0;
    if v.is_sign_negative() {
        *buf.first_mut()? = b'-';
        pos = 1;
    }
    let dh = swar8(hi);
    // Drop leading zero digits (low bytes), keeping at least one integer digit.
    let zeros = (dh.trailing_zeros() / 8).min(6);
    let w = dh >> (8 * zeros);
    let ndig = 7 - zeros; // 1..=7 integer digits
    let int_mask = (1u64 << (8 * ndig)) - 1;
    let first_frac = (w >> (8 * ndig)) & 0xff;
    let word =
        (w & int_mask) + (0x3030_3030_3030_3030 & int_mask) + (u64::from(b'.') << (8 * ndig));
    let ndig = ndig as usize;
    buf.get_mut(pos..pos + 8)?
        .copy_from_slice(&word.to_le_bytes());
    *buf.get_mut(pos + ndig + 1)? = b'0' + first_frac as u8;
    buf.get_mut(pos + ndig + 2..pos + ndig + 10)?
        .copy_from_slice(&(swar8(lo) | 0x3030_3030_3030_3030).to_le_bytes());
    Some(pos + ndig + 10)
}

/// a * 1e9 rounded to the nearest integer, for 0 <= a < 4e6 (None: NaN, too large or
/// an exact decimal tie).
#[inline(always)]
fn round_1e9(a: f64) -> Option<u64> {
    if a.is_nan() || a >= 4.0e6 {
        return None;
    }
    // Quick path: x = a * 1e9 < 4e15 < 2^52 is within ulp(x)/2 <= x * 2^-53 of the
    // exact product, so rounding x gives the right integer unless x's fraction is
    // that close to one half.
    let x = a * 1e9;
    let t = x as i64; // truncation = floor for 0 <= x < 2^52
    let f = x - t as f64; // exact
    if (f - 0.5).abs() > x * 1.2e-16 {
        Some((t + i64::from(f > 0.5)) as u64)
    } else {
        round_1e9_exact(a)
    }
}

/// Round a * 1e9 (0 <= a < 4e6) to the nearest integer exactly: a = m 2^e with
/// e < 0, so a * 1e9 = m 1e9 / 2^-e, done in 128-bit integers. None on an exact tie.
fn round_1e9_exact(a: f64) -> Option<u64> {
    let bits = a.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let mant = bits & ((1u64 << 52) - 1);
    let (m, e) = if biased == 0 {
        (mant, -1074)
    } else {
        (mant | (1u64 << 52), biased - 1075)
    };
    let s = u32::try_from(-e).ok().filter(|&s| s > 0)?;
    let p = u128::from(m) * 1_000_000_000u128; // < 2^83
    if s >= 84 {
        return Some(0); // p < 2^83 <= 2^(s-1): below one half
    }
    let q = p >> s;
    let rem = p & ((1u128 << s) - 1);
    let half = 1u128 << (s - 1);
    if rem == half {
        return None; // exact decimal tie: let `write!` apply its rule
    }
    u64::try_from(q + u128::from(rem > half)).ok()
}

/// The 8 decimal digits of `n` < 1e8, most significant first in little-endian byte
/// order, as digit values 0-9 (add 0x30 per byte for ASCII). SIMD-within-a-register:
/// split into two 4-digit lanes, then pairs, then digits, with multiply-shift
/// divisions exact over the lane ranges (checked exhaustively in the tests).
#[inline(always)]
fn swar8(n: u32) -> u64 {
    let n = u64::from(n);
    let x = (n / 10_000) | ((n % 10_000) << 32);
    let hi100 = ((x * 10_486) >> 20) & 0x0000_007F_0000_007F;
    let x = ((x - hi100 * 100) << 16) | hi100;
    let hi10 = ((x * 103) >> 10) & 0x000F_000F_000F_000F;
    ((x - hi10 * 10) << 8) | hi10
}

#[cfg(test)]
mod tests {
    #[test]
    fn fixed9_value_is_the_parsed_text() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut line = Vec::new();
        for k in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Magnitudes from 1e-12 to 1e8, both signs, and some exact ties.
            let m = (x >> 11) as f64 / (1u64 << 53) as f64;
            let v = match k % 4 {
                0 => (m - 0.5) * 10f64.powi((k % 21) - 12),
                1 => ((x % 2_000_001) as f64 - 1e6) * 0.5e-9,
                2 => m * 7e5,
                _ => -m * 3e7,
            };
            line.clear();
            push_fixed9(&mut line, v);
            let parsed: f64 = std::str::from_utf8(&line).unwrap().parse().unwrap();
            assert_eq!(fixed9_value(v).to_bits(), parsed.to_bits(), "{v:e}");
        }
    }

    use super::*;

    fn fixed(v: f64) -> String {
        let mut b = Vec::new();
        push_fixed9(&mut b, v);
        String::from_utf8(b).unwrap()
    }

    #[test]
    fn fixed9_matches_std_on_special_values() {
        let vals = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.9999999996,
            0.9999999995,
            0.99999999949,
            -0.9999999996,
            9.9999999996,
            999999.9999999996,
            1e-9,
            5e-10,
            4.9999999e-10,
            -5e-10,
            -1e-12,
            1e-300,
            0.0009765625, // exact tie at the 10th decimal
            -0.0009765625,
            0.5e-9,
            1.5e-9,
            2.5e-9,
            456300.104412029,
            459662.499412029,
            30.4447873701,
            114.4718632047,
            185.70235133,
            359.99999999996,
            3_999_999.999_999_999,
            4e6,
            1e9,
            1.5e9,
            -2.5e12,
            1e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for &v in &vals {
            assert_eq!(fixed(v), format!("{v:.9}"), "value {v:e}");
        }
    }

    #[test]
    fn fixed9_matches_std_on_many_values() {
        // Deterministic xorshift over several magnitudes, plus decimal-looking values.
        let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for i in 0..400_000 {
            let r = next();
            let u = (r >> 11) as f64 / (1u64 << 53) as f64; // [0, 1)
            let mag = 10f64.powi(i % 17 - 10);
            let sign = if r & 1 == 1 { -1.0 } else { 1.0 };
            let v = sign * u * mag;
            assert_eq!(fixed(v), format!("{v:.9}"), "value {v:e}");
            // Values with exactly 10 decimals (ties and near-ties in decimal).
            let d = sign * ((r >> 20) % 10_000_000_000_000) as f64 / 1e10;
            assert_eq!(fixed(d), format!("{d:.9}"), "value {d:e}");
        }
    }

    #[test]
    fn exact_rounding_agrees_with_std() {
        let mut s: u64 = 77;
        for _ in 0..300_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let a = (s >> 11) as f64 / (1u64 << 53) as f64 * 4e6 / 10f64.powi((s % 12) as i32);
            if let Some(n) = round_1e9_exact(a) {
                let want = format!("{a:.9}").replace('.', "");
                assert_eq!(n, want.parse::<u64>().unwrap(), "{a:e}");
            }
        }
        assert_eq!(round_1e9_exact(0.0), Some(0));
        assert_eq!(round_1e9_exact(0.0009765625), None); // exact tie
        assert_eq!(round_1e9_exact(5e-324), Some(0));
    }

    #[test]
    fn swar8_exhaustive() {
        for n in 0..100_000_000u32 {
            let d = swar8(n) | 0x3030_3030_3030_3030;
            let want = n / 10_000 * 10_000 + n % 10_000; // keep the optimiser honest
            let mut v = 0u32;
            for b in d.to_le_bytes() {
                v = v * 10 + u32::from(b - b'0');
            }
            assert_eq!(v, want, "{n}");
        }
    }

    #[test]
    fn kf_field_layout() {
        let mut b = Vec::new();
        push_kf_field(&mut b, 0.0);
        push_kf_field(&mut b, 456300.104412029);
        push_kf_field(&mut b, -0.000235729);
        assert_eq!(
            String::from_utf8(b).unwrap(),
            "0.000000000     456300.104412029 -0.000235729    "
        );
    }

    #[test]
    fn parse_matches_std() {
        let cases = [
            "0",
            "-0",
            "-0.000000",
            "456250.004412029",
            "-0.000000249077",
            "0.0489207176",
            "1.",
            ".5",
            "-.5",
            "+3.25",
            "1e5",
            "1.5E-3",
            "12345678901234567890123",
            "0.1234567890123456789",
            "9007199254740993",
            "nan",
            "inf",
            "-infinity",
        ];
        for c in cases {
            let a = parse_f64(c.as_bytes()).unwrap();
            let b: f64 = c.parse().unwrap();
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{c}: {a} vs {b}"
            );
        }
        for bad in ["", "-", ".", "abc", "1.2.3", "1,5", "--1", "0x10", "1e"] {
            assert_eq!(parse_f64(bad.as_bytes()), None, "{bad}");
        }
        assert_eq!(parse_i64(b"-123"), Some(-123));
        assert_eq!(parse_i64(b"1.0"), None);
        assert_eq!(parse_i64(b"99999999999999999999"), None);
    }

    #[test]
    fn parse_fast_path_is_exact() {
        let mut s: u64 = 12345;
        for _ in 0..200_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let v = (s >> 11) as f64 / 1e6 - 4e9;
            for txt in [
                format!("{v:.9}"),
                format!("{v:.3}"),
                format!("{:.12}", v / 1e9),
            ] {
                let a = parse_f64(txt.as_bytes()).unwrap();
                let b: f64 = txt.parse().unwrap();
                assert_eq!(a.to_bits(), b.to_bits(), "{txt}");
            }
        }
    }

    #[test]
    fn first_n_fast_path() {
        assert_eq!(
            parse_first_n::<3>(b"  1.5, -2\t3 junk"),
            Some([1.5, -2.0, 3.0])
        );
        assert_eq!(parse_first_n::<3>(b"1 2"), None);
        assert_eq!(parse_first_n::<3>(b"1,,2,3"), None);
        assert_eq!(parse_first_n::<3>(b"1 2 3e5"), None);
        assert_eq!(parse_first_n::<2>(b"1 2x 3"), None);
        assert_eq!(parse_first_n::<1>(b"# 1"), None);
        assert_eq!(parse_first_n::<1>(b"-"), None);
        assert_eq!(parse_first_n::<1>(b"."), None);
        assert_eq!(parse_first_n::<2>(b"1.\r2\r"), Some([1.0, 2.0]));
    }

    #[test]
    fn splitting() {
        let mut f = Vec::new();
        let cases: [(&str, &[&str]); 9] = [
            ("a b\tc", &["a", "b", "c"]),
            ("  a  b  ", &["a", "b"]),
            ("a,b,c", &["a", "b", "c"]),
            ("a, b ,c,", &["a", "b", "c"]),
            ("a,,c", &["a", "", "c"]),
            (",a", &["", "a"]),
            ("", &[]),
            ("   ", &[]),
            ("a ,\tb", &["a", "b"]),
        ];
        for (line, want) in cases {
            split_fields(line.as_bytes(), &mut f);
            let got: Vec<&str> = (0..f.len())
                .map(|k| std::str::from_utf8(field(line.as_bytes(), &f, k)).unwrap())
                .collect();
            assert_eq!(got, want, "{line:?}");
        }
    }
}
