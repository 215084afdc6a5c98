//! Unnormalised mean value weights of one point at a few vertices of a large mesh, with the sign
//! of their normaliser certified without visiting the whole mesh. Used by SkelUp (Eqs. 9–10),
//! whose localised prior needs the MVC of a joint only where the localisation L is non-zero.
//!
//! **Weights.** The MVC of a point x w.r.t. a mesh (P `#V`, T `#F`) are `w_i / W` with
//! `w_i = Σ_{T ∋ i} λ_{T,i} / d_i` (see [`super::mvc`]) and `W = Σ_i w_i`. A weight `w_i` depends
//! only on the triangles incident to vertex i, so the weights of a vertex subset cost only the
//! triangles around it. They are evaluated with [`mvc::triangle_weights`] in ascending triangle
//! order, i.e. bitwise as [`mvc::mean_value_coordinates`] accumulates them before normalising.
//!
//! **Sign of W.** W needs every triangle, but a caller that only uses the coordinates up to a
//! positive factor (SkelUp: the max-entropy solve of Eq. 11 is invariant under a positive scale of
//! the prior masses) needs only its sign. Per triangle, the contribution `c_T = Σ_j λ_{T,j} / d_j`
//! equals `n·m_T / h_T` (n the unit normal, h_T = n·(p − x) the plane's signed distance, m_T the
//! integral of the unit direction u over the triangle's spherical projection T̄), which is
//! `±∫_{T̄} dσ / r(u)` with r(u) the distance from x to the triangle along u. Since
//! `dσ = cos α dA / r²` ≤ `dA / r²`, `|c_T| ≤ area_T / dist(x, T)³`. Triangles are grouped into
//! spatial clusters (Morton order of their centroids, [`CLUSTER_SIZE`] each) with a bounding ball
//! (centre, radius ρ) and total area A, so the unevaluated triangles of a cluster contribute at
//! most `A / (|x − centre| − ρ)³` in absolute value. We evaluate exactly the triangles around the
//! requested vertices, then every cluster the point is close to (`|x − centre| < 1.5 ρ`), then the
//! other clusters by decreasing bound, until the evaluated sum W_e satisfies
//! `|W_e| > SAFETY · (bound of the rest) + ROUNDING · Σ|c_T|`; then `sign W = sign W_e`.
//! The margins cover the rounding of the full computation (it sums the same per-triangle values in
//! another order, and its far triangles carry relative errors far below SAFETY − 1).
//!
//! **Degenerate cases** (the full function then returns an interpolation, not `w / W`): the point
//! within `EPS · max distance` of a vertex (checked over all vertices), on an edge, or inside a
//! triangle. A cluster with `|x − centre| ≥ 1.5 ρ` > √2 ρ cannot contain such an edge or triangle:
//! every segment between two points of a ball of radius ρ has its diametral ball inside the
//! concentric ball of radius √2 ρ, so its angle seen from x is below 90° (the degenerate cases need
//! an angle of almost 180°, or one ≥ 120° for a spherical perimeter of 2π). Evaluated degenerate
//! triangles are detected by [`mvc::triangle_weights`]. In all these cases, and when the sign
//! cannot be certified (W ≈ 0, e.g. an open mesh seen from its hole), the result is `None` and the
//! caller uses [`mvc::mean_value_coordinates`].

use glam::DVec3;
use rayon::prelude::*;

use super::mvc::{self, EPS, TriangleWeights};

/// Triangles per spatial cluster.
pub(crate) const CLUSTER_SIZE: usize = 32;
/// A cluster is bounded instead of evaluated only when the point is at least this many cluster
/// radii from its centre (must exceed √2, see the module docs).
const FAR_RADII: f64 = 1.5;
/// Factor on the bound of the unevaluated triangles in the certification test.
const SAFETY: f64 = 2.0;
/// Clusters ordered by bound before the first certification attempts (see step 3).
const HEAD: usize = 1024;
/// Relative rounding margin on the sum of the evaluated contributions.
const ROUNDING: f64 = 1e-9;

/// A spatial group of triangles: bounding ball and total area.
#[derive(Debug, Clone)]
struct Cluster {
    centre: DVec3,
    radius: f64,
    area: f64,
    /// Range into `cluster_triangles`.
    start: u32,
    end: u32,
}

/// Precomputed adjacency and clusters of a mesh for [`LocalMvc::weights_at`].
#[derive(Debug, Clone)]
pub(crate) struct LocalMvc<'a> {
    positions: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    /// Vertex → incident triangles (CSR, ascending triangle index), `#V + 1` offsets.
    vertex_triangle_start: Vec<u32>,
    vertex_triangles: Vec<u32>,
    /// Vertices of no triangle (outside every cluster; checked one by one for snapping).
    isolated_vertices: Vec<u32>,
    clusters: Vec<Cluster>,
    /// Triangle indices grouped by cluster, `#F`.
    cluster_triangles: Vec<u32>,
}

/// Per-thread scratch of [`LocalMvc::weights_at`] (`#V` weights, `#F` flags); allocate once per
/// thread with [`LocalMvc::scratch`]. Left clean by every call.
#[derive(Debug, Clone)]
pub(crate) struct LocalMvcScratch {
    /// Accumulated weight per mesh vertex, `#V` (non-zero only during a call).
    weight: Vec<f64>,
    /// Bit set of the evaluated triangles, `⌈#F / 64⌉` words.
    evaluated: Vec<u64>,
    /// The triangles around the requested vertices, ascending.
    incident: Vec<u32>,
    /// Distance from the point to every cluster centre, `#clusters`.
    distance: Vec<f64>,
    /// (bound, cluster) of the clusters not evaluated yet, then suffix sums of the bounds.
    pending: Vec<(f64, u32)>,
    remaining: Vec<f64>,
}

impl<'a> LocalMvc<'a> {
    /// Builds the vertex → triangle adjacency and the triangle clusters, O(#V + #F log #F).
    /// Triangle indices must be in range (as guaranteed by [`crate::mesh::TriMesh::new`]).
    pub(crate) fn new(positions: &'a [DVec3], triangles: &'a [[u32; 3]]) -> Self {
        let mut vertex_triangle_start = vec![0u32; positions.len() + 1];
        for tri in triangles {
            for &v in tri {
                vertex_triangle_start[v as usize + 1] += 1;
            }
        }
        for v in 0..positions.len() {
            vertex_triangle_start[v + 1] += vertex_triangle_start[v];
        }
        let mut fill = vertex_triangle_start.clone();
        let mut vertex_triangles = vec![0u32; vertex_triangle_start[positions.len()] as usize];
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                // A triangle listing a vertex twice appears twice; harmless (flags dedupe).
                vertex_triangles[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }
        let isolated_vertices = (0..positions.len())
            .filter(|&v| vertex_triangle_start[v] == vertex_triangle_start[v + 1])
            .map(|v| v as u32)
            .collect();

        let corners = |t: usize| triangles[t].map(|i| positions[i as usize]);
        let centroids: Vec<DVec3> = (0..triangles.len())
            .into_par_iter()
            .map(|t| corners(t).iter().sum::<DVec3>() / 3.0)
            .collect();
        let (lo, hi) = crate::mesh::bounding_box(&centroids);
        let extent = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let codes: Vec<u32> = centroids
            .par_iter()
            .map(|c| morton_code((*c - lo) / extent))
            .collect();
        let cluster_triangles = sort_by_code(&codes);
        let clusters = cluster_triangles
            .par_chunks(CLUSTER_SIZE)
            .enumerate()
            .map(|(c, members)| {
                let points = members.iter().flat_map(|&t| corners(t as usize));
                let (lo, hi) = points
                    .clone()
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(p), hi.max(p))
                    });
                let centre = 0.5 * (lo + hi);
                // Slightly enlarged against rounding: the bounds need every point inside.
                let radius = points.map(|p| p.distance(centre)).fold(0.0, f64::max) * (1.0 + 1e-12);
                let area = members
                    .iter()
                    .map(|&t| {
                        let [a, b, c] = corners(t as usize);
                        0.5 * (b - a).cross(c - a).length()
                    })
                    .sum::<f64>()
                    * (1.0 + 1e-12);
                let start = (c * CLUSTER_SIZE) as u32;
                Cluster {
                    centre,
                    radius,
                    area,
                    start,
                    end: start + members.len() as u32,
                }
            })
            .collect();
        Self {
            positions,
            triangles,
            vertex_triangle_start,
            vertex_triangles,
            isolated_vertices,
            clusters,
            cluster_triangles,
        }
    }

    /// A scratch buffer sized for this mesh.
    pub(crate) fn scratch(&self) -> LocalMvcScratch {
        LocalMvcScratch {
            weight: vec![0.0; self.positions.len()],
            evaluated: vec![0; self.triangles.len().div_ceil(64)],
            incident: Vec::new(),
            distance: Vec::new(),
            pending: Vec::new(),
            remaining: Vec::new(),
        }
    }

    /// Writes the unnormalised MVC weight `w_i` of `point` for every `i` in `vertices` into
    /// `out` (`vertices.len()`, same order) and returns `Some(sign of W)` (±1.0), so that the
    /// coordinates are `w_i · sign / |W|`. Returns `None` (`out` unspecified) when the full
    /// [`mvc::mean_value_coordinates`] is needed: degenerate positions or an uncertifiable sign.
    /// `vertices` must be in range and without duplicates.
    pub(crate) fn weights_at(
        &self,
        point: DVec3,
        vertices: &[usize],
        scratch: &mut LocalMvcScratch,
        out: &mut [f64],
    ) -> Option<f64> {
        debug_assert_eq!(vertices.len(), out.len());
        if self.triangles.is_empty() || self.snapped(point, scratch) {
            return None;
        }
        let result = self.certified_weights(point, vertices, scratch, out);
        for &t in &scratch.incident {
            for v in self.triangles[t as usize] {
                scratch.weight[v as usize] = 0.0;
            }
        }
        scratch.evaluated.iter_mut().for_each(|w| *w = 0);
        result
    }

    /// The work of [`Self::weights_at`] after the snapping test (which fills
    /// `scratch.distance`); leaves the flags and weights of the visited triangles set (the
    /// caller resets them).
    fn certified_weights(
        &self,
        point: DVec3,
        vertices: &[usize],
        scratch: &mut LocalMvcScratch,
        out: &mut [f64],
    ) -> Option<f64> {
        // 1. The triangles around the requested vertices, in ascending order (bit set scan).
        for &v in vertices {
            let range =
                self.vertex_triangle_start[v] as usize..self.vertex_triangle_start[v + 1] as usize;
            for &t in &self.vertex_triangles[range] {
                scratch.evaluated[t as usize / 64] |= 1 << (t % 64);
            }
        }
        scratch.incident.clear();
        for (w, &word) in scratch.evaluated.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                scratch
                    .incident
                    .push((w * 64) as u32 + bits.trailing_zeros());
                bits &= bits - 1;
            }
        }
        let mut sum = Sum::default();
        for &t in &scratch.incident {
            let tri = self.triangles[t as usize];
            match mvc::triangle_weights(self.positions, tri, point) {
                TriangleWeights::Add(w) => {
                    for (v, wj) in tri.iter().zip(w) {
                        scratch.weight[*v as usize] += wj;
                    }
                    sum.add(w);
                }
                TriangleWeights::Skip => {}
                TriangleWeights::OnEdge { .. } | TriangleWeights::OnTriangle => return None,
            }
        }
        for (o, &v) in out.iter_mut().zip(vertices) {
            *o = scratch.weight[v];
        }

        // 2. Clusters close to the point; the others with their bounds.
        scratch.pending.clear();
        let mut total_bound = 0.0;
        for (c, cluster) in self.clusters.iter().enumerate() {
            let distance = scratch.distance[c];
            if distance < FAR_RADII * cluster.radius {
                self.evaluate_cluster(cluster, point, scratch, &mut sum)?;
            } else {
                let gap = distance - cluster.radius;
                let bound = cluster.area / (gap * gap * gap);
                total_bound += bound;
                scratch.pending.push((bound, c as u32));
            }
        }
        if sum.certain(total_bound) {
            return Some(sum.total.signum());
        }
        // 3. The rest by decreasing bound until the sign is certain. Usually a few hundred
        //    clusters suffice: order the first HEAD, and the others only if needed.
        let descending = |a: &(f64, u32), b: &(f64, u32)| b.0.total_cmp(&a.0);
        let pending = &mut scratch.pending;
        let head = pending.len().min(HEAD);
        if head < pending.len() {
            pending.select_nth_unstable_by(head, descending);
        }
        pending[..head].sort_unstable_by(descending);
        // remaining[k] = Σ_{k' ≥ k} bound_k' (any order of the tail gives the same set).
        let remaining = &mut scratch.remaining;
        remaining.clear();
        remaining.resize(pending.len() + 1, 0.0);
        for k in (0..pending.len()).rev() {
            remaining[k] = remaining[k + 1] + pending[k].0;
        }
        for k in 0..=scratch.pending.len() {
            if sum.certain(scratch.remaining[k]) {
                return Some(sum.total.signum());
            }
            if k == head && head < scratch.pending.len() {
                scratch.pending[head..].sort_unstable_by(descending);
            }
            if k < scratch.pending.len() {
                let cluster = &self.clusters[scratch.pending[k].1 as usize];
                self.evaluate_cluster(cluster, point, scratch, &mut sum)?;
            }
        }
        None
    }

    /// Adds the contributions of the not yet evaluated triangles of `cluster` to `sum`; `None`
    /// on a degenerate triangle.
    fn evaluate_cluster(
        &self,
        cluster: &Cluster,
        point: DVec3,
        scratch: &mut LocalMvcScratch,
        sum: &mut Sum,
    ) -> Option<()> {
        for &t in &self.cluster_triangles[cluster.start as usize..cluster.end as usize] {
            let (word, bit) = (t as usize / 64, 1u64 << (t % 64));
            if scratch.evaluated[word] & bit != 0 {
                continue;
            }
            scratch.evaluated[word] |= bit;
            match mvc::triangle_weights(self.positions, self.triangles[t as usize], point) {
                TriangleWeights::Add(w) => sum.add(w),
                TriangleWeights::Skip => {}
                TriangleWeights::OnEdge { .. } | TriangleWeights::OnTriangle => return None,
            }
        }
        Some(())
    }

    /// Whether [`mvc::mean_value_coordinates`] snaps `point` to a vertex (nearest distance ≤
    /// `EPS` · farthest distance). Decided from the cluster balls (the vertices of the few
    /// clusters whose ball comes within the threshold are measured) when that leaves a factor-2
    /// margin, else over all vertices. Fills `scratch.distance` (point to cluster centres).
    fn snapped(&self, point: DVec3, scratch: &mut LocalMvcScratch) -> bool {
        let mut farthest_upper: f64 = 0.0;
        scratch.distance.clear();
        for cluster in &self.clusters {
            let d = point.distance(cluster.centre);
            scratch.distance.push(d);
            farthest_upper = farthest_upper.max(d + cluster.radius);
        }
        let mut nearest_lower = f64::INFINITY;
        for &v in &self.isolated_vertices {
            let d = self.positions[v as usize].distance(point);
            nearest_lower = nearest_lower.min(d);
            farthest_upper = farthest_upper.max(d);
        }
        let threshold = 2.0 * EPS * farthest_upper;
        for (cluster, &d) in self.clusters.iter().zip(&scratch.distance) {
            let gap = if d - cluster.radius > threshold {
                d - cluster.radius
            } else {
                self.cluster_triangles[cluster.start as usize..cluster.end as usize]
                    .iter()
                    .flat_map(|&t| self.triangles[t as usize])
                    .map(|v| self.positions[v as usize].distance(point))
                    .fold(f64::INFINITY, f64::min)
            };
            nearest_lower = nearest_lower.min(gap);
        }
        if nearest_lower > threshold {
            return false;
        }
        let mut nearest = f64::INFINITY;
        let mut farthest: f64 = 0.0;
        for p in self.positions {
            let d = p.distance(point);
            nearest = nearest.min(d);
            farthest = farthest.max(d);
        }
        nearest <= EPS * farthest
    }
}

/// Running sum of evaluated contributions W_e and of their magnitudes.
#[derive(Debug, Default)]
struct Sum {
    total: f64,
    magnitude: f64,
}

impl Sum {
    fn add(&mut self, w: [f64; 3]) {
        self.total += w[0] + w[1] + w[2];
        self.magnitude += w[0].abs() + w[1].abs() + w[2].abs();
    }

    /// Whether sign(W_e + rest) = sign(W_e) for any rest with |rest| ≤ `bound`.
    fn certain(&self, bound: f64) -> bool {
        self.total.is_finite()
            && bound.is_finite()
            && self.total.abs() > SAFETY * bound + ROUNDING * self.magnitude
    }
}

/// Indices `0..codes.len()` ordered by their 30-bit code (ties by index): LSD radix sort, three
/// stable passes of 10 bits.
fn sort_by_code(codes: &[u32]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..codes.len() as u32).collect();
    let mut next = vec![0u32; codes.len()];
    for shift in [0, 10, 20] {
        let digit = |t: u32| ((codes[t as usize] >> shift) & 0x3ff) as usize;
        let mut start = vec![0usize; 1025];
        for &t in &order {
            start[digit(t) + 1] += 1;
        }
        for d in 0..1024 {
            start[d + 1] += start[d];
        }
        for &t in &order {
            let d = digit(t);
            next[start[d]] = t;
            start[d] += 1;
        }
        std::mem::swap(&mut order, &mut next);
    }
    order
}

/// 30-bit Morton code of a point of the unit cube.
fn morton_code(unit: DVec3) -> u32 {
    let spread = |x: f64| -> u32 {
        let mut v = (x.clamp(0.0, 1.0) * 1023.0) as u32;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    };
    (spread(unit.x) << 2) | (spread(unit.y) << 1) | spread(unit.z)
}

#[cfg(test)]
#[path = "local_mvc_tests.rs"]
mod tests;
