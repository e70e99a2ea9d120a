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

    /// `std must be > 0, found V`.
    pub fn std_not_positive(path: &Path, line: usize, field: &str, value: f64) -> Self {
        InputError::at_field(path, line, field, format!("std must be > 0, found {value}"))
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
    fn open_error_has_no_os_code() {
        let err = std::fs::File::open("/nonexistent/navfuse/x.txt").unwrap_err();
        let e = InputError::open("/nonexistent/navfuse/x.txt", &err);
        assert_eq!(
            e.to_string(),
            "/nonexistent/navfuse/x.txt: cannot open: No such file or directory"
        );
    }
}
