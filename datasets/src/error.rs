//! The one error type every reader returns: it names the file, where in it, and what was wrong.

use std::fmt;
use std::path::PathBuf;

/// Where in a file a problem was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// 1-based line of a text file.
    Line(usize),
    /// 0-based byte offset of a binary file (or of a binary section of a text file).
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// What was wrong. Tests match on these variants, so each names one kind of fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ErrorKind {
    #[error("cannot read: {0}")]
    Io(String),
    #[error("file ends early: expected {expected}")]
    Truncated { expected: String },
    #[error("expected {expected}, found {found:?}")]
    Syntax { expected: String, found: String },
    #[error("{what}: expected {expected}, found {found}")]
    CountMismatch {
        what: String,
        expected: u64,
        found: u64,
    },
    #[error("{what} index {index} is out of range (only {limit} exist)")]
    IndexOutOfRange {
        what: String,
        index: u64,
        limit: u64,
    },
    #[error("{what} {index} is not finite ({value})")]
    NonFinite {
        what: String,
        index: u64,
        value: f64,
    },
    #[error("unsupported cell type {0}")]
    UnknownCellType(String),
    #[error("mesh has no tetrahedra{0}")]
    EmptyMesh(String),
    #[error("{count} {what} do not fit 32-bit indices")]
    IndexOverflow { what: String, count: u64 },
    #[error("byte order: {0}")]
    ByteOrder(String),
    #[error("no array named {name:?} (available: {available:?})")]
    MissingArray {
        name: String,
        available: Vec<String>,
    },
    #[error("unsupported: {0}")]
    Unsupported(String),
    #[error("unrecognised file format: {0}")]
    UnknownFormat(String),
    /// A named data set's file is absent from the data directory.
    #[error("missing data file {file} (for data set {dataset}); public copy: {origin}")]
    MissingDataFile {
        dataset: String,
        file: String,
        origin: String,
    },
    #[error("{0}")]
    Invalid(String),
}

/// A load failure: file, optional location, and the kind of fault.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadError {
    pub path: PathBuf,
    pub location: Option<Location>,
    pub kind: ErrorKind,
}

impl LoadError {
    pub fn new(path: impl Into<PathBuf>, kind: ErrorKind) -> Self {
        LoadError {
            path: path.into(),
            location: None,
            kind,
        }
    }
    pub fn at(path: impl Into<PathBuf>, location: Location, kind: ErrorKind) -> Self {
        LoadError {
            path: path.into(),
            location: Some(location),
            kind,
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some(loc) => write!(f, "{}: {}: {}", self.path.display(), loc, self.kind),
            None => write!(f, "{}: {}", self.path.display(), self.kind),
        }
    }
}

impl std::error::Error for LoadError {}
