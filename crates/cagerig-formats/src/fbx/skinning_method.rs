//! The skinning method of an FBX character and its per-vertex DQ blend weights, as Maya poses
//! it. Each skin deformer has a method (ufbx's `skinning_method`: linear, rigid, dual quaternion,
//! or Maya's "weight blended" blend of linear and dual quaternion with a weight per vertex), and
//! ufbx gives every skin vertex its DQ blend weight `dq_weight` (the file's value in a blended
//! skin; Maya's default elsewhere: 1 in a dual-quaternion skin, 0 otherwise). Vertex v of a
//! skin is posed `(1 − b_v)·LBS + b_v·DQS` in every mode (ufbx's `ufbx_get_skin_vertex_matrix`),
//! so one blended rig with those weights reproduces any mix of skins.

use std::path::Path;

use cagerig::skinning::{DqBlendWeights, SkinningMethod};

use crate::error::FormatError;

/// The method of the character's skinned meshes (the nodes with a mesh and a skin deformer, in
/// scene order, as the importer concatenates them) and their DQ blend weights (`#V`, the
/// vertices of those meshes in the same order): LBS when every skin is linear or rigid, DQS when
/// every skin is dual-quaternion, the blend otherwise (a "weight blended" skin, or skins of
/// different methods). `None` when nothing is skinned. Errors naming the file and the vertex
/// when a blend weight is not a finite number in [0, 1], or when the weights do not cover the
/// `num_vertices` imported vertices.
pub(super) fn file_skinning(
    scene: &ufbx::Scene,
    path: &Path,
    num_vertices: usize,
) -> Result<(Option<SkinningMethod>, Option<DqBlendWeights>), FormatError> {
    let skins: Vec<&ufbx::SkinDeformer> = scene
        .nodes
        .iter()
        .filter_map(|n| n.mesh.as_ref())
        .filter_map(|m| m.skin_deformers.first())
        .map(|d| &**d)
        .collect();
    let Some(first) = skins.first() else {
        return Ok((None, None));
    };
    let method_of = |skin: &ufbx::SkinDeformer| match skin.skinning_method {
        ufbx::SkinningMethod::Linear | ufbx::SkinningMethod::Rigid => SkinningMethod::Lbs,
        ufbx::SkinningMethod::DualQuaternion => SkinningMethod::Dqs,
        ufbx::SkinningMethod::BlendedDqLinear => SkinningMethod::Blended,
    };
    let first_method = method_of(first);
    let method = if skins.iter().all(|s| method_of(s) == first_method) {
        first_method
    } else {
        SkinningMethod::Blended
    };
    let values: Vec<f64> = skins
        .iter()
        .flat_map(|s| s.vertices.iter().map(|v| v.dq_weight))
        .collect();
    let rig_error = |source| FormatError::Rig {
        path: path.to_path_buf(),
        element: "skin DQ blend weights (Maya \"weight blended\" skinning)".into(),
        source,
    };
    let weights = DqBlendWeights::new(values).map_err(rig_error)?;
    weights.check_vertices(num_vertices).map_err(rig_error)?;
    Ok((Some(method), Some(weights)))
}
