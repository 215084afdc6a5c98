//! FBX → [`StaticMesh`] through ufbx: every mesh node in scene order, its control points placed
//! in world space in glTF's convention (the same conversion as [`super::import_fbx`]: axes and
//! unit by ufbx's load options), faces triangulated by ufbx, winding reversed where the world
//! transform mirrors (det < 0: a left-handed file, or a mirrored node). A mesh with a skin
//! deformer is placed at bind time (`geometry_to_world` of its first cluster), exactly as
//! [`super::import_fbx`] places the rest skin M; any other mesh by its node's
//! `geometry_to_world` at the file's default pose. A mesh node named `<name>_cage` without a
//! skin is the cage.

use std::path::Path;

use cagerig::{TriMesh, Warning};
use glam::DVec3;

use super::{affine, load_scene, mesh_triangles};
use crate::character::is_cage_name;
use crate::error::{FormatError, invalid};
use crate::static_mesh::{MergedParts, StaticMesh, append_part, name_of};

/// Reads an FBX file (binary or ASCII) as a static mesh (see the module doc).
pub fn import_fbx_static(path: &Path) -> Result<StaticMesh, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    import_fbx_static_bytes(&bytes, path)
}

/// [`import_fbx_static`] on the bytes of a file (`path` names it in messages).
pub fn import_fbx_static_bytes(bytes: &[u8], path: &Path) -> Result<StaticMesh, FormatError> {
    let (scene, space) = load_scene(bytes, path)?;
    let mut warnings = Vec::new();
    let mut merged = MergedParts::default();
    let mut cage = None;
    let mut had_skin = false;
    let mut mirrored_nodes = 0usize;
    for node in scene.nodes.iter() {
        let Some(mesh) = node.mesh.as_ref() else {
            continue;
        };
        let name = &*node.element.name;
        let source = format!("mesh node {name:?}");
        let skin = mesh.skin_deformers.first();
        had_skin |= skin.is_some();
        let local: Vec<DVec3> = mesh
            .vertices
            .iter()
            .map(|p| DVec3::new(p.x, p.y, p.z))
            .collect();
        let local_triangles = mesh_triangles(mesh, path, &source)?;
        let bind_cluster = skin.and_then(|s| s.clusters.first());
        let world_from_geometry = match bind_cluster {
            Some(cluster) => affine(&cluster.geometry_to_world),
            None => affine(&node.geometry_to_world),
        };
        if is_cage_name(name) && skin.is_none() {
            if cage.is_none() {
                let (mut p, mut t) = (Vec::new(), Vec::new());
                append_part(
                    &world_from_geometry,
                    &local,
                    &local_triangles,
                    &mut p,
                    &mut t,
                );
                cage = Some(TriMesh::new(p, t).map_err(|source_err| FormatError::Rig {
                    path: path.to_path_buf(),
                    element: format!("cage {source}"),
                    source: source_err,
                })?);
            }
            continue;
        }
        if world_from_geometry.matrix3.determinant() < 0.0 {
            mirrored_nodes += 1;
        }
        merged.add(source, &world_from_geometry, &local, &local_triangles, true);
    }
    if merged.triangles.is_empty() {
        return Err(invalid(
            path,
            "scene",
            "no mesh node has faces (expected at least one mesh with polygons outside the \
             `<name>_cage` node)",
        ));
    }
    if mirrored_nodes > 0 {
        warnings.push(Warning::Note {
            message: format!(
                "{mirrored_nodes} mesh node(s) mirrored into right-handed +Y up (left-handed \
                 axes or a negative scale); their triangle winding reversed"
            ),
        });
    }
    let mesh =
        TriMesh::new(merged.positions, merged.triangles).map_err(|source| FormatError::Rig {
            path: path.to_path_buf(),
            element: "meshes".into(),
            source,
        })?;
    Ok(StaticMesh {
        mesh,
        cage,
        name: name_of(path),
        primitives: merged.primitives,
        space,
        had_skin,
        warnings,
    })
}
