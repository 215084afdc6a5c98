//! Batched mean value coordinates: the regular (off-surface) case of [`super::mvc`] for
//! [`LANES`] points at a time, in structure-of-arrays layout so the compiler vectorises across
//! points (runtime-dispatched to AVX-512 / AVX2 where available).
//!
//! Same formulation as [`MvcEvaluator::evaluate`]: per point x and cage vertex k, `u_k` and
//! `1/d_k`; per edge (a, b), `c = u_a × u_b`, θ = atan2(|c|, u_a·u_b) and `θ / (2|c|)`; per
//! triangle, the mean vector `m_T = Σ_j k_j c_j` in the basis u_i0, u_i1, u_i2. The arctangent is
//! the branch-free Cephes rational approximation with a single division per edge
//! ([`half_angle_over_sin`], a few ulp).
//!
//! A lane is flagged (and recomputed by the robust scalar [`MvcEvaluator::evaluate`]) if its point
//! is near a vertex, on an edge line (`|c| < ε`), near a triangle's plane (`|det| < ε`) or the
//! weight sum is not usable — exactly the situations where the scalar code takes a special case.

use faer::MatMut;
use glam::DVec3;

use super::mvc::{EPS, MvcEvaluator, MvcScratch};

/// Points per batch.
pub(crate) const LANES: usize = 8;

type Lanes = [f64; LANES];

/// Per-thread buffers for [`evaluate_rows`].
#[derive(Debug, Clone)]
pub(crate) struct BatchScratch {
    /// Per cage vertex: u_k (x, y, z) and 1/d_k, per lane.
    unit_x: Vec<Lanes>,
    unit_y: Vec<Lanes>,
    unit_z: Vec<Lanes>,
    inv_dist: Vec<Lanes>,
    /// Per edge: c = u_a × u_b and θ / (2|c|), per lane.
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
    pub(crate) fn new(evaluator: &MvcEvaluator) -> Self {
        let (num_vertices, num_edges) = (evaluator.num_vertices(), evaluator.edges.len());
        let per_vertex = vec![[0.0; LANES]; num_vertices];
        let per_edge = vec![[0.0; LANES]; num_edges];
        Self {
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

/// MVC of `points` (`n`) into the rows of `out` (`n × #C`, any strides).
pub(crate) fn evaluate_rows(
    evaluator: &MvcEvaluator,
    points: &[DVec3],
    scratch: &mut BatchScratch,
    out: MatMut<'_, f64>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports the enabled feature (checked just above).
            return unsafe { evaluate_rows_avx512(evaluator, points, scratch, out) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { evaluate_rows_avx2(evaluator, points, scratch, out) };
        }
    }
    evaluate_rows_generic(evaluator, points, scratch, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn evaluate_rows_avx512(
    evaluator: &MvcEvaluator,
    points: &[DVec3],
    scratch: &mut BatchScratch,
    out: MatMut<'_, f64>,
) {
    evaluate_rows_generic(evaluator, points, scratch, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn evaluate_rows_avx2(
    evaluator: &MvcEvaluator,
    points: &[DVec3],
    scratch: &mut BatchScratch,
    out: MatMut<'_, f64>,
) {
    evaluate_rows_generic(evaluator, points, scratch, out)
}

#[inline(always)]
fn evaluate_rows_generic(
    evaluator: &MvcEvaluator,
    points: &[DVec3],
    scratch: &mut BatchScratch,
    mut out: MatMut<'_, f64>,
) {
    debug_assert_eq!(out.nrows(), points.len());
    let num_cage = evaluator.num_vertices();
    for (batch, chunk) in points.chunks(LANES).enumerate() {
        let start = batch * LANES;
        // Pad a short last batch with its last point.
        let lane_point = |l: usize| chunk[l.min(chunk.len() - 1)];
        let px: Lanes = std::array::from_fn(|l| lane_point(l).x);
        let py: Lanes = std::array::from_fn(|l| lane_point(l).y);
        let pz: Lanes = std::array::from_fn(|l| lane_point(l).z);
        let needs_robust = evaluate_batch(evaluator, &px, &py, &pz, scratch);
        for k in 0..num_cage {
            let w = &scratch.weights[k];
            for (l, &value) in w.iter().enumerate().take(chunk.len()) {
                out[(start + l, k)] = value;
            }
        }
        for (l, &point) in chunk.iter().enumerate() {
            if needs_robust[l] {
                evaluator.evaluate(point, &mut scratch.robust, &mut scratch.row);
                for (k, &w) in scratch.row.iter().enumerate() {
                    out[(start + l, k)] = w;
                }
            }
        }
    }
}

/// Normalised weights of the batch into `scratch.weights`; returns the lanes that need the
/// robust scalar path (their weights are garbage).
#[inline(always)]
fn evaluate_batch(
    evaluator: &MvcEvaluator,
    px: &Lanes,
    py: &Lanes,
    pz: &Lanes,
    scratch: &mut BatchScratch,
) -> [bool; LANES] {
    let mut nearest = [f64::INFINITY; LANES];
    let mut farthest = [0.0f64; LANES];
    for (k, p) in evaluator.positions.iter().enumerate() {
        let vx: Lanes = std::array::from_fn(|l| p.x - px[l]);
        let vy: Lanes = std::array::from_fn(|l| p.y - py[l]);
        let vz: Lanes = std::array::from_fn(|l| p.z - pz[l]);
        let dist: Lanes =
            std::array::from_fn(|l| (vx[l] * vx[l] + vy[l] * vy[l] + vz[l] * vz[l]).sqrt());
        let inv: Lanes = std::array::from_fn(|l| 1.0 / dist[l]);
        scratch.unit_x[k] = std::array::from_fn(|l| vx[l] * inv[l]);
        scratch.unit_y[k] = std::array::from_fn(|l| vy[l] * inv[l]);
        scratch.unit_z[k] = std::array::from_fn(|l| vz[l] * inv[l]);
        scratch.inv_dist[k] = inv;
        nearest = std::array::from_fn(|l| {
            if dist[l] < nearest[l] {
                dist[l]
            } else {
                nearest[l]
            }
        });
        farthest = std::array::from_fn(|l| {
            if dist[l] > farthest[l] {
                dist[l]
            } else {
                farthest[l]
            }
        });
        scratch.weights[k] = [0.0; LANES];
    }
    let mut degenerate = [false; LANES];
    for l in 0..LANES {
        degenerate[l] = nearest[l] <= EPS * farthest[l];
    }
    for (e, &[a, b]) in evaluator.edges.iter().enumerate() {
        let (a, b) = (a as usize, b as usize);
        let (ax, ay, az) = (scratch.unit_x[a], scratch.unit_y[a], scratch.unit_z[a]);
        let (bx, by, bz) = (scratch.unit_x[b], scratch.unit_y[b], scratch.unit_z[b]);
        let mut cx = [0.0; LANES];
        let mut cy = [0.0; LANES];
        let mut cz = [0.0; LANES];
        let mut k = [0.0; LANES];
        for l in 0..LANES {
            cx[l] = ay[l] * bz[l] - az[l] * by[l];
            cy[l] = az[l] * bx[l] - ax[l] * bz[l];
            cz[l] = ax[l] * by[l] - ay[l] * bx[l];
            let sin = (cx[l] * cx[l] + cy[l] * cy[l] + cz[l] * cz[l]).sqrt();
            let cos = ax[l] * bx[l] + ay[l] * by[l] + az[l] * bz[l];
            k[l] = half_angle_over_sin(sin, cos);
            // Near the edge's line: the scalar code decides (on the edge, or a tiny |c|).
            degenerate[l] |= sin < EPS;
        }
        scratch.cross_x[e] = cx;
        scratch.cross_y[e] = cy;
        scratch.cross_z[e] = cz;
        scratch.half_angle_over_sin[e] = k;
    }
    for (tri, tri_edges) in evaluator.triangles.iter().zip(&evaluator.triangle_edges) {
        let idx = tri.map(|i| i as usize);
        let [e0, e1, e2] = tri_edges.map(|(e, _)| e as usize);
        let sign = tri_edges.map(|(_, reversed)| if reversed { -1.0 } else { 1.0 });
        let (u0x, u0y, u0z) = (
            &scratch.unit_x[idx[0]],
            &scratch.unit_y[idx[0]],
            &scratch.unit_z[idx[0]],
        );
        let inv = idx.map(|i| scratch.inv_dist[i]);
        let mut w = [[0.0; LANES]; 3];
        for l in 0..LANES {
            let c0 = [
                sign[0] * scratch.cross_x[e0][l],
                sign[0] * scratch.cross_y[e0][l],
                sign[0] * scratch.cross_z[e0][l],
            ];
            let c1 = [
                sign[1] * scratch.cross_x[e1][l],
                sign[1] * scratch.cross_y[e1][l],
                sign[1] * scratch.cross_z[e1][l],
            ];
            let c2 = [
                sign[2] * scratch.cross_x[e2][l],
                sign[2] * scratch.cross_y[e2][l],
                sign[2] * scratch.cross_z[e2][l],
            ];
            let (k0, k1, k2) = (
                scratch.half_angle_over_sin[e0][l],
                scratch.half_angle_over_sin[e1][l],
                scratch.half_angle_over_sin[e2][l],
            );
            let det = u0x[l] * c0[0] + u0y[l] * c0[1] + u0z[l] * c0[2];
            degenerate[l] |= det.abs() < EPS;
            let mean = [
                k0 * c0[0] + k1 * c1[0] + k2 * c2[0],
                k0 * c0[1] + k1 * c1[1] + k2 * c2[1],
                k0 * c0[2] + k1 * c1[2] + k2 * c2[2],
            ];
            let inv_det = 1.0 / det;
            let dot = |c: [f64; 3]| c[0] * mean[0] + c[1] * mean[1] + c[2] * mean[2];
            w[0][l] = dot(c0) * inv_det * inv[0][l];
            w[1][l] = dot(c1) * inv_det * inv[1][l];
            w[2][l] = dot(c2) * inv_det * inv[2][l];
        }
        for j in 0..3 {
            let target = &mut scratch.weights[idx[j]];
            for l in 0..LANES {
                target[l] += w[j][l];
            }
        }
    }
    let mut total = [0.0; LANES];
    for w in &scratch.weights {
        for l in 0..LANES {
            total[l] += w[l];
        }
    }
    let mut inv_total = [0.0; LANES];
    for l in 0..LANES {
        degenerate[l] |= !(total[l] != 0.0 && total[l].is_finite());
        inv_total[l] = 1.0 / total[l];
    }
    for w in &mut scratch.weights {
        for l in 0..LANES {
            w[l] *= inv_total[l];
        }
    }
    degenerate
}

/// Cephes `atan` coefficients: atan x = x + x·z·P(z)/Q(z), z = x², |x| ≤ 0.66.
const ATAN_P: [f64; 5] = [
    -8.750_608_600_031_904e-1,
    -1.615_753_718_733_365e1,
    -7.500_855_792_314_705e1,
    -1.228_866_684_490_136e2,
    -6.485_021_904_942_025e1,
];
const ATAN_Q: [f64; 5] = [
    2.485_846_490_142_306e1,
    1.650_270_098_316_988_5e2,
    4.328_810_604_912_903e2,
    4.853_903_996_359_137e2,
    1.945_506_571_482_614e2,
];
/// Low part of π/2 (π/2 = FRAC_PI_2 + this, to ~1e-33).
const FRAC_PI_2_LOW: f64 = 6.123_233_995_736_766e-17;

/// `θ / (2 sin θ)` with θ = atan2(sin, cos) ∈ [0, π], for the sine and cosine of the angle
/// between two unit vectors (`sin ≥ 0`, `sin² + cos² ≈ 1`; other inputs give garbage, never a
/// trap). Branch-free (selects only) with ONE division: the Cephes reduction of t = sin/|cos| to
/// x = num/den ∈ {t, (t−1)/(t+1), −1/t} (|x| ≤ 0.66, den ∈ [0.8, 2]) and the rational
/// approximation atan x = x + x·z·P(z)/Q(z), z = x², written homogeneously in (num, den):
/// atan x = num·(Q̃ + num²·P̃) / (den·Q̃) with P̃ = den⁸ P(z), Q̃ = den¹⁰ Q(z). Relative error a
/// few ulp. `sin = 0` gives ½ (the limit θ/sin θ → 1) when `cos > 0`.
#[inline(always)]
pub(crate) fn half_angle_over_sin(sin: f64, cos: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let abs_cos = cos.abs();
    let big = sin > 2.414_213_562_373_095 * abs_cos;
    let mid = sin > 0.66 * abs_cos;
    let (num, den, base, low) = if big {
        (-abs_cos, sin, FRAC_PI_2, FRAC_PI_2_LOW)
    } else if mid {
        (sin - abs_cos, sin + abs_cos, FRAC_PI_4, 0.5 * FRAC_PI_2_LOW)
    } else {
        (sin, abs_cos, 0.0, 0.0)
    };
    // θ = base + atan x (cos ≥ 0) or π − base − atan x (cos < 0).
    let (sign, offset) = if cos < 0.0 {
        (-1.0, (PI - base) - low)
    } else {
        (1.0, base + low)
    };
    let (n2, d2) = (num * num, den * den);
    let (d4, d6, d8) = (d2 * d2, d2 * d2 * d2, d2 * d2 * d2 * d2);
    let p = (((ATAN_P[0] * n2 + ATAN_P[1] * d2) * n2 + ATAN_P[2] * d4) * n2 + ATAN_P[3] * d6) * n2
        + ATAN_P[4] * d8;
    let q = ((((n2 + ATAN_Q[0] * d2) * n2 + ATAN_Q[1] * d4) * n2 + ATAN_Q[2] * d6) * n2
        + ATAN_Q[3] * d8)
        * n2
        + ATAN_Q[4] * d8 * d2;
    let den_q = den * q;
    let theta_times_den_q = offset * den_q + sign * num * (q + n2 * p);
    if sin > 0.0 {
        0.5 * theta_times_den_q / (den_q * sin)
    } else {
        0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
