//! Geodesic distance through the solid voxels from a joint's bone segments (Dionne & de Lasa,
//! *Geodesic Voxel Binding for Production Character Meshes*, SCA 2013), sampled at the mesh
//! vertices.
//!
//! Dijkstra on the 26-connected solid voxels (edge lengths h, h√2, h√3), seeded at the solid
//! voxels a bone crosses with their distance to the bone. A bone that crosses no solid voxel
//! (a bone outside the body) is seeded at the solid voxels nearest to it, with their distance,
//! so that being outside costs what it measures. A vertex's distance is the least, over the
//! solid voxel centres c of the 2×2×2 block around it, of `D(c) + |v − c|`: continuous in v
//! and exact to within a voxel.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;

use super::bones::BoneSegment;
use super::voxel_grid::VoxelGrid;
use crate::cage_gen::geometry::closest_point_on_segment;

/// The solid voxels of a grid with a compact numbering (`#solid`).
#[derive(Debug, Clone)]
pub struct SolidVoxels {
    /// The grid.
    pub grid: VoxelGrid,
    /// Compact index of each voxel (`#voxels`), `u32::MAX` outside the solid.
    pub compact: Vec<u32>,
    /// Grid index of each solid voxel (`#solid`).
    pub voxels: Vec<u32>,
}

impl SolidVoxels {
    /// Numbers the `true` voxels of `solid` (`#voxels`).
    pub fn new(grid: VoxelGrid, solid: &[bool]) -> Self {
        let mut compact = vec![u32::MAX; solid.len()];
        let mut voxels = Vec::new();
        for (i, _) in solid.iter().enumerate().filter(|(_, s)| **s) {
            compact[i] = voxels.len() as u32;
            voxels.push(i as u32);
        }
        Self {
            grid,
            compact,
            voxels,
        }
    }

    /// Number of solid voxels.
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// True when no voxel is solid.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// Compact index of voxel `[x, y, z]` if it is solid.
    #[inline]
    fn solid_index(&self, c: [usize; 3]) -> Option<usize> {
        let k = self.compact[self.grid.index(c)];
        (k != u32::MAX).then_some(k as usize)
    }

    /// Points along each of `bones`, at most half a voxel apart (both ends included), with the
    /// bone they lie on.
    fn bone_samples<'a>(
        &self,
        bones: &'a [BoneSegment],
    ) -> impl Iterator<Item = (&'a BoneSegment, DVec3)> + 'a {
        let h = self.grid.spacing;
        bones.iter().flat_map(move |bone| {
            let steps = (2.0 * bone.start.distance(bone.end) / h).ceil() as usize;
            (0..=steps).map(move |s| {
                let t = if steps == 0 {
                    0.0
                } else {
                    s as f64 / steps as f64
                };
                (bone, bone.start.lerp(bone.end, t))
            })
        })
    }

    /// Each solid voxel's centre's least distance to `bones` (`#solid`).
    fn distances_to_bones<'a>(
        &'a self,
        bones: &'a [BoneSegment],
    ) -> impl Iterator<Item = f64> + 'a {
        self.voxels.iter().map(move |&i| {
            let centre = self.grid.centre(self.grid.coords(i as usize));
            bones
                .iter()
                .map(|b| centre.distance(closest_point_on_segment(centre, b.start, b.end)))
                .fold(f64::INFINITY, f64::min)
        })
    }

    /// How far a joint's bones stay outside the solid: 0 when a bone crosses a solid voxel,
    /// else the least distance from the bones to a solid voxel's centre (model units).
    pub fn distance_outside(&self, bones: &[BoneSegment]) -> f64 {
        let h = self.grid.spacing;
        let crosses = self.bone_samples(bones).any(|(_, p)| {
            let c = self.grid.voxel_of(p);
            let within = (p - self.grid.centre(c)).abs().max_element() <= 0.5 * h;
            within && self.solid_index(c).is_some()
        });
        if crosses {
            return 0.0;
        }
        self.distances_to_bones(bones).fold(f64::INFINITY, f64::min)
    }

    /// `(compact index, initial distance)` of the seeds of a joint's bones.
    pub fn seeds(&self, bones: &[BoneSegment]) -> Vec<(usize, f64)> {
        let h = self.grid.spacing;
        let mut seeds: Vec<(usize, f64)> = Vec::new();
        for (bone, p) in self.bone_samples(bones) {
            let c = self.grid.voxel_of(p);
            if let Some(k) = self.solid_index(c) {
                let centre = self.grid.centre(c);
                let d = centre.distance(closest_point_on_segment(centre, bone.start, bone.end));
                seeds.push((k, d));
            }
        }
        if seeds.is_empty() {
            // Outside the body: seed at the solid voxels within a voxel of the nearest ones.
            let distances: Vec<f64> = self.distances_to_bones(bones).collect();
            let nearest = distances.iter().copied().fold(f64::INFINITY, f64::min);
            seeds.extend(
                distances
                    .iter()
                    .enumerate()
                    .filter(|(_, d)| **d <= nearest + h)
                    .map(|(k, d)| (k, *d)),
            );
        }
        seeds
    }

    /// Geodesic distance (world units) from the seeds to every solid voxel (`#solid`;
    /// `f32::INFINITY` where unreachable).
    pub fn distances(&self, seeds: &[(usize, f64)]) -> Vec<f32> {
        let h = self.grid.spacing as f32;
        let steps = neighbour_steps(h);
        let mut dist = vec![f32::INFINITY; self.len()];
        // f32 distances are non-negative, so their bit patterns order like the values.
        let mut heap: BinaryHeap<Reverse<(u32, u32)>> = BinaryHeap::new();
        for &(k, d) in seeds {
            let d = d as f32;
            if d < dist[k] {
                dist[k] = d;
                heap.push(Reverse((d.to_bits(), k as u32)));
            }
        }
        let [nx, ny, nz] = self.grid.dims.map(|d| d as isize);
        while let Some(Reverse((bits, k))) = heap.pop() {
            let d = f32::from_bits(bits);
            let k = k as usize;
            if d > dist[k] {
                continue;
            }
            let [x, y, z] = self
                .grid
                .coords(self.voxels[k] as usize)
                .map(|c| c as isize);
            for &([dx, dy, dz], step) in &steps {
                let (qx, qy, qz) = (x + dx, y + dy, z + dz);
                if qx < 0 || qy < 0 || qz < 0 || qx >= nx || qy >= ny || qz >= nz {
                    continue;
                }
                let Some(n) = self.solid_index([qx as usize, qy as usize, qz as usize]) else {
                    continue;
                };
                let candidate = d + step;
                if candidate < dist[n] {
                    dist[n] = candidate;
                    heap.push(Reverse((candidate.to_bits(), n as u32)));
                }
            }
        }
        dist
    }

    /// The distance field `dist` (`#solid`) sampled at `points` (`#points`): the least
    /// `D(c) + |p − c|` over the solid voxel centres of the 2×2×2 block around each point,
    /// widened to a 4×4×4 block when none of those is solid or reached; infinite when none is.
    pub fn sample(&self, dist: &[f32], points: &[DVec3]) -> Vec<f64> {
        points
            .iter()
            .map(|&p| {
                let near = self.sample_block(dist, p, 1);
                if near.is_finite() {
                    near
                } else {
                    self.sample_block(dist, p, 2)
                }
            })
            .collect()
    }

    fn sample_block(&self, dist: &[f32], p: DVec3, half: isize) -> f64 {
        let q = ((p - self.grid.origin) / self.grid.spacing - 0.5).to_array();
        let base = q.map(|c| c.floor() as isize);
        let mut best = f64::INFINITY;
        for dz in 1 - half..=half {
            for dy in 1 - half..=half {
                for dx in 1 - half..=half {
                    let c = [base[0] + dx, base[1] + dy, base[2] + dz];
                    if c.iter()
                        .zip(self.grid.dims)
                        .any(|(&v, d)| v < 0 || v >= d as isize)
                    {
                        continue;
                    }
                    let c = c.map(|v| v as usize);
                    if let Some(k) = self.solid_index(c)
                        && dist[k].is_finite()
                    {
                        best = best.min(dist[k] as f64 + p.distance(self.grid.centre(c)));
                    }
                }
            }
        }
        best
    }
}

/// The 26 neighbour offsets and their lengths for voxel size `h`.
fn neighbour_steps(h: f32) -> Vec<([isize; 3], f32)> {
    let mut steps = Vec::with_capacity(26);
    for dz in -1isize..=1 {
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                let k = dx.abs() + dy.abs() + dz.abs();
                if k > 0 {
                    steps.push(([dx, dy, dz], h * (k as f32).sqrt()));
                }
            }
        }
    }
    steps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A U-shaped solid: two columns joined at the bottom, in a grid of 1-unit voxels.
    fn u_shape() -> SolidVoxels {
        let grid = VoxelGrid {
            origin: DVec3::ZERO,
            spacing: 1.0,
            dims: [7, 12, 1],
        };
        let mut solid = vec![false; grid.len()];
        for y in 0..12 {
            for x in 0..7 {
                let column = x == 0 || x == 6;
                if column || y == 0 {
                    solid[grid.index([x, y, 0])] = true;
                }
            }
        }
        SolidVoxels::new(grid, &solid)
    }

    #[test]
    fn distance_goes_around_the_gap_not_across_it() {
        let solid = u_shape();
        let bone = BoneSegment {
            joint: 0,
            start: DVec3::new(0.5, 11.5, 0.5),
            end: DVec3::new(0.5, 10.5, 0.5),
        };
        let seeds = solid.seeds(&[bone]);
        assert!(!seeds.is_empty());
        let dist = solid.distances(&seeds);
        // The voxel across the 5-voxel gap at the same height: down 10, across 6, up 10 (with
        // diagonal steps at the corners), never the straight 6.
        let across = dist[solid.solid_index([6, 11, 0]).unwrap()];
        assert!(across > 20.0 && across < 27.0, "{across}");
        let below = dist[solid.solid_index([0, 5, 0]).unwrap()];
        assert!((below - 5.0).abs() < 1e-5, "{below}");
        // Sampled at a point on the far column: finite and about the voxel's distance.
        let s = solid.sample(&dist, &[DVec3::new(6.5, 11.5, 0.5)]);
        assert!((s[0] - across as f64).abs() <= 1.0, "{s:?}");
    }

    #[test]
    fn a_bone_outside_the_solid_is_seeded_at_the_nearest_voxels() {
        let solid = u_shape();
        let bone = BoneSegment {
            joint: 0,
            start: DVec3::new(3.5, 8.5, 0.5),
            end: DVec3::new(3.5, 9.5, 0.5),
        };
        let seeds = solid.seeds(&[bone]);
        // Nearest solid centres are 3 away, at both columns.
        assert!(seeds.iter().all(|&(_, d)| (3.0..=4.0 + 1e-9).contains(&d)));
        assert!(seeds.len() >= 4);
    }
}
