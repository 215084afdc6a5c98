//! The end of every event: the checkpoint saved before it, the checks after it, and the
//! restore of a refused event (see [`super::checkpoint`] and [`super::unfitted_cage`]).

use super::RigSession;
use super::checkpoint::{bad_frame, bad_point};
use super::unfitted_cage::UnfittedCagePolicy;
use crate::error::{RigError, UnfittedCage};
use glam::DVec3;

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
impl RigSession {
    /// Why C' is not CageUp's fit of the current state, when it is not (only under
    /// [`UnfittedCagePolicy::KeepEvent`], after an event whose Green CageUp found no current
    /// cage); `None` while C' is the fit.
    pub fn posed_cage_unfitted(&self) -> Option<UnfittedCage> {
        self.rest_map.unfitted()
    }

    /// The session's [`UnfittedCagePolicy`].
    pub fn unfitted_cage_policy(&self) -> UnfittedCagePolicy {
        self.options.unfitted_cage
    }

    /// Sets the [`UnfittedCagePolicy`] of the next events (an unfitted C' stays so until an
    /// event fits it).
    pub fn set_unfitted_cage_policy(&mut self, policy: UnfittedCagePolicy) {
        self.options.unfitted_cage = policy;
    }

    /// `Err` when C' is unfitted: grabs of it are refused then.
    pub(super) fn check_posed_cage_fitted(&self) -> Result<(), RigError> {
        match self.posed_cage_unfitted() {
            Some(unfitted) => Err(RigError::PosedCageUnfitted(unfitted)),
            None => Ok(()),
        }
    }

    /// Whether an event whose CageUp ended as `failure` is refused under the policy.
    pub(super) fn refuses_unfitted(&self, failure: Option<RigError>) -> Option<RigError> {
        match self.options.unfitted_cage {
            UnfittedCagePolicy::Refuse => failure,
            UnfittedCagePolicy::KeepEvent => None,
        }
    }
}
