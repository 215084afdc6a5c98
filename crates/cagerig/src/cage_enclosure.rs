//! Does the cage enclose the mesh? Mean value coordinates extrapolate outside the cage, so a
//! cage that does not wrap its character (scaled down, moved away) still "works" and deforms the
//! outside parts wildly. This module finds the mesh vertices outside the cage with the
//! generalised winding number w(p) = Σ_t Ω_t(p) / 4π (Ω_t the signed solid angle of cage
//! triangle t seen from p, Van Oosterom–Strackee): w ≈ 1 inside a closed outward-oriented cage,
//! ≈ 0 outside. Vertices within [`SURFACE_TOLERANCE`] × the cage's bbox diagonal of the cage
//! surface count as inside (a skin touching its cage is common).

use glam::DVec3;
use rayon::prelude::*;

use crate::cage::validate_cage;
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;

/// Distance to the cage surface (× the cage's bbox diagonal) below which a vertex counts as
/// inside whatever its winding number.
pub const SURFACE_TOLERANCE: f64 = 1e-6;

/// Mesh vertices found outside the cage.
#[derive(Debug, Clone, PartialEq)]
pub struct OutsideVertices {
    /// How many vertices are outside.
    pub count: usize,
    /// The vertex farthest from the cage surface, and that distance (mesh units).
    pub worst_vertex: usize,
    /// Distance of `worst_vertex` to the cage surface (mesh units).
    pub worst_distance: f64,
}

/// Signed solid angle of triangle (a, b, c) seen from the origin, in steradians.
fn solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c));
    let denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * numerator.atan2(denominator)
}

/// Distance from `p` to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
pub fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (p - (a + ab * (d1 / (d1 - d3)))).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (p - (a + ac * (d2 / (d2 - d6)))).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}

/// Distance from `p` to the cage surface.
fn distance_to_surface(cage: &TriMesh, p: DVec3) -> f64 {
    (0..cage.num_triangles())
        .map(|t| {
            let [a, b, c] = cage.corners(t);
            point_triangle_distance(p, a, b, c)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The vertices of `points` outside the closed, outward-oriented `cage`, or `None` when all are
/// inside (or within [`SURFACE_TOLERANCE`] of its surface). O(#V · #F_cage), in parallel.
pub fn vertices_outside_cage(cage: &TriMesh, points: &[DVec3]) -> Option<OutsideVertices> {
    let (lo, hi) = cage.bounding_box();
    let tolerance = SURFACE_TOLERANCE * (hi - lo).length();
    let outside: Vec<(usize, f64)> = points
        .par_iter()
        .enumerate()
        .filter_map(|(i, &p)| {
            let in_box = p.cmpge(lo - tolerance).all() && p.cmple(hi + tolerance).all();
            if in_box {
                let winding: f64 = (0..cage.num_triangles())
                    .map(|t| {
                        let [a, b, c] = cage.corners(t);
                        solid_angle(a - p, b - p, c - p)
                    })
                    .sum::<f64>()
                    / (4.0 * std::f64::consts::PI);
                if winding >= 0.5 {
                    return None;
                }
            }
            let d = distance_to_surface(cage, p);
            (d > tolerance).then_some((i, d))
        })
        .collect();
    let &(worst_vertex, worst_distance) = outside
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))?;
    Some(OutsideVertices {
        count: outside.len(),
        worst_vertex,
        worst_distance,
    })
}

/// The one cage validation of every command and of [`crate::session::RigSession::new`]: the
/// checks of [`validate_cage`] (closed, manifold, consistently oriented, no degenerate or
/// repeated-vertex triangle; flipped outwards if it faced inwards) and the mesh inside the cage.
/// Vertices outside are an error ([`RigError::MeshOutsideCage`]) unless `allow_outside`, in
/// which case they are reported as a warning (mean value coordinates extrapolate there).
pub fn validate_cage_for_mesh(
    cage: TriMesh,
    mesh_positions: &[DVec3],
    allow_outside: bool,
) -> Result<(TriMesh, Vec<Warning>), RigError> {
    let (cage, mut warnings) = validate_cage(cage)?;
    if let Some(out) = vertices_outside_cage(&cage, mesh_positions) {
        if !allow_outside {
            return Err(RigError::MeshOutsideCage {
                count: out.count,
                total: mesh_positions.len(),
                worst_vertex: out.worst_vertex,
                worst_distance: out.worst_distance,
            });
        }
        warnings.push(Warning::Note {
            message: format!(
                "{} of {} mesh vertices are outside the cage (farthest: vertex {}, {:.3e} from \
                 it); accepted as asked, mean value coordinates extrapolate there",
                out.count,
                mesh_positions.len(),
                out.worst_vertex,
                out.worst_distance
            ),
        });
    }
    Ok((cage, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit cube [0,1]³, outward triangles.
    fn cube() -> TriMesh {
        TriMesh::cuboid(DVec3::ZERO, DVec3::ONE).unwrap()
    }

    #[test]
    fn winding_number_separates_inside_from_outside() {
        let c = cube();
        assert!(c.signed_volume() > 0.0);
        let inside = [
            DVec3::splat(0.5),
            DVec3::new(0.01, 0.99, 0.5),
            DVec3::new(0.0, 0.5, 0.5),
        ];
        assert_eq!(vertices_outside_cage(&c, &inside), None);
        let points = [
            DVec3::splat(0.5),
            DVec3::new(1.5, 0.5, 0.5),
            DVec3::new(0.5, -3.0, 0.5),
        ];
        let out = vertices_outside_cage(&c, &points).unwrap();
        assert_eq!(out.count, 2);
        assert_eq!(out.worst_vertex, 2);
        assert!((out.worst_distance - 3.0).abs() < 1e-12);
    }

    #[test]
    fn validation_rejects_by_default_and_accepts_on_request() {
        let far = [DVec3::new(0.5, 0.5, 2.0)];
        let e = validate_cage_for_mesh(cube(), &far, false).unwrap_err();
        assert!(matches!(
            e,
            RigError::MeshOutsideCage {
                count: 1,
                worst_vertex: 0,
                ..
            }
        ));
        assert!(e.to_string().contains("1 of 1"), "{e}");
        let (_, w) = validate_cage_for_mesh(cube(), &far, true).unwrap();
        assert_eq!(w.len(), 1);
    }

    #[test]
    fn point_triangle_distance_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert!((point_triangle_distance(DVec3::new(0.2, 0.2, 1.0), a, b, c) - 1.0).abs() < 1e-15);
        assert!(
            (point_triangle_distance(DVec3::new(-1.0, -1.0, 0.0), a, b, c) - 2f64.sqrt()).abs()
                < 1e-15
        );
        assert!((point_triangle_distance(DVec3::new(0.5, -2.0, 0.0), a, b, c) - 2.0).abs() < 1e-15);
        assert!(
            (point_triangle_distance(DVec3::new(1.0, 1.0, 0.0), a, b, c) - 0.5f64.sqrt()).abs()
                < 1e-15
        );
    }
}
