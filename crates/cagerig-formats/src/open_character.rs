//! A character file opened as the parts of a rig: the one rule every front end (the CLI, the
//! editor, the Python package) follows. Import the file ([`crate::import_character`]), choose its
//! cage ([`cagerig::cage_source::choose_cage`]: the one given, else the file's cage node, else a
//! generated one when asked for), and assemble M, S, Ω, C and the DQ blend weights.

use std::path::Path;

use cagerig::Warning;
use cagerig::cage_source::{CageOrigin, CageRequest, CageSourceError, choose_cage};
use cagerig::session::RigParts;
use cagerig::skinning::SkinningMethod;

use crate::character::{ImportSummary, ImportedAnimation, ImportedCharacter, MorphTargets};
use crate::error::FormatError;
use crate::{CharacterInput, ImportOptions};

/// A character opened as a rig's parts, with what the file brought beside them.
#[derive(Debug)]
pub struct OpenedCharacter {
    /// Rest skin M, rest skeleton S, Ω, rest cage C and the file's DQ blend weights.
    pub parts: RigParts,
    /// Where the cage came from (a generated cage carries the generator's report).
    pub cage_origin: CageOrigin,
    /// The importer's notes (a generated cage's note is the front end's to word).
    pub warnings: Vec<Warning>,
    /// The file's animations of its skeleton.
    pub animations: Vec<ImportedAnimation>,
    /// The file's morph targets.
    pub morph_targets: MorphTargets,
    /// The skinning method the file's skin says its authoring tool uses, if it says one.
    pub skinning: Option<SkinningMethod>,
    /// What the importer read from the file (counts, skins, animations, space).
    pub summary: ImportSummary,
}

/// Why a character could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenCharacterError {
    /// The file could not be imported.
    #[error(transparent)]
    Import(#[from] FormatError),
    /// No cage could be chosen for it.
    #[error(transparent)]
    Cage(#[from] CageSourceError),
}

/// Opens the character at `path` (`.glb`, `.gltf`, `.fbx`) with `options`, its cage chosen by
/// `cage` (see the module doc).
pub fn open_character(
    path: &Path,
    options: &ImportOptions,
    cage: &CageRequest<'_>,
) -> Result<OpenedCharacter, OpenCharacterError> {
    open_character_input(CharacterInput::File(path), options, cage)
}

/// [`open_character`] on a file or on a file's bytes already in memory.
pub fn open_character_input(
    input: CharacterInput<'_>,
    options: &ImportOptions,
    cage: &CageRequest<'_>,
) -> Result<OpenedCharacter, OpenCharacterError> {
    let imported = input.import(options)?;
    Ok(open_imported_character(input.path(), imported, cage)?)
}

/// The rule of [`open_character`] after the import: the cage chosen by `cage` and the parts
/// assembled from a character already imported — by this crate's importers, or by a loader of
/// another crate that returns an [`ImportedCharacter`] (`tests/toy_loader.rs` is one). `path`
/// names the character in messages and places a generated cage's report.
pub fn open_imported_character(
    path: &Path,
    imported: ImportedCharacter,
    cage: &CageRequest<'_>,
) -> Result<OpenedCharacter, CageSourceError> {
    let ImportedCharacter {
        mesh,
        skeleton,
        skin_weights,
        cage: found,
        animations,
        morph_targets,
        warnings,
        skinning,
        dq_blend_weights,
        summary,
        ..
    } = imported;
    let rig = cagerig::cage_gen::CageRig {
        skeleton: &skeleton,
        weights: Some(&skin_weights),
    };
    let chosen = choose_cage(path, &mesh, Some(rig), found, cage)?;
    Ok(OpenedCharacter {
        parts: RigParts::new(mesh, skeleton, skin_weights, chosen.cage)
            .with_dq_blend_weights(dq_blend_weights),
        cage_origin: chosen.origin,
        warnings,
        animations,
        morph_targets,
        skinning,
        summary,
    })
}
