//! The session's pose interactions: the skinning method, joint rotations (S' edits), whole
//! poses from animation, and back to rest. Each public method is one event: checkpoint, the
//! event, then `finish_event` (all-or-nothing).

use super::parts::CageFitSource;
use super::{RigSession, roots_only};
use crate::error::RigError;
use crate::pose::{LocalPose, rotation_of};
use crate::skinning::SkinningMethod;
use glam::{DQuat, DVec3};

impl RigSession {
    /// Switches the skinning method; computes CoR centres on the first switch to CoR. The
    /// blended method needs the rig's DQ blend weights ([`RigError::NoDqBlendWeights`]), the
    /// external one a method passed in `SessionOptions::external_skinning`
    /// ([`RigError::NoExternalSkinning`]). Selecting the method in use changes nothing: no
    /// structure moves and CageUp does not fit again (a Green fit starts from the last C', so
    /// a second fit of the same pose would move C' by round-off).
    pub fn set_skinning(&mut self, method: SkinningMethod) -> Result<(), RigError> {
        if method == self.skinning.method() {
            return Ok(());
        }
        self.save_checkpoint();
        let result = self.select_skinning(method).map(|()| self.pose_and_fit());
        self.finish_event(result)
    }

    /// Selects `method` and builds what it needs (CoR centres), without posing: the first half
    /// of [`RigSession::set_skinning`], also used once at binding.
    pub(super) fn select_skinning(&mut self, method: SkinningMethod) -> Result<(), RigError> {
        if method.needs_dq_blend_weights() && self.skinning.dq_blend_weights().is_none() {
            return Err(RigError::NoDqBlendWeights);
        }
        if method == SkinningMethod::Cor {
            self.build_cor()?;
        }
        self.skinning.select(method)
    }

    /// Selects what CageUp fits for DQS / CoR (see [`CageFitSource`]).
    pub fn set_fit_source(&mut self, source: CageFitSource) {
        self.options_fit_source = source;
        self.pose_and_fit();
    }

    /// S' edit: rotates joint `joint` by `angle` radians about the world-space `axis`, pivoting
    /// on the joint's current position; descendants follow. Then M' and C' follow.
    pub fn rotate_joint(&mut self, joint: usize, axis: DVec3, angle: f64) -> Result<(), RigError> {
        self.save_checkpoint();
        let result = self.rotate_joint_event(joint, axis, angle);
        self.finish_event(result)
    }

    /// [`RigSession::rotate_joint`] without the checkpoint.
    fn rotate_joint_event(
        &mut self,
        joint: usize,
        axis: DVec3,
        angle: f64,
    ) -> Result<(), RigError> {
        self.check_joint(joint)?;
        let axis = axis
            .try_normalize()
            .ok_or_else(|| RigError::Invalid(format!("rotation axis {axis} has no direction")))?;
        if !angle.is_finite() {
            return Err(RigError::Invalid(format!(
                "rotation angle {angle} is not finite"
            )));
        }
        let world_rotation = DQuat::from_axis_angle(axis, angle);
        let joint_world = rotation_of(&self.posed_world_from_joint[joint].matrix3);
        let parent_world = match self.skeleton.parent(joint) {
            Some(p) => rotation_of(&self.posed_world_from_joint[p].matrix3),
            None => DQuat::IDENTITY,
        };
        self.posed_local_rotation[joint] =
            (parent_world.inverse() * world_rotation * joint_world).normalize();
        self.rest_map.invalidate_reverser();
        self.pose_and_fit();
        Ok(())
    }

    /// S' edit: sets all local rotations (parent_from_joint linear parts, `#J`) and root motions
    /// (current minus rest translation of each root; ignored for other joints). Scales return to
    /// the rest scales.
    pub fn set_pose(
        &mut self,
        local_rotations: &[DQuat],
        root_motion: &[DVec3],
    ) -> Result<(), RigError> {
        self.set_local_pose(&roots_only(local_rotations, root_motion))
    }

    /// S' edit: sets the full pose of [`crate::pose`] (rotations, scales, translation offsets).
    pub fn set_local_pose(&mut self, pose: &LocalPose) -> Result<(), RigError> {
        self.save_checkpoint();
        let result = self.set_local_pose_event(pose);
        self.finish_event(result)
    }

    /// [`RigSession::set_local_pose`] without the checkpoint.
    fn set_local_pose_event(&mut self, pose: &LocalPose) -> Result<(), RigError> {
        self.store_pose(pose)?;
        self.pose_and_fit();
        Ok(())
    }

    /// Local scales of the rest skeleton as loaded, `#J` (what [`LocalPose::scales`] = `None` means).
    pub fn rest_local_scales(&self) -> &[DVec3] {
        &self.rest_local_scale
    }

    /// Validates and stores a pose without running the sync chain.
    pub(super) fn store_pose(&mut self, pose: &LocalPose) -> Result<(), RigError> {
        let nj = self.skeleton.len();
        let scales_len = pose.scales.map_or(nj, <[DVec3]>::len);
        if pose.rotations.len() != nj || pose.translation_offsets.len() != nj || scales_len != nj {
            return Err(RigError::SizeMismatch {
                what: "pose joints",
                expected: nj,
                actual: pose
                    .rotations
                    .len()
                    .min(pose.translation_offsets.len())
                    .min(scales_len),
            });
        }
        if let Some(j) = (0..nj).find(|&j| {
            let q = pose.rotations[j];
            let bad_scale = pose
                .scales
                .is_some_and(|s| !s[j].is_finite() || s[j].cmpeq(DVec3::ZERO).any());
            !q.is_finite()
                || q.length_squared() == 0.0
                || !pose.translation_offsets[j].is_finite()
                || bad_scale
        }) {
            return Err(RigError::NonFinite {
                what: "pose joint (rotation, scale or translation)",
                index: j,
            });
        }
        for j in 0..nj {
            self.posed_local_rotation[j] = pose.rotations[j].normalize();
            self.posed_local_scale[j] = match pose.scales {
                Some(s) => s[j],
                None => self.rest_local_scale[j],
            };
            self.translation_offset[j] = if pose.roots_only && self.skeleton.parent(j).is_some() {
                DVec3::ZERO
            } else {
                pose.translation_offsets[j]
            };
        }
        self.rest_map.invalidate_reverser();
        Ok(())
    }

    /// Back to the rest pose (rest cage edits are kept).
    pub fn reset_pose(&mut self) {
        let mut locals = std::mem::take(&mut self.scratch_locals);
        self.skeleton
            .locals_from_worlds(&self.rest_world_from_joint, &mut locals);
        for (q, l) in self.posed_local_rotation.iter_mut().zip(&locals) {
            *q = rotation_of(&l.matrix3);
        }
        self.scratch_locals = locals;
        self.posed_local_scale
            .copy_from_slice(&self.rest_local_scale);
        self.translation_offset
            .iter_mut()
            .for_each(|m| *m = DVec3::ZERO);
        self.rest_map.invalidate_reverser();
        self.pose_and_fit();
    }
}
