//! The format-independent result of importing a file as a static mesh: every triangle of the
//! file's meshes in world space, with no skeleton or weights — a sculpt or a scan to be bound
//! (`cagerig weights … --skeleton`, or a skeleton built in the studio).
//!
//! Spaces: the file's world space at its default pose, in glTF's convention (right-handed, +Y
//! up, metres; FBX files are converted as by [`crate::import_character`], see
//! [`SpaceSummary`]). A node whose world transform mirrors (det < 0) has its triangles' winding
//! reversed, so that faces outward in the file stay outward.
//!
//! Skinned meshes are read too, in their bind shape, placed as [`crate::import_character`]
//! places them: for a file whose skinned meshes form one skin (one node per skin in glTF), the
//! mesh's skinned vertices are those of the character's rest skin M, in its order and at its
//! positions; unskinned mesh nodes of the same file (props, eyes under a bone) are merged too.
//!
//! Vertex order: glTF: nodes of the default scene in index order, then the primitives of each
//! node's mesh, vertices in accessor order; FBX: mesh nodes in scene order, control points in
//! file order. No welding. The cage node is not part of the mesh.

use std::path::Path;

use cagerig::{TriMesh, Warning};

use crate::character::{PrimitiveSummary, SpaceSummary};

/// A mesh read from a glTF or FBX file without its skin (if it has one).
#[derive(Debug, Clone)]
pub struct StaticMesh {
    /// Every triangle primitive of every mesh node (the cage node excepted), merged: positions
    /// f64 in world space (see the module doc), `#V` vertices.
    pub mesh: TriMesh,
    /// A cage found in the file: the first unskinned mesh node named `<name>_cage` (glTF: node
    /// or mesh name, or `extras.cagerig_cage`), in the same space, welded by exact position.
    pub cage: Option<TriMesh>,
    /// The character's name: the file's stem (`Fox` for `data/fox/Fox.glb`).
    pub name: String,
    /// The primitives (glTF) or mesh nodes (FBX) merged into `mesh`, in vertex order.
    pub primitives: Vec<PrimitiveSummary>,
    /// The file's axes and unit and the conversion applied (glTF: its own convention, kept).
    pub space: SpaceSummary,
    /// Whether the file has a skin (its skinned meshes were read in their bind shape; its
    /// skeleton and weights were not read).
    pub had_skin: bool,
    /// Import notes: primitives skipped (points, lines), morph targets applied, axes mirrored.
    pub warnings: Vec<Warning>,
}

/// The name of the character in `path`: its file stem.
pub(crate) fn name_of(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Merges one part (local positions, local triangles) into `positions`/`triangles`, placed by
/// `world_from_local` and with its winding reversed when that map mirrors (det < 0). Returns
/// the number of triangles appended.
pub(crate) fn append_part(
    world_from_local: &glam::DAffine3,
    local: &[glam::DVec3],
    local_triangles: &[[u32; 3]],
    positions: &mut Vec<glam::DVec3>,
    triangles: &mut Vec<[u32; 3]>,
) -> usize {
    let base = positions.len() as u32;
    let mirrored = world_from_local.matrix3.determinant() < 0.0;
    positions.extend(local.iter().map(|p| world_from_local.transform_point3(*p)));
    triangles.extend(local_triangles.iter().map(|&[a, b, c]| {
        let t = if mirrored { [a, c, b] } else { [a, b, c] };
        t.map(|i| i + base)
    }));
    local_triangles.len()
}

/// Parts being merged into one mesh (`#V` positions, `#F` triangles) with the summary of each
/// part, in vertex order: what both static importers build.
#[derive(Debug, Default)]
pub(crate) struct MergedParts {
    pub(crate) positions: Vec<glam::DVec3>,
    pub(crate) triangles: Vec<[u32; 3]>,
    pub(crate) primitives: Vec<PrimitiveSummary>,
}

impl MergedParts {
    /// Merges one part ([`append_part`]) and records its summary under `source`.
    pub(crate) fn add(
        &mut self,
        source: String,
        world_from_local: &glam::DAffine3,
        local: &[glam::DVec3],
        local_triangles: &[[u32; 3]],
        indexed: bool,
    ) {
        let first_vertex = self.positions.len();
        let triangles = append_part(
            world_from_local,
            local,
            local_triangles,
            &mut self.positions,
            &mut self.triangles,
        );
        self.primitives.push(PrimitiveSummary {
            source,
            first_vertex,
            vertices: local.len(),
            triangles,
            indexed,
        });
    }
}
