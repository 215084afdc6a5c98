//! Several skinned meshes on one skeleton: files (Blender, Maya, Sketchfab exports) often give
//! each mesh its own `skin` object over the same joint nodes with the same bind pose. Such skins
//! are one rig: their meshes are merged into the chosen skin's character, each mesh's joint
//! indices mapped to the chosen skin's.

use std::path::Path;

use glam::DAffine3;
use gltf::accessor::Dimensions;

use super::buffers::Buffers;
use super::scene::affine_from_cols;
use crate::character::max_abs_diff;
use crate::error::{FormatError, invalid};

/// Relative agreement of two inverse bind matrices of one joint node for two skins to share it.
const SHARED_BIND_TOLERANCE: f64 = 1e-5;

/// The inverse bind matrices of `skin` (`#joints`; identities when the skin has none).
pub(super) fn inverse_bind_matrices(
    skin: &gltf::Skin,
    buffers: &Buffers,
    path: &Path,
) -> Result<Vec<DAffine3>, FormatError> {
    let element = format!("skin {}", skin.index());
    let nj = skin.joints().count();
    let Some(acc) = skin.inverse_bind_matrices() else {
        return Ok(vec![DAffine3::IDENTITY; nj]);
    };
    if acc.count() < nj {
        return Err(invalid(
            path,
            &element,
            format!("has {nj} joints but {} inverse bind matrices", acc.count()),
        ));
    }
    let values = buffers.read(&acc, "inverse bind matrices", &[Dimensions::Mat4])?;
    (0..nj)
        .map(|j| {
            let mut cols = [0.0; 16];
            cols.copy_from_slice(&values[16 * j..16 * j + 16]);
            affine_from_cols(cols, path, &format!("{element} inverse bind matrix {j}"))
        })
        .collect()
}

/// For every skin of the document that shares the chosen skin's skeleton — each of its joint
/// nodes is a joint of the chosen skin (`joint_of_node`: node → chosen joint index) with the
/// same inverse bind matrix up to [`SHARED_BIND_TOLERANCE`] of its largest entry — its index and the map
/// from its joint indices to the chosen skin's. The chosen skin comes first, with the identity
/// map. Skins that cannot be read or do not match are left out.
pub(super) fn skins_sharing_joints(
    document: &gltf::Document,
    chosen: &gltf::Skin,
    joint_of_node: &[Option<usize>],
    inverse_bind: &[DAffine3],
    buffers: &Buffers,
    path: &Path,
) -> Vec<(usize, Vec<usize>)> {
    let mut shared = vec![(chosen.index(), (0..inverse_bind.len()).collect())];
    for skin in document.skins().filter(|s| s.index() != chosen.index()) {
        let map: Option<Vec<usize>> = skin
            .joints()
            .map(|n| joint_of_node.get(n.index()).copied().flatten())
            .collect();
        let Some(map) = map.filter(|m| !m.is_empty()) else {
            continue;
        };
        let Ok(own) = inverse_bind_matrices(&skin, buffers, path) else {
            continue;
        };
        let agrees = own.iter().zip(&map).all(|(m, &j)| {
            let reference = &inverse_bind[j];
            let size = max_abs_diff(reference, &DAffine3::ZERO).max(1e-300);
            max_abs_diff(m, reference) <= SHARED_BIND_TOLERANCE * size
        });
        if agrees {
            shared.push((skin.index(), map));
        }
    }
    shared
}
