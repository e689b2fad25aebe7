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
    /// An `.mra` container's fault, by cause ([`FormatError`]; its class is
    /// [`FormatError::kind`]).
    #[error(transparent)]
    Container(#[from] FormatError),
}

/// What is wrong with an `.mra` file's container (formats/MRA.md §12), by cause. Each
/// reads as one line "what … (expected …)", as [`Error::Format`] does.
#[derive(Debug, thiserror::Error)]
pub enum FormatError {
    /// Not an `.mra` signature (or too short for one).
    #[error("{what} (expected {expected})")]
    Signature {
        what: String,
        expected: &'static str,
    },
    /// A format version this reader does not implement.
    #[error("unsupported format version: {major}.{minor} ({reads})")]
    Version { major: u8, minor: u8, reads: String },
    /// A chunk whose stored CRC-32C is not its bytes'.
    #[error("CRC-32C mismatch in chunk {chunk} at byte {offset} (stored {stored:08x}, computed {computed:08x}) (expected an undamaged file)")]
    Crc {
        chunk: String,
        offset: u64,
        stored: u32,
        computed: u32,
    },
    /// A chunk the header commits to is absent.
    #[error("{what} (expected {expected})")]
    Missing {
        what: String,
        expected: &'static str,
    },
    /// A chunk where it may not be: before one it must follow, or after one it must
    /// precede.
    #[error("{what} (expected {expected})")]
    Order {
        what: String,
        expected: &'static str,
    },
    /// A second chunk of what must come once.
    #[error("{what} (expected {expected})")]
    Duplicate {
        what: String,
        expected: &'static str,
    },
    /// The file, a chunk or a payload ends early.
    #[error("{what} (expected {expected})")]
    Truncated {
        what: String,
        expected: &'static str,
    },
    /// An index, offset, length or count pointing outside what it indexes.
    #[error("{what} (expected {expected})")]
    OutOfRange {
        what: String,
        expected: &'static str,
    },
    /// A field whose value the format does not define, or that contradicts another.
    #[error("{what} (expected {expected})")]
    Invalid {
        what: String,
        expected: &'static str,
    },
    /// A critical chunk this reader does not know.
    #[error("unsupported critical chunk: {0}")]
    UnknownChunk(String),
    /// A declared size over what the file can hold or the reader allows.
    #[error("{what} of {requested} exceeds the limit of {limit}")]
    Budget {
        what: &'static str,
        requested: u64,
        limit: u64,
    },
}

impl FormatError {
    /// The broad class: an unknown version or critical chunk is
    /// [`ErrorKind::Unsupported`], a budget [`ErrorKind::LimitsExceeded`], the rest
    /// [`ErrorKind::Format`].
    pub fn kind(&self) -> ErrorKind {
        match self {
            FormatError::Version { .. } | FormatError::UnknownChunk(_) => ErrorKind::Unsupported,
            FormatError::Budget { .. } => ErrorKind::LimitsExceeded,
            _ => ErrorKind::Format,
        }
    }

    pub fn signature(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::Signature {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn missing(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::Missing {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn order(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::Order {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn duplicate(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::Duplicate {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn truncated(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::Truncated {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn out_of_range(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::OutOfRange {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn invalid(what: impl fmt::Display, expected: &'static str) -> Error {
        FormatError::Invalid {
            what: what.to_string(),
            expected,
        }
        .into()
    }
    pub fn budget(what: &'static str, requested: u64, limit: u64) -> Error {
        FormatError::Budget {
            what,
            requested,
            limit,
        }
        .into()
    }
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
            Error::Container(f) => f.kind(),
        }
    }

    /// The container fault, when this is one.
    pub fn fault(&self) -> Option<&FormatError> {
        match self {
            Error::Container(f) => Some(f),
            _ => None,
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
