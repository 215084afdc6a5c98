//! Distance sampling on a regular grid and the solid filled from outside.
//!
//! The grid covers the mesh's box padded by `offset + 2h` (h = spacing). A breadth-first fill
//! from the grid's boundary walks through every point whose distance to the mesh exceeds the
//! offset; what it cannot reach (the mesh's neighbourhood and every cavity, including the inside
//! of an open or self-intersecting mesh) is the solid. Distances are evaluated exactly (BVH
//! nearest triangle) only where a lower bound cannot decide: each point starts from its distance
//! to the mesh's box, and the 1-Lipschitz distance gives every neighbour of a point at distance
//! D the bound D − h, so exact queries happen only in a shell of width ≈ h around the offset
//! surface.
//!
//! The fill's sign is exact: a point is outside only if its distance is known to exceed the
//! offset. The field values (used to place the surface) are the sampled distances minus the
//! offset, kept at least [`MIN_FIELD`]·h away from 0.

use std::collections::VecDeque;

use glam::DVec3;

use super::bvh::{Aabb, TriangleBvh};

/// Smallest |field| in units of the spacing: keeps surface vertices away from grid points.
pub const MIN_FIELD: f64 = 0.02;

/// A regular grid of sample points with `dims` points per axis.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleGrid {
    /// Position of point (0, 0, 0).
    pub origin: DVec3,
    /// Distance h between neighbouring points.
    pub spacing: f64,
    /// Points per axis.
    pub dims: [usize; 3],
}

impl SampleGrid {
    /// The grid of spacing `spacing` around `bounds` padded by `padding` on every side.
    pub fn around(bounds: Aabb, spacing: f64, padding: f64) -> Self {
        let origin = bounds.min - DVec3::splat(padding);
        let extent = bounds.max + DVec3::splat(padding) - origin;
        let dims = (extent / spacing)
            .ceil()
            .as_uvec3()
            .to_array()
            .map(|n| n as usize + 1);
        Self {
            origin,
            spacing,
            dims,
        }
    }

    /// Number of grid points (product of `dims`).
    pub fn num_points(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Linear index of the point at integer coordinates `[x, y, z]` (x fastest).
    pub fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Integer coordinates `[x, y, z]` of the point of linear index `i`.
    pub fn coords(&self, i: usize) -> [usize; 3] {
        let x = i % self.dims[0];
        let y = (i / self.dims[0]) % self.dims[1];
        [x, y, i / (self.dims[0] * self.dims[1])]
    }

    /// Whether point `i` lies on the grid's boundary (a first or last index on some axis).
    pub fn on_boundary(&self, i: usize) -> bool {
        let [x, y, z] = self.coords(i);
        let [nx, ny, nz] = self.dims;
        x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz
    }

    /// The up to six points that share a face of the grid's cells with point `i`.
    pub fn face_neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let c = self.coords(i);
        let strides = [
            1isize,
            self.dims[0] as isize,
            (self.dims[0] * self.dims[1]) as isize,
        ];
        (0..3).flat_map(move |axis| {
            [-1isize, 1].into_iter().filter_map(move |dir| {
                let coord = c[axis] as isize + dir;
                (coord >= 0 && coord < self.dims[axis] as isize)
                    .then(|| (i as isize + dir * strides[axis]) as usize)
            })
        })
    }

    /// Position of the point at integer coordinates `[x, y, z]`.
    pub fn position(&self, [x, y, z]: [usize; 3]) -> DVec3 {
        self.origin + DVec3::new(x as f64, y as f64, z as f64) * self.spacing
    }
}

/// Signed field on a [`SampleGrid`]: > 0 outside (reached from the boundary, farther than the
/// offset from the mesh), < 0 in the solid.
#[derive(Debug, Clone, PartialEq)]
pub struct OutsideField {
    /// The sample grid.
    pub grid: SampleGrid,
    /// One value per grid point.
    pub values: Vec<f64>,
    /// Exact nearest-triangle queries made.
    pub exact_queries: usize,
}

/// Fills the grid from outside at distance `offset` from the mesh in `bvh` (see module docs).
/// The grid must have at least `offset + 2h` of padding around `mesh_bounds`.
pub fn fill_from_outside(
    grid: SampleGrid,
    bvh: &TriangleBvh,
    mesh_bounds: Aabb,
    offset: f64,
) -> OutsideField {
    const UNVISITED: u8 = 0;
    const OUTSIDE: u8 = 1;
    const SOLID: u8 = 2;
    let n = grid.num_points();
    let h = grid.spacing;
    let cap = offset + 3.0 * h;
    let mut state = vec![UNVISITED; n];
    // Distance value: a lower bound for outside points (exact where `exact`), exact (< cap) in
    // the solid's visited shell.
    let mut value = vec![0.0; n];
    let mut exact = vec![false; n];
    let mut queries = 0usize;
    let mut queue = VecDeque::new();
    let [nx, ny, nz] = grid.dims;
    for i in 0..n {
        let [x, y, z] = grid.coords(i);
        if x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz {
            let bound = mesh_bounds
                .distance_squared(grid.position([x, y, z]))
                .sqrt();
            if bound > offset {
                state[i] = OUTSIDE;
                value[i] = bound;
                queue.push_back(i);
            }
        }
    }
    while let Some(i) = queue.pop_front() {
        let c = grid.coords(i);
        for j in grid.face_neighbours(i) {
            if state[j] == SOLID && !exact[i] {
                // A crossing edge: make its outside end exact for a good surface position.
                value[i] = bvh.nearest_distance(grid.position(c), cap);
                exact[i] = true;
                queries += 1;
            }
            if state[j] != UNVISITED {
                continue;
            }
            let p = grid.position(grid.coords(j));
            let bound = (value[i] - h).max(mesh_bounds.distance_squared(p).sqrt());
            if bound > offset {
                state[j] = OUTSIDE;
                value[j] = bound;
                queue.push_back(j);
                continue;
            }
            let d = bvh.nearest_distance(p, cap);
            queries += 1;
            exact[j] = true;
            value[j] = d;
            if d > offset {
                state[j] = OUTSIDE;
                queue.push_back(j);
            } else {
                state[j] = SOLID;
            }
        }
    }
    let min_field = MIN_FIELD * h;
    let values = (0..n)
        .map(|i| match state[i] {
            OUTSIDE => (value[i] - offset).max(min_field),
            SOLID => (value[i] - offset).min(-min_field),
            _ => -h,
        })
        .collect();
    let _ = nz;
    OutsideField {
        grid,
        values,
        exact_queries: queries,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_like_point_fill_has_exact_sign() {
        // A single tiny triangle at the origin: the solid is (about) the ball of radius offset.
        let t = [DVec3::ZERO, DVec3::X * 1e-3, DVec3::Y * 1e-3];
        let bvh = TriangleBvh::new(vec![t]);
        let bounds = Aabb::of_triangle(&t);
        let (h, offset) = (0.1, 0.55);
        let grid = SampleGrid::around(bounds, h, offset + 2.0 * h);
        let field = fill_from_outside(grid.clone(), &bvh, bounds, offset);
        for i in 0..grid.num_points() {
            let p = grid.position(grid.coords(i));
            let d = bvh.nearest_distance(p, f64::INFINITY);
            assert_eq!(field.values[i] > 0.0, d > offset, "point {p}");
        }
        assert!(field.exact_queries < grid.num_points());
    }
}
