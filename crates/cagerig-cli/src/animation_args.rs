//! The animation options shared by `animate`, `render` and `export`: which animation a command
//! plays, by one set of flags with one help text and one rule.

use std::path::PathBuf;

use crate::interchange::{AnimationTracks, animation_tracks};
use crate::rig_source::LoadedRig;

/// What to say when a command needs an animation and none was given.
pub const NO_ANIMATION: &str =
    "give --skeleton-anim (or --animation for glTF/FBX) and/or --cage-anim";

/// The animation a command plays: a skeleton track (the paper tool's text file, or the glTF/FBX
/// file's own animation) and/or a cage track.
#[derive(Debug, Clone, clap::Args)]
pub struct AnimationSourceArgs {
    /// Skeleton animation (the paper tool's V1/V2/V3 text format).
    #[arg(long)]
    pub skeleton_anim: Option<PathBuf>,
    /// Cage animation (rest-cage offsets; exported as morph targets).
    #[arg(long)]
    pub cage_anim: Option<PathBuf>,
    /// glTF/FBX: the file's animation, by name or index (all its channels).
    #[arg(long, conflicts_with = "skeleton_anim")]
    pub animation: Option<String>,
}

impl AnimationSourceArgs {
    /// Whether any animation was given.
    pub fn is_given(&self) -> bool {
        self.skeleton_anim.is_some() || self.cage_anim.is_some() || self.animation.is_some()
    }

    /// The tracks to play on `loaded` (see [`animation_tracks`]).
    pub fn tracks(&self, loaded: &mut LoadedRig) -> anyhow::Result<AnimationTracks> {
        animation_tracks(
            loaded,
            self.skeleton_anim.as_deref(),
            self.animation.as_deref(),
            self.cage_anim.as_deref(),
        )
    }
}
