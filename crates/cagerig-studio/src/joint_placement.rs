//! Where a click puts a new joint: in the middle of the body under the cursor, along the view
//! ray, halfway between the point where the ray enters the skin and the point where it leaves
//! it (Blender's and Maya's "snap to the volume").

use glam::DVec3;

use crate::picking::ray_triangle;

/// The middle of the first stretch of the ray `origin + t·dir` (t > 0, `dir` unit) inside the
/// skin `positions` (`#V`) / `triangles` (`#F`): halfway between the first hit and the next
/// distinct one; the first hit itself when the ray meets the skin once (an open mesh); `None`
/// when it misses.
pub fn joint_in_body(
    origin: DVec3,
    dir: DVec3,
    positions: &[DVec3],
    triangles: &[[u32; 3]],
) -> Option<DVec3> {
    let mut hits: Vec<f64> = triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|i| positions.get(i as usize).copied());
            ray_triangle(origin, dir, a?, b?, c?)
        })
        .filter(|t| *t > 0.0 && t.is_finite())
        .collect();
    hits.sort_by(f64::total_cmp);
    let entry = *hits.first()?;
    // Hits on a shared edge or vertex count once.
    let gap = 1e-9 * entry.max(1.0);
    let exit = hits.iter().copied().find(|&t| t > entry + gap);
    let t = exit.map_or(entry, |exit| 0.5 * (entry + exit));
    Some(origin + t * dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's 8 vertices and 12 triangles.
    fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let cube = cagerig::mesh::TriMesh::cuboid(DVec3::ZERO, DVec3::ONE)
            .expect("a unit cube is a valid mesh");
        (cube.positions, cube.triangles)
    }

    #[test]
    fn the_joint_goes_halfway_through_the_body() {
        let (v, t) = cube();
        let p = joint_in_body(DVec3::new(0.3, 0.4, 5.0), -DVec3::Z, &v, &t).unwrap();
        assert!((p - DVec3::new(0.3, 0.4, 0.5)).length() < 1e-12, "{p}");
        // Through a diagonal edge of the faces: the shared edge counts once.
        let p = joint_in_body(DVec3::new(0.5, 0.5, 5.0), -DVec3::Z, &v, &t).unwrap();
        assert!((p.z - 0.5).abs() < 1e-12, "{p}");
        assert!(joint_in_body(DVec3::new(3.0, 0.4, 5.0), -DVec3::Z, &v, &t).is_none());
    }

    #[test]
    fn an_open_skin_hit_once_gives_the_hit() {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let p = joint_in_body(DVec3::new(0.2, 0.2, 1.0), -DVec3::Z, &v, &[[0, 1, 2]]).unwrap();
        assert!((p - DVec3::new(0.2, 0.2, 0.0)).length() < 1e-12);
    }
}
