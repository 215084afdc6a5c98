//! Errors of the file readers and writers: every variant names the file and, where there is one,
//! the 1-based line.

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::animation::AnimationError;
use crate::error::RigError;

/// A file could not be read, parsed or written.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ParseError {
    /// The operating system refused to open, read or write the file.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The kind of the I/O error.
        kind: std::io::ErrorKind,
        /// The operating system's message.
        message: String,
    },
    /// A line that does not follow the format.
    #[error("{}:{line}: expected {expected}, found {found:?}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// The 1-based line of the file.
        line: usize,
        /// What the format expects there (e.g. "a number").
        expected: String,
        /// The text found instead.
        found: String,
    },
    /// A line that is not valid UTF-8.
    #[error("{}:{line}: the line is not valid UTF-8", path.display())]
    InvalidUtf8 {
        /// The file.
        path: PathBuf,
        /// The 1-based line of the file.
        line: usize,
    },
    /// An index on a line refers to an element that does not exist.
    #[error("{}:{line}: {what} index {index} is out of range (there are {len})", path.display())]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// The 1-based line of the file.
        line: usize,
        /// What the index refers to (e.g. "father joint", "cage vertex").
        what: &'static str,
        /// The index as written in the file (may be negative).
        index: i64,
        /// Number of elements it may index (valid indices are `0..len`).
        len: usize,
    },
    /// The line is well formed but its content is inconsistent with the rest of the file
    /// (duplicate entry, wrong count, keyframe order, …).
    #[error("{}:{line}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The 1-based line of the file.
        line: usize,
        /// What is inconsistent.
        message: String,
    },
    /// The parsed data failed rig validation (e.g. a cycle in the skeleton).
    #[error("{}: {source}", path.display())]
    Rig {
        /// The file.
        path: PathBuf,
        /// The validation error.
        source: RigError,
    },
    /// The parsed keyframes failed animation validation.
    #[error("{}: {source}", path.display())]
    Animation {
        /// The file.
        path: PathBuf,
        /// The validation error.
        source: AnimationError,
    },
    /// The data cannot be expressed in the format (e.g. a sheared joint frame in a `.skt`).
    #[error("{}: cannot be written in this format: {message}", path.display())]
    Unrepresentable {
        /// The file.
        path: PathBuf,
        /// What cannot be written, and why.
        message: String,
    },
}

impl ParseError {
    pub(crate) fn io(path: &Path, err: &std::io::Error) -> Self {
        ParseError::Io {
            path: path.to_path_buf(),
            kind: err.kind(),
            message: err.to_string(),
        }
    }

    /// The 1-based line the error refers to, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            ParseError::Malformed { line, .. }
            | ParseError::InvalidUtf8 { line, .. }
            | ParseError::IndexOutOfRange { line, .. }
            | ParseError::Invalid { line, .. } => Some(*line),
            _ => None,
        }
    }

    /// The message without the file it names, for a caller whose own error names the file: the
    /// operating system's reason for [`ParseError::Io`], the whole message otherwise.
    pub fn reason(&self) -> String {
        match self {
            ParseError::Io { message, .. } => message.clone(),
            other => other.to_string(),
        }
    }

    /// The file the error refers to.
    pub fn path(&self) -> &Path {
        match self {
            ParseError::Io { path, .. }
            | ParseError::Malformed { path, .. }
            | ParseError::InvalidUtf8 { path, .. }
            | ParseError::IndexOutOfRange { path, .. }
            | ParseError::Invalid { path, .. }
            | ParseError::Rig { path, .. }
            | ParseError::Animation { path, .. }
            | ParseError::Unrepresentable { path, .. } => path,
        }
    }
}
