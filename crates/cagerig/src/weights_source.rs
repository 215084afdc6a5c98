//! Where a character's skinning weights Ω come from: the one rule every front end applies.
//!
//! The rule: the character's own weights (the `.skw` beside an OBJ, the skin of a glTF/FBX
//! file) unless the user gives a `.skw` file (`--weights`) or asks for automatic weights
//! (`--auto-weights`, [`crate::auto_weights`]). Replacing Ω drops what was derived from the old
//! one (CoR rows, Ψ, Λ); Φ and the MaxVol rows depend on M and C only and are kept.

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
    File(PathBuf),
    /// Computed from the mesh and skeleton (with the rig's cage bounding the volume).
    Automatic(AutoWeightsOptions),
}

impl WeightsSource {
    /// True when the character's own weights are not needed (an OBJ rig may lack its `.skw`).
    pub fn replaces_character_weights(&self) -> bool {
        match self {
            WeightsSource::Character => false,
            WeightsSource::File(_) | WeightsSource::Automatic(_) => true,
        }
    }
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
/// character in errors. Returns the warnings of the new weights and the file read, if any.
pub fn apply_weights_source(
    source: &WeightsSource,
    parts: &mut RigParts,
    name: &str,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(Vec<Warning>, Option<PathBuf>), WeightsSourceError> {
    let (weights, warnings, file) = match source {
        WeightsSource::Character => return Ok((Vec::new(), None)),
        WeightsSource::File(path) => {
            let (w, warnings) = read_for(path, parts)?;
            (w, warnings, Some(path.clone()))
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
            (result.weights, result.report.warnings, None)
        }
    };
    parts.skin_weights = weights;
    parts.cor_rows = None;
    parts.joint_coords = None;
    parts.cor_centre_coords = None;
    Ok((warnings, file))
}

fn read_for(
    path: &Path,
    parts: &RigParts,
) -> Result<(crate::SkinWeights, Vec<Warning>), ParseError> {
    crate::io::skw::read_skw(path, parts.mesh.num_vertices(), parts.skeleton.len())
}
