//! Why an animation could not be exported ([`super::export_animation`],
//! [`super::export_resampling`]).

use cagerig::RigError;
use thiserror::Error;

/// Why an animation could not be exported.
#[derive(Debug, Error)]
pub enum ExportAnimationError {
    /// No sample time was given.
    #[error("no sample times")]
    NoSamples,
    /// The resampling bound is not a positive number.
    #[error("the resampling bound {bound} must be positive")]
    InvalidBound {
        /// The bound given (world units).
        bound: f64,
    },
    /// The baked morph targets would not fit glTF's binary chunk.
    #[error(
        "baking {samples} samples of {vertices} vertices takes {gib:.1} GiB, past glTF's 4 GiB \
         binary limit: export fewer samples (--fps, --max-samples) or leave --bake out"
    )]
    TooLarge {
        /// Samples asked for.
        samples: usize,
        /// Skin vertices.
        vertices: usize,
        /// The bytes the bake would take, in GiB.
        gib: f64,
    },
    /// The character's document could not be written
    /// ([`super::export::session_to_gltf`]'s message: too many joints for glTF).
    #[error("{0}")]
    Document(String),
    /// The rig refused (or could not reach) the state of a sample.
    #[error("sample t = {time} s: {source}")]
    Sample {
        /// The sample's time, seconds.
        time: f64,
        /// Why.
        #[source]
        source: RigError,
    },
    /// The state the export started from could not be restored after the resampling's checks.
    #[error("restoring the state the export started from: {source}")]
    Restore {
        /// Why.
        #[source]
        source: RigError,
    },
}
