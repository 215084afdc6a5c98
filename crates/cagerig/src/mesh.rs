//! Triangle meshes: the skin M and the cage C share this representation.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::RigError;

/// A triangle mesh with f64 positions and u32 triangle indices (counter-clockwise = outward).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TriMesh {
    /// Vertex positions, `#V`.
    pub positions: Vec<DVec3>,
    /// Triangles as vertex indices, `#F`.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Builds a mesh, checking that positions are finite and at most
    /// [`crate::error::MAX_INPUT_MAGNITUDE`] in magnitude, and that every index is in range.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, RigError> {
        for (index, p) in positions.iter().enumerate() {
            if let Some(value) = crate::error::first_bad_component(*p) {
                return Err(RigError::ValueOutOfBounds {
                    what: "vertex",
                    index,
                    value,
                });
            }
        }
        let len = positions.len();
        for tri in &triangles {
            for &i in tri {
                if i as usize >= len {
                    return Err(RigError::IndexOutOfRange {
                        what: "triangle vertex",
                        index: i as usize,
                        len,
                    });
                }
            }
        }
        Ok(Self {
            positions,
            triangles,
        })
    }

    /// The axis-aligned box `[lo, hi]`: 8 vertices (vertex `i` takes `hi.x` when bit 0 of `i`
    /// is set, else `lo.x`; bit 1 → y, bit 2 → z) and 12 outward-oriented triangles.
    pub fn cuboid(lo: DVec3, hi: DVec3) -> Result<Self, RigError> {
        let positions = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Self::new(positions, triangles)
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Axis-aligned bounding box `(min, max)`; `(0, 0)` for an empty mesh.
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        bounding_box(&self.positions)
    }

    /// Signed enclosed volume (positive when triangles face outwards).
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Unit area-weighted vertex normals written into `out` (`#V`); isolated vertices get zero.
    pub fn vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]], out: &mut [DVec3]) {
        out.iter_mut().for_each(|n| *n = DVec3::ZERO);
        for &[a, b, c] in triangles {
            let (pa, pb, pc) = (
                positions[a as usize],
                positions[b as usize],
                positions[c as usize],
            );
            let n = (pb - pa).cross(pc - pa);
            out[a as usize] += n;
            out[b as usize] += n;
            out[c as usize] += n;
        }
        out.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    }
}

/// Axis-aligned bounding box of a point set `(min, max)`; `(0, 0)` when empty.
pub fn bounding_box(points: &[DVec3]) -> (DVec3, DVec3) {
    if points.is_empty() {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// Generalised winding number of `point` with respect to a closed triangle mesh: the sum of the
/// signed solid angles its triangles subtend at `point`, divided by 4π (Van Oosterom–Strackee
/// formula). For a closed, outward-oriented mesh it is 1 inside, 0 outside and ½ on the surface
/// (up to rounding); for an open mesh it varies smoothly. Cost O(#F).
pub fn winding_number(positions: &[DVec3], triangles: &[[u32; 3]], point: DVec3) -> f64 {
    let mut total = 0.0;
    for &[a, b, c] in triangles {
        let va = positions[a as usize] - point;
        let vb = positions[b as usize] - point;
        let vc = positions[c as usize] - point;
        let (la, lb, lc) = (va.length(), vb.length(), vc.length());
        let numerator = va.dot(vb.cross(vc));
        let denominator = la * lb * lc + va.dot(vb) * lc + va.dot(vc) * lb + vb.dot(vc) * la;
        total += 2.0 * numerator.atan2(denominator);
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Largest distance between corresponding points of two equally long slices.
pub fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {

    #[test]
    fn cuboid_is_closed_outward_with_the_box_volume() {
        let m = TriMesh::cuboid(DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 3.0, 2.5)).unwrap();
        assert_eq!((m.num_vertices(), m.num_triangles()), (8, 12));
        assert!((m.signed_volume() - 2.0 * 3.0 * 0.5).abs() < 1e-12);
        assert_eq!(m.positions[5], DVec3::new(1.0, 0.0, 2.5));
    }

    use super::*;

    #[test]
    fn rejects_out_of_range_and_nan() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(matches!(
            TriMesh::new(p.clone(), vec![[0, 1, 3]]),
            Err(RigError::IndexOutOfRange { index: 3, .. })
        ));
        let mut q = p.clone();
        q[1].y = f64::NAN;
        assert!(matches!(
            TriMesh::new(q, vec![[0, 1, 2]]),
            Err(RigError::ValueOutOfBounds { index: 1, .. })
        ));
        // Finite but large enough to overflow the method's products.
        let mut r = p.clone();
        r[2].x = 1e308;
        assert!(matches!(
            TriMesh::new(r, vec![[0, 1, 2]]),
            Err(RigError::ValueOutOfBounds { index: 2, value, .. }) if value == 1e308
        ));
        assert!(TriMesh::new(p, vec![[0, 1, 2]]).is_ok());
    }

    #[test]
    fn winding_number_of_tetra_is_one_inside_zero_outside() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let inside = winding_number(&p, &t, DVec3::splat(0.2));
        assert!((inside - 1.0).abs() < 1e-12, "{inside}");
        let outside = winding_number(&p, &t, DVec3::new(1.0, 1.0, 1.0));
        assert!(outside.abs() < 1e-12, "{outside}");
        // Inverted orientation gives −1 inside.
        let flipped: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert!((winding_number(&p, &flipped, DVec3::splat(0.2)) + 1.0).abs() < 1e-12);
    }

    #[test]
    fn tetra_volume() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let m = TriMesh::new(p, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).unwrap();
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-15);
    }
}
