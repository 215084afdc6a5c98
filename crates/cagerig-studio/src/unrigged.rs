//! Opening a mesh with no skeleton (an OBJ with no `.skt` beside it): the mesh, its cage
//! (given, found beside it, or generated), and a placeholder rig — one joint at the middle of
//! the mesh's box holding every vertex — that the studio shows as an empty skeleton and does
//! not let the user pose until the first Bind.

use std::path::{Path, PathBuf};

use cagerig::cage_gen::CageOptions;
use cagerig::cage_source::{CageOrigin, CageRequest, CageSourceError, choose_cage};
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

/// A mesh opened with no skeleton: its placeholder rig, the load warnings and the files read
/// as (role, path).
pub type UnriggedMesh = (RigParts, Vec<Warning>, Vec<(String, PathBuf)>);

/// The mesh of the OBJ `path` with its cage: `cage` if given, else the one beside it, else one
/// generated with `auto_cage` vertices (the default generator when `None`).
pub fn open_unrigged_obj(
    path: &Path,
    cage: Option<&Path>,
    auto_cage: Option<usize>,
) -> Result<UnriggedMesh, OpenError> {
    let mesh = cagerig::io::obj::read_obj(path)?;
    let mut warnings = cagerig::rig_files::check_character_mesh(path, &mesh)?;
    let mut files = vec![("mesh".to_string(), path.to_path_buf())];
    let found_cage = cagerig::io::discovery::discover(path, cage).cage;
    let request = CageRequest {
        given: cage.or(found_cage.as_deref()),
        generate: Some(auto_cage.map_or_else(
            CageOptions::default,
            cagerig::cage_source::cage_options_with_vertices,
        )),
    };
    let chosen = choose_cage(path, &mesh, None, &request).map_err(|e| match e {
        CageSourceError::Read(e) => OpenError::from(e),
        CageSourceError::Generate { character, source } => OpenError::Generate {
            path: character,
            source,
        },
        CageSourceError::Missing { character } => OpenError::NoCage { path: character },
    })?;
    match &chosen.origin {
        CageOrigin::Given(p) => files.push(("cage".into(), p.clone())),
        CageOrigin::Generated(g) => warnings.push(crate::rig_open::generated_note(g)),
        CageOrigin::Found => {}
    }
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
    Ok((parts, warnings, files))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

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
}
