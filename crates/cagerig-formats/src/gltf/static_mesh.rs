//! glTF 2.0 → [`StaticMesh`]: every triangle primitive of every mesh node of the default scene,
//! placed by the node's world transform (node transforms at rest: `matrix` or TRS, non-uniform
//! and mirroring scales included; winding reversed where det < 0, as glTF specifies), morph
//! targets at their default weights, accessors read as for a character (sparse,
//! KHR_mesh_quantization). A skinned node is read in its bind shape placed by its own world
//! transform, which is where [`crate::gltf::import_gltf`] places the bind shape of the first
//! node using a skin; its JOINTS_n/WEIGHTS_n are not read.

use std::path::Path;

use super::buffers::Buffers;
use super::cage::{find_cage, is_cage_node};
use super::parse::parse_validated;
use super::primitive::{PrimitiveGeometry, primitive_source, read_geometry};
use super::scene::NodeTree;
use crate::character::SpaceSummary;
use crate::error::{FormatError, invalid};
use crate::static_mesh::{MergedParts, StaticMesh, name_of};

/// Reads a `.gltf` or `.glb` file as a static mesh (see the module doc).
pub fn import_gltf_static(path: &Path) -> Result<StaticMesh, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    import_gltf_static_bytes(&bytes, path)
}

/// [`import_gltf_static`] on glTF/GLB bytes; `path` names the file in messages and locates
/// external buffers.
pub fn import_gltf_static_bytes(bytes: &[u8], path: &Path) -> Result<StaticMesh, FormatError> {
    let (gltf, mut warnings) = parse_validated(bytes, path)?;
    let document = &gltf.document;
    let buffers = Buffers::load(document, gltf.blob.as_deref(), path)?;
    let tree = NodeTree::new(document, path)?;
    let locals = tree.rest_affines();
    let mut world = vec![glam::DAffine3::IDENTITY; locals.len()];
    tree.globals(&locals, &mut world);
    let in_scene = default_scene_nodes(document);
    let mut merged = MergedParts::default();
    for node in document.nodes() {
        let Some(mesh) = node.mesh() else { continue };
        if !in_scene[node.index()] || is_cage_node(&node) {
            continue;
        }
        for primitive in mesh.primitives() {
            let source = primitive_source(&node, &mesh, &primitive);
            let world_from_node = world[node.index()];
            let Some(PrimitiveGeometry {
                local,
                triangles: local_triangles,
                indexed,
            }) = read_geometry(
                &primitive,
                &node,
                &buffers,
                path,
                &source,
                &world_from_node,
                None,
                &mut warnings,
            )?
            else {
                continue;
            };
            merged.add(source, &world_from_node, &local, &local_triangles, indexed);
        }
    }
    if merged.triangles.is_empty() {
        return Err(invalid(
            path,
            "meshes",
            "no mesh node of the default scene has triangles (expected at least one primitive \
             of mode TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN outside the cage node)",
        ));
    }
    let mesh = cagerig::TriMesh::new(merged.positions, merged.triangles).map_err(|source| {
        FormatError::Rig {
            path: path.to_path_buf(),
            element: "meshes".into(),
            source,
        }
    })?;
    let cage = find_cage(document, &buffers, &world, path)?;
    Ok(StaticMesh {
        mesh,
        cage,
        name: name_of(path),
        primitives: merged.primitives,
        space: SpaceSummary::default(),
        had_skin: document.skins().next().is_some(),
        warnings,
    })
}

/// Which nodes belong to the default scene (`scene`, else the first scene): its root nodes and
/// their descendants. A file without scenes has all its nodes in view.
fn default_scene_nodes(document: &gltf::Document) -> Vec<bool> {
    let n = document.nodes().len();
    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return vec![true; n];
    };
    let mut in_scene = vec![false; n];
    // The node tree has been checked for cycles and shared children (`NodeTree::new`).
    let mut stack: Vec<gltf::Node> = scene.nodes().collect();
    while let Some(node) = stack.pop() {
        if !in_scene[node.index()] {
            in_scene[node.index()] = true;
            stack.extend(node.children());
        }
    }
    in_scene
}
