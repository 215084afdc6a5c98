//! Smooth vertex normals of a deforming mesh for display, in parallel: the vertex → triangle
//! adjacency is built once per topology ([`VertexNormals::new`]), then every frame computes the
//! area-weighted triangle normals and gathers them per vertex ([`VertexNormals::apply`]), with
//! no allocation and no write conflicts (each vertex sums its own triangles).
//!
//! The result equals `cagerig::mesh::TriMesh::vertex_normals` up to the order of the sums
//! (a few ulps), which display does not see.

use glam::DVec3;
use rayon::prelude::*;

/// Triangles per rayon task.
const GRAIN: usize = 16_384;

/// The adjacency of one triangle list and the per-frame scratch.
#[derive(Debug, Clone, Default)]
pub struct VertexNormals {
    /// CSR offsets (`#V + 1`) into `faces`.
    offsets: Vec<u32>,
    /// Triangles around each vertex (`3 #F`).
    faces: Vec<u32>,
    /// Area-weighted triangle normals of the current frame (`#F`).
    face_normals: Vec<DVec3>,
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
            face_normals: vec![DVec3::ZERO; triangles.len()],
        }
    }

    /// Number of vertices this adjacency was built for.
    pub fn num_vertices(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Unit vertex normals of `positions` (`#V`) into `out` (`#V`); zero where a vertex has no
    /// triangle or its triangles are degenerate. `triangles` must be the list given to `new`.
    pub fn apply(&mut self, positions: &[DVec3], triangles: &[[u32; 3]], out: &mut [DVec3]) {
        self.face_normals
            .par_iter_mut()
            .zip(triangles.par_iter())
            .with_min_len(GRAIN)
            .for_each(|(n, &[a, b, c])| {
                let (pa, pb, pc) = (
                    positions[a as usize],
                    positions[b as usize],
                    positions[c as usize],
                );
                *n = (pb - pa).cross(pc - pa);
            });
        let faces = &self.faces;
        let offsets = &self.offsets;
        let face_normals = &self.face_normals;
        out.par_iter_mut()
            .enumerate()
            .with_min_len(GRAIN)
            .for_each(|(v, n)| {
                let (lo, hi) = (offsets[v] as usize, offsets[v + 1] as usize);
                let sum: DVec3 = faces[lo..hi]
                    .iter()
                    .map(|&f| face_normals[f as usize])
                    .sum();
                *n = sum.normalize_or_zero();
            });
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
        let mut normals = VertexNormals::new(cube.positions.len(), &cube.triangles);
        let mut out = vec![DVec3::ZERO; cube.positions.len()];
        normals.apply(&cube.positions, &cube.triangles, &mut out);
        for (a, b) in out.iter().zip(&reference) {
            assert!(a.distance(*b) < 1e-12, "{a} vs {b}");
            assert!((a.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn an_isolated_vertex_gets_a_zero_normal() {
        let positions = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::splat(5.0)];
        let triangles = [[0u32, 1, 2]];
        let mut normals = VertexNormals::new(4, &triangles);
        let mut out = vec![DVec3::ONE; 4];
        normals.apply(&positions, &triangles, &mut out);
        assert_eq!(out[3], DVec3::ZERO);
        assert!(out[0].distance(DVec3::Z) < 1e-15);
    }
}
