//! A cage stored inside a glTF file: a mesh node named `<name>_cage` (node or mesh name,
//! [`is_cage_name`]) or with `extras.cagerig_cage`, in world space, its vertices welded by exact position (a cage written
//! without an index buffer is a triangle soup).

use std::path::Path;

use cagerig::TriMesh;
use glam::{DAffine3, DVec3};
use gltf::accessor::Dimensions;

use super::buffers::Buffers;
use super::import::to_vec3;
use super::primitive::primitive_triangles;
use crate::character::is_cage_name;
use crate::error::{FormatError, invalid};
use crate::static_mesh::append_part;

/// Merges vertices with bit-identical positions (a cage written without an index buffer is a
/// triangle soup); first occurrence order is kept.
fn weld_exact(positions: &[DVec3], triangles: &[[u32; 3]]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut index = std::collections::HashMap::with_capacity(positions.len());
    let mut welded = Vec::with_capacity(positions.len());
    let remap: Vec<u32> = positions
        .iter()
        .map(|p| {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            *index.entry(key).or_insert_with(|| {
                welded.push(*p);
                (welded.len() - 1) as u32
            })
        })
        .collect();
    let triangles = triangles
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .collect();
    (welded, triangles)
}

/// Whether `node` is marked as the character's cage: an unskinned mesh node whose node or mesh
/// name is a cage name ([`is_cage_name`]), or with `extras.cagerig_cage`.
pub(super) fn is_cage_node(node: &gltf::Node) -> bool {
    let Some(mesh) = node.mesh() else {
        return false;
    };
    let named = node.name().is_some_and(is_cage_name) || mesh.name().is_some_and(is_cage_name);
    let marked = node
        .extras()
        .as_ref()
        .is_some_and(|e| e.get().contains("cagerig_cage"));
    (named || marked) && node.skin().is_none()
}

/// The first node marked as the character's cage ([`is_cage_node`]); its positions in world
/// space (the node's world transform applied; the winding reversed when that transform
/// mirrors, det < 0, as glTF specifies, so that outward faces stay outward).
pub(super) fn find_cage(
    document: &gltf::Document,
    buffers: &Buffers,
    rest_globals: &[DAffine3],
    path: &Path,
) -> Result<Option<TriMesh>, FormatError> {
    for node in document.nodes() {
        let Some(mesh) = node.mesh().filter(|_| is_cage_node(&node)) else {
            continue;
        };
        let world_from_node = rest_globals[node.index()];
        let source = format!("cage node {} {:?}", node.index(), node.name().unwrap_or(""));
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let mut notes = Vec::new();
        for primitive in mesh.primitives() {
            let acc = primitive
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| invalid(path, &source, "has no POSITION"))?;
            let p = to_vec3(&buffers.read(&acc, "cage POSITION", &[Dimensions::Vec3])?);
            let indices = match primitive.indices() {
                Some(acc) => {
                    Some(buffers.read_indices(&acc, "cage indices", &[Dimensions::Scalar])?)
                }
                None => None,
            };
            if let Some(t) = primitive_triangles(
                primitive.mode(),
                indices,
                p.len(),
                path,
                &source,
                &mut notes,
            )? {
                append_part(&world_from_node, &p, &t, &mut positions, &mut triangles);
            }
        }
        let (positions, triangles) = weld_exact(&positions, &triangles);
        let cage = TriMesh::new(positions, triangles).map_err(|source_err| FormatError::Rig {
            path: path.to_path_buf(),
            element: source.clone(),
            source: source_err,
        })?;
        return Ok(Some(cage));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welding_merges_identical_positions_only() {
        let p = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::X,
            DVec3::Y,
            DVec3::new(1.0, 1.0, 1e-300),
        ];
        let (w, t) = weld_exact(&p, &[[0, 1, 2], [3, 4, 5]]);
        assert_eq!(w.len(), 4);
        assert_eq!(t, vec![[0, 1, 2], [1, 2, 3]]);
    }
}
