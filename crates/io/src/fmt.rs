//! Fast text helpers shared by the readers and writers:
//!
//! - [`LineReader`]: buffered line reading into a reused buffer, with line numbers;
//! - [`split_fields`]: field splitting on spaces, tabs and commas;
//! - [`parse_f64`]: decimal parsing with an exact fast path;
//! - [`push_fixed9`] / [`push_kf_field`]: fixed 9-decimal formatting, identical to
//!   `format!("{:.9}", v)`, several times faster.

use crate::error::InputError;
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

/// Capacity of the read and write buffers (1 MiB).
pub const BUF_CAPACITY: usize = 1 << 20;

/// Reads a text file line by line into a reused buffer.
pub struct LineReader {
    path: PathBuf,
    reader: BufReader<File>,
    buf: Vec<u8>,
    line_no: usize,
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
        Ok(LineReader {
            path: path.to_path_buf(),
            reader: BufReader::with_capacity(BUF_CAPACITY, file),
            buf: Vec::with_capacity(256),
            line_no: 0,
        })
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
    pub fn next_line(&mut self) -> Result<Option<(usize, &[u8])>, InputError> {
        self.buf.clear();
        let n = self
            .reader
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| InputError::read(&self.path, &e).with_line(self.line_no + 1))?;
        if n == 0 {
            return Ok(None);
        }
        self.line_no += 1;
        let mut end = self.buf.len();
        while end > 0 && matches!(self.buf.get(end - 1), Some(b'\n') | Some(b'\r')) {
            end -= 1;
        }
        Ok(self.buf.get(..end).map(|l| (self.line_no, l)))
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

/// Parse a decimal number. Plain `[-+]digits[.digits]` with at most 15-16 significant
/// digits takes an exact fast path (integer mantissa divided by an exact power of ten:
/// one correctly rounded operation); anything else (exponents, long mantissas, `nan`,
/// `inf`) goes to `str::parse::<f64>`. The result can be NaN or infinite: callers
/// check. None if the text is not a number.
pub fn parse_f64(s: &[u8]) -> Option<f64> {
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, s.get(1..).unwrap_or(&[])),
        Some(b'+') => (false, s.get(1..).unwrap_or(&[])),
        _ => (false, s),
    };
    let mut m: u64 = 0;
    let mut frac_digits: usize = 0;
    let mut seen_dot = false;
    let mut n_digits = 0usize;
    let mut fast = !digits.is_empty();
    for &b in digits {
        if b.is_ascii_digit() {
            if m >= 100_000_000_000_000_000 {
                fast = false;
                break;
            }
            m = m * 10 + u64::from(b - b'0');
            n_digits += 1;
            if seen_dot {
                frac_digits += 1;
            }
        } else if b == b'.' && !seen_dot {
            seen_dot = true;
        } else {
            fast = false;
            break;
        }
    }
    if fast && n_digits > 0 && m <= (1u64 << 53) && frac_digits < POW10.len() {
        let v = m as f64 / POW10.get(frac_digits).copied().unwrap_or(1.0);
        return Some(if neg { -v } else { v });
    }
    std::str::from_utf8(s).ok()?.parse::<f64>().ok()
}

/// Parse a plain integer `[-+]digits` (no dot, no exponent), None otherwise.
pub fn parse_i64(s: &[u8]) -> Option<i64> {
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

const DIGIT_PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Append `v` with exactly 9 decimals, byte for byte as `format!("{:.9}", v)`.
///
/// Fast path for |v| < 4e6: `x = |v| * 1e9` is within half an ulp of the exact
/// product, so rounding `x` to an integer is exact unless the fraction of `x` is
/// within that error of one half; such near-ties, larger values and non-finite values
/// use `write!`.
pub fn push_fixed9(out: &mut Vec<u8>, v: f64) {
    let a = v.abs();
    if a < 4.0e6 {
        let x = a * 1e9;
        let fl = x.floor();
        let f = x - fl;
        // |x - exact| <= ulp(x)/2 <= x * 2^-53; keep a factor of 4 of margin.
        let margin = x * 4.5e-16;
        if (f - 0.5).abs() > margin {
            let n = fl as u64 + u64::from(f > 0.5);
            if v.is_sign_negative() {
                out.push(b'-');
            }
            push_u64_with_frac9(out, n);
            return;
        }
    }
    let _ = write!(out, "{v:.9}");
}

/// Append `n / 1e9` as `INT.FFFFFFFFF`.
#[inline]
fn push_u64_with_frac9(out: &mut Vec<u8>, n: u64) {
    let mut int = n / 1_000_000_000;
    let mut frac = (n % 1_000_000_000) as u32;
    // Integer part, at most 20 digits.
    let mut tmp = [0u8; 20];
    let mut pos = tmp.len();
    loop {
        let d = (int % 10) as u8;
        int /= 10;
        pos -= 1;
        if let Some(slot) = tmp.get_mut(pos) {
            *slot = b'0' + d;
        }
        if int == 0 || pos == 0 {
            break;
        }
    }
    out.extend_from_slice(tmp.get(pos..).unwrap_or(&[]));
    // Fraction: 9 digits = 4 pairs + 1.
    let mut f = [0u8; 10];
    f[0] = b'.';
    let last = frac % 10;
    frac /= 10;
    f[9] = b'0' + last as u8;
    let mut p = 9;
    while p > 1 {
        let pair = (frac % 100) as usize;
        frac /= 100;
        f[p - 2] = DIGIT_PAIRS[2 * pair];
        f[p - 1] = DIGIT_PAIRS[2 * pair + 1];
        p -= 2;
    }
    out.extend_from_slice(&f);
}

/// Append one field as C `"%-15.9lf "`: 9 decimals, left-justified in 15 characters,
/// then one space (KF-GINS output files).
#[inline]
pub fn push_kf_field(out: &mut Vec<u8>, v: f64) {
    let start = out.len();
    push_fixed9(out, v);
    let width = out.len() - start;
    if width < 15 {
        out.resize(start + 15, b' ');
    }
    out.push(b' ');
}

#[cfg(test)]
mod tests {
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
            let mag = 10f64.powi((i % 17) as i32 - 10);
            let sign = if r & 1 == 1 { -1.0 } else { 1.0 };
            let v = sign * u * mag;
            assert_eq!(fixed(v), format!("{v:.9}"), "value {v:e}");
            // Values with exactly 10 decimals (ties and near-ties in decimal).
            let d = sign * ((r >> 20) % 10_000_000_000_000) as f64 / 1e10;
            assert_eq!(fixed(d), format!("{d:.9}"), "value {d:e}");
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
