//! Errors of the interchange-format readers and writers. Every message names the file, the
//! element (accessor, node, buffer, …), what was expected and what was found.

use std::path::PathBuf;

use cagerig::RigError;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum FormatError {
    #[error("{path}: {message}", path = path.display())]
    Io { path: PathBuf, message: String },
    #[error("{path}: not a valid glTF 2.0 file: {message}", path = path.display())]
    Gltf { path: PathBuf, message: String },
    #[error("{path}: {element}: {message}", path = path.display())]
    Invalid {
        path: PathBuf,
        element: String,
        message: String,
    },
    #[error("{path}: {element}: {source}", path = path.display())]
    Rig {
        path: PathBuf,
        element: String,
        #[source]
        source: RigError,
    },
    #[error("{path}: FBX: {message}", path = path.display())]
    Fbx { path: PathBuf, message: String },
}

/// Shorthand for [`FormatError::Invalid`].
pub(crate) fn invalid(
    path: &std::path::Path,
    element: impl Into<String>,
    message: impl Into<String>,
) -> FormatError {
    FormatError::Invalid {
        path: path.to_path_buf(),
        element: element.into(),
        message: message.into(),
    }
}
