//! File formats: OBJ and the paper tool's formats (`.skt`, `.skw`, cage weights, CoR weights,
//! MaxVol rows, skeleton and cage animations). Assembling a whole rig from them is
//! [`crate::rig_files`], above this module.
//!
//! Every reader has a `read_*(path, …)` form and a `parse_*(bytes, source, …)` form (for tests
//! and in-memory data); every writer has a `write_*(path, …)` form that replaces the file
//! atomically ([`write_atomically`]) and a `write_*_to(writer, …)` form; an output of several files
//! goes into a folder that appears complete or not at all ([`StagedDir`]). Readers never panic:
//! any malformed input gives a [`ParseError`] naming the file and line.

pub mod atomic;
pub mod cage_animation;
pub mod cage_weights;
pub mod cor_weights;
pub mod discovery;
pub mod dq_blend_weights;
pub mod error;
pub mod euler;
mod keyframes;
pub mod maxvol;
pub mod obj;
pub mod skeleton_animation;
pub mod skt;
pub mod skw;
pub mod staged_dir;
pub mod text;

pub use atomic::write_atomically;
pub use cage_animation::{parse_cage_animation, read_cage_animation, write_cage_animation};
pub use cage_weights::{parse_cage_weights, read_cage_weights, write_cage_weights};
pub use cor_weights::{parse_cor_weights, read_cor_weights, write_cor_weights};
pub use discovery::{DiscoveredFiles, discover};
pub use dq_blend_weights::{parse_dq_blend_weights, read_dq_blend_weights, write_dq_blend_weights};
pub use error::ParseError;
pub use maxvol::{parse_maxvol, read_maxvol, write_maxvol};
pub use obj::{parse_obj, read_obj, write_obj};
pub use skeleton_animation::{
    LocalComposition, SkeletonAnimationVersion, parse_skeleton_animation,
    parse_skeleton_animation_with, read_skeleton_animation, read_skeleton_animation_with,
    write_skeleton_animation,
};
pub use skt::{parse_skt, read_skt, write_skt};
pub use skw::{parse_skw, read_skw, read_skw_for_skeleton, write_skw};
pub use staged_dir::{FolderNaming, StagedDir, StagedDirError};
pub use text::FloatFormat;
