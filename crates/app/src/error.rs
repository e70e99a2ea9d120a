//! [`Error`]: why a run could not start, failed or stopped. Every variant displays the
//! whole message (with what it happened in, e.g. `time-offset estimation pass: ...`),
//! so `{e}` is what `navfuse run` prints after `navfuse: error: `.

use crate::stop::Interrupted;
use navfuse_core::NavError;
use navfuse_io::config::ConfigError;
use navfuse_io::InputError;

/// Why a run (or the preparation of its inputs) failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The configuration could not be read or is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// An input file could not be read, or an output file not written.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The navigator could not start or had to stop (no initial pose, numerical failure).
    #[error(transparent)]
    Nav(#[from] NavError),
    /// The run was stopped by its [`StopFlag`](crate::StopFlag); the outputs hold every
    /// epoch up to the one it names.
    #[error(transparent)]
    Interrupted(#[from] Interrupted),
    /// Plausibility checks refused the inputs or the result (messages joined by `; `).
    #[error("{0}")]
    Refused(String),
    /// A file or directory operation, with what was being done.
    #[error("{context}: {error}")]
    Io {
        context: String,
        error: std::io::Error,
    },
    /// summary.json could not be formatted.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// An error with what it happened in.
    #[error("{context}: {inner}")]
    Context { context: String, inner: Box<Error> },
    /// Anything else, as a message.
    #[error("{0}")]
    Other(String),
}

impl Error {
    /// The [`Interrupted`] behind this error (also under added context), if the run was
    /// stopped rather than failed.
    pub fn interrupted(&self) -> Option<&Interrupted> {
        match self {
            Error::Interrupted(i) => Some(i),
            Error::Context { inner, .. } => inner.interrupted(),
            _ => None,
        }
    }

    /// This error with `context` put in front of it.
    pub fn context(self, context: impl Into<String>) -> Error {
        Error::Context {
            context: context.into(),
            inner: Box::new(self),
        }
    }

    pub(crate) fn io(context: impl Into<String>, error: std::io::Error) -> Error {
        Error::Io {
            context: context.into(),
            error,
        }
    }
}

/// `.context(..)` / `.with_context(|| ..)` on results whose error converts into [`Error`].
pub(crate) trait ResultExt<T> {
    fn context(self, c: impl Into<String>) -> Result<T, Error>;
    fn with_context<S: Into<String>>(self, f: impl FnOnce() -> S) -> Result<T, Error>;
}

impl<T, E: Into<Error>> ResultExt<T> for Result<T, E> {
    fn context(self, c: impl Into<String>) -> Result<T, Error> {
        self.map_err(|e| e.into().context(c))
    }
    fn with_context<S: Into<String>>(self, f: impl FnOnce() -> S) -> Result<T, Error> {
        self.map_err(|e| e.into().context(f()))
    }
}
