//! The sync chain behind every event: checks, M = ΦC (in full or incrementally), SkelUp,
//! forward kinematics, skinning and CageUp, and the lazily built CoR state.

use super::RigSession;
use super::green_cage_up::CageUpInputs;
use super::parts::compute_centre_coords;
use super::rest_map::{CageMap, RestMeshState};
use super::skinning::CorState;
use crate::cage_coords::CoordsPrecision;
use crate::error::RigError;
use crate::pose::local_transform;
use crate::skeleton::Skeleton;
use crate::skinning::SkinningMethod;
use crate::skinning::cor::CorScratch;
use crate::skinning::dqs::DqsScratch;
use glam::DVec3;

impl RigSession {
    pub(super) fn check_joint(&self, joint: usize) -> Result<(), RigError> {
        if joint >= self.skeleton.len() {
            return Err(RigError::IndexOutOfRange {
                what: "joint",
                index: joint,
                len: self.skeleton.len(),
            });
        }
        Ok(())
    }

    pub(super) fn check_cage_edit(
        &self,
        vertices: &[usize],
        offsets: &[DVec3],
    ) -> Result<(), RigError> {
        if offsets.len() != 1 && offsets.len() != vertices.len() {
            return Err(RigError::SizeMismatch {
                what: "cage edit offsets (one, or one per vertex)",
                expected: vertices.len(),
                actual: offsets.len(),
            });
        }
        if let Some(&bad) = vertices.iter().find(|&&v| v >= self.rest_cage.len()) {
            return Err(RigError::IndexOutOfRange {
                what: "cage vertex",
                index: bad,
                len: self.rest_cage.len(),
            });
        }
        if let Some(i) = offsets.iter().position(|o| !o.is_finite()) {
            return Err(RigError::NonFinite {
                what: "cage offset",
                index: i,
            });
        }
        Ok(())
    }

    /// Builds the CoR state (Λ and the centres Λ·C) unless it is built: from the Λ given with
    /// the parts, the loaded centre rows (Λ = S·Φ) or computed (see [`compute_centre_coords`]).
    pub(super) fn build_cor(&mut self) -> Result<(), RigError> {
        if self.skinning.has_cor() {
            return Ok(());
        }
        self.ensure_exact_rest_mesh();
        let Self {
            skinning,
            rest_mesh,
            rest_cage,
            mesh_triangles,
            skin_weights,
            rest_map,
            ..
        } = self;
        skinning.build_cor(|source| {
            let centre_coords = match (&source.rows, source.given.take()) {
                (_, Some(lambda)) => {
                    if lambda.num_vertices() != rest_mesh.len()
                        || lambda.num_cage_vertices() != rest_cage.len()
                    {
                        return Err(RigError::SizeMismatch {
                            what: "CoR cage coordinates Λ (#V × #C)",
                            expected: rest_mesh.len() * rest_cage.len(),
                            actual: lambda.num_vertices() * lambda.num_cage_vertices(),
                        });
                    }
                    lambda
                }
                // Loaded rows: Λ = S·Φ (O(nnz(S)·#C); fine for the rows the tool writes, which
                // address the original vertices, also after subdivision).
                (Some(rows), None) => rows.compose_dense(rest_map.coords())?,
                (None, None) => compute_centre_coords(
                    rest_mesh,
                    mesh_triangles,
                    skin_weights,
                    rest_map.coords(),
                    &source.options,
                )?,
            };
            let mut centre_coords = centre_coords;
            if rest_map.coords().precision() == CoordsPrecision::F32 {
                centre_coords.round_to_f32();
            }
            rest_map.build_centre_terms(|coords| match &source.rows {
                Some(rows) => rows.compose_dense(coords),
                None => compute_centre_coords(
                    rest_mesh,
                    mesh_triangles,
                    skin_weights,
                    coords,
                    &source.options,
                ),
            })?;
            let mut centres = vec![DVec3::ZERO; rest_mesh.len()];
            centre_coords.apply(rest_cage, &mut centres);
            rest_map.add_centre_terms(&mut centres);
            Ok(CorState::new(centre_coords, centres, skin_weights))
        })
    }

    /// After C changed everywhere: M = ΦC, and the CoR centres Λ·C (or marked stale when CoR
    /// skinning is not active).
    pub(super) fn rest_from_cage_in_full(&mut self) {
        self.rest_map
            .rest_mesh_in_full(&self.rest_cage, &mut self.rest_mesh);
        self.rest_mesh_computed_in_full();
    }

    /// After M was computed in full from C: M is ΦC (+ terms) on every row, its revision moves
    /// on, and the CoR centres follow C.
    fn rest_mesh_computed_in_full(&mut self) {
        self.rest_map.set_mesh_state(RestMeshState::Map);
        self.rest_mesh_changed();
        self.centres_from_cage_in_full();
    }

    /// The CoR centres Λ·C after C changed everywhere (or marked stale when CoR skinning is not
    /// active).
    pub(super) fn centres_from_cage_in_full(&mut self) {
        let (rest_cage, rest_map) = (&self.rest_cage, &self.rest_map);
        self.skinning.centres_follow_cage(|centre_coords, centres| {
            centre_coords.apply(rest_cage, centres);
            rest_map.add_centre_terms(centres);
        });
    }

    /// Applies ΔC on a few rest-cage vertices to C, M and the CoR centres.
    pub(super) fn apply_rest_cage_delta_sparse(&mut self, vertices: &[usize], deltas: &[DVec3]) {
        self.ensure_exact_rest_mesh();
        self.rest_mesh_changed();
        for (&k, d) in vertices.iter().zip(deltas) {
            self.rest_cage[k] += *d;
        }
        match self.rest_map.mesh_state() {
            RestMeshState::AsLoaded => {
                self.rest_map
                    .rest_mesh_in_full(&self.rest_cage, &mut self.rest_mesh);
                self.rest_map.set_mesh_state(RestMeshState::Map);
            }
            // `ensure_exact_rest_mesh` above made M whole.
            RestMeshState::Map | RestMeshState::MapOnRows => self.rest_map.apply_rest_delta(
                vertices,
                deltas,
                &self.rest_cage,
                &mut self.rest_mesh,
            ),
        }
        // Non-linear maps refresh the centres in full (their terms changed too).
        self.skinning
            .centres_follow_cage_delta(vertices, deltas, self.rest_map.is_linear());
    }

    /// After C changed: SkelUp (A = ΨC, or Ψ_φC + Ψ_ψ g(C) for Green rigs; rest frames
    /// re-placed), FK, skinning, CageUp.
    pub(super) fn sync_from_rest_cage(&mut self) {
        self.skeleton_from_cage();
        self.pose_and_fit();
    }

    /// SkelUp: the rest joints A = ΨC (+ Ψ_ψ g(C)) placed in the rest frames, unless locked.
    fn skeleton_from_cage(&mut self) {
        if !self.locks.skel_up {
            self.skeleton_updater.apply(
                &self.rest_cage,
                self.rest_map.terms(),
                &mut self.scratch_joints,
            );
            for (frame, a) in self
                .rest_world_from_joint
                .iter_mut()
                .zip(&self.scratch_joints)
            {
                frame.translation = *a;
            }
        }
    }

    /// After C changed everywhere: M, SkelUp, FK, skinning and CageUp, as
    /// [`Self::rest_from_cage_for_event`] followed by [`Self::sync_from_rest_cage`] (the same
    /// bits). On the exact path under LBS, M and M' come out of one pass over the rows: each
    /// tile of M = ΦC (+ ψ·g) is skinned while it is in the core's cache
    /// ([`CageCoords::apply_then`]), so M is not read back from memory (`tests/display_path.rs`
    /// checks M and M' against the display path's exact ones, computed in two passes).
    pub(super) fn rest_and_sync_from_cage(&mut self) {
        if self.display.is_some() || self.skinning.method() != SkinningMethod::Lbs {
            self.rest_from_cage_for_event();
            self.sync_from_rest_cage();
            return;
        }
        self.rest_map.update_terms(&self.rest_cage);
        self.skeleton_from_cage();
        self.pose();
        let lbs = self.skinning.lbs();
        let transforms = &self.posed_from_rest;
        self.rest_map.coords().apply_then(
            &self.rest_cage,
            self.rest_map
                .extra_coords()
                .map(|e| (e, self.rest_map.terms())),
            &mut self.rest_mesh,
            &mut self.posed_mesh,
            |first, rest, posed| lbs.apply_range(transforms, first, rest, posed),
        );
        self.rest_mesh_computed_in_full();
        if !self.locks.cage_up {
            self.fit_cage();
        }
    }

    /// FK of the current pose on the current rest skeleton, skinning, CageUp.
    pub(super) fn pose_and_fit(&mut self) {
        self.pose();
        if !self.locks.cage_up && self.skin_beside_green_fit() {
            return;
        }
        self.skin();
        if !self.locks.cage_up {
            self.fit_cage();
        }
    }

    /// Skinning and CageUp side by side, for Green rigs on the exact path under LBS (returns
    /// false, doing nothing, otherwise): CageUp's rows M'_R are skinned first on their own
    /// (`ghost_lbs`: LBS of those rows, the bits of the same rows of M'), then the Gauss–Newton
    /// fit, which costs about the same whatever the skin's size, runs on this thread while the
    /// skin M' is computed on the others (`rayon::join`; the skin's chunks are spread over
    /// every thread once the fit is done). The same M' and C' as [`Self::skin`] followed by
    /// [`Self::fit_cage`].
    fn skin_beside_green_fit(&mut self) -> bool {
        if self.display.is_some()
            || self.skinning.method() != SkinningMethod::Lbs
            || self.rest_map.is_linear()
        {
            return false;
        }
        self.refresh_stale_centres();
        // Under LBS the ghost rows are the exact skinned rows.
        self.posed_fit_rows(true);
        let CageMap::Green(green) = self.rest_map.cage_map_mut() else {
            return false;
        };
        green
            .cage_up
            .target_rows
            .copy_from_slice(&self.scratch_rows_posed);
        let inputs = CageUpInputs {
            posed_from_rest: &self.posed_from_rest,
            rest_cage: &self.rest_cage,
            original_rest_cage: &self.original_rest_cage,
            unfitted_policy: self.options.unfitted_cage,
            limit: green.fit_limit(),
        };
        let (lbs, transforms) = (self.skinning.lbs(), &self.posed_from_rest);
        let (rest_mesh, posed_mesh) = (&self.rest_mesh, &mut self.posed_mesh);
        rayon::join(
            || green.cage_up.fit_cage(inputs, &mut self.posed_cage),
            || lbs.apply(transforms, rest_mesh, posed_mesh),
        );
        true
    }

    /// FK of the current pose on the current rest skeleton: the current joints and the
    /// skinning transforms.
    fn pose(&mut self) {
        // Locals: rest bone offset o_j + offset d_j, current rotation and scale.
        for j in 0..self.skeleton.len() {
            let rest_offset = match self.skeleton.parent(j) {
                Some(p) => self.rest_world_from_joint[p]
                    .inverse()
                    .transform_point3(self.rest_world_from_joint[j].translation),
                None => self.rest_world_from_joint[j].translation,
            };
            self.scratch_locals[j] = local_transform(
                rest_offset + self.translation_offset[j],
                self.posed_local_rotation[j],
                self.posed_local_scale[j],
            );
        }
        self.skeleton
            .forward_kinematics(&self.scratch_locals, &mut self.posed_world_from_joint);
        Skeleton::skinning_transforms(
            &self.rest_world_from_joint,
            &self.posed_world_from_joint,
            &mut self.posed_from_rest,
        );
    }

    /// M' from M under the current method: the exact f64 M', or on the display path the f32
    /// display mesh (see [`super::display_path`]).
    pub(super) fn skin(&mut self) {
        self.refresh_stale_centres();
        if self.display.is_some() {
            if self.skin_display().is_ok() {
                return;
            }
            // Unreachable: the display kernels are sized like M at construction. Fall back to
            // the exact path rather than show a stale mesh.
            self.ensure_exact_rest_mesh();
            self.display = None;
        }
        self.skinning
            .apply(&self.posed_from_rest, &self.rest_mesh, &mut self.posed_mesh);
    }

    /// The CoR centres that went stale since the rest cage changed, recomputed from it.
    fn refresh_stale_centres(&mut self) {
        let (rest_cage, rest_map) = (&self.rest_cage, &self.rest_map);
        self.skinning
            .refresh_stale_centres(|centre_coords, centres| {
                centre_coords.apply(rest_cage, centres);
                rest_map.add_centre_terms(centres);
            });
    }

    /// The exact M' (`#V`, f64) of the current state into `out`, from the exact `rest_mesh` M.
    pub(super) fn skin_exact(
        &self,
        rest_mesh: &[DVec3],
        dqs_scratch: &mut DqsScratch,
        cor_scratch: &mut CorScratch,
        out: &mut [DVec3],
    ) {
        self.skinning.apply_with(
            &self.posed_from_rest,
            rest_mesh,
            dqs_scratch,
            cor_scratch,
            out,
        );
    }

    /// CageUp's target M'_R (`#R`) into `scratch_rows_posed`: the ghost LBS of the fitting
    /// rows (`ghost`, Sec. 4.3), else the exact skinned rows (skinned here on the display path).
    fn posed_fit_rows(&mut self, ghost: bool) {
        if ghost {
            for (r, &row) in self.scratch_rows_rest.iter_mut().zip(self.rest_map.rows()) {
                *r = self.rest_mesh[row];
            }
            self.ghost_lbs.apply(
                &self.posed_from_rest,
                &self.scratch_rows_rest,
                &mut self.scratch_rows_posed,
            );
        } else if self.display.is_some() {
            self.skin_rows_exact();
        } else {
            for (r, &row) in self.scratch_rows_posed.iter_mut().zip(self.rest_map.rows()) {
                *r = self.posed_mesh[row];
            }
        }
    }

    /// MVC CageUp: C' = P·M'_R (Sec. 4.1, Eq. 8), or the regularised C' = K·M'_R + Q·P(C, S')
    /// ([`crate::sync::cage_prior`]).
    pub(super) fn fit_linear_cage(&mut self, ghost: bool) {
        self.posed_fit_rows(ghost);
        self.rest_map.fit_linear(
            &self.scratch_rows_posed,
            &self.posed_from_rest,
            &self.rest_cage,
            &mut self.posed_cage,
        );
    }

    /// Green CageUp: M'_R, then the Gauss–Newton fit.
    pub(super) fn fit_green_cage_rows(&mut self, ghost: bool) {
        self.posed_fit_rows(ghost);
        if let CageMap::Green(green) = self.rest_map.cage_map_mut() {
            green
                .cage_up
                .target_rows
                .copy_from_slice(&self.scratch_rows_posed);
        }
        self.fit_green_cage();
    }
}

#[cfg(test)]
mod tests {
    use super::super::{RigParts, RigSession, SessionOptions};
    use crate::CoordsKind;
    use glam::DVec3;

    /// A Green rig's skin and CageUp side by side give the M' and C' of the skin followed by
    /// the fit, bit for bit: the fit's rows are the rows of that M'.
    #[test]
    fn green_cage_up_beside_the_skin_gives_the_bits_of_one_after_the_other() {
        let rig = crate::demo::builtin("bar", Some(8)).unwrap();
        let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        let options = SessionOptions {
            coords: CoordsKind::Green,
            ..SessionOptions::default()
        };
        let (mut session, _) = RigSession::new(parts, options).unwrap();
        for (joint, angle) in [(1, 0.4), (2, -0.7), (1, 0.3)] {
            let mut sequential = session.clone();
            session.rotate_joint(joint, DVec3::X, angle).unwrap();
            sequential
                .posed_local_rotation
                .clone_from(&session.posed_local_rotation);
            sequential.pose();
            sequential.skin();
            sequential.fit_cage();
            assert_eq!(session.posed_mesh, sequential.posed_mesh);
            assert_eq!(session.posed_cage, sequential.posed_cage);
            assert!(session.rest_map.unfitted().is_none());
        }
    }
}
