//! The session's editable state read and restored, and the sync locks (see
//! [`super::editable_state`]).

use super::RigSession;
use super::editable_state::{EditableState, SyncLocks};
use super::parts::PHI_C_TOLERANCE;
use crate::coords_kind::CoordsKind;
use crate::error::RigError;
use crate::pose::LocalPose;
use glam::{DAffine3, DQuat, DVec3};

impl RigSession {
    /// Local rotations q_j of the current pose (parent_from_joint rotation), `#J`.
    pub fn posed_local_rotations(&self) -> &[DQuat] {
        &self.posed_local_rotation
    }

    /// Local scales s_j of the current pose, `#J`.
    pub fn posed_local_scales(&self) -> &[DVec3] {
        &self.posed_local_scale
    }

    /// d_j of [`crate::pose`]: current local translation minus the rest bone offset, `#J`.
    pub fn translation_offsets(&self) -> &[DVec3] {
        &self.translation_offset
    }

    /// The locks in force.
    pub fn sync_locks(&self) -> SyncLocks {
        self.locks
    }

    /// Switches SkelUp / CageUp off or on. Switching one back on runs the full sync (S = ΨC,
    /// FK, skinning, C' fit), so the rig is in consensus again.
    pub fn set_sync_locks(&mut self, locks: SyncLocks) {
        let unlocked =
            (self.locks.skel_up && !locks.skel_up) || (self.locks.cage_up && !locks.cage_up);
        self.replace_locks(locks);
        if unlocked {
            self.sync_from_rest_cage();
        }
    }

    /// Sets SkelUp's lock without the sync that unlocking runs: for an animation sample whose
    /// skeleton keys already contain the rest joints' motion ([`crate::playback`]).
    pub(crate) fn set_skel_up_lock_quietly(&mut self, locked: bool) {
        self.replace_locks(SyncLocks {
            skel_up: locked,
            ..self.locks
        });
    }

    /// Sets the locks; a change of SkelUp's drops Eq. 19's factors, whose skeleton term
    /// depends on it (the Green CageRev keys its own on the lock).
    fn replace_locks(&mut self, locks: SyncLocks) {
        if locks.skel_up != self.locks.skel_up {
            self.rest_map.invalidate_reverser();
        }
        self.locks = locks;
    }

    /// The editable state now.
    pub fn editable_state(&self) -> EditableState {
        EditableState {
            rest_cage: self.rest_cage.clone(),
            rest_joints: self.rest_joints().collect(),
            posed_cage: (self.locks.cage_up || self.posed_cage_unfitted().is_some())
                .then(|| self.posed_cage.clone()),
            rotations: self.posed_local_rotation.clone(),
            scales: self.posed_local_scale.clone(),
            translation_offsets: self.translation_offset.clone(),
            skinning: self.skinning.method(),
            locks: self.locks,
            coords: self.coords_kind(),
            unfitted_cage: self.unfitted_cage_policy(),
            cage_fit: self.requested_cage_fit(),
            green_face_term: self.green_face_term(),
        }
    }

    /// Restores a state taken with [`RigSession::editable_state`] (from this rig: the sizes
    /// must match, every number finite). One all-or-nothing event. A state bound with other
    /// cage coordinates, or a Green state with another face term, rebinds the rig first
    /// ([`RigSession::rebound_with`]).
    pub fn restore_editable_state(&mut self, state: &EditableState) -> Result<(), RigError> {
        let other_map = match state.coords {
            CoordsKind::Mvc => false,
            CoordsKind::Green => state.green_face_term != self.green_face_term(),
        };
        if state.coords != self.coords_kind() || other_map {
            let (mut rebound, _) = self.rebound_with(state.coords, state.green_face_term)?;
            let mut adapted = state.clone();
            if !state.locks.skel_up && state.rest_cage.len() == rebound.rest_cage.len() {
                // SkelUp of the new binding places the joints (its Ψ differs), unless the
                // state's joints already agree with it (then they are kept bit for bit: an undo
                // restores the exact state).
                let terms = rebound.rest_map.terms_of(&state.rest_cage);
                rebound
                    .skeleton_updater
                    .apply(&state.rest_cage, &terms, &mut adapted.rest_joints);
                let (lo, hi) = crate::mesh::bounding_box(&state.rest_cage);
                let agree = crate::mesh::max_distance(&adapted.rest_joints, &state.rest_joints)
                    <= PHI_C_TOLERANCE * (hi - lo).length();
                if agree {
                    adapted.rest_joints.clone_from(&state.rest_joints);
                }
            }
            rebound.restore_editable_state(&adapted)?;
            *self = rebound;
            return Ok(());
        }
        // A mean value rig only records the face term (its map does not use it).
        self.options.green_face_term = state.green_face_term;
        if state.cage_fit != self.requested_cage_fit() {
            // All or nothing: switch a copy, restore into it, keep it only if both succeed.
            let mut switched = self.clone();
            switched.set_cage_fit(state.cage_fit)?;
            switched.restore_editable_state(state)?;
            *self = switched;
            return Ok(());
        }
        let nc = self.rest_cage.len();
        let nj = self.skeleton.len();
        let posed_cage = state.posed_cage.as_deref().unwrap_or(&state.rest_cage);
        for (what, expected, actual) in [
            ("rest cage vertices of the state", nc, state.rest_cage.len()),
            ("current cage vertices of the state", nc, posed_cage.len()),
            ("rest joints of the state", nj, state.rest_joints.len()),
        ] {
            if expected != actual {
                return Err(RigError::SizeMismatch {
                    what,
                    expected,
                    actual,
                });
            }
        }
        for (what, points) in [
            ("rest cage vertex of the state", &state.rest_cage[..]),
            ("current cage vertex of the state", posed_cage),
            ("rest joint of the state", &state.rest_joints[..]),
        ] {
            if let Some(index) = points.iter().position(|p| !p.is_finite()) {
                return Err(RigError::NonFinite { what, index });
            }
        }
        if state.skinning != self.skinning.method() {
            self.set_skinning(state.skinning)?;
        }
        // The state's policy decides whether its pose may leave C' unfitted; a refused restore
        // keeps the session's.
        let policy = self.unfitted_cage_policy();
        self.set_unfitted_cage_policy(state.unfitted_cage);
        self.save_checkpoint();
        let result = self.restore_event(state);
        let result = self.finish_event(result);
        if result.is_err() {
            self.set_unfitted_cage_policy(policy);
        }
        result
    }

    fn restore_event(&mut self, state: &EditableState) -> Result<(), RigError> {
        self.store_pose(&LocalPose {
            rotations: &state.rotations,
            scales: Some(&state.scales),
            translation_offsets: &state.translation_offsets,
            roots_only: false,
        })?;
        // Rotations that are already unit are kept bit for bit (normalising again may move
        // the last bit).
        for (q, s) in self.posed_local_rotation.iter_mut().zip(&state.rotations) {
            if (s.length() - 1.0).abs() <= 1e-12 {
                *q = *s;
            }
        }
        self.replace_locks(state.locks);
        self.rest_cage.copy_from_slice(&state.rest_cage);
        self.rest_from_cage_in_full();
        for (frame, a) in self
            .rest_world_from_joint
            .iter_mut()
            .zip(&state.rest_joints)
        {
            frame.translation = *a;
        }
        self.pose_and_fit();
        // A locked C' is the state's; so is an unfitted one (the closest cage the fit found
        // then, which depends on where it started), unless this fit found the cage.
        let unfitted = self.posed_cage_unfitted().is_some();
        if let (true, Some(posed)) = (self.locks.cage_up || unfitted, &state.posed_cage) {
            self.posed_cage.copy_from_slice(posed);
        }
        Ok(())
    }

    /// Rest frames of the joints (`#J`, world from joint), for callers that need more than
    /// the positions.
    pub fn rest_frames(&self) -> &[DAffine3] {
        &self.rest_world_from_joint
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::test_rigs::bar;
    use crate::skinning::SkinningMethod;

    #[test]
    fn restoring_a_state_gives_back_the_editable_state_exactly() {
        let mut s = bar();
        let before = s.editable_state();
        let posed_before = s.posed_mesh().to_vec();
        s.rotate_joint(1, DVec3::Z, 0.7).unwrap();
        s.move_rest_cage(&[0, 3], &[DVec3::new(0.1, -0.2, 0.05)])
            .unwrap();
        s.move_posed_cage(&[5], &[DVec3::new(0.0, 0.3, 0.0)])
            .unwrap();
        s.set_skinning(SkinningMethod::Dqs).unwrap();
        let after = s.editable_state();
        assert_ne!(after, before);
        s.restore_editable_state(&before).unwrap();
        assert_eq!(s.editable_state(), before);
        for (a, b) in s.posed_mesh().iter().zip(&posed_before) {
            assert!(a.distance(*b) < 1e-12, "{a} vs {b}");
        }
        s.restore_editable_state(&after).unwrap();
        assert_eq!(s.editable_state(), after);
    }

    #[test]
    fn skel_up_lock_keeps_the_rest_joints_and_unlocking_resyncs() {
        let mut s = bar();
        let joints: Vec<DVec3> = s.rest_joints().collect();
        s.set_sync_locks(SyncLocks {
            skel_up: true,
            cage_up: false,
        });
        let all: Vec<usize> = (0..s.rest_cage().len()).collect();
        s.move_rest_cage(&all, &[DVec3::new(0.5, 0.0, 0.0)])
            .unwrap();
        assert_eq!(s.rest_joints().collect::<Vec<_>>(), joints);
        s.set_sync_locks(SyncLocks::default());
        for (a, b) in s.rest_joints().zip(&joints) {
            assert!((a - *b - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-9);
        }
    }

    #[test]
    fn cage_up_lock_keeps_the_current_cage_and_refuses_current_cage_edits() {
        let mut s = bar();
        s.set_sync_locks(SyncLocks {
            skel_up: false,
            cage_up: true,
        });
        let cage = s.posed_cage().to_vec();
        s.rotate_joint(1, DVec3::Z, 0.5).unwrap();
        assert_eq!(s.posed_cage(), &cage[..]);
        let err = s.move_posed_cage(&[0], &[DVec3::X]).unwrap_err();
        assert!(err.to_string().contains("CageUp is locked"), "{err}");
        s.set_sync_locks(SyncLocks::default());
        assert_ne!(s.posed_cage(), &cage[..]);
    }

    #[test]
    fn a_state_of_the_wrong_size_is_refused_without_change() {
        let mut s = bar();
        let mut state = s.editable_state();
        state.rest_cage.pop();
        let err = s.restore_editable_state(&state).unwrap_err();
        assert!(err.to_string().contains("rest cage vertices"), "{err}");
    }
}
