//! Where a character's skinning weights Ω come from: the one rule every front end applies.
//!
//! The rule: the character's own weights (the `.skw` beside an OBJ, the skin of a glTF/FBX
//! file) unless the user gives a `.skw` file (`--weights`) or asks for automatic weights
//! (`--auto-weights`, [`crate::auto_weights`]). Replacing Ω drops what was derived from the old
//! one (CoR rows, Ψ, Λ); Φ and the MaxVol rows depend on M and C only and are kept.
//!
//! A `.skw` belongs to a skeleton: it is read against the rig's skeleton, or paired with the
//! skeleton it was made for (a `.skt`), which then replaces the rig's. A `.skw` that names its
//! joints (as `cagerig weights` writes it) must name those of that skeleton
//! ([`crate::io::skw::read_skw_for_skeleton`]).

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::Warning;
use crate::auto_weights::{AutoWeights, AutoWeightsError, AutoWeightsOptions, Progress};
use crate::io::ParseError;
use crate::session::RigParts;

/// What the user asked for about the weights.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum WeightsSource {
    /// The character's own weights.
    #[default]
    Character,
    /// A `.skw` file in cagerig's vertex order and joint indices.
    File {
        /// The `.skw`.
        weights: PathBuf,
        /// The skeleton (`.skt`) the weights were made for, which replaces the rig's; `None`:
        /// the rig's own skeleton.
        skeleton: Option<PathBuf>,
    },
    /// Computed from the mesh and skeleton (with the rig's cage bounding the volume).
    Automatic(AutoWeightsOptions),
}

impl WeightsSource {
    /// True when the character's own weights are not needed (an OBJ rig may lack its `.skw`).
    pub fn replaces_character_weights(&self) -> bool {
        match self {
            WeightsSource::Character => false,
            WeightsSource::File { .. } | WeightsSource::Automatic(_) => true,
        }
    }

    /// The skeleton file paired with the weights, if any (it replaces the rig's skeleton).
    pub fn paired_skeleton(&self) -> Option<&Path> {
        match self {
            WeightsSource::File {
                skeleton: Some(p), ..
            } => Some(p),
            _ => None,
        }
    }
}

/// What [`apply_weights_source`] read.
#[derive(Debug, Default)]
pub struct AppliedWeights {
    /// The warnings of the new weights.
    pub warnings: Vec<Warning>,
    /// `(role, path)` of the files read: `skin_weights`, and `skeleton` when paired.
    pub files: Vec<(&'static str, PathBuf)>,
}

/// Why the weights asked for could not be used.
#[derive(Debug, Error)]
pub enum WeightsSourceError {
    /// The `.skw` could not be read or does not fit the rig.
    #[error(transparent)]
    Read(#[from] ParseError),
    /// The automatic weights failed.
    #[error("automatic weights for {name}: {source}")]
    Automatic {
        /// The character.
        name: String,
        /// Why.
        source: AutoWeightsError,
    },
}

/// Applies `source` to `parts` (a no-op for [`WeightsSource::Character`]); `name` names the
/// character in errors, `skeleton_source` the file the rig's skeleton was read from. A skeleton
/// paired with the weights replaces `parts.skeleton`. Returns the warnings of the new weights
/// and the files read.
pub fn apply_weights_source(
    source: &WeightsSource,
    parts: &mut RigParts,
    name: &str,
    skeleton_source: &str,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<AppliedWeights, WeightsSourceError> {
    let mut files = Vec::new();
    let (weights, warnings) = match source {
        WeightsSource::Character => return Ok(AppliedWeights::default()),
        WeightsSource::File { weights, skeleton } => {
            // `parts` changes only once both files are read.
            let paired = match skeleton {
                Some(p) => Some((crate::io::skt::read_skt(p)?, p)),
                None => None,
            };
            let read = match &paired {
                Some((paired_skeleton, p)) => crate::io::skw::read_skw_for_skeleton(
                    weights,
                    parts.mesh.num_vertices(),
                    paired_skeleton,
                    &p.display().to_string(),
                )?,
                None => crate::io::skw::read_skw_for_skeleton(
                    weights,
                    parts.mesh.num_vertices(),
                    &parts.skeleton,
                    skeleton_source,
                )?,
            };
            if let Some((paired_skeleton, p)) = paired {
                parts.skeleton = paired_skeleton;
                files.push(("skeleton", p.clone()));
            }
            files.push(("skin_weights", weights.clone()));
            read
        }
        WeightsSource::Automatic(options) => {
            let automatic = |source| WeightsSourceError::Automatic {
                name: name.to_string(),
                source,
            };
            let result = AutoWeights::new(options.clone())
                .map_err(automatic)?
                .compute_with_progress(&parts.mesh, &parts.skeleton, Some(&parts.cage), progress)
                .map_err(automatic)?;
            (result.weights, result.report.warnings)
        }
    };
    parts.skin_weights = weights;
    parts.cor_rows = None;
    parts.joint_coords = None;
    parts.cor_centre_coords = None;
    Ok(AppliedWeights { warnings, files })
}
