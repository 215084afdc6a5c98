//! Caps over the holes of a mesh, so that its volume can be filled (the Arm is open at the
//! shoulder: without a cap the flood fill enters it and only the surface shell is solid).
//!
//! The mesh is welded by position (triangle soups), its boundary edges (used by exactly one
//! triangle) are grouped into connected boundary components, and each component whose box
//! diagonal is below `max_fraction` × the mesh's is capped by a fan of triangles from its
//! centroid to each of its edges. The caps are only voxelised, never added to the mesh; a
//! larger opening (the hem of a skirt, the bottom of a cloak) is left open, since capping it
//! would join what it surrounds (the legs) into one volume.

use std::collections::HashMap;

use glam::DVec3;

use crate::cage_gen::weld::weld_by_position;

/// Default [`hole_caps`] `max_fraction`.
pub const DEFAULT_MAX_HOLE_FRACTION: f64 = 0.3;

/// Cap triangles (world-space corners, `#caps`) over the holes of the mesh smaller than
/// `max_fraction` × the mesh's bounding-box diagonal, and the number of holes capped.
pub fn hole_caps(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    max_fraction: f64,
) -> (Vec<[DVec3; 3]>, usize) {
    let welded = weld_by_position(positions, 0.0);
    let w = |i: u32| welded.welded_of[i as usize];
    // Undirected edges of the welded mesh and how many triangles use each.
    let mut uses: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 3);
    for t in triangles {
        let [a, b, c] = t.map(w);
        if a == b || b == c || a == c {
            continue;
        }
        for (p, q) in [(a, b), (b, c), (c, a)] {
            *uses.entry((p.min(q), p.max(q))).or_insert(0) += 1;
        }
    }
    let boundary: Vec<(u32, u32)> = uses
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect();
    if boundary.is_empty() {
        return (Vec::new(), 0);
    }
    // A position for each welded vertex.
    let mut position = vec![DVec3::ZERO; welded.num_welded];
    for (i, &k) in welded.welded_of.iter().enumerate() {
        position[k as usize] = positions[i];
    }
    // Union-find over the boundary vertices: the connected boundary components.
    let mut parent: Vec<u32> = (0..welded.num_welded as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for &(a, b) in &boundary {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra as usize] = rb;
        }
    }
    let mut components: HashMap<u32, Vec<(u32, u32)>> = HashMap::new();
    for &(a, b) in &boundary {
        let root = find(&mut parent, a);
        components.entry(root).or_default().push((a, b));
    }
    let (lo, hi) = crate::mesh::bounding_box(positions);
    let limit = max_fraction * (hi - lo).length();
    let mut caps = Vec::new();
    let mut holes = 0;
    let mut roots: Vec<u32> = components.keys().copied().collect();
    roots.sort_unstable();
    for root in roots {
        let edges = &components[&root];
        let points: Vec<DVec3> = edges
            .iter()
            .flat_map(|&(a, b)| [position[a as usize], position[b as usize]])
            .collect();
        let (clo, chi) = crate::mesh::bounding_box(&points);
        if (chi - clo).length() > limit {
            continue;
        }
        holes += 1;
        let centroid = points.iter().copied().sum::<DVec3>() / points.len() as f64;
        caps.extend(
            edges
                .iter()
                .map(|&(a, b)| [centroid, position[a as usize], position[b as usize]]),
        );
    }
    (caps, holes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TriMesh;

    #[test]
    fn a_closed_mesh_has_no_cap_and_an_open_box_gets_one() {
        let cube = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE).unwrap();
        assert_eq!(
            hole_caps(&cube.positions, &cube.triangles, 0.3),
            (Vec::new(), 0)
        );
        // One face removed: a 4-edge hole of diagonal √2 in a box of diagonal √3.
        let open = &cube.triangles[2..];
        let (caps, holes) = hole_caps(&cube.positions, open, 1.0);
        assert_eq!((caps.len(), holes), (4, 1));
        let centre = caps[0][0];
        assert!(caps.iter().all(|c| c[0] == centre));
        // Too large for a small limit: left open.
        assert_eq!(hole_caps(&cube.positions, open, 0.5).1, 0);
    }

    #[test]
    fn a_soup_is_welded_before_looking_for_holes() {
        let cube = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE).unwrap();
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for t in 0..cube.num_triangles() {
            let base = positions.len() as u32;
            positions.extend(cube.corners(t));
            triangles.push([base, base + 1, base + 2]);
        }
        assert_eq!(hole_caps(&positions, &triangles, 1.0).1, 0);
    }
}
