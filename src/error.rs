//! The library's error type. Each variant carries the values involved and reads
//! "what … (expected …)". The library never prints and never exits; the CLI adds
//! the file name and turns an error into one line on stderr and exit code 2.

use std::fmt;

/// What went wrong, by actor: the caller's parameters, the input's format, a limit,
/// something we do not support, or the operating system.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter given by the caller is out of its range.
    #[error("invalid {name}: {value} (expected {expected})")]
    Parameter {
        name: &'static str,
        value: String,
        expected: &'static str,
    },
    /// The input data is malformed.
    #[error("{what} (expected {expected})")]
    Format {
        what: String,
        expected: &'static str,
    },
    /// The input is valid but uses a feature this crate does not implement.
    #[error("unsupported {what}: {value}")]
    Unsupported { what: &'static str, value: String },
    /// A decode asked for a resolution level the file does not hold (levels `0..=levels`;
    /// a [`ErrorKind::Parameter`] error: the caller's to fix, never clamped).
    #[error("invalid level: {level} of a file with levels 0 to {levels} (expected one of the levels the file holds)")]
    Level { level: usize, levels: usize },
    /// A size declared by the input exceeds what it can hold or what we allow.
    #[error("{what} of {requested} exceeds the limit of {limit}")]
    LimitsExceeded {
        what: &'static str,
        requested: u64,
        limit: u64,
    },
    /// Reading or writing failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// The broad class of an [`Error`], for tests and callers that branch on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    Parameter,
    Format,
    Unsupported,
    LimitsExceeded,
    Io,
}

impl Error {
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Parameter { .. } | Error::Level { .. } => ErrorKind::Parameter,
            Error::Format { .. } => ErrorKind::Format,
            Error::Unsupported { .. } => ErrorKind::Unsupported,
            Error::LimitsExceeded { .. } => ErrorKind::LimitsExceeded,
            Error::Io(_) => ErrorKind::Io,
        }
    }

    /// Shorthand for a [`Error::Parameter`].
    pub fn parameter(name: &'static str, value: impl fmt::Display, expected: &'static str) -> Self {
        Error::Parameter {
            name,
            value: value.to_string(),
            expected,
        }
    }

    /// Shorthand for a [`Error::Format`].
    pub fn format(what: impl fmt::Display, expected: &'static str) -> Self {
        Error::Format {
            what: what.to_string(),
            expected,
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;
