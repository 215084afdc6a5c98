//! Interchange formats for cagerig: glTF 2.0 (the `gltf` crate) and FBX (the `ufbx` crate) read
//! into an [`ImportedCharacter`] — rest skin M, rest skeleton S, Ω, animations as skeleton
//! tracks — in the file's world space (see [`character`] for spaces and vertex order). The
//! numerical core (`cagerig`) depends on none of this.

#![warn(missing_docs)]

pub mod character;
pub mod character_format;
pub mod error;
#[cfg_attr(target_arch = "wasm32", path = "fbx_web.rs")]
pub mod fbx;
pub mod gltf;
pub mod morph_cage_track;
pub mod open_character;
pub mod static_mesh;

use std::path::Path;

pub use character::{
    ImportSummary, ImportedAnimation, ImportedCharacter, MorphTargets, SpaceSummary,
};
pub use character_format::{
    CharacterFormat, export_character, export_character_baked, export_character_baked_glb,
};
pub use error::FormatError;
pub use morph_cage_track::{MorphCageTrack, morph_cage_track};
pub use open_character::{
    OpenCharacterError, OpenedCharacter, open_character, open_character_input,
};
pub use static_mesh::StaticMesh;

/// Import choices.
#[derive(Debug, Clone)]
pub struct ImportOptions {
    /// The skin to import, by name or index (default: the first, with a note listing the others).
    pub skin: Option<String>,
    /// Sampling rate for channels that are not piecewise linear (glTF CUBICSPLINE), samples/s.
    pub resample_fps: f64,
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self {
            skin: None,
            resample_fps: 60.0,
        }
    }
}

/// A character file to read: a file on disk, or the bytes of one already in memory (a
/// browser's file input), named by `path` (its extension gives the format; messages name it).
#[derive(Debug, Clone, Copy)]
pub enum CharacterInput<'a> {
    /// A file, read when imported.
    File(&'a Path),
    /// A file's bytes, already read.
    Bytes {
        /// The file's name: its format by extension, and the name in messages.
        path: &'a Path,
        /// Its content.
        bytes: &'a [u8],
    },
}

impl CharacterInput<'_> {
    /// The file's path or name.
    pub fn path(&self) -> &Path {
        match self {
            Self::File(path) | Self::Bytes { path, .. } => path,
        }
    }

    /// Imports the character (see [`import_character`]).
    pub fn import(&self, options: &ImportOptions) -> Result<ImportedCharacter, FormatError> {
        let format = format_of(self.path())?;
        match self {
            Self::File(path) => format.import(path, options),
            Self::Bytes { path, bytes } => format.import_bytes(bytes, path, options),
        }
    }

    /// Imports the file's meshes as one static mesh (see [`import_static_mesh`]).
    pub fn import_static(&self) -> Result<StaticMesh, FormatError> {
        let format = format_of(self.path())?;
        match self {
            Self::File(path) => format.import_static(path),
            Self::Bytes { path, bytes } => format.import_static_bytes(bytes, path),
        }
    }
}

/// Imports a character from a `.glb`, `.gltf` or `.fbx` file. A file without a skin is
/// refused with [`FormatError::NoSkin`]; read it with [`import_static_mesh`].
pub fn import_character(
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportedCharacter, FormatError> {
    CharacterInput::File(path).import(options)
}

/// Imports the meshes of a `.glb`, `.gltf` or `.fbx` file as one static mesh in world space,
/// with its cage node if it has one: a sculpt or a scan without a skin, to bind to a skeleton
/// (a skinned file gives its bind shape; see [`StaticMesh`]).
pub fn import_static_mesh(path: &Path) -> Result<StaticMesh, FormatError> {
    CharacterInput::File(path).import_static()
}

/// The character format of `path`, or an error naming the extensions read.
fn format_of(path: &Path) -> Result<CharacterFormat, FormatError> {
    CharacterFormat::of(path).ok_or_else(|| FormatError::Io {
        path: path.to_path_buf(),
        message: "unsupported character format (expected .glb, .gltf or .fbx)".into(),
    })
}
