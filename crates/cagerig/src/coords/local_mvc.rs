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
mod tests {
    use super::*;
    use crate::coords::mvc::mean_value_coordinates;
    use crate::coords::mvc::tests::icosphere;
    use proptest::prelude::*;

    /// Unnormalised weights of all vertices, summed and normalised, reproduce the MVC.
    fn check_against_full(pos: &[DVec3], tris: &[[u32; 3]], x: DVec3) {
        let local = LocalMvc::new(pos, tris);
        let mut scratch = local.scratch();
        let all: Vec<usize> = (0..pos.len()).collect();
        let mut w = vec![0.0; pos.len()];
        let sign = local
            .weights_at(x, &all, &mut scratch, &mut w)
            .expect("regular point");
        let total: f64 = w.iter().sum();
        assert_eq!(sign, total.signum());
        let mut full = vec![0.0; pos.len()];
        mean_value_coordinates(pos, tris, x, &mut full);
        for (a, b) in w.iter().zip(&full) {
            assert!((a / total - b).abs() < 1e-12 * (1.0 + b.abs()), "{a} {b}");
        }
        // A subset gives bitwise the same weights and the same sign.
        let subset: Vec<usize> = (0..pos.len()).step_by(5).collect();
        let mut ws = vec![0.0; subset.len()];
        assert_eq!(
            local.weights_at(x, &subset, &mut scratch, &mut ws),
            Some(sign)
        );
        for (k, &v) in subset.iter().enumerate() {
            assert_eq!(ws[k], w[v]);
        }
        // The scratch is clean again.
        assert!(scratch.weight.iter().all(|v| *v == 0.0));
        assert!(scratch.evaluated.iter().all(|e| *e == 0));
    }

    #[test]
    fn reproduces_full_mvc_inside_and_outside() {
        let radii: Vec<f64> = (0..42).map(|i| 1.0 + 0.1 * (i % 5) as f64).collect();
        let (pos, tris) = icosphere(&radii);
        for x in [
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(0.0, 0.0, 0.95),
            DVec3::new(3.0, 1.0, -2.0),
            DVec3::new(0.0, 1.2, 0.1),
        ] {
            check_against_full(&pos, &tris, x);
        }
    }

    #[test]
    fn sign_is_positive_inside_negative_outside() {
        // A long tube of many small triangles: most clusters are bounded, not evaluated.
        let (pos, tris) = tube(200, 24, 0.5, 0.05);
        let local = LocalMvc::new(&pos, &tris);
        let mut scratch = local.scratch();
        let vertices = vec![100 * 24 + 3, 100 * 24 + 4];
        let mut w = vec![0.0; 2];
        let inside = DVec3::new(0.1, 0.0, 5.0);
        assert_eq!(
            local.weights_at(inside, &vertices, &mut scratch, &mut w),
            Some(1.0)
        );
        assert!(w.iter().all(|v| *v > 0.0));
        let evaluated_inside = count_work(&local, inside, &vertices);
        assert!(
            evaluated_inside < tris.len() / 2,
            "{evaluated_inside} of {}",
            tris.len()
        );
        let outside = DVec3::new(1.5, 0.0, 5.0);
        assert_eq!(
            local.weights_at(outside, &vertices, &mut scratch, &mut w),
            Some(-1.0)
        );
        // Outside, W < 0: the full (normalised) coordinates are w / W.
        let mut full = vec![0.0; pos.len()];
        mean_value_coordinates(&pos, &tris, outside, &mut full);
        let ratio = w[0] / full[vertices[0]];
        assert!(ratio < 0.0);
        assert!((w[1] / full[vertices[1]] - ratio).abs() < 1e-9 * ratio.abs());
    }

    #[test]
    fn degenerate_points_need_the_full_function() {
        let (pos, tris) = icosphere(&[1.0]);
        let local = LocalMvc::new(&pos, &tris);
        let mut scratch = local.scratch();
        let mut w = vec![0.0; 1];
        let face = tris[7].map(|i| pos[i as usize]);
        for x in [
            pos[3],
            0.5 * (face[0] + face[1]),
            (face[0] + face[1] + face[2]) / 3.0,
        ] {
            // Far from the requested vertex too: found through the near clusters.
            assert_eq!(local.weights_at(x, &[41], &mut scratch, &mut w), None);
        }
    }

    #[test]
    fn open_mesh_seen_from_its_hole_is_uncertain_or_right() {
        // A hemisphere-like open cap: W changes sign across the hole; wherever a sign is
        // returned it must be that of the full sum.
        let (pos, tris) = icosphere(&[1.0]);
        let open: Vec<[u32; 3]> = tris
            .iter()
            .copied()
            .filter(|t| t.iter().any(|&i| pos[i as usize].z > 0.0))
            .collect();
        let local = LocalMvc::new(&pos, &open);
        let mut scratch = local.scratch();
        let all: Vec<usize> = (0..pos.len()).collect();
        let mut w = vec![0.0; pos.len()];
        for k in 0..40 {
            let x = DVec3::new(0.1, 0.05, -1.5 + 0.05 * k as f64);
            if let Some(sign) = local.weights_at(x, &all, &mut scratch, &mut w) {
                let total: f64 = w.iter().sum();
                assert_eq!(sign, total.signum(), "x = {x}");
            }
        }
    }

    #[test]
    fn triangle_contribution_is_bounded_by_area_over_distance_cubed() {
        let mut worst: f64 = 0.0;
        for i in 0..2000 {
            let f = i as f64;
            let p = [
                DVec3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 0.11).sin()),
                DVec3::new((f * 0.19).cos(), (f * 0.53).sin(), (f * 0.97).cos()),
                DVec3::new((f * 0.61).sin(), (f * 0.29).sin(), (f * 0.43).cos()),
            ];
            let x = DVec3::new((f * 1.3).sin(), (f * 2.1).cos(), (f * 0.7).sin()) * 2.0;
            let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            let dist = distance_to_triangle(x, p);
            if let TriangleWeights::Add(w) = mvc::triangle_weights(&p, [0, 1, 2], x) {
                let c = (w[0] + w[1] + w[2]).abs();
                worst = worst.max(c * dist.powi(3) / area);
            }
        }
        assert!(worst <= 1.0, "{worst}");
        assert!(worst > 0.1, "the bound should be reasonably tight: {worst}");
    }

    proptest! {
        #[test]
        fn subset_weights_match_full_mvc(
            radii in proptest::collection::vec(0.5f64..2.0, 42),
            dir in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            t in 0.0f64..3.0,
        ) {
            let (pos, tris) = icosphere(&radii);
            let d = DVec3::new(dir.0, dir.1, dir.2);
            prop_assume!(d.length() > 1e-3);
            let x = d.normalize() * t;
            let local = LocalMvc::new(&pos, &tris);
            let mut scratch = local.scratch();
            let subset: Vec<usize> = (0..pos.len()).step_by(3).collect();
            let mut w = vec![0.0; subset.len()];
            let mut full = vec![0.0; pos.len()];
            mean_value_coordinates(&pos, &tris, x, &mut full);
            if let Some(sign) = local.weights_at(x, &subset, &mut scratch, &mut w) {
                // Same direction as the normalised coordinates: w · sign = |W| · mvc.
                let scale = subset.iter().zip(&w).map(|(&v, wk)| wk * sign * full[v]).sum::<f64>();
                prop_assert!(scale > 0.0);
                let norm = w.iter().map(|v| v * v).sum::<f64>();
                let factor = norm / scale; // |W|
                for (k, &v) in subset.iter().enumerate() {
                    prop_assert!((w[k] * sign - factor * full[v]).abs() <= 1e-9 * norm.sqrt());
                }
            }
        }
    }

    fn count_work(local: &LocalMvc, x: DVec3, vertices: &[usize]) -> usize {
        let mut scratch = local.scratch();
        let mut w = vec![0.0; vertices.len()];
        assert!(!local.snapped(x, &mut scratch));
        local.certified_weights(x, vertices, &mut scratch, &mut w);
        scratch
            .evaluated
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// Closed tube along z: `rings × segments` vertices of radius `radius`, ring spacing `step`,
    /// capped by two fans.
    fn tube(rings: usize, segments: usize, radius: f64, step: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut pos = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let a = std::f64::consts::TAU * s as f64 / segments as f64;
                pos.push(DVec3::new(
                    radius * a.cos(),
                    radius * a.sin(),
                    step * r as f64,
                ));
            }
        }
        let bottom = pos.len() as u32;
        pos.push(DVec3::ZERO);
        let top = pos.len() as u32;
        pos.push(DVec3::new(0.0, 0.0, step * (rings - 1) as f64));
        let id = |r: usize, s: usize| (r * segments + s % segments) as u32;
        let mut tris = Vec::new();
        for r in 0..rings - 1 {
            for s in 0..segments {
                tris.push([id(r, s), id(r, s + 1), id(r + 1, s + 1)]);
                tris.push([id(r, s), id(r + 1, s + 1), id(r + 1, s)]);
            }
        }
        for s in 0..segments {
            tris.push([bottom, id(0, s + 1), id(0, s)]);
            tris.push([top, id(rings - 1, s), id(rings - 1, s + 1)]);
        }
        (pos, tris)
    }

    /// Euclidean distance from x to a triangle (closest point by regions, Ericson's method).
    fn distance_to_triangle(x: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
        let (ab, ac, ap) = (b - a, c - a, x - a);
        let (d1, d2) = (ab.dot(ap), ac.dot(ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return x.distance(a);
        }
        let bp = x - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        if d3 >= 0.0 && d4 <= d3 {
            return x.distance(b);
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return x.distance(a + ab * (d1 / (d1 - d3)));
        }
        let cp = x - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return x.distance(c);
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return x.distance(a + ac * (d2 / (d2 - d6)));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return x.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
        }
        let denom = 1.0 / (va + vb + vc);
        x.distance(a + ab * (vb * denom) + ac * (vc * denom))
    }
}
