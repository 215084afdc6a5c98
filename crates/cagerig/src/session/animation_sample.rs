//! Animation samples: a pose and a rest cage (or a blend of two precomputed cage keyframes)
//! set in one event, then SkelUp, skinning and CageUp.

use super::rest_map::RestMeshState;
use super::{RestKeyframe, RigSession, roots_only};
use crate::error::RigError;
use crate::pose::LocalPose;
use glam::{DQuat, DVec3};

impl RigSession {
    /// Animation sample: rest-cage offsets from C₀ (`#C`), local rotations and root motions
    /// (`#J`); runs SkelUp so that bones follow the cage, then skinning and CageUp.
    pub fn set_animation_sample(
        &mut self,
        rest_cage_offsets: Option<&[DVec3]>,
        local_rotations: &[DQuat],
        root_motion: &[DVec3],
    ) -> Result<(), RigError> {
        self.set_animation_sample_local(
            rest_cage_offsets,
            &roots_only(local_rotations, root_motion),
        )
    }

    /// [`RigSession::set_animation_sample`] with the full pose of [`crate::pose`].
    pub fn set_animation_sample_local(
        &mut self,
        rest_cage_offsets: Option<&[DVec3]>,
        pose: &LocalPose,
    ) -> Result<(), RigError> {
        self.save_checkpoint();
        let result = self.set_animation_sample_local_event(rest_cage_offsets, pose);
        self.finish_event(result)
    }

    /// [`RigSession::set_animation_sample_local`] without the checkpoint.
    pub(super) fn set_animation_sample_local_event(
        &mut self,
        rest_cage_offsets: Option<&[DVec3]>,
        pose: &LocalPose,
    ) -> Result<(), RigError> {
        if let Some(offsets) = rest_cage_offsets {
            self.check_cage_offsets(offsets)?;
        }
        self.store_pose(pose)?;
        if let Some(offsets) = rest_cage_offsets {
            for ((c, o), c0) in self
                .rest_cage
                .iter_mut()
                .zip(offsets)
                .zip(&self.original_rest_cage)
            {
                *c = *c0 + *o;
            }
            // On the display path: M̃ for display and the exact MaxVol rows (see
            // `display_path`), as for a current-cage grab; on the exact path under LBS, M and
            // M' in one pass.
            self.rest_and_sync_from_cage();
        } else {
            self.sync_from_rest_cage();
        }
        Ok(())
    }

    /// Precomputes the rest state of a cage keyframe (offsets from C₀, `#C`).
    pub fn rest_keyframe(&self, offsets: &[DVec3]) -> Result<RestKeyframe, RigError> {
        self.check_cage_offsets(offsets)?;
        let cage: Vec<DVec3> = self
            .original_rest_cage
            .iter()
            .zip(offsets)
            .map(|(c, o)| *c + *o)
            .collect();
        let mut mesh = vec![DVec3::ZERO; self.rest_mesh.len()];
        self.rest_mesh_of_cage(&cage, &mut mesh);
        let terms = self.rest_map.terms_of(&cage);
        let centres = self.skinning.cor().map(|cor| {
            let mut centres = vec![DVec3::ZERO; self.rest_mesh.len()];
            self.centres_of_cage(cor, &cage, &mut centres);
            centres
        });
        Ok(RestKeyframe {
            cage,
            mesh,
            centres,
            terms,
        })
    }

    /// Animation sample between two precomputed cage keyframes (weight `a` on `hi`): C, M and
    /// the CoR centres are lerped (Green rigs: C and M are lerped and M corrected by
    /// ψ·(g(C) − lerp of the keys' g) on the faces where g is not linear along the blend; the
    /// CoR centres evaluated), then pose, SkelUp, skinning and CageUp as in
    /// [`RigSession::set_animation_sample`]. No allocation.
    pub fn set_animation_sample_between(
        &mut self,
        lo: &RestKeyframe,
        hi: &RestKeyframe,
        a: f64,
        local_rotations: &[DQuat],
        root_motion: &[DVec3],
    ) -> Result<(), RigError> {
        self.set_animation_sample_between_local(
            lo,
            hi,
            a,
            &roots_only(local_rotations, root_motion),
        )
    }

    /// [`RigSession::set_animation_sample_between`] with the full pose of [`crate::pose`].
    pub fn set_animation_sample_between_local(
        &mut self,
        lo: &RestKeyframe,
        hi: &RestKeyframe,
        a: f64,
        pose: &LocalPose,
    ) -> Result<(), RigError> {
        self.save_checkpoint();
        let result = self.set_animation_sample_between_local_event(lo, hi, a, pose);
        self.finish_event(result)
    }

    /// [`RigSession::set_animation_sample_between_local`] without the checkpoint.
    pub(super) fn set_animation_sample_between_local_event(
        &mut self,
        lo: &RestKeyframe,
        hi: &RestKeyframe,
        a: f64,
        pose: &LocalPose,
    ) -> Result<(), RigError> {
        let nv = self.rest_mesh.len();
        let nc = self.rest_cage.len();
        if lo.mesh.len() != nv || hi.mesh.len() != nv || lo.cage.len() != nc || hi.cage.len() != nc
        {
            return Err(RigError::SizeMismatch {
                what: "rest keyframe vertices",
                expected: nv,
                actual: lo.mesh.len().min(hi.mesh.len()),
            });
        }
        if !a.is_finite() {
            return Err(RigError::Invalid(format!("blend weight {a} is not finite")));
        }
        self.store_pose(pose)?;
        lerp_into(&lo.cage, &hi.cage, a, &mut self.rest_cage);
        // M is the blend of the keys' meshes (exact where M is linear in C), plus what the
        // kind's terms add beyond the blend of the keys' terms (Green: ψ·(g(C) − lerp(g_lo,
        // g_hi)) on the faces where that is above round-off; MVC: nothing). The display path
        // rounds this exact M.
        lerp_into(&lo.mesh, &hi.mesh, a, &mut self.rest_mesh);
        self.rest_map.add_keyframe_blend_terms(
            &lo.terms,
            &hi.terms,
            a,
            &self.rest_cage,
            &mut self.rest_mesh,
        );
        if let Some(display) = self.display.as_deref_mut() {
            display.forget_exact_rest();
        }
        self.rest_map.set_mesh_state(RestMeshState::Map);
        self.rest_mesh_changed();
        if !self.rest_map.is_linear() {
            // The centres' terms are not linear in C either: evaluated in full.
            self.centres_from_cage_in_full();
        } else {
            let blend = match (&lo.centres, &hi.centres) {
                (Some(l), Some(h)) => Some(|centres: &mut [DVec3]| lerp_into(l, h, a, centres)),
                (Some(_) | None, _) => None,
            };
            self.skinning.centres_follow_keyframes(blend);
        }
        self.sync_from_rest_cage();
        Ok(())
    }

    pub(super) fn check_cage_offsets(&self, offsets: &[DVec3]) -> Result<(), RigError> {
        if offsets.len() != self.rest_cage.len() {
            return Err(RigError::SizeMismatch {
                what: "cage animation offsets",
                expected: self.rest_cage.len(),
                actual: offsets.len(),
            });
        }
        if let Some(i) = offsets.iter().position(|o| !o.is_finite()) {
            return Err(RigError::NonFinite {
                what: "cage animation offset",
                index: i,
            });
        }
        Ok(())
    }
}

/// out = (1 − a)·lo + a·hi, in parallel for big point sets.
fn lerp_into(lo: &[DVec3], hi: &[DVec3], a: f64, out: &mut [DVec3]) {
    use rayon::prelude::*;
    out.par_chunks_mut(8192)
        .zip(lo.par_chunks(8192).zip(hi.par_chunks(8192)))
        .for_each(|(o, (l, h))| {
            for ((o, l), h) in o.iter_mut().zip(l).zip(h) {
                *o = l.lerp(*h, a);
            }
        });
}
