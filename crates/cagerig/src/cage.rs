//! Deformation cages: closed, consistently oriented triangle meshes (C and C' share connectivity).

use std::collections::HashMap;

use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;

/// Relative area below which a cage triangle counts as degenerate (× squared bbox diagonal).
pub const DEGENERATE_AREA_RATIO: f64 = 1e-14;

/// Validates a cage mesh: closed (every edge in exactly two triangles), manifold, consistently
/// oriented, no repeated-vertex or zero-area triangle. A cage that faces inwards as a whole is
/// flipped and reported.
pub fn validate_cage(mut cage: TriMesh) -> Result<(TriMesh, Vec<Warning>), RigError> {
    if cage.triangles.is_empty() {
        return Err(RigError::EmptyCage);
    }
    let (lo, hi) = cage.bounding_box();
    let diag2 = (hi - lo).length_squared();
    for t in 0..cage.num_triangles() {
        let [a, b, c] = cage.triangles[t];
        if a == b || b == c || a == c {
            return Err(RigError::CageRepeatedVertex { triangle: t });
        }
        let [pa, pb, pc] = cage.corners(t);
        let area = 0.5 * (pb - pa).cross(pc - pa).length();
        if area <= DEGENERATE_AREA_RATIO * diag2 {
            return Err(RigError::CageDegenerateTriangle { triangle: t, area });
        }
    }
    // Undirected edge -> (count, first triangle, directed occurrences a->b with a<b).
    let mut edges: HashMap<(u32, u32), (usize, usize, i32)> = HashMap::new();
    for (t, tri) in cage.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let e = edges.entry(key).or_insert((0, t, 0));
            e.0 += 1;
            e.2 += if a < b { 1 } else { -1 };
        }
    }
    let mut sorted: Vec<_> = edges.into_iter().collect();
    sorted.sort_by_key(|(k, _)| *k);
    for ((a, b), (count, triangle, balance)) in sorted {
        match count {
            1 => return Err(RigError::CageOpenBoundary { a, b, triangle }),
            2 if balance != 0 => {
                let second = cage
                    .triangles
                    .iter()
                    .enumerate()
                    .rposition(|(_, t)| t.contains(&a) && t.contains(&b))
                    .unwrap_or(triangle);
                return Err(RigError::CageInconsistentOrientation {
                    a,
                    b,
                    first: triangle,
                    second,
                });
            }
            2 => {}
            _ => return Err(RigError::CageNonManifoldEdge { a, b, count }),
        }
    }
    let mut warnings = Vec::new();
    let volume = cage.signed_volume();
    if volume < 0.0 {
        for t in &mut cage.triangles {
            t.swap(1, 2);
        }
        warnings.push(Warning::CageOrientationFlipped {
            signed_volume: volume,
        });
    }
    Ok((cage, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn tetra() -> TriMesh {
        TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn accepts_tetra_and_flips_inverted() {
        let (c, w) = validate_cage(tetra()).unwrap();
        assert!(w.is_empty() && c.signed_volume() > 0.0);
        let mut inv = tetra();
        inv.triangles.iter_mut().for_each(|t| t.swap(0, 1));
        let (c, w) = validate_cage(inv).unwrap();
        assert!(c.signed_volume() > 0.0);
        assert!(matches!(w[0], Warning::CageOrientationFlipped { .. }));
    }

    #[test]
    fn names_the_bad_element() {
        let mut open = tetra();
        open.triangles.pop();
        assert!(matches!(
            validate_cage(open),
            Err(RigError::CageOpenBoundary { .. })
        ));
        let mut flipped_one = tetra();
        flipped_one.triangles[3].swap(0, 1);
        assert!(matches!(
            validate_cage(flipped_one),
            Err(RigError::CageInconsistentOrientation { .. })
        ));
        let mut degenerate = tetra();
        degenerate.positions[3] = DVec3::new(0.5, 0.5, 0.0);
        degenerate.positions[2] = DVec3::new(1.0, 0.0, 0.0);
        assert!(matches!(
            validate_cage(degenerate),
            Err(RigError::CageDegenerateTriangle { .. })
        ));
        let mut nm = tetra();
        nm.positions.push(DVec3::new(-1.0, -1.0, -1.0));
        nm.triangles.push([0, 1, 4]);
        assert!(matches!(
            validate_cage(nm),
            Err(RigError::CageNonManifoldEdge { .. }) | Err(RigError::CageOpenBoundary { .. })
        ));
    }
}
