//! The geometric checks of one edge collapse of [`super::simplify`], cheapest first: shape and
//! orientation of the new triangles, no mesh piece swept across, the margin to the mesh, no
//! self-intersection of the cage.
//!
//! Self-intersection is decided in two parts. Two triangles sharing a vertex v both lie in the
//! star of v; when that star (after the collapse) projects one-to-one onto the plane orthogonal
//! to its mean normal N — every triangle faces N (n·N ≥ [`FAN_MIN_COSINE`]·|n|) and the angles
//! at v sum to one turn, not two or more — its triangles meet only along their shared corners
//! and edges, so every pair sharing v is cleared at once ([`fan_embeds`]). A star that fails
//! (a sharp ridge, a fold) is checked pair by pair with [`cage_triangles_conflict`]. Every
//! vertex of a new triangle is the collapsed vertex or on the link of the edge, so checking
//! those stars covers all pairs with a new triangle that share a vertex; the pairs sharing none
//! come from the triangle hash and take the distance test.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

#[cfg(doc)]
use super::bvh::TriangleBvh;
use super::bvh::{Aabb, covering_radius};
use super::geometry::{area_normal, cage_triangles_conflict, solid_angle};
use super::simplify::{State, shape_quality};

/// Least cosine between a star's triangle normals and its mean normal for [`fan_embeds`]: keeps
/// neighbouring triangles of an accepted star well away from folding onto each other.
pub const FAN_MIN_COSINE: f64 = 0.01;
/// Least projected angle at the centre of a star accepted by [`fan_embeds`], radians.
pub const FAN_MIN_ANGLE: f64 = 1e-3;

/// Whether the star of a vertex at `centre`, given as its triangles' other corners `(next,
/// previous)` in their outward order, projects one-to-one along its mean normal (see module
/// docs). Sufficient for its triangles to meet only along shared corners and edges.
pub fn fan_embeds(centre: DVec3, fan: &[(DVec3, DVec3)]) -> bool {
    let normal: DVec3 = fan
        .iter()
        .map(|&(x, y)| (x - centre).cross(y - centre))
        .sum();
    let Some(n) = normal.try_normalize() else {
        return false;
    };
    let mut turn = 0.0;
    for &(x, y) in fan {
        let (u, v) = (x - centre, y - centre);
        let (area, dot) = (u.cross(v), u.dot(v) - u.dot(n) * v.dot(n));
        let sine = area.dot(n);
        if sine < FAN_MIN_COSINE * area.length() {
            return false;
        }
        let angle = sine.atan2(dot);
        if angle < FAN_MIN_ANGLE {
            return false;
        }
        turn += angle;
    }
    // Positively oriented triangles around a closed fan turn by a whole number of turns.
    turn < TAU + PI
}

impl State<'_> {
    /// Whether collapsing edge (a, b) to `p` keeps every constraint (the scratch holds the
    /// star and the new corners of this position).
    pub(super) fn acceptable(&mut self, a: u32, b: u32, p: DVec3) -> bool {
        self.shapes_acceptable()
            && self.no_piece_swept()
            && self.margin_kept(a, p)
            && self.no_self_intersection(a, b, p)
    }

    /// No flip, no degenerate triangle, no sliver worse than the star already had.
    fn shapes_acceptable(&self) -> bool {
        let s = &self.scratch;
        let worst_old = s
            .kept_old
            .iter()
            .map(|t| shape_quality(*t))
            .fold(1.0, f64::min);
        let min_quality = self.quality_floor.min(worst_old);
        if s.new_corners
            .iter()
            .any(|t| shape_quality(*t) < min_quality)
        {
            return false;
        }
        s.kept_old.iter().zip(&s.new_corners).all(|(old, new)| {
            let (n_old, n_new) = (area_normal(*old), area_normal(*new));
            let scale = (new[1] - new[0])
                .length_squared()
                .max((new[2] - new[0]).length_squared());
            n_new.length() > 1e-10 * scale && n_new.dot(n_old) > 0.0
        })
    }

    /// No mesh piece changed side: its representative point has winding number 0 about the
    /// closed surface of the old star and the reversed new star.
    fn no_piece_swept(&self) -> bool {
        let s = &self.scratch;
        let region = s
            .old_corners
            .iter()
            .chain(&s.new_corners)
            .fold(Aabb::EMPTY, |b, t| b.union(Aabb::of_triangle(t)));
        self.constraints.piece_points.iter().all(|&point| {
            if !region.contains(point) {
                return true;
            }
            let swept: f64 = s
                .old_corners
                .iter()
                .map(|t| solid_angle(point, *t))
                .sum::<f64>()
                - s.new_corners
                    .iter()
                    .map(|t| solid_angle(point, *t))
                    .sum::<f64>();
            swept.abs() <= TAU
        })
    }

    /// Every new triangle at least `margin` from the mesh ([`TriangleBvh::clear_of`] with the
    /// corners' cached distances; the new vertex's is queried up to the margin plus the largest
    /// covering radius of its triangles, beyond which a lower bound serves as well).
    fn margin_kept(&mut self, a: u32, p: DVec3) -> bool {
        let (s, c) = (&mut self.scratch, &self.constraints);
        if s.new_vertex_clearance.is_nan() {
            let reach = s
                .new_corners
                .iter()
                .map(|t| covering_radius(*t))
                .fold(0.0, f64::max);
            s.new_vertex_clearance = c.mesh.nearest_distance(p, c.margin + reach);
        }
        let clearance = &self.clearance;
        s.new_corners.iter().zip(&s.new_ids).all(|(t, ids)| {
            let d = ids.map(|v| {
                if v == a {
                    s.new_vertex_clearance
                } else {
                    clearance[v as usize]
                }
            });
            c.mesh.clear_of(*t, d, c.margin)
        })
    }

    /// No new triangle meets another cage triangle (see module docs).
    fn no_self_intersection(&mut self, a: u32, b: u32, p: DVec3) -> bool {
        let separation = self.constraints.separation;
        // Stars of the collapsed vertex and of the link vertices after the collapse.
        let mut s = std::mem::take(&mut self.scratch);
        s.embedded_stars.clear();
        let position = |v: u32| {
            if v == a || v == b {
                p
            } else {
                self.positions[v as usize]
            }
        };
        let mut fan = std::mem::take(&mut s.fan);
        for centre in std::iter::once(a).chain(s.link.iter().copied()) {
            fan.clear();
            let star: &[u32] = if centre == a {
                &s.kept
            } else {
                &self.vertex_faces[centre as usize]
            };
            for &f in star {
                if s.shared.contains(&f) {
                    continue;
                }
                let tri = self.faces[f as usize];
                let Some(k) = tri
                    .iter()
                    .position(|&v| v == centre || (centre == a && v == b))
                else {
                    continue;
                };
                fan.push((position(tri[(k + 1) % 3]), position(tri[(k + 2) % 3])));
            }
            if fan_embeds(position(centre), &fan) {
                s.embedded_stars.push(centre);
            }
        }
        s.fan = fan;
        let ok = self.no_conflict_with_others(&s, separation);
        self.scratch = s;
        ok
    }

    /// Pairs of a new triangle and another (new or kept) cage triangle: those sharing a vertex
    /// whose star embeds are cleared; the others take [`cage_triangles_conflict`].
    fn no_conflict_with_others(&mut self, s: &super::simplify::Scratch, separation: f64) -> bool {
        let embedded = |v: u32| s.embedded_stars.contains(&v);
        // New triangles among themselves: they all share the collapsed vertex.
        for i in 0..s.new_ids.len() {
            for j in i + 1..s.new_ids.len() {
                if !shares_embedded_vertex(s.new_ids[i], s.new_ids[j], embedded)
                    && cage_triangles_conflict(
                        s.new_corners[i],
                        s.new_ids[i],
                        s.new_corners[j],
                        s.new_ids[j],
                        separation,
                    )
                {
                    return false;
                }
            }
        }
        // One hash query for the whole new star, then each nearby triangle against each new one.
        let boxes = &mut self.scratch_boxes;
        boxes.clear();
        boxes.extend(
            s.new_corners
                .iter()
                .map(|t| Aabb::of_triangle(t).expanded(separation)),
        );
        let star_box = boxes.iter().fold(Aabb::EMPTY, |u, b| u.union(*b));
        let (faces, face_alive, positions) = (&self.faces, &self.face_alive, &self.positions);
        let mut conflict = false;
        self.hash.query(&star_box, |f| {
            if conflict || !face_alive[f as usize] || s.old_face_stamp[f as usize] == s.stamp {
                return;
            }
            let other = faces[f as usize];
            let other_corners = other.map(|v| positions[v as usize]);
            let other_box = Aabb::of_triangle(&other_corners);
            if !other_box.overlaps(&star_box) {
                return;
            }
            conflict = s.new_ids.iter().zip(&s.new_corners).zip(boxes.iter()).any(
                |((ids, corners), b)| {
                    b.overlaps(&other_box)
                        && !shares_embedded_vertex(*ids, other, embedded)
                        && cage_triangles_conflict(*corners, *ids, other_corners, other, separation)
                },
            );
        });
        !conflict
    }
}

/// Whether triangles `t1` and `t2` share a vertex for which `embedded` holds.
fn shares_embedded_vertex(t1: [u32; 3], t2: [u32; 3], embedded: impl Fn(u32) -> bool) -> bool {
    t1.iter().any(|&v| t2.contains(&v) && embedded(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn regular_fan(k: usize, lift: f64) -> Vec<(DVec3, DVec3)> {
        let ring: Vec<DVec3> = (0..k)
            .map(|i| {
                let t = TAU * i as f64 / k as f64;
                DVec3::new(t.cos(), t.sin(), lift * (3.0 * t).cos())
            })
            .collect();
        (0..k).map(|i| (ring[i], ring[(i + 1) % k])).collect()
    }

    #[test]
    fn flat_and_wavy_fans_embed() {
        assert!(fan_embeds(DVec3::ZERO, &regular_fan(6, 0.0)));
        assert!(fan_embeds(DVec3::new(0.0, 0.0, 0.3), &regular_fan(9, 0.4)));
    }

    #[test]
    fn fans_winding_twice_or_folded_do_not_embed() {
        // The link runs around the centre twice.
        let k = 10;
        let ring: Vec<DVec3> = (0..k)
            .map(|i| {
                let t = 2.0 * TAU * i as f64 / k as f64;
                DVec3::new(t.cos(), t.sin(), 0.1 * i as f64)
            })
            .collect();
        let twice: Vec<_> = (0..k).map(|i| (ring[i], ring[(i + 1) % k])).collect();
        assert!(!fan_embeds(DVec3::ZERO, &twice));
        // One triangle reversed (folded over its neighbours).
        let mut folded = regular_fan(6, 0.0);
        folded[2] = (folded[2].1, folded[2].0);
        assert!(!fan_embeds(DVec3::ZERO, &folded));
        // A sharp peak embeds; a centre outside its link's hull does not.
        let cone = [
            (DVec3::new(1.0, 0.0, -1.0), DVec3::new(0.0, 1.0, -1.0)),
            (DVec3::new(0.0, 1.0, -1.0), DVec3::new(-1.0, -1.0, -1.0)),
            (DVec3::new(-1.0, -1.0, -1.0), DVec3::new(1.0, 0.0, -1.0)),
        ];
        assert!(fan_embeds(DVec3::ZERO, &cone));
        let outside_hull = [
            (DVec3::new(1.0, 0.0, 0.0), DVec3::new(2.0, 1.0, 0.0)),
            (DVec3::new(2.0, 1.0, 0.0), DVec3::new(2.0, -1.0, 0.0)),
            (DVec3::new(2.0, -1.0, 0.0), DVec3::new(1.0, 0.0, 0.0)),
        ];
        assert!(!fan_embeds(DVec3::ZERO, &outside_hull));
    }

    /// Every pair of a fan accepted by `fan_embeds` passes the pairwise test.
    #[test]
    fn embedded_fans_have_no_pairwise_conflict() {
        for (k, lift, h) in [(5, 0.0, 0.0), (7, 0.3, 0.2), (12, 0.5, -0.4), (4, 0.1, 0.9)] {
            let fan = regular_fan(k, lift);
            let centre = DVec3::new(0.05, -0.02, h);
            assert!(fan_embeds(centre, &fan));
            let ids: Vec<[u32; 3]> = (0..k as u32)
                .map(|i| [0, 1 + i, 1 + (i + 1) % k as u32])
                .collect();
            for i in 0..k {
                for j in i + 1..k {
                    let (ti, tj) = ([centre, fan[i].0, fan[i].1], [centre, fan[j].0, fan[j].1]);
                    assert!(!cage_triangles_conflict(ti, ids[i], tj, ids[j], 1e-9));
                }
            }
        }
    }
}
