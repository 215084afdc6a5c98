//! Events are all-or-nothing: the small state of a session (O(#C + #J): C, C', the rest and
//! current joint frames, the pose parameters: local rotations, scales, translation offsets) is saved before each event into preallocated
//! buffers, and checked after it. An event that would leave any of it non-finite, or beyond
//! [`MAX_STATE_MAGNITUDE`], is refused: the saved state is restored, M, M' and C' are recomputed
//! from it, and the event returns [`RigError::EventRefused`].
//!
//! Why the meshes need no scan: M = ΦC with every |Φ| ≤ [`crate::error::MAX_INPUT_MAGNITUDE`]
//! (checked where Φ enters) and |C| ≤ [`MAX_STATE_MAGNITUDE`] stays below
//! #C · 1e12 · 1e15 ≪ f64::MAX, and M' applies finite rigid transforms (checked here) to M, so
//! both meshes are finite whenever the checked state is.

use glam::{DAffine3, DQuat, DVec3};

use crate::skinning::SkinningMethod;

/// Largest coordinate a session accepts in C, C' or a joint position after an event (the inputs
/// are at most [`crate::error::MAX_INPUT_MAGNITUDE`]; edits may add up past it, but not this far).
pub const MAX_STATE_MAGNITUDE: f64 = 1e15;

/// The state saved before an event (buffers sized once, copied into without allocation).
#[derive(Debug, Clone)]
pub(super) struct Checkpoint {
    pub(super) rest_cage: Vec<DVec3>,
    pub(super) posed_cage: Vec<DVec3>,
    pub(super) rest_world_from_joint: Vec<DAffine3>,
    pub(super) posed_local_rotation: Vec<DQuat>,
    pub(super) posed_local_scale: Vec<DVec3>,
    pub(super) translation_offset: Vec<DVec3>,
    pub(super) method: SkinningMethod,
}

impl Checkpoint {
    pub(super) fn new(num_cage_vertices: usize, num_joints: usize) -> Self {
        Self {
            rest_cage: vec![DVec3::ZERO; num_cage_vertices],
            posed_cage: vec![DVec3::ZERO; num_cage_vertices],
            rest_world_from_joint: vec![DAffine3::IDENTITY; num_joints],
            posed_local_rotation: vec![DQuat::IDENTITY; num_joints],
            posed_local_scale: vec![DVec3::ONE; num_joints],
            translation_offset: vec![DVec3::ZERO; num_joints],
            method: SkinningMethod::Lbs,
        }
    }
}

pub(super) fn bad_point(points: &[DVec3]) -> Option<(usize, DVec3)> {
    points
        .iter()
        .position(|p| !(p.is_finite() && p.abs().max_element() <= MAX_STATE_MAGNITUDE))
        .map(|k| (k, points[k]))
}

pub(super) fn bad_frame(frames: &[DAffine3]) -> Option<(usize, DVec3)> {
    frames
        .iter()
        .position(|f| !(f.is_finite() && f.translation.abs().max_element() <= MAX_STATE_MAGNITUDE))
        .map(|k| (k, frames[k].translation))
}
