//! Interchange formats for cagerig: glTF 2.0 (the `gltf` crate) and FBX (the `ufbx` crate) read
//! into an [`ImportedCharacter`] — rest skin M, rest skeleton S, Ω, animations as skeleton
//! tracks — in the file's world space (see [`character`] for spaces and vertex order). The
//! numerical core (`cagerig`) depends on none of this.

#![warn(missing_docs)]

pub mod character;
pub mod error;
pub mod fbx;
pub mod gltf;
pub mod morph_cage_track;

use std::path::Path;

pub use character::{
    ImportSummary, ImportedAnimation, ImportedCharacter, MorphTargets, SpaceSummary,
};
pub use error::FormatError;
pub use morph_cage_track::{MorphCageTrack, morph_cage_track};

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

/// The interchange format of `path` by extension (`.glb`, `.gltf`, `.fbx`, any case).
pub fn format_of(path: &Path) -> Option<&'static str> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "glb" | "gltf" => Some("glTF"),
        "fbx" => Some("FBX"),
        _ => None,
    }
}

/// Imports a character from a `.glb`, `.gltf` or `.fbx` file.
pub fn import_character(
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportedCharacter, FormatError> {
    match format_of(path) {
        Some("glTF") => gltf::import_gltf(path, options),
        Some("FBX") => fbx::import_fbx(path, options),
        _ => Err(FormatError::Io {
            path: path.to_path_buf(),
            message: "unsupported interchange format (expected .glb, .gltf or .fbx)".into(),
        }),
    }
}
