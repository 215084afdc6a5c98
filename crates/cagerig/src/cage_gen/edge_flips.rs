//! Edge flips after the collapses: replace the shared edge of two nearly coplanar cage
//! triangles by the other diagonal when that raises the worse triangle's shape quality, keeping
//! every constraint of the collapses (margin to the mesh, no self-intersection, no mesh piece
//! swept across).
//!
//! The collapses order edges by quadric error, which is zero along flat directions: on a flat
//! or cylindrical part they can leave needles (angles of 0.02°, measured on an FBX character)
//! that no later collapse removes. A flip keeps every vertex where it is and changes the
//! surface only inside the tetrahedron of the two triangles, which is thin when they are
//! nearly coplanar ([`FLIP_MAX_DIHEDRAL`]).

use std::f64::consts::TAU;

use super::bvh::Aabb;
use super::geometry::{Triangle, area_normal, cage_triangles_conflict, solid_angle};
use super::simplify::{State, shape_quality};

/// Pairs whose worse triangle has at least this shape quality are left as they are.
pub const FLIP_BELOW_QUALITY: f64 = 0.25;
/// A flip must raise the worse triangle's quality by at least this factor.
pub const FLIP_GAIN: f64 = 1.25;
/// Largest angle between the two triangles' normals for a flip, radians (20°).
pub const FLIP_MAX_DIHEDRAL: f64 = 20.0 * std::f64::consts::PI / 180.0;
/// Passes over all edges at most.
const MAX_PASSES: usize = 8;

impl State<'_> {
    /// Flips edges while some flip improves a poor pair (see the module docs); returns the
    /// number of flips.
    pub(super) fn improve_by_flips(&mut self) -> usize {
        let mut flips = 0;
        for _ in 0..MAX_PASSES {
            let before = flips;
            for f in 0..self.faces.len() {
                for k in 0..3 {
                    if !self.face_alive[f] {
                        break;
                    }
                    let tri = self.faces[f];
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    if self.try_flip(f as u32, a, b) {
                        flips += 1;
                    }
                }
            }
            if flips == before {
                break;
            }
        }
        flips
    }

    /// Flips edge a→b of face `f1` = (a, b, c) with its neighbour (b, a, d) into (c, a, d) and
    /// (c, d, b) when that is an improvement and keeps every constraint.
    fn try_flip(&mut self, f1: u32, a: u32, b: u32) -> bool {
        let Some(f2) = self.vertex_faces[a as usize]
            .iter()
            .copied()
            .find(|&g| g != f1 && self.faces[g as usize].contains(&b))
        else {
            return false;
        };
        let third = |tri: [u32; 3]| tri.into_iter().find(|&v| v != a && v != b);
        let (Some(c), Some(d)) = (
            third(self.faces[f1 as usize]),
            third(self.faces[f2 as usize]),
        ) else {
            return false;
        };
        // A vertex of valence 3 would be left with two triangles; an existing edge c–d would
        // be doubled.
        if c == d
            || self.vertex_faces[a as usize].len() <= 3
            || self.vertex_faces[b as usize].len() <= 3
            || self.vertex_faces[c as usize]
                .iter()
                .any(|&g| self.faces[g as usize].contains(&d))
        {
            return false;
        }
        let p = |v: u32| self.positions[v as usize];
        let old: [Triangle; 2] = [[p(a), p(b), p(c)], [p(b), p(a), p(d)]];
        let new: [Triangle; 2] = [[p(c), p(a), p(d)], [p(c), p(d), p(b)]];
        let worst_old = shape_quality(old[0]).min(shape_quality(old[1]));
        let worst_new = shape_quality(new[0]).min(shape_quality(new[1]));
        if worst_old >= FLIP_BELOW_QUALITY || worst_new < FLIP_GAIN * worst_old {
            return false;
        }
        let old_normals = old.map(|t| area_normal(t).normalize_or_zero());
        let new_normals = new.map(|t| area_normal(t).normalize_or_zero());
        let cos_max = FLIP_MAX_DIHEDRAL.cos();
        if old_normals[0].dot(old_normals[1]) < cos_max
            || new_normals
                .iter()
                .any(|n| n.dot(old_normals[0]) < cos_max || n.dot(old_normals[1]) < cos_max)
        {
            return false;
        }
        let new_ids = [[c, a, d], [c, d, b]];
        if !self.flip_keeps_margin(&new, &new_ids)
            || !self.flip_sweeps_no_piece(&old, &new)
            || self.flip_conflicts(&new, &new_ids, [f1, f2])
        {
            return false;
        }
        // Apply: a loses f2, b loses f1, c gains f2, d gains f1.
        self.faces[f1 as usize] = new_ids[0];
        self.faces[f2 as usize] = new_ids[1];
        self.vertex_faces[a as usize].retain(|&g| g != f2);
        self.vertex_faces[b as usize].retain(|&g| g != f1);
        self.vertex_faces[c as usize].push(f2);
        self.vertex_faces[d as usize].push(f1);
        for (f, t) in [f1, f2].into_iter().zip(&new) {
            self.hash.remove(f);
            self.hash.insert(f, &Aabb::of_triangle(t));
        }
        true
    }

    /// Both new triangles at least the margin from the mesh.
    fn flip_keeps_margin(&mut self, new: &[Triangle; 2], ids: &[[u32; 3]; 2]) -> bool {
        for (t, tri) in new.iter().zip(ids) {
            let distances = tri.map(|v| self.clearance(v));
            let margin = self.constraints.margin;
            if !self.constraints.mesh.clear_of(*t, distances, margin) {
                return false;
            }
        }
        true
    }

    /// No mesh piece inside the tetrahedron between the old and the new pair.
    fn flip_sweeps_no_piece(&self, old: &[Triangle; 2], new: &[Triangle; 2]) -> bool {
        let region = old
            .iter()
            .fold(Aabb::EMPTY, |r, t| r.union(Aabb::of_triangle(t)));
        self.constraints.piece_points.iter().all(|&point| {
            if !region.contains(point) {
                return true;
            }
            let swept: f64 = old.iter().map(|t| solid_angle(point, *t)).sum::<f64>()
                - new.iter().map(|t| solid_angle(point, *t)).sum::<f64>();
            swept.abs() <= TAU
        })
    }

    /// Whether a new triangle meets another cage triangle (or the other new one) closer than
    /// the separation, except along what they share.
    fn flip_conflicts(&mut self, new: &[Triangle; 2], ids: &[[u32; 3]; 2], old: [u32; 2]) -> bool {
        let separation = self.constraints.separation;
        if cage_triangles_conflict(new[0], ids[0], new[1], ids[1], separation) {
            return true;
        }
        let boxes = new.map(|t| Aabb::of_triangle(&t).expanded(separation));
        let region = boxes[0].union(boxes[1]);
        let (faces, face_alive, positions) = (&self.faces, &self.face_alive, &self.positions);
        let mut conflict = false;
        self.hash.query(&region, |g| {
            if conflict || !face_alive[g as usize] || old.contains(&g) {
                return;
            }
            let other = faces[g as usize];
            let corners = other.map(|v| positions[v as usize]);
            let other_box = Aabb::of_triangle(&corners);
            conflict = (0..2).any(|i| {
                boxes[i].overlaps(&other_box)
                    && cage_triangles_conflict(new[i], ids[i], corners, other, separation)
            });
        });
        conflict
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    /// The quality gain a flip is asked for: a needle pair in a plane becomes two fair triangles.
    #[test]
    fn flipping_the_long_diagonal_of_a_flat_needle_pair_improves_both() {
        // Quad a, c, b, d in the plane z = 0 with the long diagonal a–b.
        let (a, b) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(10.0, 0.0, 0.0));
        let (c, d) = (DVec3::new(5.0, 0.3, 0.0), DVec3::new(5.0, -0.3, 0.0));
        let old = [[a, b, c], [b, a, d]];
        let new = [[c, a, d], [c, d, b]];
        let worst = |p: [Triangle; 2]| shape_quality(p[0]).min(shape_quality(p[1]));
        assert!(worst(old) < FLIP_BELOW_QUALITY);
        assert!(worst(new) > FLIP_GAIN * worst(old));
        // Same orientation before and after.
        for t in new {
            assert!(area_normal(t).dot(area_normal(old[0])) > 0.0);
        }
    }
}
