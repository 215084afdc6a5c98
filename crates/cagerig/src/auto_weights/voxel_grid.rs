//! The solid voxelisation of a mesh: a regular grid of cubic voxels, the voxels the surface
//! touches, and everything they enclose.
//!
//! Robust to triangle soups, several pieces, non-manifold edges and self-intersections: the
//! surface voxels are found triangle by triangle (positions only, no connectivity), and the
//! solid is everything a flood fill from the grid's border cannot reach. Holes narrower than
//! about `2·closing + 1` voxels are closed: the fill's barrier is the surface dilated by
//! `closing` voxels, and the outside then grows back by `closing` voxels through non-surface
//! voxels. When a cage is given, its (closed) interior is added to the barrier, so a hole in
//! the mesh cannot let the fill inside the character.

use std::collections::VecDeque;

use glam::DVec3;
use rayon::prelude::*;

use crate::cage_gen::geometry::point_triangle_distance;

/// Voxels left empty around the mesh's box on every side (the fill starts there).
const PADDING: usize = 2;

/// A regular grid of cubic voxels; voxel `[x, y, z]` spans `origin + h·[x, y, z]` to
/// `origin + h·[x+1, y+1, z+1]` (h = `spacing`).
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelGrid {
    /// Lower corner of voxel (0, 0, 0), world space.
    pub origin: DVec3,
    /// Edge length h of a voxel, world units.
    pub spacing: f64,
    /// Voxels per axis.
    pub dims: [usize; 3],
}

impl VoxelGrid {
    /// The grid around the box `[lo, hi]` whose longest side spans `resolution` voxels, with
    /// [`PADDING`] empty voxels on every side. `hi − lo` must have a positive longest side.
    pub fn around(lo: DVec3, hi: DVec3, resolution: usize) -> Self {
        let extent = hi - lo;
        let spacing = extent.max_element() / resolution.max(1) as f64;
        let origin = lo - DVec3::splat(spacing * PADDING as f64);
        let dims = extent.to_array().map(|e| {
            // Voxels covering [lo, hi] on this axis, then the padding on both sides.
            let inside = ((e / spacing).ceil() as usize).max(1);
            inside + 2 * PADDING
        });
        Self {
            origin,
            spacing,
            dims,
        }
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// True when the grid has no voxel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Linear index of voxel `[x, y, z]` (x fastest).
    #[inline]
    pub fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Integer coordinates of the voxel with linear index `i`.
    #[inline]
    pub fn coords(&self, i: usize) -> [usize; 3] {
        let x = i % self.dims[0];
        let yz = i / self.dims[0];
        [x, yz % self.dims[1], yz / self.dims[1]]
    }

    /// Centre of voxel `[x, y, z]`.
    #[inline]
    pub fn centre(&self, [x, y, z]: [usize; 3]) -> DVec3 {
        self.origin + self.spacing * (DVec3::new(x as f64, y as f64, z as f64) + 0.5)
    }

    /// The voxel containing `p`, clamped to the grid.
    #[inline]
    pub fn voxel_of(&self, p: DVec3) -> [usize; 3] {
        let q = ((p - self.origin) / self.spacing).to_array();
        std::array::from_fn(|a| (q[a].floor().max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// Voxel coordinates of the box `[lo, hi]`, clamped to the grid (inclusive ranges).
    fn voxel_range(&self, lo: DVec3, hi: DVec3) -> ([usize; 3], [usize; 3]) {
        (self.voxel_of(lo), self.voxel_of(hi))
    }

    /// The 6-neighbours of voxel `[x, y, z]` inside the grid.
    fn face_neighbours(&self, [x, y, z]: [usize; 3]) -> impl Iterator<Item = [usize; 3]> + '_ {
        let candidates = [
            (x > 0).then(|| [x.wrapping_sub(1), y, z]),
            (x + 1 < self.dims[0]).then_some([x + 1, y, z]),
            (y > 0).then(|| [x, y.wrapping_sub(1), z]),
            (y + 1 < self.dims[1]).then_some([x, y + 1, z]),
            (z > 0).then(|| [x, y, z.wrapping_sub(1)]),
            (z + 1 < self.dims[2]).then_some([x, y, z + 1]),
        ];
        candidates.into_iter().flatten()
    }
}

/// Marks (`true`) every voxel within half a voxel diagonal of a triangle (`#voxels`).
///
/// Conservative: every voxel the surface crosses is marked, and a few that it passes within
/// h·√3/2 of. Triangles are independent (a soup is fine).
pub fn surface_voxels(grid: &VoxelGrid, positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<bool> {
    let reach = grid.spacing * 3f64.sqrt() * 0.5;
    let touched: Vec<Vec<u32>> = triangles
        .par_chunks(1024)
        .map(|chunk| {
            let mut out = Vec::new();
            for tri in chunk {
                let t = tri.map(|i| positions[i as usize]);
                let lo = t[0].min(t[1]).min(t[2]) - DVec3::splat(reach);
                let hi = t[0].max(t[1]).max(t[2]) + DVec3::splat(reach);
                let (a, b) = grid.voxel_range(lo, hi);
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            let c = [x, y, z];
                            if point_triangle_distance(grid.centre(c), t) <= reach {
                                out.push(grid.index(c) as u32);
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    let mut marked = vec![false; grid.len()];
    for i in touched.into_iter().flatten() {
        marked[i as usize] = true;
    }
    marked
}

/// `marked` grown by `radius` voxels (6-connected steps).
fn dilate(grid: &VoxelGrid, marked: &[bool], radius: usize) -> Vec<bool> {
    let mut out = marked.to_vec();
    let mut frontier: Vec<usize> = (0..marked.len()).filter(|&i| marked[i]).collect();
    for _ in 0..radius {
        let mut next = Vec::new();
        for &i in &frontier {
            for n in grid.face_neighbours(grid.coords(i)) {
                let k = grid.index(n);
                if !out[k] {
                    out[k] = true;
                    next.push(k);
                }
            }
        }
        frontier = next;
    }
    out
}

/// Every voxel a 6-connected fill from the grid's border reaches without entering `barrier`.
fn fill_from_border(grid: &VoxelGrid, barrier: &[bool]) -> Vec<bool> {
    let mut reached = vec![false; grid.len()];
    let mut queue = VecDeque::new();
    let [nx, ny, nz] = grid.dims;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let on_border =
                    x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz;
                let i = grid.index([x, y, z]);
                if on_border && !barrier[i] {
                    reached[i] = true;
                    queue.push_back(i);
                }
            }
        }
    }
    while let Some(i) = queue.pop_front() {
        for n in grid.face_neighbours(grid.coords(i)) {
            let k = grid.index(n);
            if !reached[k] && !barrier[k] {
                reached[k] = true;
                queue.push_back(k);
            }
        }
    }
    reached
}

/// The solid (`#voxels`, `true` inside): the surface voxels and everything they enclose.
///
/// `surface` from [`surface_voxels`]; `closing` closes holes of about `2·closing + 1` voxels;
/// `cage_solid`, when given, is a solid (this function applied to a closed cage) that the fill
/// may not enter either.
pub fn solid_voxels(
    grid: &VoxelGrid,
    surface: &[bool],
    closing: usize,
    cage_solid: Option<&[bool]>,
) -> Vec<bool> {
    let mut barrier = dilate(grid, surface, closing);
    if let Some(cage) = cage_solid {
        barrier.iter_mut().zip(cage).for_each(|(b, c)| *b |= *c);
    }
    let outside = fill_from_border(grid, &barrier);
    // Grow the outside back by `closing` voxels, never into the surface itself.
    let mut outside_grown = outside.clone();
    let mut frontier: Vec<usize> = (0..outside.len()).filter(|&i| outside[i]).collect();
    for _ in 0..closing {
        let mut next = Vec::new();
        for &i in &frontier {
            for n in grid.face_neighbours(grid.coords(i)) {
                let k = grid.index(n);
                let in_cage = cage_solid.is_some_and(|c| c[k]);
                if !outside_grown[k] && !surface[k] && !in_cage {
                    outside_grown[k] = true;
                    next.push(k);
                }
            }
        }
        frontier = next;
    }
    outside_grown.iter().map(|&o| !o).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TriMesh;

    /// A unit cube whose faces are `n × n` quads, with the quads listed in `holes` (face 0)
    /// left out.
    fn subdivided_cube(n: usize, holes: &[usize]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        // Each face: an origin corner and two edge directions (a soup: no shared vertices).
        let faces = [
            (DVec3::ZERO, DVec3::Y, DVec3::X),
            (DVec3::Z, DVec3::X, DVec3::Y),
            (DVec3::ZERO, DVec3::X, DVec3::Z),
            (DVec3::Y, DVec3::Z, DVec3::X),
            (DVec3::ZERO, DVec3::Z, DVec3::Y),
            (DVec3::X, DVec3::Y, DVec3::Z),
        ];
        for (f, (o, u, v)) in faces.into_iter().enumerate() {
            for q in 0..n * n {
                if f == 0 && holes.contains(&q) {
                    continue;
                }
                let (i, j) = ((q % n) as f64, (q / n) as f64);
                let s = 1.0 / n as f64;
                let base = positions.len() as u32;
                for (di, dj) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                    positions.push(o + u * s * (i + di) + v * s * (j + dj));
                }
                triangles.push([base, base + 1, base + 2]);
                triangles.push([base, base + 2, base + 3]);
            }
        }
        (positions, triangles)
    }

    fn centre_is_solid(n: usize, holes: &[usize], closing: usize) -> bool {
        let (positions, triangles) = subdivided_cube(n, holes);
        let grid = VoxelGrid::around(DVec3::ZERO, DVec3::ONE, 20);
        let surface = surface_voxels(&grid, &positions, &triangles);
        let solid = solid_voxels(&grid, &surface, closing, None);
        let count = solid.iter().filter(|&&s| s).count();
        assert!(count <= 24 * 24 * 24, "{count}");
        solid[grid.index(grid.voxel_of(DVec3::splat(0.5)))]
    }

    #[test]
    fn grid_maps_points_and_indices_consistently() {
        let grid = VoxelGrid::around(DVec3::ZERO, DVec3::new(2.0, 1.0, 0.5), 8);
        assert_eq!(grid.spacing, 0.25);
        assert_eq!(grid.dims, [8 + 4, 4 + 4, 2 + 4]);
        for i in [0, 17, grid.len() - 1] {
            let c = grid.coords(i);
            assert_eq!(grid.index(c), i);
            assert_eq!(grid.voxel_of(grid.centre(c)), c);
        }
        assert_eq!(grid.voxel_of(DVec3::splat(-100.0)), [0, 0, 0]);
    }

    #[test]
    fn a_closed_soup_is_filled_and_its_outside_is_not() {
        assert!(centre_is_solid(4, &[], 0));
        let (positions, triangles) = subdivided_cube(4, &[]);
        let grid = VoxelGrid::around(DVec3::ZERO, DVec3::ONE, 20);
        let solid = solid_voxels(
            &grid,
            &surface_voxels(&grid, &positions, &triangles),
            0,
            None,
        );
        assert!(!solid[grid.index([0, 0, 0])]);
        let count = solid.iter().filter(|&&s| s).count();
        // 20³ voxels inside plus at most a two-voxel shell on each side.
        assert!((8000..=24 * 24 * 24).contains(&count), "{count}");
    }

    #[test]
    fn small_holes_are_closed_and_wide_ones_are_not() {
        // 2 × 2 quads of 1/10 (a square hole four voxels wide) missing: the fill leaks in
        // without closing, not with it.
        assert!(!centre_is_solid(10, &[44, 45, 54, 55], 0));
        assert!(centre_is_solid(10, &[44, 45, 54, 55], 1));
        // A whole face missing cannot be closed.
        let all: Vec<usize> = (0..100).collect();
        assert!(!centre_is_solid(10, &all, 1));
    }

    #[test]
    fn a_cage_bounds_the_volume_of_an_open_mesh() {
        let all: Vec<usize> = (0..16).collect();
        let (positions, triangles) = subdivided_cube(4, &all);
        let grid = VoxelGrid::around(DVec3::splat(-0.2), DVec3::splat(1.2), 28);
        let surface = surface_voxels(&grid, &positions, &triangles);
        let cage = TriMesh::cuboid(DVec3::splat(-0.1), DVec3::splat(1.1)).unwrap();
        let cage_surface = surface_voxels(&grid, &cage.positions, &cage.triangles);
        let cage_solid = solid_voxels(&grid, &cage_surface, 0, None);
        let centre = grid.index(grid.voxel_of(DVec3::splat(0.5)));
        assert!(!solid_voxels(&grid, &surface, 1, None)[centre]);
        assert!(solid_voxels(&grid, &surface, 1, Some(&cage_solid))[centre]);
    }
}
