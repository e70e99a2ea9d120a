//! [`InputError`]: a bad input (or an output that could not be written), located by
//! file, line and field. Displayed as `FILE:LINE: field 'F': MESSAGE`, with absent
//! parts left out. Messages say what was expected and what was found.

use std::fmt;
use std::path::{Path, PathBuf};

/// An error in a file, located as precisely as possible.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line number (text files), if the error belongs to one line.
    pub line: Option<usize>,
    /// The field (column name, key or record) at fault, if any.
    pub field: Option<String>,
    /// What was expected and what was found.
    pub message: String,
}

impl InputError {
    /// An error about the whole file.
    pub fn new(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        InputError {
            path: path.into(),
            line: None,
            field: None,
            message: message.into(),
        }
    }

    /// An error on one line.
    pub fn at_line(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        InputError::new(path, message).with_line(line)
    }

    /// An error in one field of one line.
    pub fn at_field(
        path: impl Into<PathBuf>,
        line: usize,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        InputError::new(path, message)
            .with_line(line)
            .with_field(field)
    }

    /// Set the line number.
    pub fn with_line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }

    /// Set the field name.
    pub fn with_field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }

    /// The file could not be opened: `cannot open: No such file or directory`.
    pub fn open(path: impl Into<PathBuf>, err: &std::io::Error) -> Self {
        InputError::new(path, format!("cannot open: {}", io_message(err)))
    }

    /// Reading failed after opening: `cannot read: ...`.
    pub fn read(path: impl Into<PathBuf>, err: &std::io::Error) -> Self {
        InputError::new(path, format!("cannot read: {}", io_message(err)))
    }

    /// An output file could not be created: `cannot create: ...`.
    pub fn create(path: impl Into<PathBuf>, err: &std::io::Error) -> Self {
        InputError::new(path, format!("cannot create: {}", io_message(err)))
    }

    /// Writing an output file failed: `cannot write: ...`.
    pub fn write(path: impl Into<PathBuf>, err: &std::io::Error) -> Self {
        InputError::new(path, format!("cannot write: {}", io_message(err)))
    }

    /// `expected N columns (WHAT), found M`.
    pub fn columns(
        path: &Path,
        line: usize,
        expected: impl fmt::Display,
        what: &str,
        found: usize,
    ) -> Self {
        InputError::at_line(
            path,
            line,
            format!("expected {expected} columns ({what}), found {found}"),
        )
    }

    /// `expected a number, found "TEXT"` (the text shortened if long).
    pub fn not_a_number(path: &Path, line: usize, field: &str, text: &[u8]) -> Self {
        InputError::at_field(
            path,
            line,
            field,
            format!("expected a number, found \"{}\"", shorten(text)),
        )
    }

    /// `NaN is not allowed` / `infinity is not allowed`.
    pub fn not_finite(path: &Path, line: usize, field: &str, value: f64) -> Self {
        let what = if value.is_nan() { "NaN" } else { "infinity" };
        InputError::at_field(path, line, field, format!("{what} is not allowed"))
    }

    /// `time T goes backwards (previous P)`.
    pub fn backwards(path: &Path, line: usize, t: f64, previous: f64) -> Self {
        InputError::at_field(
            path,
            line,
            "time",
            format!("time {t} goes backwards (previous {previous})"),
        )
    }

    /// A record's time `t` after the previous record's: a duplicate or a time going
    /// backwards is an error naming the line and the field `time`.
    pub fn check_time_order(
        path: &Path,
        line: usize,
        t: f64,
        previous: Option<f64>,
    ) -> Result<(), Self> {
        match previous {
            Some(p) if t == p => Err(InputError::at_field(
                path,
                line,
                "time",
                format!("duplicate record: time {t} repeats the previous record"),
            )),
            Some(p) if t < p => Err(InputError::backwards(path, line, t, p)),
            _ => Ok(()),
        }
    }

    /// `std must be > 0, found V`.
    pub fn std_not_positive(path: &Path, line: usize, field: &str, value: f64) -> Self {
        InputError::at_field(path, line, field, format!("std must be > 0, found {value}"))
    }

    /// A std, variance, rate or scale `value` (file units) that is `si` in SI units,
    /// checked with [`check_scale`].
    pub fn scale(
        path: &Path,
        line: usize,
        field: &str,
        what: &str,
        value: f64,
        si: f64,
    ) -> Result<f64, Self> {
        check_scale(what, value, si).map_err(|m| InputError::at_field(path, line, field, m))
    }

    /// A sample value `value` (file units) that is `si` after unit scaling: finite.
    pub fn scaled(path: &Path, line: usize, field: &str, value: f64, si: f64) -> Result<f64, Self> {
        check_finite_si(value, si).map_err(|m| InputError::at_field(path, line, field, m))
    }

    /// The warning for a damaged last line that was dropped:
    /// `FILE:LINE: damaged last line dropped (file cut mid-write?): ERROR`.
    pub fn last_line_warning(&self) -> String {
        let mut out = self.path.display().to_string();
        if let Some(line) = self.line {
            out.push_str(&format!(":{line}"));
        }
        out.push_str(": damaged last line dropped (file cut mid-write?): ");
        if let Some(f) = &self.field {
            out.push_str(&format!("field '{f}': "));
        }
        out.push_str(&self.message);
        out
    }
}

/// Smallest and largest accepted magnitude of a std, variance, rate or scale in SI
/// units: its square stays a finite normal number.
pub(crate) const SCALE_MIN_SI: f64 = 1e-150;
pub(crate) const SCALE_MAX_SI: f64 = 1e150;

/// Check a std, variance, rate or scale after conversion to SI: `value` is what the
/// file gave, `si` the converted value. It must be > 0 and finite, and its square
/// finite and non-zero (so variances neither underflow to 0 nor overflow to inf):
/// SI value in [1e-150, 1e150]. Returns `si` or the message.
pub fn check_scale(what: &str, value: f64, si: f64) -> Result<f64, String> {
    if value.is_nan() || value <= 0.0 {
        return Err(format!("{what} must be > 0, found {value}"));
    }
    if !(SCALE_MIN_SI..=SCALE_MAX_SI).contains(&si) {
        let conv = if si == value {
            String::new()
        } else {
            format!(" ({si:e} in SI units)")
        };
        return Err(format!(
            "{what} {value:e}{conv} is out of range: expected {SCALE_MIN_SI:e} to {SCALE_MAX_SI:e} \
             in SI units (its square must be a finite non-zero number)"
        ));
    }
    Ok(si)
}

/// Check a value after unit scaling: `value` finite as read, `si` must be finite too.
pub(crate) fn check_finite_si(value: f64, si: f64) -> Result<f64, String> {
    if si.is_finite() {
        Ok(si)
    } else {
        Err(format!(
            "{value:e} overflows to {si} after conversion to SI units: expected a finite value"
        ))
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        f.write_str(": ")?;
        if let Some(field) = &self.field {
            write!(f, "field '{field}': ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for InputError {}

/// The OS message of an I/O error without the ` (os error N)` suffix.
fn io_message(err: &std::io::Error) -> String {
    let s = err.to_string();
    match s.find(" (os error ") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

/// Input text for a message: lossy UTF-8, at most 40 characters.
pub(crate) fn shorten(text: &[u8]) -> String {
    let s = String::from_utf8_lossy(text);
    let mut out: String = s.chars().take(40).collect();
    if s.chars().count() > 40 {
        out.push_str("...");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_omits_absent_parts() {
        let e = InputError::new("a.txt", "boom");
        assert_eq!(e.to_string(), "a.txt: boom");
        let e = InputError::at_line("a.txt", 3, "boom");
        assert_eq!(e.to_string(), "a.txt:3: boom");
        let e = InputError::at_field("a.txt", 3, "lat", "boom");
        assert_eq!(e.to_string(), "a.txt:3: field 'lat': boom");
        let e = InputError::new("a.txt", "boom").with_field("id");
        assert_eq!(e.to_string(), "a.txt: field 'id': boom");
    }

    #[test]
    fn scale_checks_after_conversion() {
        assert_eq!(check_scale("std", 2.0, 4.0), Ok(4.0));
        for (v, si) in [
            (0.0, 0.0),
            (-1.0, -1.0),
            (f64::NAN, f64::NAN),
            (1e-300, 1e-300),
        ] {
            assert!(check_scale("std", v, si).is_err(), "{v}");
        }
        let e = check_scale("std", 5e-324, 5e-324 * 0.017).unwrap_err();
        assert!(
            e.contains("out of range: expected 1e-150 to 1e150 in SI"),
            "{e}"
        );
        assert!(check_scale("std", 1e300, 1e300).is_err());
        assert!(check_finite_si(1e308, f64::INFINITY)
            .unwrap_err()
            .contains("overflows to inf"));
        let w = InputError::at_field("a.txt", 9, "lat", "boom").last_line_warning();
        assert_eq!(
            w,
            "a.txt:9: damaged last line dropped (file cut mid-write?): field 'lat': boom"
        );
    }

    #[test]
    fn open_error_has_no_os_code() {
        let err = std::fs::File::open("/nonexistent/navfuse/x.txt").unwrap_err();
        let e = InputError::open("/nonexistent/navfuse/x.txt", &err);
        assert_eq!(
            e.to_string(),
            "/nonexistent/navfuse/x.txt: cannot open: No such file or directory"
        );
    }
}
