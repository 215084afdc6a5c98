//! Smooth vertex normals of a deforming mesh for display, in parallel: the vertex → triangle
//! adjacency is built once per topology ([`VertexNormals::new`]), then every frame computes the
//! area-weighted triangle normals and gathers them per vertex ([`VertexNormals::apply`]), with
//! no allocation and no write conflicts (each vertex sums its own triangles).
//!
//! The result equals `cagerig::mesh::TriMesh::vertex_normals` up to the order of the sums
//! (a few ulps), which display does not see.

use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;

use crate::scene::MeshPositions;

/// Triangles per rayon task.
const GRAIN: usize = 16_384;

/// The adjacency of one triangle list and the per-frame scratch.
#[derive(Debug, Clone, Default)]
pub struct VertexNormals {
    /// CSR offsets (`#V + 1`) into `faces`.
    offsets: Vec<u32>,
    /// Triangles around each vertex (`3 #F`).
    faces: Vec<u32>,
    /// Area-weighted triangle normals of the current frame (`#F`), for f64 positions.
    face_normals: Vec<DVec3>,
    /// The same for f32 positions (the display path).
    face_normals_f32: Vec<Vec3A>,
}

impl VertexNormals {
    /// Adjacency of `triangles` over `num_vertices` vertices (indices must be in range).
    pub fn new(num_vertices: usize, triangles: &[[u32; 3]]) -> Self {
        let mut counts = vec![0u32; num_vertices + 1];
        for t in triangles {
            for &v in t {
                counts[v as usize + 1] += 1;
            }
        }
        for i in 0..num_vertices {
            counts[i + 1] += counts[i];
        }
        let offsets = counts;
        let mut fill = offsets.clone();
        let mut faces = vec![0u32; 3 * triangles.len()];
        for (f, t) in triangles.iter().enumerate() {
            for &v in t {
                let slot = &mut fill[v as usize];
                faces[*slot as usize] = f as u32;
                *slot += 1;
            }
        }
        Self {
            offsets,
            faces,
            face_normals: Vec::new(),
            face_normals_f32: Vec::new(),
        }
    }

    /// Number of vertices this adjacency was built for.
    pub fn num_vertices(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Unit vertex normals of `positions` (`#V`) into `out` (`#V`, f32 for upload); zero where a
    /// vertex has no triangle or its triangles are degenerate. `triangles` must be the list
    /// given to `new`. f64 positions are processed in f64, f32 ones in f32.
    pub fn apply(
        &mut self,
        positions: MeshPositions<'_>,
        triangles: &[[u32; 3]],
        out: &mut [Vec3],
    ) {
        match positions {
            MeshPositions::F64(p) => {
                self.face_normals.resize(triangles.len(), DVec3::ZERO);
                gather(
                    &self.offsets,
                    &self.faces,
                    &mut self.face_normals,
                    triangles,
                    |i| p[i],
                    out,
                )
            }
            MeshPositions::F32(p) => {
                self.face_normals_f32.resize(triangles.len(), Vec3A::ZERO);
                gather(
                    &self.offsets,
                    &self.faces,
                    &mut self.face_normals_f32,
                    triangles,
                    |i| Vec3A::from(p[i]),
                    out,
                )
            }
        }
    }
}

/// Vector arithmetic of [`gather`] in the positions' precision.
trait NormalVector: Copy + Send + Sync + std::ops::Sub<Output = Self> + std::iter::Sum {
    fn cross(self, other: Self) -> Self;
    /// Unit vector (zero for a zero sum), rounded to f32.
    fn unit_f32(self) -> Vec3;
}

impl NormalVector for DVec3 {
    fn cross(self, other: Self) -> Self {
        DVec3::cross(self, other)
    }
    fn unit_f32(self) -> Vec3 {
        self.normalize_or_zero().as_vec3()
    }
}

impl NormalVector for Vec3A {
    fn cross(self, other: Self) -> Self {
        Vec3A::cross(self, other)
    }
    fn unit_f32(self) -> Vec3 {
        self.normalize_or_zero().into()
    }
}

/// Triangle normals into `face_normals` (`#F`), then per-vertex sums over the CSR adjacency
/// `offsets`/`faces`, normalised into `out`.
fn gather<V: NormalVector>(
    offsets: &[u32],
    faces: &[u32],
    face_normals: &mut [V],
    triangles: &[[u32; 3]],
    position: impl Fn(usize) -> V + Sync,
    out: &mut [Vec3],
) {
    face_normals
        .par_iter_mut()
        .zip(triangles.par_iter())
        .with_min_len(GRAIN)
        .for_each(|(n, &[a, b, c])| {
            let (pa, pb, pc) = (
                position(a as usize),
                position(b as usize),
                position(c as usize),
            );
            *n = (pb - pa).cross(pc - pa);
        });
    let face_normals = &*face_normals;
    out.par_iter_mut()
        .enumerate()
        .with_min_len(GRAIN)
        .for_each(|(v, n)| {
            let (lo, hi) = (offsets[v] as usize, offsets[v + 1] as usize);
            let sum: V = faces[lo..hi]
                .iter()
                .map(|&f| face_normals[f as usize])
                .sum();
            *n = sum.unit_f32();
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use cagerig::mesh::TriMesh;

    #[test]
    fn normals_match_the_serial_reference_on_a_box() {
        let cube =
            TriMesh::cuboid(DVec3::new(-1.0, -2.0, -0.5), DVec3::new(1.0, 2.0, 0.5)).unwrap();
        let mut reference = vec![DVec3::ZERO; cube.positions.len()];
        TriMesh::vertex_normals(&cube.positions, &cube.triangles, &mut reference);
        let mut normals = VertexNormals::new(cube.positions.len(), &cube.triangles);
        let mut out = vec![Vec3::ZERO; cube.positions.len()];
        normals.apply(
            MeshPositions::F64(&cube.positions),
            &cube.triangles,
            &mut out,
        );
        let mut out32 = vec![Vec3::ZERO; cube.positions.len()];
        let positions32: Vec<Vec3> = cube.positions.iter().map(|p| p.as_vec3()).collect();
        normals.apply(
            MeshPositions::F32(&positions32),
            &cube.triangles,
            &mut out32,
        );
        for ((a, a32), b) in out.iter().zip(&out32).zip(&reference) {
            assert!(a.as_dvec3().distance(*b) < 1e-6, "{a} vs {b}");
            assert!(a32.as_dvec3().distance(*b) < 1e-6, "{a32} vs {b}");
            assert!((a.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn an_isolated_vertex_gets_a_zero_normal() {
        let positions = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::splat(5.0)];
        let triangles = [[0u32, 1, 2]];
        let mut normals = VertexNormals::new(4, &triangles);
        let mut out = vec![Vec3::ONE; 4];
        normals.apply(MeshPositions::F64(&positions), &triangles, &mut out);
        assert_eq!(out[3], Vec3::ZERO);
        assert!(out[0].distance(Vec3::Z) < 1e-7);
    }
}
