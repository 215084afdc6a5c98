//! Limbs kept apart (the skeleton layout of cage generation): the offset solid is cut where the
//! skins of two separate body parts come close, so that no cage webbing joins two legs, or an
//! arm and the torso (after the skeleton-driven cages of Casti et al., C&G 2019, and Le and
//! Deng, I3D 2017, whose parts follow the bones).
//!
//! **Body parts.** Every skin vertex belongs to its dominant joint (the heaviest skinning
//! weight, or the nearest bone when the rig has no weights yet), and every skin triangle to the
//! joints of its corners. Two joints a, b are *separable* when their skins may be cut apart:
//! they are neither the same joint nor parent and child, and when one is an ancestor of the
//! other, the path between them branches (the ancestor or a joint between them has several
//! children), so that the descendant lies on a side branch (a forearm off the chest, a shin off
//! the hips). Joints along one unbranched chain (spine segments, the phalanges of a finger) are
//! never separable; siblings and cousins (the two thighs, the fingers) always are.
//!
//! **The cut.** With d(p) the distance of a point p to the skin M and d_j(p) the distance to the
//! triangles of joint j, the solid {d ≤ offset} of [`super::distance_grid`] loses every point p
//! with
//!
//! ```text
//! min over separable (a, b) of max(d_a, d_b) − d  <  slab    and    d  >  keep,
//! ```
//!
//! that is the points about equally near two separable parts (within `slab` of their bisector
//! surface) and farther than `keep` from the skin. The field becomes
//! F = max(d − offset, min(slab − Δ, d − keep)) with Δ the first term; the cut is a sheet of
//! thickness about `slab` between two limbs, which marching tetrahedra resolve when `slab` is a
//! few grid spacings. Points within `keep` of the skin are never cut, so every skin vertex stays
//! inside and the margin is verified as for the uncut surface
//! ([`super::surface_clearance::check_start_surface`]); where two separable parts touch (legs
//! pressed together), the neighbourhood of the contact stays solid and the cut ends there.
//! Cut points that the outside cannot reach (pockets inside the solid) are filled again, so the
//! surface stays one closed piece.

use std::collections::VecDeque;

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::TriangleBvh;
use super::distance_grid::{MIN_FIELD, OutsideField};
use super::geometry::Triangle;
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;

/// The body parts of a skin: its triangles grouped by dominant joint, one BVH per joint, and
/// which joints may be cut apart (see the module docs).
#[derive(Debug, Clone)]
pub struct BodyParts {
    /// The joints that dominate at least one skin vertex (`#P`, ascending joint indices).
    pub joints: Vec<usize>,
    /// Triangles of each part (`#P`): a triangle belongs to the part of each of its corners.
    bvhs: Vec<TriangleBvh>,
    /// `#P × #P`, row-major: whether parts p and q are separable.
    separable: Vec<bool>,
}

/// Why body parts could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BodyPartsError {
    /// The dominant joints do not cover the skin's vertices.
    #[error("expected a dominant joint for each of the {expected} skin vertices, found {found}")]
    VertexCount {
        /// Skin vertices `#V`.
        expected: usize,
        /// Dominant joints given.
        found: usize,
    },
    /// A dominant joint is not a joint of the skeleton.
    #[error(
        "skin vertex {vertex} is dominated by joint {joint}, but the skeleton has {joints} joints"
    )]
    UnknownJoint {
        /// The skin vertex.
        vertex: usize,
        /// Its dominant joint.
        joint: usize,
        /// Joints of the skeleton.
        joints: usize,
    },
}

impl BodyParts {
    /// Groups `mesh`'s triangles by `dominant` (one joint of `skeleton` per mesh vertex, `#V`).
    pub fn new(
        mesh: &TriMesh,
        skeleton: &Skeleton,
        dominant: &[usize],
    ) -> Result<Self, BodyPartsError> {
        if dominant.len() != mesh.num_vertices() {
            return Err(BodyPartsError::VertexCount {
                expected: mesh.num_vertices(),
                found: dominant.len(),
            });
        }
        if let Some((vertex, &joint)) = dominant
            .iter()
            .enumerate()
            .find(|&(_, &j)| j >= skeleton.len())
        {
            return Err(BodyPartsError::UnknownJoint {
                vertex,
                joint,
                joints: skeleton.len(),
            });
        }
        let mut part_of_joint = vec![usize::MAX; skeleton.len()];
        let mut joints: Vec<usize> = dominant.to_vec();
        joints.sort_unstable();
        joints.dedup();
        for (p, &j) in joints.iter().enumerate() {
            part_of_joint[j] = p;
        }
        let mut triangles: Vec<Vec<Triangle>> = vec![Vec::new(); joints.len()];
        for t in 0..mesh.num_triangles() {
            let corners = mesh.corners(t);
            let mut parts = mesh.triangles[t].map(|v| part_of_joint[dominant[v as usize]]);
            parts.sort_unstable();
            for (i, &p) in parts.iter().enumerate() {
                if i == 0 || parts[i - 1] != p {
                    triangles[p].push(corners);
                }
            }
        }
        let bvhs = triangles.into_iter().map(TriangleBvh::new).collect();
        let joint_separable = separable_joints(skeleton);
        let n = joints.len();
        let separable = (0..n * n)
            .map(|i| joint_separable[joints[i / n] * skeleton.len() + joints[i % n]])
            .collect();
        Ok(Self {
            joints,
            bvhs,
            separable,
        })
    }

    /// Whether any two parts are separable (else the cut never removes anything).
    pub fn has_separable_parts(&self) -> bool {
        self.separable.iter().any(|&s| s)
    }

    /// How near `p` lies to the bisector of two separable parts: min over separable (a, b) of
    /// max(d_a, d_b), the parts' distances capped at `cap`; `cap` when no two separable parts
    /// lie nearer than `cap`.
    pub fn separable_pair_distance(&self, p: DVec3, cap: f64) -> f64 {
        let distances: Vec<f64> = self
            .bvhs
            .iter()
            .map(|bvh| bvh.nearest_distance(p, cap))
            .collect();
        let n = distances.len();
        let mut best = cap;
        for a in 0..n {
            if distances[a] >= best {
                continue;
            }
            for b in (a + 1)..n {
                if self.separable[a * n + b] {
                    best = best.min(distances[a].max(distances[b]));
                }
            }
        }
        best
    }
}

/// `#J × #J`, row-major: whether joints a and b are separable (see the module docs).
pub fn separable_joints(skeleton: &Skeleton) -> Vec<bool> {
    let n = skeleton.len();
    let mut children = vec![0usize; n];
    for j in 0..n {
        if let Some(p) = skeleton.parent(j) {
            children[p] += 1;
        }
    }
    // Ancestors of each joint, nearest first.
    let chains: Vec<Vec<usize>> = (0..n)
        .map(|j| {
            let mut chain = Vec::new();
            let mut at = skeleton.parent(j);
            while let Some(a) = at {
                chain.push(a);
                at = skeleton.parent(a);
            }
            chain
        })
        .collect();
    let mut separable = vec![false; n * n];
    for a in 0..n {
        for b in 0..n {
            if a == b || skeleton.parent(a) == Some(b) || skeleton.parent(b) == Some(a) {
                continue;
            }
            // When one is an ancestor of the other: does the path from it branch (the ancestor
            // or a joint between them has several children)?
            let branches_towards = |ancestor: usize, descendant: usize| {
                let chain = &chains[descendant];
                chain
                    .iter()
                    .position(|&j| j == ancestor)
                    .map(|depth| chain[..=depth].iter().any(|&j| children[j] >= 2))
            };
            separable[a * n + b] = branches_towards(a, b)
                .or_else(|| branches_towards(b, a))
                .unwrap_or(true);
        }
    }
    separable
}

/// The dominant joint of every vertex of `mesh` (`#V`) by its nearest bone, for a rig without
/// skinning weights: a bone is the segment from a joint to each of its children, and belongs to
/// the joint; a joint without children gets the continuation of its parent's bone, as long
/// (a point when it has no parent).
pub fn dominant_joints_by_bones(mesh: &TriMesh, skeleton: &Skeleton) -> Vec<usize> {
    let positions = skeleton.rest_positions();
    let mut bones: Vec<(usize, DVec3, DVec3)> = Vec::new();
    for j in 0..skeleton.len() {
        let mut has_child = false;
        for c in 0..skeleton.len() {
            if skeleton.parent(c) == Some(j) {
                bones.push((j, positions[j], positions[c]));
                has_child = true;
            }
        }
        if !has_child {
            let tip = skeleton
                .parent(j)
                .map_or(positions[j], |p| 2.0 * positions[j] - positions[p]);
            bones.push((j, positions[j], tip));
        }
    }
    mesh.positions
        .par_iter()
        .map(|&p| {
            bones
                .iter()
                .map(|&(j, a, b)| (point_segment_distance(p, a, b), j))
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .map_or(0, |(_, j)| j)
        })
        .collect()
}

fn point_segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Cuts the solid of `field` (filled at `offset` from the skin in `mesh`) between separable
/// body parts (see the module docs): a point of the solid farther than `keep` from the skin
/// and within `slab` of two separable parts' bisector turns outside, with field value
/// min(slab − Δ, d − keep); cut points the outside cannot reach are filled again. Returns the
/// number of grid points cut.
pub fn cut_between_parts(
    field: &mut OutsideField,
    mesh: &TriangleBvh,
    parts: &BodyParts,
    offset: f64,
    keep: f64,
    slab: f64,
) -> usize {
    if !parts.has_separable_parts() || keep >= offset {
        return 0;
    }
    let grid = field.grid.clone();
    let h = grid.spacing;
    let min_field = MIN_FIELD * h;
    let cap = offset + slab;
    // F = max(d − offset, min(slab − Δ, d − keep)) at every solid point near two separable
    // parts (elsewhere the second term is below the first), so that the surface lies where F
    // crosses 0 on both sides of the cut.
    let updates: Vec<(usize, f64)> = field
        .values
        .par_iter()
        .enumerate()
        .filter(|&(_, &v)| v < 0.0)
        .filter_map(|(i, _)| {
            let p = grid.position(grid.coords(i));
            let d = mesh.nearest_distance(p, cap);
            if d > offset {
                return None;
            }
            let delta = parts.separable_pair_distance(p, cap) - d;
            let value = (d - offset).max((slab - delta).min(d - keep));
            (value > d - offset).then_some((i, value))
        })
        .collect();
    let mut cuts = Vec::new();
    for &(i, value) in &updates {
        if value > 0.0 {
            field.values[i] = value.max(min_field);
            cuts.push(i);
        } else {
            field.values[i] = value.min(-min_field);
        }
    }
    // Fill again the cut points the outside does not reach.
    let mut reached = vec![false; grid.num_points()];
    let mut queue = VecDeque::new();
    for (i, &v) in field.values.iter().enumerate() {
        if v > 0.0 && grid.on_boundary(i) {
            reached[i] = true;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        for j in grid.face_neighbours(i) {
            if !reached[j] && field.values[j] > 0.0 {
                reached[j] = true;
                queue.push_back(j);
            }
        }
    }
    let mut kept = 0;
    for &i in &cuts {
        if reached[i] {
            kept += 1;
        } else {
            field.values[i] = -min_field;
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cage_gen::bvh::Aabb;
    use crate::cage_gen::distance_grid::{SampleGrid, fill_from_outside};
    use crate::cage_gen::marching_tets::extract_surface;
    use crate::cage_gen::validate::count_pieces;
    use crate::skeleton::Joint;

    /// hips → (spine → chest → (neck, arm → forearm → hand), thigh.L, thigh.R).
    fn body() -> Skeleton {
        Skeleton::new(vec![
            Joint::at("hips", None, DVec3::ZERO),
            Joint::at("spine", Some(0), DVec3::Y),
            Joint::at("chest", Some(1), DVec3::Y * 2.0),
            Joint::at("neck", Some(2), DVec3::Y * 3.0),
            Joint::at("arm", Some(2), DVec3::new(1.0, 2.0, 0.0)),
            Joint::at("forearm", Some(4), DVec3::new(1.0, 1.0, 0.0)),
            Joint::at("thigh.L", Some(0), DVec3::new(-0.3, -1.0, 0.0)),
            Joint::at("thigh.R", Some(0), DVec3::new(0.3, -1.0, 0.0)),
            Joint::at("hand", Some(5), DVec3::new(1.0, 0.5, 0.0)),
        ])
        .unwrap()
    }

    #[test]
    fn chains_stay_together_and_branches_separate() {
        let s = body();
        let sep = separable_joints(&s);
        let n = s.len();
        let is = |a: usize, b: usize| {
            assert_eq!(sep[a * n + b], sep[b * n + a], "symmetric ({a}, {b})");
            sep[a * n + b]
        };
        // Parent and child, and an unbranched chain: never.
        assert!(!is(0, 1) && !is(1, 2) && !is(4, 5) && !is(3, 3));
        assert!(!is(4, 8));
        // Paths that branch: hips (three children) → spine → chest; spine → chest (two
        // children) → arm → forearm.
        assert!(is(0, 2) && is(1, 4) && is(1, 5) && is(2, 5));
        // Siblings and cousins: the thighs, a thigh and the spine, the neck and the arm.
        assert!(is(6, 7) && is(6, 1) && is(3, 4) && is(5, 6));
    }

    #[test]
    fn nearest_bones_label_the_vertices() {
        let s = body();
        let mesh = TriMesh::new(
            vec![
                DVec3::new(-0.35, -1.5, 0.1),
                DVec3::new(0.35, -1.5, 0.1),
                DVec3::new(1.1, 1.4, 0.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_eq!(dominant_joints_by_bones(&mesh, &s), vec![6, 7, 4]);
    }

    /// Two parallel boxes (legs) `gap` apart along x, each of half-size (w, 2, w), as one mesh.
    fn two_legs(gap: f64, w: f64) -> (TriMesh, Vec<usize>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let mut dominant = Vec::new();
        for (leg, cx) in [(6usize, -(gap / 2.0 + w)), (7, gap / 2.0 + w)] {
            let base = positions.len() as u32;
            for i in 0..8 {
                let sx = if i & 1 == 0 { -w } else { w };
                let sy = if i & 2 == 0 { -2.0 } else { 2.0 };
                let sz = if i & 4 == 0 { -w } else { w };
                positions.push(DVec3::new(cx + sx, sy - 1.0, sz));
                dominant.push(leg);
            }
            for t in [
                [0, 2, 1],
                [1, 2, 3],
                [4, 5, 6],
                [5, 7, 6],
                [0, 1, 4],
                [1, 5, 4],
                [2, 6, 3],
                [3, 6, 7],
                [0, 4, 2],
                [2, 4, 6],
                [1, 3, 5],
                [3, 7, 5],
            ] {
                triangles.push(t.map(|v: u32| base + v));
            }
        }
        (TriMesh::new(positions, triangles).unwrap(), dominant)
    }

    #[test]
    fn the_cut_separates_two_legs_that_the_offset_merges() {
        let (mesh, dominant) = two_legs(0.3, 0.25);
        let parts = BodyParts::new(&mesh, &body(), &dominant).unwrap();
        assert_eq!(parts.joints, vec![6, 7]);
        let primitives = crate::cage_gen::validate::mesh_primitives(&mesh);
        let bvh = TriangleBvh::new(primitives);
        let (lo, hi) = mesh.bounding_box();
        let bounds = Aabb { min: lo, max: hi };
        let (h, offset) = (0.03, 0.2);
        let grid = SampleGrid::around(bounds, h, offset + 2.5 * h);
        let mut field = fill_from_outside(grid, &bvh, bounds, offset);
        // Uncut, the 0.3 gap is under 2 × 0.2: one solid; a point on the bisector is inside.
        let mid = field.grid.index([
            ((0.0 - field.grid.origin.x) / h).round() as usize,
            ((-1.0 - field.grid.origin.y) / h).round() as usize,
            ((0.0 - field.grid.origin.z) / h).round() as usize,
        ]);
        assert!(field.values[mid] < 0.0);
        let uncut = extract_surface(&field);
        assert_eq!(count_pieces(&uncut.triangles, uncut.positions.len()), 1);
        let cut = cut_between_parts(&mut field, &bvh, &parts, offset, 0.06, 2.0 * h);
        assert!(cut > 0);
        // Cut: the bisector point is outside, and the surface is two tubes (two pieces), each
        // farther than keep − h√3 from the mesh.
        assert!(field.values[mid] > 0.0);
        let surface = extract_surface(&field);
        assert_eq!(count_pieces(&surface.triangles, surface.positions.len()), 2);
        for &p in &surface.positions {
            assert!(bvh.nearest_distance(p, 1.0) > 0.06 - h * 3f64.sqrt());
        }
        // Nothing is cut between parts that are not separable (a parent and its child).
        let (mesh, mut dominant) = two_legs(0.3, 0.25);
        dominant[8..].fill(5);
        dominant[..8].fill(4);
        let parts = BodyParts::new(&mesh, &body(), &dominant).unwrap();
        let grid = SampleGrid::around(bounds, h, offset + 2.5 * h);
        let mut field = fill_from_outside(grid, &bvh, bounds, offset);
        assert_eq!(
            cut_between_parts(&mut field, &bvh, &parts, offset, 0.06, 2.0 * h),
            0
        );
    }

    #[test]
    fn bad_dominant_joints_are_named() {
        let (mesh, mut dominant) = two_legs(0.3, 0.25);
        let err = BodyParts::new(&mesh, &body(), &dominant[1..]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "expected a dominant joint for each of the 16 skin vertices, found 15"
        );
        dominant[3] = 99;
        let err = BodyParts::new(&mesh, &body(), &dominant).unwrap_err();
        assert_eq!(
            err.to_string(),
            "skin vertex 3 is dominated by joint 99, but the skeleton has 9 joints"
        );
    }
}
