//! Opening a mesh with no skeleton (an OBJ with no `.skt` beside it, or a glTF / FBX file with
//! no skin): the mesh, its cage (given, found beside it or in the file, or generated), and a
//! placeholder rig — one joint at the middle of
//! the mesh's box holding every vertex — that the studio shows as an empty skeleton and does
//! not let the user pose until the first Bind.

use std::path::{Path, PathBuf};

use cagerig::cage_gen::{CageOptions, GeneratedCage};
use cagerig::cage_source::{CageOrigin, CageRequest, choose_cage};
use cagerig::session::RigParts;
use cagerig::{Joint, RigError, Skeleton, SkinWeights, TriMesh, Warning};
use glam::DAffine3;

use crate::rig_open::OpenError;

/// Name of the placeholder joint (never shown).
pub const PLACEHOLDER_JOINT: &str = "placeholder";

/// Whether `path` is an OBJ with no skeleton beside it.
pub fn is_unrigged_obj(path: &Path) -> bool {
    cagerig_formats::CharacterFormat::of(path).is_none()
        && cagerig::io::discovery::discover(path, None)
            .skeleton
            .is_none()
}

/// The placeholder rig of `mesh` (`#V`) in `cage`: one joint at the middle of the mesh's box,
/// Ω = 1 on it for every vertex.
pub fn placeholder_parts(mesh: TriMesh, cage: TriMesh) -> Result<RigParts, RigError> {
    let (lo, hi) = cagerig::mesh::bounding_box(&mesh.positions);
    let skeleton = Skeleton::new(vec![Joint {
        name: PLACEHOLDER_JOINT.into(),
        parent: None,
        rest_world_from_joint: DAffine3::from_translation(0.5 * (lo + hi)),
    }])?;
    let n = mesh.num_vertices();
    let (weights, _) = SkinWeights::from_triplets(n, 1, (0..n).map(|v| (v, 0, 1.0)))?;
    Ok(RigParts::new(mesh, skeleton, weights, cage))
}

/// A mesh opened with no skeleton: its placeholder rig, the load warnings, the files read as
/// (role, path) and the cage generated for it (when none was given or found).
pub type UnriggedMesh = (
    RigParts,
    Vec<Warning>,
    Vec<(String, PathBuf)>,
    Option<Box<GeneratedCage>>,
);

/// The mesh of the OBJ `path` with its cage: `cage` if given, else the one beside it, else one
/// generated with `auto_cage` vertices (the default generator when `None`).
pub fn open_unrigged_obj(
    path: &Path,
    cage: Option<&Path>,
    auto_cage: Option<usize>,
) -> Result<UnriggedMesh, OpenError> {
    let mesh = cagerig::io::obj::read_obj(path)?;
    let warnings = cagerig::rig_files::check_character_mesh(path, &mesh)?;
    let found_cage = cagerig::io::discovery::discover(path, cage).cage;
    unrigged(
        path,
        mesh,
        None,
        &mesh_cage_request(cage.or(found_cage.as_deref()), auto_cage, None),
        warnings,
        vec![("mesh".to_string(), path.to_path_buf())],
    )
}

/// The mesh of the glTF / FBX file `path`, which has no skin, with its cage: `cage` if given,
/// else the `<name>_cage` mesh in the file, else one generated with `auto_cage` vertices.
pub fn open_unskinned_character(
    input: cagerig_formats::CharacterInput<'_>,
    cage: Option<&Path>,
    auto_cage: Option<usize>,
    generated: Option<&GeneratedCage>,
) -> Result<UnriggedMesh, OpenError> {
    let imported = input.import_static()?;
    let path = input.path();
    unrigged(
        path,
        imported.mesh,
        imported.cage,
        &mesh_cage_request(cage, auto_cage, generated),
        imported.warnings,
        vec![("character".to_string(), path.to_path_buf())],
    )
}

/// A mesh's cage request: `cage` if given, else one generated with `auto_cage` vertices (the
/// default generator when `None`), or `generated` when it was made beforehand.
fn mesh_cage_request<'a>(
    cage: Option<&'a Path>,
    auto_cage: Option<usize>,
    generated: Option<&'a GeneratedCage>,
) -> CageRequest<'a> {
    CageRequest {
        given: cage,
        generate: Some(auto_cage.map_or_else(
            CageOptions::default,
            cagerig::cage_source::cage_options_with_vertices,
        )),
        generated,
    }
}

/// The placeholder rig of `mesh` in its chosen cage (the cage-source rule applied to
/// `request`), with the notes.
fn unrigged(
    path: &Path,
    mesh: TriMesh,
    cage_in_file: Option<TriMesh>,
    request: &CageRequest<'_>,
    mut warnings: Vec<Warning>,
    mut files: Vec<(String, PathBuf)>,
) -> Result<UnriggedMesh, OpenError> {
    let chosen = choose_cage(path, &mesh, None, cage_in_file, request)?;
    let made = match chosen.origin {
        CageOrigin::Given(p) => {
            files.push(("cage".into(), p));
            None
        }
        CageOrigin::Generated(g) => {
            warnings.push(crate::rig_open::generated_note(&g));
            Some(g)
        }
        CageOrigin::Found => None,
    };
    warnings.push(Warning::Note {
        message: format!(
            "{}: no skeleton: build one in the rest view (Skeleton panel: add joints by \
             clicking on the mesh), then Bind",
            path.display()
        ),
    });
    let parts = placeholder_parts(mesh, chosen.cage).map_err(|source| OpenError::Rig {
        name: path.display().to_string(),
        source,
    })?;
    Ok((parts, warnings, files, made))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use std::path::{Path, PathBuf};

    #[test]
    fn the_placeholder_holds_every_vertex_at_the_middle() {
        let mesh = TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
        };
        let parts = placeholder_parts(mesh.clone(), mesh).unwrap();
        assert_eq!(parts.skeleton.len(), 1);
        assert_eq!(parts.skeleton.rest_positions()[0], DVec3::splat(0.5));
        assert!((0..4).all(|v| parts.skin_weights.get(v, 0) == 1.0));
    }

    /// A glTF of the bar with no skin (positions f32, u32 indices, an external buffer).
    fn write_unskinned_gltf(dir: &Path) -> (PathBuf, usize) {
        let bar = crate::rig_open::open_rig(&crate::rig_open::RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        })
        .unwrap()
        .session;
        let mut bytes: Vec<u8> = bar
            .rest_mesh()
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(|x| (x as f32).to_le_bytes())
            .collect();
        let positions_len = bytes.len();
        bytes.extend(
            bar.mesh_triangles()
                .iter()
                .flatten()
                .flat_map(|i| i.to_le_bytes()),
        );
        std::fs::write(dir.join("bar.bin"), &bytes).unwrap();
        let (lo, hi) = cagerig::mesh::bounding_box(bar.rest_mesh());
        let f = |v: DVec3| v.to_array().map(|x| x as f32);
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"name": "bar", "mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"byteLength": bytes.len(), "uri": "bar.bin"}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": positions_len},
                {"buffer": 0, "byteOffset": positions_len,
                 "byteLength": bytes.len() - positions_len}
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": bar.num_vertices(),
                 "type": "VEC3", "min": f(lo), "max": f(hi)},
                {"bufferView": 1, "componentType": 5125,
                 "count": 3 * bar.mesh_triangles().len(), "type": "SCALAR"}
            ]
        });
        let path = dir.join("bar.gltf");
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        (path, bar.num_vertices())
    }

    #[test]
    fn a_gltf_with_no_skin_opens_on_the_placeholder_with_a_generated_cage() {
        let dir = std::env::temp_dir().join(format!("cagerig-unskinned-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (path, vertices) = write_unskinned_gltf(&dir);
        let opened = crate::rig_open::open_rig(&crate::rig_open::RigSource::File {
            path: path.clone(),
            cage: None,
            skin: None,
            auto_cage: Some(30),
        })
        .unwrap();
        assert!(!opened.rigged);
        assert_eq!(opened.session.num_vertices(), vertices);
        assert_eq!(opened.session.skeleton().joint(0).name, PLACEHOLDER_JOINT);
        let notes: Vec<String> = opened.warnings.iter().map(|w| w.to_string()).collect();
        assert!(notes.iter().any(|n| n.contains("no skeleton")), "{notes:?}");
        assert!(notes.iter().any(|n| n.contains("generated")), "{notes:?}");
        std::fs::remove_dir_all(dir).ok();
    }
}
