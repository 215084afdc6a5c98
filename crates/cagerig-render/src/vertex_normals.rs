//! Smooth vertex normals of a deforming mesh for display, in parallel: the vertex → triangle
//! adjacency is built once per topology ([`VertexNormals::new`]), then every frame computes the
//! area-weighted triangle normals ([`VertexNormals::face_normals`]) and each vertex sums its own
//! triangles ([`VertexNormals::vertex_sum`], called by the vertex packing), with no allocation
//! and no write conflicts. The sum is uploaded unnormalised: the mesh vertex shader normalises
//! it (a zero sum, at an isolated vertex or among degenerate triangles, stays zero and the
//! fragment shader falls back to the flat normal).
//!
//! The directions equal `cagerig::mesh::TriMesh::vertex_normals` up to the order of the sums
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
    /// Which of the two the last frame filled.
    precision: Precision,
}

/// The precision of the last frame's positions.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
enum Precision {
    #[default]
    F64,
    F32,
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
            precision: Precision::F64,
        }
    }

    /// Number of vertices this adjacency was built for.
    pub fn num_vertices(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The area-weighted triangle normals of `positions` (`#V`) for this frame. `triangles`
    /// must be the list given to `new`. f64 positions are processed in f64, f32 ones in f32.
    pub fn face_normals(&mut self, positions: MeshPositions<'_>, triangles: &[[u32; 3]]) {
        match positions {
            MeshPositions::F64(p) => {
                self.precision = Precision::F64;
                self.face_normals.resize(triangles.len(), DVec3::ZERO);
                triangle_normals(&mut self.face_normals, triangles, |i| p[i]);
            }
            MeshPositions::F32(p) => {
                self.precision = Precision::F32;
                self.face_normals_f32.resize(triangles.len(), Vec3A::ZERO);
                triangle_normals(&mut self.face_normals_f32, triangles, |i| Vec3A::from(p[i]));
            }
        }
    }

    /// The sum of the triangle normals around vertex `v` from the last
    /// [`VertexNormals::face_normals`], unnormalised, rounded to f32 (zero for an isolated
    /// vertex).
    #[inline]
    pub fn vertex_sum(&self, v: usize) -> Vec3 {
        let (lo, hi) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
        let faces = &self.faces[lo..hi];
        match self.precision {
            Precision::F64 => faces
                .iter()
                .map(|&f| self.face_normals[f as usize])
                .sum::<DVec3>()
                .as_vec3(),
            Precision::F32 => faces
                .iter()
                .map(|&f| self.face_normals_f32[f as usize])
                .sum::<Vec3A>()
                .into(),
        }
    }
}

/// Triangle normals (cross products of two edges, twice the area) into `face_normals` (`#F`).
fn triangle_normals<V>(
    face_normals: &mut [V],
    triangles: &[[u32; 3]],
    position: impl Fn(usize) -> V + Sync,
) where
    V: Copy + Send + std::ops::Sub<Output = V> + Cross,
{
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
}

/// The cross product in the positions' precision.
trait Cross {
    fn cross(self, other: Self) -> Self;
}

impl Cross for DVec3 {
    fn cross(self, other: Self) -> Self {
        DVec3::cross(self, other)
    }
}

impl Cross for Vec3A {
    fn cross(self, other: Self) -> Self {
        Vec3A::cross(self, other)
    }
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
        let n = cube.positions.len();
        let mut normals = VertexNormals::new(n, &cube.triangles);
        normals.face_normals(MeshPositions::F64(&cube.positions), &cube.triangles);
        let out: Vec<Vec3> = (0..n).map(|v| normals.vertex_sum(v)).collect();
        let positions32: Vec<Vec3> = cube.positions.iter().map(|p| p.as_vec3()).collect();
        normals.face_normals(MeshPositions::F32(&positions32), &cube.triangles);
        let out32: Vec<Vec3> = (0..n).map(|v| normals.vertex_sum(v)).collect();
        for ((a, a32), b) in out.iter().zip(&out32).zip(&reference) {
            // The shader's normalisation of the uploaded sums.
            let (a, a32) = (a.normalize(), a32.normalize());
            assert!(a.as_dvec3().distance(*b) < 1e-6, "{a} vs {b}");
            assert!(a32.as_dvec3().distance(*b) < 1e-6, "{a32} vs {b}");
        }
    }

    #[test]
    fn an_isolated_vertex_gets_a_zero_normal() {
        let positions = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::splat(5.0)];
        let triangles = [[0u32, 1, 2]];
        let mut normals = VertexNormals::new(4, &triangles);
        normals.face_normals(MeshPositions::F64(&positions), &triangles);
        assert_eq!(normals.vertex_sum(3), Vec3::ZERO);
        assert!(normals.vertex_sum(0).normalize().distance(Vec3::Z) < 1e-7);
    }
}
