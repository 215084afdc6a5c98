//! Rebinding a rig with other cage coordinates (MVC ↔ Green), keeping every edit: what an
//! editor's "coordinates" switch and the restore of a saved state with another kind do.

use super::RigSession;
use super::parts::{GivenCageCoords, RigParts, SessionOptions};
use crate::coords::stretched_normals::FaceTermKind;
use crate::coords_kind::CoordsKind;
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;
use glam::DVec3;

impl RigSession {
    /// The same rig bound with `coords`: rebuilt from the rest skin at the binding cage C₀
    /// (M₀ = the map of C₀), the skeleton as loaded, Ω and C₀, with the options this session was
    /// built with; the display precision is carried over. The edits (C, the pose, the method)
    /// are not applied: restore them with [`RigSession::restore_editable_state`] (which does
    /// this rebind itself when a state's coordinates differ).
    pub fn rebound(&self, coords: CoordsKind) -> Result<(RigSession, Vec<Warning>), RigError> {
        self.rebound_with(coords, self.options.green_face_term)
    }

    /// [`RigSession::rebound`] with the Green face term `green_face_term`.
    pub fn rebound_with(
        &self,
        coords: CoordsKind,
        green_face_term: FaceTermKind,
    ) -> Result<(RigSession, Vec<Warning>), RigError> {
        let mut binding_mesh = vec![DVec3::ZERO; self.rest_mesh.len()];
        self.rest_mesh_of_cage(&self.original_rest_cage, &mut binding_mesh);
        let dq_blend_weights = self.dq_blend_weights().cloned();
        let parts = RigParts::new(
            TriMesh {
                positions: binding_mesh,
                triangles: self.mesh_triangles.clone(),
            },
            self.skeleton.clone(),
            self.skin_weights.clone(),
            TriMesh {
                positions: self.original_rest_cage.clone(),
                triangles: self.cage_triangles.clone(),
            },
        )
        .with_dq_blend_weights(dq_blend_weights);
        let options = SessionOptions {
            coords,
            green_face_term,
            skinning: self.skinning.method(),
            // The binding mesh is the map of C₀: nothing to recompute or keep.
            given_cage_coords: GivenCageCoords::RecomputeIfInexact,
            ..self.options.clone()
        };
        let (mut session, warnings) = RigSession::new(parts, options)?;
        session.set_display_precision(self.display_precision())?;
        Ok((session, warnings))
    }
}
