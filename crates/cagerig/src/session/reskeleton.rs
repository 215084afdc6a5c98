//! Binding the character to another skeleton and other skinning weights at its current rest
//! pose: what an editor's "Bind" does after the user built or changed the skeleton.
//!
//! The rest skin M (exactly the map of the current rest cage C), C and the options carry
//! over; the new session computes its cage coordinates, MaxVol rows, Ψ and Λ afresh, and its
//! binding cage C₀ is the current C. The pose is not carried: its joints may differ.

use super::RigSession;
use super::parts::{GivenCageCoords, RigParts, SessionOptions};
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use glam::DVec3;

impl RigSession {
    /// The parts of this character at its current rest pose — M exactly the map of C
    /// (`#V`), its triangles, C (`#C`) and its triangles — with the rest skeleton `skeleton`
    /// (world-space rest frames at this pose) and Ω = `skin_weights` (`#V × #J`), and the DQ
    /// blend weights of this rig (per vertex, so they carry over). With
    /// [`RigSession::rebinding_options`] they make the session [`RigSession::new`] builds.
    pub fn parts_with_skeleton(&self, skeleton: Skeleton, skin_weights: SkinWeights) -> RigParts {
        let mut rest_mesh = vec![DVec3::ZERO; self.rest_mesh.len()];
        self.rest_mesh_of_cage(&self.rest_cage, &mut rest_mesh);
        RigParts::new(
            TriMesh {
                positions: rest_mesh,
                triangles: self.mesh_triangles.clone(),
            },
            skeleton,
            skin_weights,
            TriMesh {
                positions: self.rest_cage.clone(),
                triangles: self.cage_triangles.clone(),
            },
        )
        // The DQ blend weights are per vertex, not per joint: they carry over.
        .with_dq_blend_weights(self.dq_blend_weights().cloned())
    }

    /// M₀, the rest skin at the binding cage C₀ ([`RigSession::original_rest_cage`]), `#V`:
    /// with C₀, Ω and S at C₀ it rebuilds this rig as bound.
    pub fn binding_rest_mesh(&self) -> Vec<DVec3> {
        let mut mesh = vec![DVec3::ZERO; self.rest_mesh.len()];
        self.rest_mesh_of_cage(&self.original_rest_cage, &mut mesh);
        mesh
    }

    /// The options this session was built with, with its current skinning method and cage
    /// coordinates kind: what a rebind to another skeleton uses.
    pub fn rebinding_options(&self) -> SessionOptions {
        SessionOptions {
            skinning: self.skinning.method(),
            coords: self.coords_kind(),
            // M is the exact map of C: nothing to recompute or keep.
            given_cage_coords: GivenCageCoords::RecomputeIfInexact,
            ..self.options.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::test_rigs::bar;
    use crate::skinning::SkinningMethod;

    /// Rebinding to the same skeleton and weights after a rest-cage edit reproduces the
    /// edited rest mesh and keeps the method; the new binding cage is the edited cage.
    #[test]
    fn a_rebind_at_the_current_rest_pose_keeps_the_rest_mesh() {
        let mut s = bar();
        s.set_skinning(SkinningMethod::Dqs).unwrap();
        s.move_rest_cage(&[0, 1], &[DVec3::new(0.0, 0.05, 0.0)])
            .unwrap();
        let skeleton = s
            .skeleton()
            .with_rest_positions(&s.rest_joints().collect::<Vec<_>>());
        let parts = s.parts_with_skeleton(skeleton, s.skin_weights().clone());
        let (rebound, _) = RigSession::new(parts, s.rebinding_options()).unwrap();
        assert_eq!(rebound.skinning(), SkinningMethod::Dqs);
        assert_eq!(rebound.original_rest_cage(), s.rest_cage());
        let moved = crate::mesh::max_distance(rebound.rest_mesh(), s.rest_mesh());
        assert!(moved < 1e-12, "{moved}");
        let joints_moved = rebound
            .rest_joints()
            .zip(s.rest_joints())
            .map(|(a, b)| a.distance(b))
            .fold(0.0, f64::max);
        assert!(joints_moved < 1e-9, "{joints_moved}");
    }
}
