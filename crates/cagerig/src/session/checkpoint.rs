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

use super::RigSession;
use crate::error::RigError;
use crate::skinning::SkinningMethod;

/// Largest coordinate a session accepts in C, C' or a joint position after an event (the inputs
/// are at most [`crate::error::MAX_INPUT_MAGNITUDE`]; edits may add up past it, but not this far).
pub const MAX_STATE_MAGNITUDE: f64 = 1e15;

/// The state saved before an event (buffers sized once, copied into without allocation).
#[derive(Debug, Clone)]
pub(super) struct Checkpoint {
    rest_cage: Vec<DVec3>,
    posed_cage: Vec<DVec3>,
    rest_world_from_joint: Vec<DAffine3>,
    posed_local_rotation: Vec<DQuat>,
    posed_local_scale: Vec<DVec3>,
    translation_offset: Vec<DVec3>,
    method: SkinningMethod,
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

fn bad_point(points: &[DVec3]) -> Option<(usize, DVec3)> {
    points
        .iter()
        .position(|p| !(p.is_finite() && p.abs().max_element() <= MAX_STATE_MAGNITUDE))
        .map(|k| (k, points[k]))
}

fn bad_frame(frames: &[DAffine3]) -> Option<(usize, DVec3)> {
    frames
        .iter()
        .position(|f| !(f.is_finite() && f.translation.abs().max_element() <= MAX_STATE_MAGNITUDE))
        .map(|k| (k, frames[k].translation))
}

impl RigSession {
    /// Saves the small state before an event.
    pub(super) fn save_checkpoint(&mut self) {
        let c = &mut self.checkpoint;
        c.rest_cage.copy_from_slice(&self.rest_cage);
        c.posed_cage.copy_from_slice(&self.posed_cage);
        c.rest_world_from_joint
            .copy_from_slice(&self.rest_world_from_joint);
        c.posed_local_rotation
            .copy_from_slice(&self.posed_local_rotation);
        c.posed_local_scale.copy_from_slice(&self.posed_local_scale);
        c.translation_offset
            .copy_from_slice(&self.translation_offset);
        c.method = self.skinning.method();
    }

    /// After an event: the first structure that is not finite (or too large), if any.
    fn first_bad_state(&self) -> Option<(&'static str, usize, DVec3)> {
        if let Some((k, p)) = bad_point(&self.rest_cage) {
            return Some(("rest cage vertex", k, p));
        }
        if let Some((k, p)) = bad_point(&self.posed_cage) {
            return Some(("current cage vertex", k, p));
        }
        if let Some((k, p)) = bad_frame(&self.rest_world_from_joint) {
            return Some(("rest joint", k, p));
        }
        if let Some((k, p)) = bad_frame(&self.posed_world_from_joint) {
            return Some(("current joint", k, p));
        }
        None
    }

    /// Ends an event that returned `result`: keeps it when the state is finite and bounded,
    /// otherwise (or when the event failed midway) restores the checkpoint and recomputes the
    /// meshes from it, so the session is as it was before the event.
    pub(super) fn finish_event(&mut self, result: Result<(), RigError>) -> Result<(), RigError> {
        let c = &self.checkpoint;
        let changed = self.rest_cage != c.rest_cage
            || self.posed_local_rotation != c.posed_local_rotation
            || self.posed_local_scale != c.posed_local_scale
            || self.translation_offset != c.translation_offset
            || self.skinning.method() != c.method;
        let refused = match result {
            Err(e) if !changed => return Err(e),
            Err(e) => Some(e),
            Ok(()) => {
                // A CageUp that found no current cage refuses the event unless the policy keeps
                // it (`session/unfitted_cage.rs`).
                let failure = self.rest_map.take_fit_failure();
                self.refuses_unfitted(failure).or_else(|| {
                    self.first_bad_state()
                        .map(|(what, index, value)| RigError::EventRefused {
                            what,
                            index,
                            value: value.to_array(),
                        })
                })
            }
        };
        let Some(error) = refused else {
            return Ok(());
        };
        let rest_changed = self.rest_cage != self.checkpoint.rest_cage;
        let c = &self.checkpoint;
        self.rest_cage.copy_from_slice(&c.rest_cage);
        self.rest_world_from_joint
            .copy_from_slice(&c.rest_world_from_joint);
        self.posed_local_rotation
            .copy_from_slice(&c.posed_local_rotation);
        self.posed_local_scale.copy_from_slice(&c.posed_local_scale);
        self.translation_offset
            .copy_from_slice(&c.translation_offset);
        self.skinning.restore(c.method);
        if rest_changed || !self.rest_mesh.iter().all(|p| p.is_finite()) {
            self.rest_from_cage_in_full();
        }
        self.rest_map.invalidate_reverser();
        // The saved C' is CageUp's answer for the restored state: start there (Green).
        self.posed_cage.copy_from_slice(&self.checkpoint.posed_cage);
        self.rest_map.start_next_fit_from_posed_cage();
        self.pose_and_fit();
        self.posed_cage.copy_from_slice(&self.checkpoint.posed_cage);
        // The restored state's own fit is not this event's: its failure is not reported.
        self.rest_map.take_fit_failure();
        Err(error)
    }
}
