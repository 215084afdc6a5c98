//! Read access to a session's structures and operators.

use super::RigSession;
use super::parts::CageFitSource;
use super::rest_map::RestMeshState;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use crate::skinning::{DqBlendWeights, SkinningMethod};
use crate::sync::cage_fit_kind::CageFitKind;
use crate::sync::cage_reverser::ReverserMethod;
use crate::sync::cage_updater::CageUpdater;
use crate::sync::skeleton_updater::SkeletonUpdater;
use glam::{DAffine3, DVec3};

use crate::coords::stretched_normals::FaceTermKind;

impl RigSession {
    /// Rest skin M (`#V`), exact (on the f32 display path, after a current-cage edit it is
    /// computed in f64 on the first call; [`RigSession::display_rest_mesh`] is the drawn one).
    pub fn rest_mesh(&self) -> &[DVec3] {
        match self.display.as_deref() {
            Some(display) if self.rest_map.mesh_state() == RestMeshState::MapOnRows => {
                self.exact_rest_mesh(display)
            }
            _ => &self.rest_mesh,
        }
    }
    /// Number of skin vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.rest_mesh.len()
    }
    /// Current skin M' (`#V`), exact (on the f32 display path it is skinned in f64 on the
    /// first call after an event; [`RigSession::display_mesh`] is the drawn one).
    pub fn posed_mesh(&self) -> &[DVec3] {
        match self.display.as_deref() {
            Some(display) => self.exact_posed_mesh(display),
            None => &self.posed_mesh,
        }
    }
    /// Rest cage C (`#C`).
    pub fn rest_cage(&self) -> &[DVec3] {
        &self.rest_cage
    }
    /// Current cage C' (`#C`).
    pub fn posed_cage(&self) -> &[DVec3] {
        &self.posed_cage
    }
    /// The original rest cage C₀ as loaded.
    pub fn original_rest_cage(&self) -> &[DVec3] {
        &self.original_rest_cage
    }
    /// Triangles of the skin, shared by M and M' (indices into `#V`).
    pub fn mesh_triangles(&self) -> &[[u32; 3]] {
        &self.mesh_triangles
    }
    /// Identifies [`RigSession::mesh_triangles`], which never change during a session's life:
    /// two sessions (or clones) with the same id have the same triangles, and ids are never
    /// reused within a process. Lets a renderer skip comparing the triangle lists every frame.
    pub fn topology_id(&self) -> u64 {
        self.topology_id
    }
    /// Triangles of the cage, shared by C and C' (indices into `#C`).
    pub fn cage_triangles(&self) -> &[[u32; 3]] {
        &self.cage_triangles
    }
    /// The skeleton topology and its rest frames as loaded.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }
    /// Skinning weights Ω (`#V × #J`).
    pub fn skin_weights(&self) -> &SkinWeights {
        &self.skin_weights
    }
    /// DQ blend weights b (`#V`) of [`SkinningMethod::Blended`], when the rig has them.
    pub fn dq_blend_weights(&self) -> Option<&DqBlendWeights> {
        self.skinning.dq_blend_weights()
    }
    /// Φ.
    pub fn cage_coords(&self) -> &CageCoords {
        self.rest_map.coords()
    }
    /// The SkelUp operator: Ψ (`#J × #C`) with A = ΨC.
    pub fn skeleton_updater(&self) -> &SkeletonUpdater {
        &self.skeleton_updater
    }

    /// The kind's terms of the current rest cage C, the second input of SkelUp and of the extra
    /// coordinate columns: g(C) (`#F`) for Green rigs, empty for MVC rigs. A = Ψ·C + Ψ_ψ·g(C) is
    /// `skeleton_updater().apply(rest_cage(), rest_cage_terms(), ..)`.
    pub fn rest_cage_terms(&self) -> &[DVec3] {
        self.rest_map.terms()
    }
    /// The CageUp operator: C' fitted to the selected rows of M'.
    pub fn cage_updater(&self) -> &CageUpdater {
        self.rest_map.linear_fit()
    }

    /// The CageUp fit in use: the options' [`CageFitKind`] for mean value rigs; for Green rigs
    /// `Regularised` when the Gauss–Newton fit on the rows is regularised towards the carried
    /// cage, `Paper` when it fits the rows alone.
    pub fn cage_fit(&self) -> CageFitKind {
        self.rest_map.fit_kind()
    }

    /// The face term a Green rig's stretched normals use ([`FaceTermKind`]; the options' choice,
    /// which mean value rigs keep for a rebind).
    pub fn green_face_term(&self) -> FaceTermKind {
        self.options.green_face_term
    }

    /// Current rest frames of the joints (S).
    pub fn rest_world_from_joint(&self) -> &[DAffine3] {
        &self.rest_world_from_joint
    }
    /// Current posed frames of the joints (S').
    pub fn posed_world_from_joint(&self) -> &[DAffine3] {
        &self.posed_world_from_joint
    }
    /// Skinning transforms T_j = posed_from_rest (Eq. 1–3).
    pub fn posed_from_rest(&self) -> &[DAffine3] {
        &self.posed_from_rest
    }
    /// The rest points whose LBS under the current pose is the current skin M' (`#V`, into
    /// `out`): x_v = R_v⁻¹·(M'_v − t_v) ([`crate::skinning::LinearBlendSkinning::rest_preimage`]). A host that
    /// skins with LBS only shows any method's M' by skinning these (Blender's CoR shape key).
    pub fn lbs_rest_preimage(&self, out: &mut [DVec3]) -> Result<(), RigError> {
        self.skinning
            .lbs()
            .rest_preimage(&self.posed_from_rest, self.posed_mesh(), out)
    }
    /// Rest joint positions (`#J`).
    pub fn rest_joints(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.rest_world_from_joint.iter().map(|t| t.translation)
    }
    /// Current joint positions (`#J`).
    pub fn posed_joints(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.posed_world_from_joint.iter().map(|t| t.translation)
    }
    /// The current skinning method.
    pub fn skinning(&self) -> SkinningMethod {
        self.skinning.method()
    }
    /// Which mesh CageUp fits when the skinning method is not LBS.
    pub fn fit_source(&self) -> CageFitSource {
        self.options_fit_source
    }
    /// CoR centres (`#V`), if CoR data exists. They follow the cage while CoR skinning is active
    /// and are refreshed when it next runs otherwise.
    pub fn cor_centres(&self) -> Option<&[DVec3]> {
        self.skinning.cor().map(|c| c.centres.as_slice())
    }
    /// Chooses how CageRev factorises Eq. 19 (low-rank by default, see [`ReverserMethod`]).
    pub fn set_reverser_method(&mut self, method: ReverserMethod) {
        self.rest_map.set_reverser_method(method);
    }

    /// Whether the held CageRev factorisation is the low-rank (Woodbury) one.
    pub fn reverser_is_low_rank(&self) -> bool {
        self.rest_map.reverser_is_low_rank()
    }

    /// Whether the reverse cage deformer currently holds a factorisation.
    pub fn reverser_is_factorised(&self) -> bool {
        self.rest_map.reverser_is_factorised()
    }
}

#[cfg(test)]
mod tests {
    use crate::session::test_rigs::bar;

    #[test]
    fn topology_ids_are_shared_by_clones_and_unique_otherwise() {
        let (a, b) = (bar(), bar());
        assert_eq!(a.mesh_triangles(), b.mesh_triangles());
        assert_ne!(a.topology_id(), b.topology_id(), "a new session, a new id");
        assert_eq!(a.clone().topology_id(), a.topology_id());
    }
}
