//! Constrained simplification by edge collapses (Garland & Heckbert's QEM order, the
//! constraints of progressive hulls / nested cages: Sander et al. 2000, Sacht et al. 2015).
//!
//! Edges are collapsed cheapest quadric error first; each collapse tries the quadric minimiser,
//! the midpoint and both end points, and is accepted only if afterwards
//! 1. the surface is still a closed 2-manifold (link condition, more than four vertices);
//! 2. no surviving triangle flips or degenerates (normal turns by less than 90°);
//! 3. every new triangle stays at least `margin` from every mesh triangle (mesh BVH, with the
//!    cage vertices' distances to the mesh cached: [`TriangleBvh::clear_of`]);
//! 4. no new triangle intersects or comes within `separation` of another cage triangle
//!    (dynamic triangle hash; triangles sharing a vertex are cleared together when the star of
//!    that vertex projects one-to-one, see [`super::collapse_checks`], else pairwise by the
//!    adjacency-aware test of [`cage_triangles_conflict`]);
//! 5. no piece of the mesh changed side: the old and new triangles around the edge form a closed
//!    surface, and the winding number of each mesh piece's representative point about it is 0.
//!    A mesh piece never touches the cage (3.), so one point decides for the whole piece.
//!
//! Given a starting surface that is embedded, encloses the mesh and keeps the margin, every
//! intermediate surface does too. Edges rejected for every candidate are retried after their
//! neighbourhood changes, and once more in a final sweep. The checks live in
//! [`super::collapse_checks`].

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;

use super::bvh::{Aabb, TriangleBvh};
#[cfg(doc)]
use super::geometry::cage_triangles_conflict;
use super::geometry::{Triangle, area_normal};
use super::marching_tets::Surface;
use super::quadric::Quadric;
use super::skeleton_guide::{CageGuide, GUIDE_WEIGHT};
use super::triangle_hash::TriangleHash;

/// Passes over all edges (the first, then retries of edges rejected before their
/// neighbourhood changed).
const MAX_SWEEPS: usize = 3;

/// Least shape quality ([`shape_quality`]) a collapse may create, unless the star was already
/// worse, while more than [`QUALITY_PHASE`] × the target count remain. Quadric error alone is
/// zero along flat and cylindrical directions, where it grows slivers across the whole part:
/// they slow every intersection query. Near the target the floor is lowered to
/// [`FINAL_SHAPE_QUALITY`], and dropped only where no collapse above that is left, so that it
/// never keeps a cage from reaching its size.
const MIN_SHAPE_QUALITY: f64 = 0.1;
const QUALITY_PHASE: usize = 3;
/// The floor of the final phase: low enough to let the quadric order finish the cage, high
/// enough to forbid needles (a 60 × 2 × 2 beam got angles of 0.04° without it, shape quality
/// 1.2e-3; Green coordinates' stretched normals turn fast on such triangles).
const FINAL_SHAPE_QUALITY: f64 = 0.02;

/// 4√3·area / Σ squared edge lengths: 1 for an equilateral triangle, 0 for a degenerate one.
pub(super) fn shape_quality(t: Triangle) -> f64 {
    let sum =
        t[0].distance_squared(t[1]) + t[1].distance_squared(t[2]) + t[2].distance_squared(t[0]);
    if sum <= 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * area_normal(t).length() / sum
}

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
    /// Stop at this many vertices.
    Vertices(usize),
    /// Stop at this many triangles.
    Faces(usize),
}

/// Result of [`simplify`].
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// Vertex positions of the simplified surface.
    pub positions: Vec<DVec3>,
    /// Its triangles (indices into `positions`), oriented outward.
    pub triangles: Vec<[u32; 3]>,
    /// Whether the stopping count was reached.
    pub reached: bool,
    /// Edge collapses applied.
    pub collapses: usize,
    /// Candidate positions rejected by the geometric constraints.
    pub rejections: usize,
    /// Edge flips after the collapses ([`super::edge_flips`]).
    pub flips: usize,
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

pub(super) struct State<'a> {
    pub(super) positions: Vec<DVec3>,
    pub(super) faces: Vec<[u32; 3]>,
    pub(super) face_alive: Vec<bool>,
    pub(super) vertex_faces: Vec<Vec<u32>>,
    vertex_alive: Vec<bool>,
    /// Distance of each cage vertex to the mesh: exact below the margin, a lower bound above
    /// it; NaN until first needed.
    pub(super) clearance: Vec<f64>,
    quadrics: Vec<Quadric>,
    versions: Vec<u32>,
    pub(super) hash: TriangleHash,
    pub(super) constraints: CollapseConstraints<'a>,
    rejections: usize,
    /// [`MIN_SHAPE_QUALITY`] while many vertices remain, then [`FINAL_SHAPE_QUALITY`], then 0
    /// where that blocks the target.
    pub(super) quality_floor: f64,
    /// Buffers of one collapse attempt, reused.
    pub(super) scratch: Scratch,
    /// Boxes of the new triangles (self-intersection check), reused.
    pub(super) scratch_boxes: Vec<Aabb>,
}

/// The star of an edge (a, b) being collapsed, and buffers of its checks.
#[derive(Debug, Default)]
pub(super) struct Scratch {
    /// The two faces containing both a and b (removed).
    pub(super) shared: Vec<u32>,
    /// Neighbours of a and of b (sorted), for the link condition.
    neighbours_a: Vec<u32>,
    neighbours_b: Vec<u32>,
    /// Vertices of the link of the edge: neighbours of a or b other than a and b.
    pub(super) link: Vec<u32>,
    /// Every face around a or b.
    pub(super) old_faces: Vec<u32>,
    /// Faces around a or b that survive (b renamed a).
    pub(super) kept: Vec<u32>,
    pub(super) new_ids: Vec<[u32; 3]>,
    pub(super) old_corners: Vec<Triangle>,
    pub(super) kept_old: Vec<Triangle>,
    pub(super) new_corners: Vec<Triangle>,
    /// Distance of the collapsed vertex at its new position to the mesh (as `clearance`; NaN
    /// until the margin check needs it).
    pub(super) new_vertex_clearance: f64,
    /// Per face: the attempt that last marked it as part of the old star.
    pub(super) old_face_stamp: Vec<u32>,
    pub(super) stamp: u32,
    /// The star of one vertex after the collapse, as (next, previous) corner positions.
    pub(super) fan: Vec<(DVec3, DVec3)>,
    /// Vertices (a and the link) whose star after the collapse projects one-to-one.
    pub(super) embedded_stars: Vec<u32>,
}

/// Candidate positions of a collapse with their quadric errors, cheapest first.
#[derive(Debug, Clone, Copy)]
struct Positions {
    items: [(f64, DVec3); 4],
    len: usize,
}

impl Positions {
    fn as_slice(&self) -> &[(f64, DVec3)] {
        &self.items[..self.len]
    }
}

/// Simplifies `surface` (closed, embedded, enclosing the mesh with the margin) until `stop`;
/// `clearances` are its vertices' distances to the mesh (exact below the margin, lower bounds
/// above; NaN where unknown).
pub fn simplify(
    surface: Surface,
    clearances: Vec<f64>,
    guide: &CageGuide,
    stop: StopAt,
    constraints: CollapseConstraints<'_>,
) -> Simplified {
    let Surface {
        positions,
        triangles: faces,
    } = surface;
    let num_vertices = positions.len();
    let num_faces = faces.len();
    let mut state = State {
        quadrics: vec![Quadric::default(); num_vertices],
        vertex_faces: vec![Vec::new(); num_vertices],
        vertex_alive: vec![true; num_vertices],
        versions: vec![0; num_vertices],
        clearance: if clearances.len() == num_vertices {
            clearances
        } else {
            vec![f64::NAN; num_vertices]
        },
        face_alive: vec![true; faces.len()],
        hash: TriangleHash::new(Aabb::EMPTY.expanded(-1.0), 1.0),
        positions,
        faces,
        constraints,
        rejections: 0,
        quality_floor: MIN_SHAPE_QUALITY,
        scratch: Scratch {
            old_face_stamp: vec![0; num_faces],
            ..Scratch::default()
        },
        scratch_boxes: Vec::new(),
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
    if !guide.planes.is_empty() {
        // Guide planes (skeleton_guide): band = the mean edge length, weight ∝ mean area.
        let (mut area, mut edge) = (0.0, 0.0);
        for tri in &state.faces {
            let c = tri.map(|v| state.positions[v as usize]);
            area += 0.5 * area_normal(c).length();
            edge += c[0].distance(c[1]);
        }
        let n = state.faces.len().max(1) as f64;
        let (area, band) = (area / n, edge / n);
        for (q, p) in state.quadrics.iter_mut().zip(&state.positions) {
            *q = *q + guide.quadric_at(*p, band, GUIDE_WEIGHT * area);
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
        state.push_edge_candidates(&mut heap);
        while !done(num_alive_vertices, num_alive_faces) {
            let remaining = match stop {
                StopAt::Vertices(n) => num_alive_vertices > QUALITY_PHASE * n,
                StopAt::Faces(n) => num_alive_faces > QUALITY_PHASE * n,
            };
            if !remaining && state.quality_floor > FINAL_SHAPE_QUALITY {
                // Entering the final phase: edges blocked by the floor become candidates again.
                state.quality_floor = FINAL_SHAPE_QUALITY;
                state.push_edge_candidates(&mut heap);
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
        let stalled = collapses == collapses_before_sweep || sweeps >= MAX_SWEEPS;
        if !done(num_alive_vertices, num_alive_faces) && stalled && state.quality_floor > 0.0 {
            // No collapse above the floor is left: drop it (the edges it blocked become
            // candidates again) rather than stop short of the target.
            state.quality_floor = 0.0;
            sweeps = 0;
            continue;
        }
        if done(num_alive_vertices, num_alive_faces) || stalled {
            break;
        }
    }
    let reached = done(num_alive_vertices, num_alive_faces);
    let flips = state.improve_by_flips();
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
        flips,
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

    /// Pushes the collapse of every edge of the alive faces onto `heap`, each edge once (from
    /// its face where it runs from the lower index up), faces and edges in order.
    fn push_edge_candidates(&self, heap: &mut BinaryHeap<Candidate>) {
        for (face, _) in self
            .faces
            .iter()
            .zip(&self.face_alive)
            .filter(|(_, alive)| **alive)
        {
            for k in 0..3 {
                let (a, b) = (face[k], face[(k + 1) % 3]);
                if a < b {
                    heap.push(self.candidate(a, b));
                }
            }
        }
    }

    fn candidate(&self, a: u32, b: u32) -> Candidate {
        let positions = self.candidate_positions(a as usize, b as usize);
        Candidate {
            cost: positions.items[0].0,
            a,
            b,
            version_a: self.versions[a as usize],
            version_b: self.versions[b as usize],
        }
    }

    /// The quadric minimiser (when well defined and near the edge), the midpoint and both ends,
    /// cheapest first.
    fn candidate_positions(&self, a: usize, b: usize) -> Positions {
        let q = self.quadrics[a] + self.quadrics[b];
        let (pa, pb) = (self.positions[a], self.positions[b]);
        let mid = 0.5 * (pa + pb);
        let mut out = Positions {
            items: [(0.0, DVec3::ZERO); 4],
            len: 0,
        };
        if let Some(x) = q.minimiser()
            && x.distance(mid) <= 2.0 * pa.distance(pb)
        {
            out.items[0] = (q.evaluate(x), x);
            out.len = 1;
        }
        for p in [mid, pa, pb] {
            out.items[out.len] = (q.evaluate(p), p);
            out.len += 1;
        }
        out.items[..out.len].sort_by(|x, y| x.0.total_cmp(&y.0));
        out
    }

    /// Distance of cage vertex `v` to the mesh (cached).
    pub(super) fn clearance(&mut self, v: u32) -> f64 {
        let d = &mut self.clearance[v as usize];
        if d.is_nan() {
            *d = self
                .constraints
                .mesh
                .nearest_distance(self.positions[v as usize], f64::INFINITY);
        }
        *d
    }

    fn corners(&self, tri: [u32; 3]) -> Triangle {
        tri.map(|v| self.positions[v as usize])
    }

    /// Tries the candidate positions of edge (a, b) in order; applies the first that keeps
    /// every constraint.
    fn try_collapse(&mut self, a: usize, b: usize) -> bool {
        if !self.gather_star(a as u32, b as u32) {
            return false;
        }
        let positions = self.candidate_positions(a, b);
        for &(_, p) in positions.as_slice() {
            let clearance = if p == self.positions[a] {
                self.clearance(a as u32)
            } else if p == self.positions[b] {
                self.clearance(b as u32)
            } else {
                f64::NAN
            };
            self.place_new_vertex(a as u32, p, clearance);
            if self.acceptable(a as u32, b as u32, p) {
                let s = std::mem::take(&mut self.scratch);
                self.apply(a, b, p, &s.shared, &s.kept);
                self.clearance[a] = s.new_vertex_clearance;
                self.scratch = s;
                return true;
            }
            self.rejections += 1;
        }
        false
    }

    /// Fills the scratch star of edge (a, b); `false` when the collapse would break
    /// manifoldness (link condition) or leave a tetrahedron.
    fn gather_star(&mut self, a: u32, b: u32) -> bool {
        let s = &mut self.scratch;
        let (star_a, star_b) = (
            &self.vertex_faces[a as usize],
            &self.vertex_faces[b as usize],
        );
        s.shared.clear();
        s.shared
            .extend(star_a.iter().copied().filter(|f| star_b.contains(f)));
        if s.shared.len() != 2 {
            return false;
        }
        // Link condition: the common neighbours of a and b are exactly the two opposite corners.
        let faces = &self.faces;
        let neighbours = |out: &mut Vec<u32>, star: &[u32], v: u32| {
            out.clear();
            out.extend(
                star.iter()
                    .flat_map(|&f| faces[f as usize])
                    .filter(|&x| x != v),
            );
            out.sort_unstable();
            out.dedup();
        };
        neighbours(&mut s.neighbours_a, star_a, a);
        neighbours(&mut s.neighbours_b, star_b, b);
        let (na, nb) = (&s.neighbours_a, &s.neighbours_b);
        let common = na.iter().filter(|x| nb.binary_search(x).is_ok()).count();
        if common != 2 || na.len() + nb.len() - common - 2 < 3 {
            return false;
        }
        s.link.clear();
        s.link
            .extend(na.iter().chain(nb).filter(|&&x| x != a && x != b));
        s.link.sort_unstable();
        s.link.dedup();
        // Old star (all faces around a or b) and the surviving faces with b renamed a.
        s.old_faces.clear();
        s.old_faces.extend(star_a);
        s.old_faces
            .extend(star_b.iter().filter(|f| !s.shared.contains(f)));
        s.kept.clear();
        s.kept
            .extend(s.old_faces.iter().filter(|f| !s.shared.contains(f)));
        s.new_ids.clear();
        s.new_ids.extend(
            s.kept
                .iter()
                .map(|&f| faces[f as usize].map(|v| if v == b { a } else { v })),
        );
        let positions = &self.positions;
        let corners = |f: &u32| faces[*f as usize].map(|v| positions[v as usize]);
        s.old_corners.clear();
        s.old_corners.extend(s.old_faces.iter().map(corners));
        s.kept_old.clear();
        s.kept_old.extend(s.kept.iter().map(corners));
        s.stamp = s.stamp.wrapping_add(1);
        if s.stamp == 0 {
            s.old_face_stamp.iter_mut().for_each(|x| *x = 0);
            s.stamp = 1;
        }
        for &f in &s.old_faces {
            s.old_face_stamp[f as usize] = s.stamp;
        }
        // Cache the link vertices' distances to the mesh.
        for k in 0..self.scratch.link.len() {
            let v = self.scratch.link[k];
            self.clearance(v);
        }
        true
    }

    /// Fills the scratch's new corners for the collapsed vertex `a` at `p`, whose distance to
    /// the mesh is `clearance` (NaN when not known yet).
    fn place_new_vertex(&mut self, a: u32, p: DVec3, clearance: f64) {
        let s = &mut self.scratch;
        s.new_corners.clear();
        for tri in &s.new_ids {
            s.new_corners.push(tri.map(|v| {
                if v == a {
                    p
                } else {
                    self.positions[v as usize]
                }
            }));
        }
        s.new_vertex_clearance = clearance;
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
        self.vertex_faces[a].clear();
        self.vertex_faces[a].extend_from_slice(kept);
        self.versions[a] = self.versions[a].wrapping_add(1);
        for &f in kept {
            self.hash.remove(f);
            let corners = self.corners(self.faces[f as usize]);
            self.hash.insert(f, &Aabb::of_triangle(&corners));
        }
    }
}
