//! The character file formats, as a type: every front end asks this one place which files are
//! characters, how to read them and how to write a rig back.
//!
//! A new format is one importer file returning [`ImportedCharacter`] (and one returning
//! [`StaticMesh`]) and a variant here; the compiler then points at the exhaustive matches below
//! (name, extensions, import, import_static, export).

use std::path::Path;

use cagerig::session::RigSession;

use crate::{FormatError, ImportOptions, ImportedCharacter, StaticMesh};

/// A character (skinned mesh, skeleton, weights, animations) file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CharacterFormat {
    /// glTF 2.0: `.glb` (binary) or `.gltf` (JSON with its buffers beside it).
    Gltf,
    /// Autodesk FBX (binary or ASCII), read through ufbx.
    Fbx,
}

impl CharacterFormat {
    /// Every format, in the order front ends list them.
    pub const ALL: [CharacterFormat; 2] = [Self::Gltf, Self::Fbx];

    /// The format's name for people: `"glTF"`, `"FBX"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Gltf => "glTF",
            Self::Fbx => "FBX",
        }
    }

    /// The file extensions of the format, lower case, without the dot.
    pub const fn extensions(self) -> &'static [&'static str] {
        match self {
            Self::Gltf => &["glb", "gltf"],
            Self::Fbx => &["fbx"],
        }
    }

    /// The format of `path` by its extension (any case), if it is a character format.
    pub fn of(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|f| f.extensions().contains(&ext.as_str()))
    }

    /// Reads a character from `path` in this format.
    pub fn import(
        self,
        path: &Path,
        options: &ImportOptions,
    ) -> Result<ImportedCharacter, FormatError> {
        match self {
            Self::Gltf => crate::gltf::import_gltf(path, options),
            Self::Fbx => crate::fbx::import_fbx(path, options),
        }
    }

    /// [`Self::import`] on the bytes of a file already in memory (`path` names it in messages
    /// and places what it refers to, such as a `.gltf`'s external buffers).
    pub fn import_bytes(
        self,
        bytes: &[u8],
        path: &Path,
        options: &ImportOptions,
    ) -> Result<ImportedCharacter, FormatError> {
        match self {
            Self::Gltf => crate::gltf::import_gltf_bytes(bytes, path, options),
            Self::Fbx => crate::fbx::import_fbx_bytes(bytes, path, options),
        }
    }

    /// [`Self::import_static`] on the bytes of a file already in memory.
    pub fn import_static_bytes(self, bytes: &[u8], path: &Path) -> Result<StaticMesh, FormatError> {
        match self {
            Self::Gltf => crate::gltf::import_gltf_static_bytes(bytes, path),
            Self::Fbx => crate::fbx::import_fbx_static_bytes(bytes, path),
        }
    }

    /// Reads `path` in this format as a static mesh: every mesh in world space, no skeleton or
    /// weights (a file without a skin, or a skinned one's bind shape; see [`StaticMesh`]).
    pub fn import_static(self, path: &Path) -> Result<StaticMesh, FormatError> {
        match self {
            Self::Gltf => crate::gltf::import_gltf_static(path),
            Self::Fbx => crate::fbx::import_fbx_static(path),
        }
    }

    /// Whether cagerig writes rigs in this format.
    pub const fn can_export(self) -> bool {
        match self {
            Self::Gltf => true,
            Self::Fbx => false,
        }
    }
}

/// Writes the session's current state (rest skin and skeleton after cage edits as the bind
/// shape, the current pose in the nodes) as a character file in the format of `path`'s
/// extension, replacing it atomically; `name` names the mesh and the skin.
pub fn export_character(session: &RigSession, path: &Path, name: &str) -> Result<(), FormatError> {
    writable_format(path)?;
    crate::gltf::export::export_glb(session, path, name)
}

/// [`export_character`] with the skinning result baked: under DQS, CoR or the blended method
/// the file carries one morph target (default weight 1) that turns a viewer's LBS of the
/// current pose into cagerig's M' ([`crate::gltf::export_bake::baked_state_to_gltf`]); under
/// LBS it is the plain export. Returns what the baking measured.
pub fn export_character_baked(
    session: &RigSession,
    path: &Path,
    name: &str,
) -> Result<crate::gltf::export_bake::BakeReport, FormatError> {
    writable_format(path)?;
    let (document, bin, report) = crate::gltf::export_bake::baked_state_to_gltf(session, name)
        .map_err(|message| FormatError::Io {
            path: path.to_path_buf(),
            message,
        })?;
    crate::gltf::export::write_gltf_or_glb(path, &document, &bin)?;
    Ok(report)
}

/// [`export_character_baked`] as the bytes of a `.glb` (the web edition's download); `name`
/// names the rig in the file and in messages.
pub fn export_character_baked_glb(
    session: &RigSession,
    name: &str,
) -> Result<(Vec<u8>, crate::gltf::export_bake::BakeReport), FormatError> {
    let failed = |message: String| FormatError::Io {
        path: format!("{name}.glb").into(),
        message,
    };
    let (document, bin, report) =
        crate::gltf::export_bake::baked_state_to_gltf(session, name).map_err(failed)?;
    let mut bytes = Vec::new();
    crate::gltf::export::write_glb(&mut bytes, &document, &bin)
        .map_err(|e| failed(e.to_string()))?;
    Ok((bytes, report))
}

/// Refuses a path whose extension is not a format cagerig writes.
fn writable_format(path: &Path) -> Result<(), FormatError> {
    let unsupported = |found: String| FormatError::Io {
        path: path.to_path_buf(),
        message: format!(
            "cagerig writes characters as glTF 2.0: expected a path ending in .glb (binary) or \
             .gltf (JSON), found {found}"
        ),
    };
    match CharacterFormat::of(path) {
        Some(CharacterFormat::Gltf) => Ok(()),
        Some(format @ CharacterFormat::Fbx) => {
            Err(unsupported(format!("{} (reading only)", format.name())))
        }
        None => Err(unsupported(match path.extension() {
            Some(ext) => format!(".{}", ext.to_string_lossy()),
            None => "no extension".into(),
        })),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension_in_any_case() {
        assert_eq!(
            CharacterFormat::of(Path::new("a/Fox.GLB")),
            Some(CharacterFormat::Gltf)
        );
        assert_eq!(
            CharacterFormat::of(Path::new("x.gltf")),
            Some(CharacterFormat::Gltf)
        );
        assert_eq!(
            CharacterFormat::of(Path::new("x.Fbx")),
            Some(CharacterFormat::Fbx)
        );
        assert_eq!(CharacterFormat::of(Path::new("x.obj")), None);
        assert_eq!(CharacterFormat::of(Path::new("noext")), None);
        for f in CharacterFormat::ALL {
            for ext in f.extensions() {
                assert_eq!(
                    CharacterFormat::of(&Path::new("x").with_extension(ext)),
                    Some(f)
                );
            }
        }
    }
}
