//! Closed manifold surface of the solid: marching tetrahedra (Doi & Koide 1991) on the
//! Freudenthal (Kuhn) subdivision of every grid cube into six tetrahedra around its main
//! diagonal.
//!
//! The subdivision is a conforming tetrahedralisation of the grid, and the field is never 0 at a
//! grid point, so the zero set of the piecewise-linear field is a closed 2-manifold: every output
//! edge lies in a tetrahedron face crossed by the surface, shared by exactly two tetrahedra, and
//! each tetrahedron holds one triangle or one quad. Surface vertices are shared through the grid
//! edge they lie on. Triangles face the positive (outside) side.
//!
//! Guarantee used by cage generation: every surface point lies in a tetrahedron with a positive
//! corner b, within the tetrahedron's diameter h√3 of b; as dist(b) > offset, the surface stays
//! farther than offset − h√3 from the mesh, and every tetrahedron touching the mesh has only
//! negative corners, so the mesh is inside.

use std::collections::HashMap;

use glam::DVec3;

use super::distance_grid::OutsideField;

/// Surface of [`extract_surface`]: positions and outward triangles.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Surface {
    /// Surface vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles (indices into `positions`), facing outside.
    pub triangles: Vec<[u32; 3]>,
}

/// The six tetrahedra of a cube (corner bit 0 = +x, bit 1 = +y, bit 2 = +z): paths
/// 0 → e_a → e_a + e_b → 7 over the permutations (a, b, c) of the axes.
const CUBE_TETS: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Extracts the zero set of `field` (see module docs).
pub fn extract_surface(field: &OutsideField) -> Surface {
    let grid = &field.grid;
    let [nx, ny, nz] = grid.dims;
    let mut surface = Surface::default();
    let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::new();
    let corner_offset = |bit: usize| [bit & 1, (bit >> 1) & 1, (bit >> 2) & 1];
    for z in 0..nz.saturating_sub(1) {
        for y in 0..ny.saturating_sub(1) {
            for x in 0..nx.saturating_sub(1) {
                let corners: [usize; 8] = std::array::from_fn(|bit| {
                    let o = corner_offset(bit);
                    grid.index([x + o[0], y + o[1], z + o[2]])
                });
                let signs = corners.map(|i| field.values[i] > 0.0);
                if signs.iter().all(|&s| s) || signs.iter().all(|&s| !s) {
                    continue;
                }
                for tet in CUBE_TETS {
                    let ids = tet.map(|c| corners[c]);
                    let mut inside = [0usize; 4];
                    let mut outside = [0usize; 4];
                    let (mut ni, mut no) = (0, 0);
                    for id in ids {
                        if field.values[id] > 0.0 {
                            outside[no] = id;
                            no += 1;
                        } else {
                            inside[ni] = id;
                            ni += 1;
                        }
                    }
                    let mut vertex = |a: usize, b: usize| {
                        let key = (a.min(b) as u32, a.max(b) as u32);
                        *edge_vertex.entry(key).or_insert_with(|| {
                            let (fa, fb) = (field.values[a], field.values[b]);
                            let t = fa / (fa - fb);
                            let pa = grid.position(grid.coords(a));
                            let pb = grid.position(grid.coords(b));
                            surface.positions.push(pa + (pb - pa) * t);
                            (surface.positions.len() - 1) as u32
                        })
                    };
                    let outside_centre;
                    let inside_centre;
                    let polygon: Vec<u32> = match (no, ni) {
                        (1, 3) => {
                            let o = outside[0];
                            outside_centre = vec![o];
                            inside_centre = inside[..3].to_vec();
                            inside[..3].iter().map(|&i| vertex(o, i)).collect()
                        }
                        (3, 1) => {
                            let i = inside[0];
                            outside_centre = outside[..3].to_vec();
                            inside_centre = vec![i];
                            outside[..3].iter().map(|&o| vertex(o, i)).collect()
                        }
                        (2, 2) => {
                            let (o0, o1, i0, i1) = (outside[0], outside[1], inside[0], inside[1]);
                            outside_centre = vec![o0, o1];
                            inside_centre = vec![i0, i1];
                            vec![
                                vertex(o0, i0),
                                vertex(o0, i1),
                                vertex(o1, i1),
                                vertex(o1, i0),
                            ]
                        }
                        _ => continue,
                    };
                    let centre = |ids: &[usize]| {
                        ids.iter()
                            .map(|&i| grid.position(grid.coords(i)))
                            .sum::<DVec3>()
                            / ids.len() as f64
                    };
                    let towards_outside = centre(&outside_centre) - centre(&inside_centre);
                    let mut emit = |tri: [u32; 3]| {
                        let [a, b, c] = tri.map(|v| surface.positions[v as usize]);
                        if (b - a).cross(c - a).dot(towards_outside) >= 0.0 {
                            surface.triangles.push(tri);
                        } else {
                            surface.triangles.push([tri[0], tri[2], tri[1]]);
                        }
                    };
                    emit([polygon[0], polygon[1], polygon[2]]);
                    if polygon.len() == 4 {
                        emit([polygon[0], polygon[2], polygon[3]]);
                    }
                }
            }
        }
    }
    surface
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cage_gen::bvh::{Aabb, TriangleBvh};
    use crate::cage_gen::distance_grid::{SampleGrid, fill_from_outside};
    use crate::cage_gen::validate::check_closed_manifold;
    use crate::mesh::TriMesh;

    #[test]
    fn ball_surface_is_closed_outward_and_round() {
        let t = [DVec3::ZERO, DVec3::X * 1e-3, DVec3::Y * 1e-3];
        let bvh = TriangleBvh::new(vec![t]);
        let bounds = Aabb::of_triangle(&t);
        let (h, offset) = (0.1, 0.55);
        let grid = SampleGrid::around(bounds, h, offset + 2.0 * h);
        let field = fill_from_outside(grid, &bvh, bounds, offset);
        let surface = extract_surface(&field);
        let mesh = TriMesh::new(surface.positions.clone(), surface.triangles.clone()).unwrap();
        check_closed_manifold(&mesh.triangles, mesh.num_vertices()).unwrap();
        let volume = mesh.signed_volume();
        let ball = 4.0 / 3.0 * std::f64::consts::PI * offset.powi(3);
        assert!((volume / ball - 1.0).abs() < 0.05, "{volume} vs {ball}");
        for p in &surface.positions {
            assert!((p.length() - offset).abs() < h, "{p}");
        }
    }
}
