//! Interchange formats for cagerig: glTF 2.0 (the `gltf` crate) and FBX (the `ufbx` crate) read
//! into an [`ImportedCharacter`] — rest skin M, rest skeleton S, Ω, animations as skeleton
//! tracks — in the file's world space (see [`character`] for spaces and vertex order). The
//! numerical core (`cagerig`) depends on none of this.

#![warn(missing_docs)]

pub mod character;
pub mod character_format;
pub mod error;
pub mod fbx;
pub mod gltf;
pub mod morph_cage_track;
pub mod open_character;
pub mod static_mesh;

use std::path::Path;

pub use character::{
    ImportSummary, ImportedAnimation, ImportedCharacter, MorphTargets, SpaceSummary,
};
pub use character_format::{CharacterFormat, export_character, export_character_baked};
pub use error::FormatError;
pub use morph_cage_track::{MorphCageTrack, morph_cage_track};
pub use open_character::{OpenCharacterError, OpenedCharacter, open_character};
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

/// Imports a character from a `.glb`, `.gltf` or `.fbx` file. A file without a skin is
/// refused with [`FormatError::NoSkin`]; read it with [`import_static_mesh`].
pub fn import_character(
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportedCharacter, FormatError> {
    format_of(path)?.import(path, options)
}

/// Imports the meshes of a `.glb`, `.gltf` or `.fbx` file as one static mesh in world space,
/// with its cage node if it has one: a sculpt or a scan without a skin, to bind to a skeleton
/// (a skinned file gives its bind shape; see [`StaticMesh`]).
pub fn import_static_mesh(path: &Path) -> Result<StaticMesh, FormatError> {
    format_of(path)?.import_static(path)
}

/// The character format of `path`, or an error naming the extensions read.
fn format_of(path: &Path) -> Result<CharacterFormat, FormatError> {
    CharacterFormat::of(path).ok_or_else(|| FormatError::Io {
        path: path.to_path_buf(),
        message: "unsupported character format (expected .glb, .gltf or .fbx)".into(),
    })
}
