//! Constrained simplification by edge collapses (Garland & Heckbert's QEM order, the
//! constraints of progressive hulls / nested cages: Sander et al. 2000, Sacht et al. 2015).
//!
//! Edges are collapsed cheapest quadric error first; each collapse tries the quadric minimiser,
//! the midpoint and both end points, and is accepted only if afterwards
//! 1. the surface is still a closed 2-manifold (link condition, more than four vertices);
//! 2. no surviving triangle flips or degenerates (normal turns by less than 90°);
//! 3. every new triangle stays at least `margin` from every mesh triangle (mesh BVH);
//! 4. no new triangle intersects or comes within `separation` of another cage triangle
//!    (dynamic triangle hash, adjacency-aware test of [`cage_triangles_conflict`]);
//! 5. no piece of the mesh changed side: the old and new triangles around the edge form a closed
//!    surface, and the winding number of each mesh piece's representative point about it is 0.
//!    A mesh piece never touches the cage (3.), so one point decides for the whole piece.
//!
//! Given a starting surface that is embedded, encloses the mesh and keeps the margin, every
//! intermediate surface does too. Edges rejected for every candidate are retried after their
//! neighbourhood changes, and once more in a final sweep.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;

use super::bvh::{Aabb, TriangleBvh};
use super::geometry::{Triangle, area_normal, cage_triangles_conflict, solid_angle};
use super::marching_tets::Surface;
use super::quadric::Quadric;
use super::triangle_hash::TriangleHash;

/// Passes over all edges (the first, then retries of edges rejected before their
/// neighbourhood changed).
const MAX_SWEEPS: usize = 3;

/// Least shape quality ([`shape_quality`]) a collapse may create, unless the star was already
/// worse, while more than [`QUALITY_PHASE`] × the target count remain. Quadric error alone is
/// zero along flat and cylindrical directions, where it grows slivers across the whole part:
/// they slow every intersection query. Near the target the floor is dropped, so that it never
/// keeps a cage from reaching its size.
const MIN_SHAPE_QUALITY: f64 = 0.1;
const QUALITY_PHASE: usize = 3;

/// 4√3·area / Σ squared edge lengths: 1 for an equilateral triangle, 0 for a degenerate one.
fn shape_quality(t: Triangle) -> f64 {
    let sum =
        t[0].distance_squared(t[1]) + t[1].distance_squared(t[2]) + t[2].distance_squared(t[0]);
    if sum <= 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * area_normal(t).length() / sum
}

/// Subdivision depth of the clearance test ([`TriangleBvh::clear_of`]).
const CLEARANCE_DEPTH: u32 = 4;

/// What must hold after every collapse.
#[derive(Debug, Clone, Copy)]
pub struct CollapseConstraints<'a> {
    /// BVH over the mesh triangles (M).
    pub mesh: &'a TriangleBvh,
    /// Least distance kept between cage and mesh triangles.
    pub margin: f64,
    /// Least distance kept between non-adjacent cage triangles.
    pub separation: f64,
    /// One point per connected piece of the mesh.
    pub piece_points: &'a [DVec3],
}

/// When to stop collapsing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopAt {
    Vertices(usize),
    Faces(usize),
}

/// Result of [`simplify`].
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Whether the stopping count was reached.
    pub reached: bool,
    pub collapses: usize,
    /// Candidate positions rejected by the geometric constraints.
    pub rejections: usize,
}

#[derive(Debug, Clone, Copy)]
struct Candidate {
    cost: f64,
    a: u32,
    b: u32,
    version_a: u32,
    version_b: u32,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    /// Reversed: the cheapest candidate is the heap's maximum.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .cost
            .total_cmp(&self.cost)
            .then((other.a, other.b).cmp(&(self.a, self.b)))
    }
}

struct State<'a> {
    positions: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
    face_alive: Vec<bool>,
    vertex_faces: Vec<Vec<u32>>,
    vertex_alive: Vec<bool>,
    quadrics: Vec<Quadric>,
    versions: Vec<u32>,
    hash: TriangleHash,
    constraints: CollapseConstraints<'a>,
    rejections: usize,
    /// [`MIN_SHAPE_QUALITY`] while many vertices remain, then 0.
    quality_floor: f64,
}

/// Simplifies `surface` (closed, embedded, enclosing the mesh with the margin) until `stop`.
pub fn simplify(
    surface: Surface,
    stop: StopAt,
    constraints: CollapseConstraints<'_>,
) -> Simplified {
    let Surface {
        positions,
        triangles: faces,
    } = surface;
    let num_vertices = positions.len();
    let mut state = State {
        quadrics: vec![Quadric::default(); num_vertices],
        vertex_faces: vec![Vec::new(); num_vertices],
        vertex_alive: vec![true; num_vertices],
        versions: vec![0; num_vertices],
        face_alive: vec![true; faces.len()],
        hash: TriangleHash::new(Aabb::EMPTY.expanded(-1.0), 1.0),
        positions,
        faces,
        constraints,
        rejections: 0,
        quality_floor: MIN_SHAPE_QUALITY,
    };
    for (f, tri) in state.faces.iter().enumerate() {
        let corners = tri.map(|v| state.positions[v as usize]);
        let n = area_normal(corners);
        let area = 0.5 * n.length();
        if area > 0.0 {
            let q = Quadric::from_plane(n / (2.0 * area), corners[0], area);
            for &v in tri {
                state.quadrics[v as usize] = state.quadrics[v as usize] + q;
            }
        }
        for &v in tri {
            state.vertex_faces[v as usize].push(f as u32);
        }
    }
    state.rebuild_hash();
    let mut num_alive_vertices = num_vertices;
    let mut num_alive_faces = state.faces.len();
    let done = |v: usize, f: usize| match stop {
        StopAt::Vertices(n) => v <= n,
        StopAt::Faces(n) => f <= n,
    };
    let mut heap = BinaryHeap::new();
    let mut collapses = 0;
    let mut faces_at_rebuild = num_alive_faces;
    let mut sweeps = 0;
    loop {
        let collapses_before_sweep = collapses;
        for f in 0..state.faces.len() {
            if state.face_alive[f] {
                for k in 0..3 {
                    let (a, b) = (state.faces[f][k], state.faces[f][(k + 1) % 3]);
                    if a < b {
                        heap.push(state.candidate(a, b));
                    }
                }
            }
        }
        while !done(num_alive_vertices, num_alive_faces) {
            let remaining = match stop {
                StopAt::Vertices(n) => num_alive_vertices > QUALITY_PHASE * n,
                StopAt::Faces(n) => num_alive_faces > QUALITY_PHASE * n,
            };
            if !remaining && state.quality_floor > 0.0 {
                // Entering the final phase: edges blocked by the floor become candidates again.
                state.quality_floor = 0.0;
                for f in 0..state.faces.len() {
                    if state.face_alive[f] {
                        for k in 0..3 {
                            let (a, b) = (state.faces[f][k], state.faces[f][(k + 1) % 3]);
                            if a < b {
                                heap.push(state.candidate(a, b));
                            }
                        }
                    }
                }
            }
            let Some(c) = heap.pop() else { break };
            let (a, b) = (c.a as usize, c.b as usize);
            if !state.vertex_alive[a]
                || !state.vertex_alive[b]
                || state.versions[a] != c.version_a
                || state.versions[b] != c.version_b
            {
                continue;
            }
            if state.try_collapse(a, b) {
                collapses += 1;
                num_alive_vertices -= 1;
                num_alive_faces -= 2;
                if 2 * num_alive_faces < faces_at_rebuild {
                    state.rebuild_hash();
                    faces_at_rebuild = num_alive_faces;
                }
                for &f in &state.vertex_faces[a] {
                    let tri = state.faces[f as usize];
                    for k in 0..3 {
                        let (x, y) = (tri[k], tri[(k + 1) % 3]);
                        if x < y && (x as usize == a || y as usize == a) {
                            heap.push(state.candidate(x, y));
                        }
                    }
                }
            }
        }
        sweeps += 1;
        if done(num_alive_vertices, num_alive_faces)
            || collapses == collapses_before_sweep
            || sweeps >= MAX_SWEEPS
        {
            break;
        }
    }
    let reached = done(num_alive_vertices, num_alive_faces);
    // Compact.
    let mut new_index = vec![u32::MAX; state.positions.len()];
    let mut positions = Vec::with_capacity(num_alive_vertices);
    for (v, alive) in state.vertex_alive.iter().enumerate() {
        if *alive && !state.vertex_faces[v].is_empty() {
            new_index[v] = positions.len() as u32;
            positions.push(state.positions[v]);
        }
    }
    let triangles = state
        .faces
        .iter()
        .zip(&state.face_alive)
        .filter(|(_, alive)| **alive)
        .map(|(tri, _)| tri.map(|v| new_index[v as usize]))
        .collect();
    Simplified {
        positions,
        triangles,
        reached,
        collapses,
        rejections: state.rejections,
    }
}

impl State<'_> {
    /// Rebuilds the triangle hash with cells of about twice the mean edge length (triangles
    /// grow as the surface coarsens; the hash is rebuilt whenever the face count halves).
    fn rebuild_hash(&mut self) {
        let mut bounds = Aabb::EMPTY;
        let (mut edge_sum, mut edges) = (0.0, 0usize);
        for (tri, _) in self.faces.iter().zip(&self.face_alive).filter(|(_, a)| **a) {
            let c = self.corners(*tri);
            bounds = bounds.union(Aabb::of_triangle(&c));
            edge_sum += c[0].distance(c[1]) + c[1].distance(c[2]) + c[2].distance(c[0]);
            edges += 3;
        }
        if edges == 0 {
            return;
        }
        let extent = (bounds.max - bounds.min).max_element();
        // At most ≈ 2M cells.
        let cell = (2.0 * edge_sum / edges as f64)
            .max(extent / 128.0)
            .max(f64::MIN_POSITIVE);
        self.hash = TriangleHash::new(bounds.expanded(cell), cell);
        for f in 0..self.faces.len() {
            if self.face_alive[f] {
                let c = self.corners(self.faces[f]);
                self.hash.insert(f as u32, &Aabb::of_triangle(&c));
            }
        }
    }

    fn candidate(&self, a: u32, b: u32) -> Candidate {
        let positions = self.candidate_positions(a as usize, b as usize);
        Candidate {
            cost: positions[0].0,
            a,
            b,
            version_a: self.versions[a as usize],
            version_b: self.versions[b as usize],
        }
    }

    /// The quadric minimiser (when well defined and near the edge), the midpoint and both ends,
    /// cheapest first.
    fn candidate_positions(&self, a: usize, b: usize) -> Vec<(f64, DVec3)> {
        let q = self.quadrics[a] + self.quadrics[b];
        let (pa, pb) = (self.positions[a], self.positions[b]);
        let mid = 0.5 * (pa + pb);
        let mut out = Vec::with_capacity(4);
        if let Some(x) = q.minimiser()
            && x.distance(mid) <= 2.0 * pa.distance(pb)
        {
            out.push((q.evaluate(x), x));
        }
        for p in [mid, pa, pb] {
            out.push((q.evaluate(p), p));
        }
        out.sort_by(|x, y| x.0.total_cmp(&y.0));
        out
    }

    fn corners(&self, tri: [u32; 3]) -> Triangle {
        tri.map(|v| self.positions[v as usize])
    }

    /// Tries the candidate positions of edge (a, b) in order; applies the first that keeps
    /// every constraint.
    fn try_collapse(&mut self, a: usize, b: usize) -> bool {
        let (a32, b32) = (a as u32, b as u32);
        let star_a = &self.vertex_faces[a];
        let star_b = &self.vertex_faces[b];
        let shared: Vec<u32> = star_a
            .iter()
            .copied()
            .filter(|f| star_b.contains(f))
            .collect();
        if shared.len() != 2 {
            return false;
        }
        // Link condition: the common neighbours of a and b are exactly the two opposite corners.
        let neighbours = |star: &[u32], v: u32| -> Vec<u32> {
            let mut n: Vec<u32> = star
                .iter()
                .flat_map(|&f| self.faces[f as usize])
                .filter(|&x| x != v)
                .collect();
            n.sort_unstable();
            n.dedup();
            n
        };
        let (na, nb) = (neighbours(star_a, a32), neighbours(star_b, b32));
        let common = na.iter().filter(|x| nb.binary_search(x).is_ok()).count();
        if common != 2 || na.len() + nb.len() - common - 2 < 3 {
            return false;
        }
        // Old star (all faces around a or b) and the surviving faces with b renamed a.
        let mut old_faces: Vec<u32> = star_a.clone();
        old_faces.extend(star_b.iter().filter(|f| !shared.contains(f)));
        let kept: Vec<u32> = old_faces
            .iter()
            .copied()
            .filter(|f| !shared.contains(f))
            .collect();
        let new_ids: Vec<[u32; 3]> = kept
            .iter()
            .map(|&f| self.faces[f as usize].map(|v| if v == b32 { a32 } else { v }))
            .collect();
        let old_corners: Vec<Triangle> = old_faces
            .iter()
            .map(|&f| self.corners(self.faces[f as usize]))
            .collect();
        let kept_old: Vec<Triangle> = kept
            .iter()
            .map(|&f| self.corners(self.faces[f as usize]))
            .collect();
        for (_, p) in self.candidate_positions(a, b) {
            let new_corners: Vec<Triangle> = new_ids
                .iter()
                .map(|tri| {
                    tri.map(|v| {
                        if v == a32 {
                            p
                        } else {
                            self.positions[v as usize]
                        }
                    })
                })
                .collect();
            if self.acceptable(&old_faces, &old_corners, &kept_old, &new_ids, &new_corners) {
                self.apply(a, b, p, &shared, &kept);
                return true;
            }
            self.rejections += 1;
        }
        false
    }

    fn acceptable(
        &mut self,
        old_faces: &[u32],
        old_corners: &[Triangle],
        kept_old: &[Triangle],
        new_ids: &[[u32; 3]],
        new_corners: &[Triangle],
    ) -> bool {
        let c = self.constraints;
        // 2. No flip, no degenerate triangle, no sliver worse than the star already had.
        let worst_old = kept_old
            .iter()
            .map(|t| shape_quality(*t))
            .fold(1.0, f64::min);
        let min_quality = self.quality_floor.min(worst_old);
        if new_corners.iter().any(|t| shape_quality(*t) < min_quality) {
            return false;
        }
        for (old, new) in kept_old.iter().zip(new_corners) {
            let (n_old, n_new) = (area_normal(*old), area_normal(*new));
            let scale = (new[1] - new[0])
                .length_squared()
                .max((new[2] - new[0]).length_squared());
            if n_new.length() <= 1e-10 * scale || n_new.dot(n_old) <= 0.0 {
                return false;
            }
        }
        // 3. Margin to the mesh.
        if new_corners
            .iter()
            .any(|t| !c.mesh.clear_of(*t, c.margin, CLEARANCE_DEPTH))
        {
            return false;
        }
        // 4. No self-intersection, new vs new and new vs the rest of the cage.
        for i in 0..new_ids.len() {
            for j in i + 1..new_ids.len() {
                if cage_triangles_conflict(
                    new_corners[i],
                    new_ids[i],
                    new_corners[j],
                    new_ids[j],
                    c.separation,
                ) {
                    return false;
                }
            }
        }
        for (ids, corners) in new_ids.iter().zip(new_corners) {
            let query = Aabb::of_triangle(corners).expanded(c.separation);
            let mut conflict = false;
            let (faces, face_alive, positions) = (&self.faces, &self.face_alive, &self.positions);
            self.hash.query(&query, |f| {
                if conflict || !face_alive[f as usize] || old_faces.contains(&f) {
                    return;
                }
                let other = faces[f as usize];
                let other_corners = other.map(|v| positions[v as usize]);
                if Aabb::of_triangle(&other_corners).overlaps(&query)
                    && cage_triangles_conflict(*corners, *ids, other_corners, other, c.separation)
                {
                    conflict = true;
                }
            });
            if conflict {
                return false;
            }
        }
        // 5. No mesh piece swept across.
        let region = old_corners
            .iter()
            .chain(new_corners)
            .fold(Aabb::EMPTY, |b, t| b.union(Aabb::of_triangle(t)));
        for &point in c.piece_points {
            if region.contains(point) {
                let swept: f64 = old_corners
                    .iter()
                    .map(|t| solid_angle(point, *t))
                    .sum::<f64>()
                    - new_corners
                        .iter()
                        .map(|t| solid_angle(point, *t))
                        .sum::<f64>();
                if swept.abs() > 2.0 * std::f64::consts::PI {
                    return false;
                }
            }
        }
        true
    }

    fn apply(&mut self, a: usize, b: usize, p: DVec3, shared: &[u32], kept: &[u32]) {
        let (a32, b32) = (a as u32, b as u32);
        for &f in shared {
            self.face_alive[f as usize] = false;
            self.hash.remove(f);
            for v in self.faces[f as usize] {
                if v != a32 && v != b32 {
                    self.vertex_faces[v as usize].retain(|&g| g != f);
                }
            }
        }
        for &f in kept {
            for v in &mut self.faces[f as usize] {
                if *v == b32 {
                    *v = a32;
                }
            }
        }
        self.positions[a] = p;
        self.quadrics[a] = self.quadrics[a] + self.quadrics[b];
        self.vertex_alive[b] = false;
        self.vertex_faces[b].clear();
        self.vertex_faces[a] = kept.to_vec();
        self.versions[a] = self.versions[a].wrapping_add(1);
        for &f in kept {
            self.hash.remove(f);
            let corners = self.corners(self.faces[f as usize]);
            self.hash.insert(f, &Aabb::of_triangle(&corners));
        }
    }
}
