//! A binding made in the studio (a skeleton built or changed, then bound) as a session file
//! carries it: the rest skin M and cage C it was bound at, the skeleton S and the weights Ω.
//! Opening the session rebuilds that rig exactly, whatever the source file holds.

use cagerig::session::{DisplayPrecision, RigSession};
use cagerig::{Joint, Skeleton, SkinWeights, TriMesh};
use glam::{DAffine3, DVec3};
use serde::{Deserialize, Serialize};

/// One joint of a saved skeleton.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedJoint {
    pub name: String,
    pub parent: Option<usize>,
    /// Rest frame, world from joint.
    pub rest_world_from_joint: DAffine3,
}

/// A studio binding: M (`#V`) and C (`#C`) at the bind, S (`#J`) and Ω as
/// `(vertex, joint, weight)` entries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedBinding {
    pub rest_mesh: Vec<DVec3>,
    pub rest_cage: Vec<DVec3>,
    pub joints: Vec<SavedJoint>,
    pub weights: Vec<(usize, usize, f64)>,
}

impl SavedBinding {
    /// The binding of `session`: its binding cage C₀, M at C₀, its skeleton and weights.
    pub fn of(session: &RigSession) -> Self {
        let skeleton = session.skeleton();
        let weights = session.skin_weights();
        // S and Ω hold at the binding: the rest frames are those of C₀ (SkelUp moves the
        // joints with C, the skeleton keeps the frames it was bound with).
        let rest_mesh = session.binding_rest_mesh();
        let rest_cage = session.original_rest_cage().to_vec();
        Self {
            rest_mesh,
            rest_cage,
            joints: skeleton
                .joints()
                .iter()
                .map(|j| SavedJoint {
                    name: j.name.clone(),
                    parent: j.parent,
                    rest_world_from_joint: j.rest_world_from_joint,
                })
                .collect(),
            weights: (0..weights.num_vertices())
                .flat_map(|v| {
                    let (joints, w) = weights.row(v);
                    joints
                        .iter()
                        .zip(w)
                        .map(move |(&j, &w)| (v, j as usize, w))
                        .collect::<Vec<_>>()
                })
                .collect(),
        }
    }

    /// The session of this binding for the character of `opened` (its triangles, cage
    /// triangles and options); every mismatch is an error naming what differs.
    pub fn bind(&self, opened: &RigSession) -> Result<RigSession, String> {
        let nv = opened.num_vertices();
        let nc = opened.rest_cage().len();
        if self.rest_mesh.len() != nv || self.rest_cage.len() != nc {
            return Err(format!(
                "the saved binding has {} mesh and {} cage vertices; the character has {nv} and \
                 {nc}",
                self.rest_mesh.len(),
                self.rest_cage.len()
            ));
        }
        if let Some(p) = self
            .rest_mesh
            .iter()
            .chain(&self.rest_cage)
            .find(|p| !p.is_finite())
        {
            return Err(format!("the saved binding has a non-finite position {p}"));
        }
        let skeleton = Skeleton::new(
            self.joints
                .iter()
                .map(|j| Joint {
                    name: j.name.clone(),
                    parent: j.parent,
                    rest_world_from_joint: j.rest_world_from_joint,
                })
                .collect(),
        )
        .map_err(|e| format!("the saved skeleton: {e}"))?;
        let (weights, _) =
            SkinWeights::from_triplets(nv, skeleton.len(), self.weights.iter().copied())
                .map_err(|e| format!("the saved weights: {e}"))?;
        let mut parts = opened.parts_with_skeleton(skeleton, weights);
        parts.mesh = TriMesh {
            positions: self.rest_mesh.clone(),
            triangles: parts.mesh.triangles,
        };
        parts.cage.positions = self.rest_cage.clone();
        let (mut session, _) = RigSession::new(parts, opened.rebinding_options())
            .map_err(|e| format!("the saved binding: {e}"))?;
        session
            .set_display_precision(DisplayPrecision::F32)
            .map_err(|e| e.to_string())?;
        Ok(session)
    }
}
