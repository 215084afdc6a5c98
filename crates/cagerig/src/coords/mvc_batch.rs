//! Batched mean value coordinates: the regular (off-surface) case of [`super::mvc`] for
//! [`LANES`] points at a time, in structure-of-arrays layout so the compiler vectorises across
//! points (runtime-dispatched to AVX-512 / AVX2+FMA where available).
//!
//! Same formulation as [`MvcEvaluator::evaluate`]: per point x and cage vertex k, `u_k` and
//! `1/d_k`; per edge (a, b), `c = u_a × u_b`, θ = atan2(|c|, u_a·u_b) and `θ / (2|c|)`; per
//! triangle, the mean vector `m_T = Σ_j k_j c_j` in the basis u_i0, u_i1, u_i2. The arctangent is
//! the branch-free Cephes rational approximation with a single division per edge
//! ([`half_angle_over_sin`], a few ulp).
//!
//! Cost per batch of 8 points (58-vertex cage: 168 edges, 112 triangles): one reciprocal square
//! root per vertex, one reciprocal square root and one reciprocal per edge, one reciprocal per
//! triangle. On AVX-512 these use the 14-bit hardware estimates refined by two Newton steps
//! (≈ 1 ulp, several times cheaper than `vsqrtpd` / `vdivpd`); elsewhere plain `sqrt` and `/`.
//! Edges are evaluated lazily in triangle order (see [`BatchPlan`]) so the per-edge lane data is
//! consumed while still in L1.
//!
//! A lane is flagged (and recomputed by the robust scalar [`MvcEvaluator::evaluate`]) if its point
//! is near a vertex, on an edge line (`|c| < ε`), near a triangle's plane (`|det| < ε`) or the
//! weight sum is not usable — exactly the situations where the scalar code takes a special case.
//! Flagged lanes may hold NaN or ∞ (approximate reciprocals of 0); lanes never mix.

use glam::DVec3;

use super::lane_functions::angle_fraction;
use super::mvc::{EPS, MvcEvaluator, MvcScratch};
pub(crate) use super::mvc_lanes::LANES;
#[cfg(target_arch = "x86_64")]
use super::mvc_lanes::{Avx512Math, FusedMath};
use super::mvc_lanes::{LaneMath, Lanes, Mask, PlainMath, V8, dot, not, or, per_lane};
use crate::row_blocks::RowBlock;
use crate::simd_dispatch::simd_dispatch;

/// One cage triangle as the batch kernel reads it.
#[derive(Debug, Clone, Copy)]
struct BatchTriangle {
    /// Cage vertices (i0, i1, i2).
    vertices: [u32; 3],
    /// Per corner j: the edge opposite j, as an index into the edge arrays.
    edges: [u32; 3],
    /// Per corner j: +1, or −1 if the stored edge `(a, b)` runs against the triangle order.
    edge_sign: [f64; 3],
    /// Per corner j: `edge_sign[j] · edge_sign[0]` (det(u_i0, u_i1, u_i2) = ±u_i0·c_{e0}).
    corner_factor: [f64; 3],
}

/// Evaluation schedule: triangles in cage order, each preceded by the edges it is the first to
/// use (so every edge is computed once, right before its first triangle).
#[derive(Debug, Clone)]
struct BatchPlan {
    triangles: Vec<BatchTriangle>,
    /// Edges `(a, b)` in first-use order.
    edges: Vec<[u32; 2]>,
    /// `edges[edge_starts[t]..edge_starts[t + 1]]` are computed before triangle t.
    edge_starts: Vec<usize>,
}

impl BatchPlan {
    fn new(evaluator: &MvcEvaluator) -> Self {
        let mut renumbered = vec![u32::MAX; evaluator.edges.len()];
        let mut edges = Vec::with_capacity(evaluator.edges.len());
        let mut edge_starts = Vec::with_capacity(evaluator.triangles.len() + 1);
        let mut triangles = Vec::with_capacity(evaluator.triangles.len());
        for (tri, tri_edges) in evaluator.triangles.iter().zip(&evaluator.triangle_edges) {
            edge_starts.push(edges.len());
            let local = tri_edges.map(|(e, _)| {
                let e = e as usize;
                if renumbered[e] == u32::MAX {
                    renumbered[e] = edges.len() as u32;
                    edges.push(evaluator.edges[e]);
                }
                renumbered[e]
            });
            let edge_sign = tri_edges.map(|(_, reversed)| if reversed { -1.0 } else { 1.0 });
            triangles.push(BatchTriangle {
                vertices: *tri,
                edges: local,
                edge_sign,
                corner_factor: edge_sign.map(|s| s * edge_sign[0]),
            });
        }
        edge_starts.push(edges.len());
        Self {
            triangles,
            edges,
            edge_starts,
        }
    }
}

/// Per-thread buffers for [`evaluate_rows`].
#[derive(Debug, Clone)]
pub(crate) struct BatchScratch {
    plan: BatchPlan,
    /// Per cage vertex: u_k (x, y, z) and 1/d_k, per lane.
    unit_x: Vec<Lanes>,
    unit_y: Vec<Lanes>,
    unit_z: Vec<Lanes>,
    inv_dist: Vec<Lanes>,
    /// Per edge (plan order): c = u_a × u_b and θ / (2|c|), per lane.
    cross_x: Vec<Lanes>,
    cross_y: Vec<Lanes>,
    cross_z: Vec<Lanes>,
    half_angle_over_sin: Vec<Lanes>,
    /// Per cage vertex: unnormalised weights, per lane.
    weights: Vec<Lanes>,
    /// Fallback buffers.
    robust: MvcScratch,
    row: Vec<f64>,
}

impl BatchScratch {
    /// c = u_a × u_b of plan edge `e`, per lane, as (x, y, z).
    #[inline(always)]
    fn cross_of(&self, e: usize) -> [V8; 3] {
        [
            V8(self.cross_x[e]),
            V8(self.cross_y[e]),
            V8(self.cross_z[e]),
        ]
    }

    pub(crate) fn new(evaluator: &MvcEvaluator) -> Self {
        let (num_vertices, num_edges) = (evaluator.num_vertices(), evaluator.edges.len());
        let per_vertex = vec![[0.0; LANES]; num_vertices];
        let per_edge = vec![[0.0; LANES]; num_edges];
        Self {
            plan: BatchPlan::new(evaluator),
            unit_x: per_vertex.clone(),
            unit_y: per_vertex.clone(),
            unit_z: per_vertex.clone(),
            inv_dist: per_vertex.clone(),
            cross_x: per_edge.clone(),
            cross_y: per_edge.clone(),
            cross_z: per_edge.clone(),
            half_angle_over_sin: per_edge,
            weights: per_vertex,
            robust: evaluator.scratch(),
            row: vec![0.0; num_vertices],
        }
    }
}

simd_dispatch! {
    /// MVC of `points` (`n`) into the rows of `out` (`n × #C`). Every entry of `out` is written.
    /// Returns the first row (index into `points`) holding a non-finite weight, if any.
    pub(crate) fn evaluate_rows(
        evaluator: &MvcEvaluator,
        points: &[DVec3],
        scratch: &mut BatchScratch,
        out: &mut RowBlock,
    ) -> Option<usize> => evaluate_rows_generic::<PlainMath>;
    avx512f: evaluate_rows_avx512 => evaluate_rows_generic::<Avx512Math>;
    avx2_fma: evaluate_rows_avx2 => evaluate_rows_generic::<FusedMath>;
}

#[inline(always)]
fn evaluate_rows_generic<M: LaneMath>(
    evaluator: &MvcEvaluator,
    points: &[DVec3],
    scratch: &mut BatchScratch,
    out: &mut RowBlock,
) -> Option<usize> {
    debug_assert_eq!(out.nrows(), points.len());
    let num_cage = evaluator.num_vertices();
    let mut first_non_finite = None;
    for (batch, chunk) in points.chunks(LANES).enumerate() {
        let start = batch * LANES;
        let count = chunk.len();
        // Pad a short last batch with its last point.
        let lane_point = |l: usize| chunk[l.min(count - 1)];
        let px: Lanes = std::array::from_fn(|l| lane_point(l).x);
        let py: Lanes = std::array::from_fn(|l| lane_point(l).y);
        let pz: Lanes = std::array::from_fn(|l| lane_point(l).z);
        let (needs_robust, inv_total) = evaluate_batch::<M>(evaluator, &px, &py, &pz, scratch);
        let inv_total = V8(inv_total);
        let mut finite = Mask([u64::MAX; LANES]);
        for k in 0..num_cage {
            let normalised = V8(scratch.weights[k]) * inv_total;
            finite = Mask(per_lane!(0, |l| if normalised.0[l].is_finite() {
                finite.0[l]
            } else {
                0
            }));
            out.write_lanes(start, k, &normalised.0, count);
        }
        for (l, &point) in chunk.iter().enumerate() {
            if needs_robust.test(l) {
                let row = &mut scratch.row;
                evaluator.evaluate(point, &mut scratch.robust, row);
                for (k, &w) in row.iter().enumerate() {
                    out.write(start + l, k, &[w]);
                }
                finite.0[l] = if row.iter().all(|w| w.is_finite()) {
                    u64::MAX
                } else {
                    0
                };
            }
        }
        if first_non_finite.is_none() {
            first_non_finite = (0..count).find(|&l| !finite.test(l)).map(|l| start + l);
        }
    }
    first_non_finite
}

/// Unnormalised weights of the batch into `scratch.weights`; returns the lanes that need the
/// robust scalar path (their weights are garbage) and 1 / (sum of the weights) per lane.
#[inline(always)]
fn evaluate_batch<M: LaneMath>(
    evaluator: &MvcEvaluator,
    px: &Lanes,
    py: &Lanes,
    pz: &Lanes,
    scratch: &mut BatchScratch,
) -> (Mask, Lanes) {
    let (px, py, pz) = (V8(*px), V8(*py), V8(*pz));
    let mut nearest_sq = V8::splat(f64::INFINITY);
    let mut farthest_sq = V8::splat(0.0);
    for (k, p) in evaluator.positions.iter().enumerate() {
        let vx = V8::splat(p.x) - px;
        let vy = V8::splat(p.y) - py;
        let vz = V8::splat(p.z) - pz;
        let dist_sq = M::mul_add(vx, vx, M::mul_add(vy, vy, vz * vz));
        let inv = M::rsqrt(dist_sq);
        scratch.unit_x[k] = (vx * inv).0;
        scratch.unit_y[k] = (vy * inv).0;
        scratch.unit_z[k] = (vz * inv).0;
        scratch.inv_dist[k] = inv.0;
        nearest_sq = nearest_sq.min(dist_sq);
        farthest_sq = farthest_sq.max(dist_sq);
        scratch.weights[k] = [0.0; LANES];
    }
    // Same test as the scalar code (nearest ≤ ε · farthest), squared.
    let mut degenerate = not(nearest_sq.gt(farthest_sq * (EPS * EPS)));
    let plan = &scratch.plan;
    for (t, tri) in plan.triangles.iter().enumerate() {
        for e in plan.edge_starts[t]..plan.edge_starts[t + 1] {
            let [a, b] = plan.edges[e];
            let (a, b) = (a as usize, b as usize);
            let (ax, ay, az) = (
                V8(scratch.unit_x[a]),
                V8(scratch.unit_y[a]),
                V8(scratch.unit_z[a]),
            );
            let (bx, by, bz) = (
                V8(scratch.unit_x[b]),
                V8(scratch.unit_y[b]),
                V8(scratch.unit_z[b]),
            );
            let cx = M::mul_add(ay, bz, -(az * by));
            let cy = M::mul_add(az, bx, -(ax * bz));
            let cz = M::mul_add(ax, by, -(ay * bx));
            let sin_sq = M::mul_add(cx, cx, M::mul_add(cy, cy, cz * cz));
            let cos = M::mul_add(ax, bx, M::mul_add(ay, by, az * bz));
            // Near the edge's line: the scalar code decides (on the edge, or a tiny |c|).
            degenerate = or(degenerate, not(sin_sq.ge(V8::splat(EPS * EPS))));
            let inv_sin = M::rsqrt(sin_sq);
            let (numerator, denominator) = angle_fraction::<M>(sin_sq * inv_sin, cos);
            scratch.cross_x[e] = cx.0;
            scratch.cross_y[e] = cy.0;
            scratch.cross_z[e] = cz.0;
            scratch.half_angle_over_sin[e] = (numerator * M::recip(denominator) * inv_sin * 0.5).0;
        }
        let (v, e) = (tri.vertices, tri.edges);
        let idx = [v[0] as usize, v[1] as usize, v[2] as usize];
        let edges = [e[0] as usize, e[1] as usize, e[2] as usize];
        // Built element by element: `edges.map(..)` here compiled to a 576-byte memmove per
        // triangle (29 % of the kernel's time in a profile); and with no closures (`per_lane`
        // in `mvc_lanes.rs`).
        let cross = [
            scratch.cross_of(edges[0]),
            scratch.cross_of(edges[1]),
            scratch.cross_of(edges[2]),
        ];
        let k: [V8; 3] = [
            V8(scratch.half_angle_over_sin[edges[0]]) * tri.edge_sign[0],
            V8(scratch.half_angle_over_sin[edges[1]]) * tri.edge_sign[1],
            V8(scratch.half_angle_over_sin[edges[2]]) * tri.edge_sign[2],
        ];
        let u0 = [
            V8(scratch.unit_x[idx[0]]),
            V8(scratch.unit_y[idx[0]]),
            V8(scratch.unit_z[idx[0]]),
        ];
        // det(u_i0, u_i1, u_i2) = s0 · (u_i0 · c_e0); the sign s0 is in corner_factor.
        let det = dot::<M>(&u0, &cross[0]);
        degenerate = or(degenerate, not(det.abs().ge(V8::splat(EPS))));
        let mean: [V8; 3] = [
            dot::<M>(&k, &[cross[0][0], cross[1][0], cross[2][0]]),
            dot::<M>(&k, &[cross[0][1], cross[1][1], cross[2][1]]),
            dot::<M>(&k, &[cross[0][2], cross[1][2], cross[2][2]]),
        ];
        let inv_det = M::recip(det);
        for j in 0..3 {
            let scaled = dot::<M>(&cross[j], &mean) * inv_det * tri.corner_factor[j];
            let target = &mut scratch.weights[idx[j]];
            *target = M::mul_add(scaled, V8(scratch.inv_dist[idx[j]]), V8(*target)).0;
        }
    }
    let mut total = V8::splat(0.0);
    for w in &scratch.weights {
        total = total + V8(*w);
    }
    let usable = Mask(per_lane!(
        0,
        |l| if total.0[l] != 0.0 && total.0[l].is_finite() {
            u64::MAX
        } else {
            0
        }
    ));
    (or(degenerate, not(usable)), M::recip(total).0)
}

/// `θ / (2 sin θ)` with θ = atan2(sin, cos) ∈ [0, π] (see [`angle_fraction`]), for the sine and
/// cosine of the angle between two unit vectors. `sin = 0` gives ½ (the limit θ/sin θ → 1) when
/// `cos > 0`. Scalar reference of the batch kernel's per-edge term.
#[cfg(test)]
fn half_angle_over_sin(sin: f64, cos: f64) -> f64 {
    let (numerator, denominator) = angle_fraction::<PlainMath>(V8::splat(sin), V8::splat(cos));
    if sin > 0.0 {
        0.5 * numerator.0[0] / (denominator.0[0] * sin)
    } else {
        0.5
    }
}

#[cfg(test)]
#[expect(
    unsafe_code,
    reason = "the tests run every batch kernel tier the CPU has"
)]
mod tests {
    use super::*;

    /// Every instruction-set variant of the batch kernel agrees with the robust scalar evaluator
    /// (regular points, a point on a vertex and one on a face, a short last batch).
    #[test]
    fn all_lane_math_variants_match_scalar() {
        let radii: Vec<f64> = (0..42).map(|i| 1.0 + 0.1 * (i % 5) as f64).collect();
        let (pos, tris) = super::super::mvc::tests::icosphere(&radii);
        let evaluator = MvcEvaluator::new(&pos, &tris);
        let mut points: Vec<DVec3> = (0..45)
            .map(|i| {
                let f = i as f64;
                DVec3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 0.11).sin()) * 0.7
            })
            .collect();
        points[3] = pos[5];
        points[11] =
            (pos[tris[4][0] as usize] + pos[tris[4][1] as usize] + pos[tris[4][2] as usize]) / 3.0;
        let (n, c) = (points.len(), pos.len());
        let check = |name: &str, values: &[f64]| {
            let mut robust = evaluator.scratch();
            let mut expected = vec![0.0; c];
            for (i, &x) in points.iter().enumerate() {
                evaluator.evaluate(x, &mut robust, &mut expected);
                for k in 0..c {
                    let got = values[k * n + i];
                    assert!((got - expected[k]).abs() < 1e-12, "{name}: row {i} col {k}");
                }
            }
        };
        let run = |variant: u8| -> Vec<f64> {
            let mut values = vec![f64::NAN; n * c];
            let mut scratch = BatchScratch::new(&evaluator);
            // SAFETY: `values` is n × c column-major, owned here.
            let mut out = unsafe { RowBlock::new(values.as_mut_ptr(), n, n, c) };
            let bad = match variant {
                0 => {
                    evaluate_rows_generic::<PlainMath>(&evaluator, &points, &mut scratch, &mut out)
                }
                #[cfg(target_arch = "x86_64")]
                1 if crate::simd_dispatch::cpu().avx2_fma() =>
                // SAFETY: features checked.
                unsafe { evaluate_rows_avx2(&evaluator, &points, &mut scratch, &mut out) },
                #[cfg(target_arch = "x86_64")]
                2 if crate::simd_dispatch::cpu().avx512f() =>
                // SAFETY: feature checked.
                unsafe { evaluate_rows_avx512(&evaluator, &points, &mut scratch, &mut out) },
                _ => return Vec::new(),
            };
            assert_eq!(bad, None);
            values
        };
        for (variant, name) in [(0, "plain"), (1, "avx2+fma"), (2, "avx512")] {
            let values = run(variant);
            if !values.is_empty() {
                check(name, &values);
            }
        }
    }

    #[test]
    fn half_angle_over_sin_matches_libm() {
        let mut worst = 0.0f64;
        for i in 1..400_000 {
            let theta = std::f64::consts::PI * i as f64 / 400_000.0;
            let (s, c) = (theta.sin(), theta.cos());
            let exact = 0.5 * s.atan2(c) / s;
            let err = (half_angle_over_sin(s, c) - exact).abs() / exact;
            worst = worst.max(err);
        }
        assert!(worst < 2e-15, "worst relative error {worst:e}");
        // Tiny angles (θ/sin θ → 1) and the branch boundaries.
        for theta in [1e-12, 1e-8, 1e-4, 0.5829, 0.5830, 1.1781, 1.1782, 3.0] {
            let (s, c) = (f64::sin(theta), f64::cos(theta));
            let exact = 0.5 * s.atan2(c) / s;
            assert!(
                (half_angle_over_sin(s, c) - exact).abs() <= 2e-15 * exact,
                "{theta}"
            );
        }
        assert_eq!(half_angle_over_sin(0.0, 1.0), 0.5);
        assert!((half_angle_over_sin(1.0, 0.0) - std::f64::consts::FRAC_PI_4).abs() < 2e-16);
    }
}
