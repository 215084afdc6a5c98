//! Errors of the interchange-format readers and writers. Every message names the file, the
//! element (accessor, node, buffer, …), what was expected and what was found.

use std::path::PathBuf;

use cagerig::RigError;
use thiserror::Error;

/// An interchange file (glTF, FBX) could not be read or written as a rig.
#[derive(Debug, Error)]
pub enum FormatError {
    /// The file could not be opened, read or written, or its extension is not supported.
    #[error("{path}: {message}", path = path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// The file is not valid glTF 2.0.
    #[error("{path}: not a valid glTF 2.0 file: {message}", path = path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// The glTF parser's message.
        message: String,
    },
    /// An element of the file is inconsistent or cannot be imported.
    #[error("{path}: {element}: {message}", path = path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The element (e.g. `node 3`, `skins`, an accessor).
        element: String,
        /// What was expected and what was found.
        message: String,
    },
    /// Data read from the file failed rig validation.
    #[error("{path}: {element}: {source}", path = path.display())]
    Rig {
        /// The file.
        path: PathBuf,
        /// The element the data came from (e.g. "skeleton", "skinned mesh").
        element: String,
        /// The validation error.
        #[source]
        source: RigError,
    },
    /// The file has no skin (a static mesh from a sculpting tool or a scan): it cannot be
    /// imported as a character, but [`crate::import_static_mesh`] reads its mesh for binding.
    #[error(
        "{path}: the {format} file has no skin: bind it with `cagerig weights {file} --skeleton \
         SKELETON.skt --out WEIGHTS.skw` or open it in the studio to build a skeleton",
        path = path.display(),
        file = path.display()
    )]
    NoSkin {
        /// The file.
        path: PathBuf,
        /// The format's name (`"glTF"`, `"FBX"`).
        format: &'static str,
    },
    /// The FBX reader rejected the file.
    #[error("{path}: FBX: {message}", path = path.display())]
    Fbx {
        /// The file.
        path: PathBuf,
        /// The FBX reader's error type and description.
        message: String,
    },
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
