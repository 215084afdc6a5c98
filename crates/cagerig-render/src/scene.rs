//! What to draw, as plain slices borrowed from the caller (the rig's data stays where it lives),
//! and how it looks.

use glam::{DVec3, Vec3};

/// Vertex positions (world, `#V`) of a skin: the exact f64 ones, or f32 ones from a display
/// path (`cagerig::session::DisplayPrecision::F32`), uploaded without conversion.
#[derive(Clone, Copy, Debug)]
pub enum MeshPositions<'a> {
    /// Exact f64 positions.
    F64(&'a [DVec3]),
    /// f32 positions of a display path.
    F32(&'a [Vec3]),
}

impl MeshPositions<'_> {
    /// Number of vertices `#V`.
    pub fn len(&self) -> usize {
        match self {
            Self::F64(p) => p.len(),
            Self::F32(p) => p.len(),
        }
    }

    /// Whether there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Position `i` in f64.
    pub fn get(&self, i: usize) -> DVec3 {
        match self {
            Self::F64(p) => p[i],
            Self::F32(p) => p[i].as_dvec3(),
        }
    }
}

impl<'a> From<&'a [DVec3]> for MeshPositions<'a> {
    fn from(positions: &'a [DVec3]) -> Self {
        Self::F64(positions)
    }
}

impl<'a> From<&'a [Vec3]> for MeshPositions<'a> {
    fn from(positions: &'a [Vec3]) -> Self {
        Self::F32(positions)
    }
}

/// The character's skin.
#[derive(Clone, Copy, Debug)]
pub struct MeshLayer<'a> {
    /// Vertex positions (world), `#V`.
    pub positions: MeshPositions<'a>,
    /// Triangles as vertex indices, `#T × 3`.
    pub triangles: &'a [[u32; 3]],
    /// Per-vertex sRGB colours (`#V`, e.g. a colour map); `None` = the neutral material.
    pub colors: Option<&'a [[u8; 4]]>,
    /// Faceted shading (normals per triangle) instead of smooth.
    pub flat: bool,
    /// Draw the triangle edges over the surface.
    pub wireframe: bool,
    /// When set, equal ids promise identical `triangles` from frame to frame (e.g.
    /// `RigSession::topology_id`), and the upload skips comparing the lists.
    pub topology_id: Option<u64>,
}

/// The deformation cage: translucent faces, edges and vertex handles.
#[derive(Clone, Copy, Debug)]
pub struct CageLayer<'a> {
    /// Cage vertex positions (world), `#C`.
    pub positions: &'a [DVec3],
    /// Cage triangles, `#CT × 3`.
    pub triangles: &'a [[u32; 3]],
    /// Per-handle sRGB colours (`#C`, e.g. selection or a colour map); `None` = the cage colour.
    pub handle_colors: Option<&'a [[u8; 4]]>,
}

/// The skeleton: bones from each joint to its parent, joints as discs, drawn on top.
#[derive(Clone, Copy, Debug)]
pub struct SkeletonLayer<'a> {
    /// Joint positions (world), `#J`.
    pub joints: &'a [DVec3],
    /// Parent of each joint (`#J`), `None` for roots.
    pub parents: &'a [Option<usize>],
    /// Per-joint sRGB colours (`#J`); `None` = the skeleton colour.
    pub joint_colors: Option<&'a [[u8; 4]]>,
}

/// One view's content.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scene<'a> {
    /// The skin, if drawn.
    pub mesh: Option<MeshLayer<'a>>,
    /// The cage, if drawn.
    pub cage: Option<CageLayer<'a>>,
    /// The skeleton, if drawn.
    pub skeleton: Option<SkeletonLayer<'a>>,
    /// Draw a ground grid with a contact shadow below the content.
    pub ground: bool,
}

impl Scene<'_> {
    /// Axis-aligned bounds `(lo, hi)` of everything drawn; `None` when the scene is empty.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        use rayon::prelude::*;
        let from_mesh = match self.mesh.map(|m| m.positions) {
            None => EMPTY_BOUNDS,
            Some(MeshPositions::F64(mesh)) => mesh
                .par_chunks(16_384)
                .map(|chunk| chunk.iter().fold(EMPTY_BOUNDS, |b, p| grow_bounds(b, *p)))
                .reduce(|| EMPTY_BOUNDS, merge_bounds),
            Some(MeshPositions::F32(mesh)) => mesh
                .par_chunks(16_384)
                .map(|chunk| {
                    chunk
                        .iter()
                        .fold(EMPTY_BOUNDS, |b, p| grow_bounds(b, p.as_dvec3()))
                })
                .reduce(|| EMPTY_BOUNDS, merge_bounds),
        };
        self.bounds_with_mesh(from_mesh)
    }

    /// [`Scene::bounds`] given the bounds of the mesh layer's finite points (measured while
    /// packing them for upload).
    pub fn bounds_with_mesh(&self, from_mesh: Bounds) -> Option<(DVec3, DVec3)> {
        let cage = self.cage.map(|c| c.positions).unwrap_or(&[]);
        let joints = self.skeleton.map(|s| s.joints).unwrap_or(&[]);
        let (lo, hi) = cage
            .iter()
            .chain(joints)
            .fold(from_mesh, |b, p| grow_bounds(b, *p));
        (lo.cmple(hi).all()).then_some((lo, hi))
    }
}

/// Axis-aligned bounds `(lo, hi)`; [`EMPTY_BOUNDS`] (lo > hi) when no point was added.
pub type Bounds = (DVec3, DVec3);

/// The bounds of no point.
pub const EMPTY_BOUNDS: Bounds = (DVec3::INFINITY, DVec3::NEG_INFINITY);

/// `bounds` grown by `p` when `p` is finite.
#[inline]
pub fn grow_bounds((lo, hi): Bounds, p: DVec3) -> Bounds {
    if p.is_finite() {
        (lo.min(p), hi.max(p))
    } else {
        (lo, hi)
    }
}

/// The union of two bounds.
#[inline]
pub fn merge_bounds((lo, hi): Bounds, (l, h): Bounds) -> Bounds {
    (lo.min(l), hi.max(h))
}

/// Colours (8-bit sRGB + alpha) and sizes (pixels at 1× scale) of the layers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Neutral clay material of the skin.
    pub mesh: [u8; 4],
    /// Skin triangle edges.
    pub wireframe: [u8; 4],
    /// Translucent cage faces.
    pub cage_faces: [u8; 4],
    /// Cage edges.
    pub cage_edges: [u8; 4],
    /// Cage vertex handles (when no per-handle colour is given).
    pub cage_handles: [u8; 4],
    /// Opacity (0–255) of cage edges and handles hidden behind the skin.
    pub hidden_alpha: u8,
    /// Bones.
    pub bones: [u8; 4],
    /// Joint discs (when no per-joint colour is given).
    pub joints: [u8; 4],
    /// Width of cage edges, in pixels.
    pub line_width: f32,
    /// Width of bones, in pixels.
    pub bone_width: f32,
    /// Radius of cage handles, in pixels.
    pub handle_radius: f32,
    /// Radius of joint discs, in pixels.
    pub joint_radius: f32,
    /// Multiplies every width and radius (e.g. 2 for a picture at twice the size).
    pub scale: f32,
}

impl Default for Style {
    fn default() -> Self {
        Self {
            mesh: [200, 194, 184, 255],
            wireframe: [40, 40, 48, 110],
            cage_faces: [255, 140, 30, 34],
            cage_edges: [235, 110, 10, 255],
            cage_handles: [255, 150, 40, 255],
            hidden_alpha: 70,
            bones: [30, 90, 200, 255],
            joints: [120, 190, 255, 255],
            line_width: 1.8,
            bone_width: 3.5,
            handle_radius: 4.5,
            joint_radius: 5.5,
            scale: 1.0,
        }
    }
}

/// Unique undirected edges of a triangle list, sorted `(min, max)`.
pub fn unique_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_of_a_tetrahedron_are_six() {
        let tris = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]];
        assert_eq!(unique_edges(&tris).len(), 6);
    }

    #[test]
    fn bounds_cover_every_layer_and_skip_non_finite_points() {
        let mesh = [DVec3::ZERO, DVec3::ONE];
        let cage = [DVec3::splat(-2.0), DVec3::NAN];
        let joints = [DVec3::new(0.0, 5.0, 0.0)];
        let scene = Scene {
            mesh: Some(MeshLayer {
                positions: MeshPositions::F64(&mesh),
                triangles: &[],
                colors: None,
                flat: false,
                wireframe: false,
                topology_id: None,
            }),
            cage: Some(CageLayer {
                positions: &cage,
                triangles: &[],
                handle_colors: None,
            }),
            skeleton: Some(SkeletonLayer {
                joints: &joints,
                parents: &[None],
                joint_colors: None,
            }),
            ground: true,
        };
        assert_eq!(
            scene.bounds(),
            Some((DVec3::splat(-2.0), DVec3::new(1.0, 5.0, 1.0)))
        );
        assert_eq!(Scene::default().bounds(), None);
    }
}
