//! Batched Green coordinates: the closed forms of [`super::green_triangle`] for [`LANES`] points
//! at a time, one point per lane, with everything that depends only on the cage computed once
//! ([`GreenBatchPlan`]) and everything that depends on one point and one cage vertex or edge
//! computed once per batch and shared by the faces around it.
//!
//! Per batch of 8 points η:
//! - per cage vertex k: `a_k = v_k − η` and `|a_k|`;
//! - per cage edge (a, b), all of them before the faces (independent iterations, which the
//!   processor overlaps; their lanes, 64 bytes per edge, stay in L1): the edge integral
//!   `f = ∫_edge ds/R`, one logarithm ([`ln_of_quotient`]); it does not depend on the direction
//!   of travel, so the two faces of an edge share it (the per-point code takes one per face and
//!   edge). Beside the edge (foot of η on the segment) the distance² to its line is `|a_a × e|²`,
//!   which has no cancellation (the per-point code's `(R − s)(R + s)` loses `(R/d)²` ulp). Also
//!   `a_a·a_b`, which both faces' solid angles use;
//! - per face t: `h = a₀·n`, the solid angle Ω (one arctangent fraction, [`angle_fraction`], one
//!   reciprocal) with Van Oosterom & Strackee's triple product taken as `a₀·(a₁ × a₂) = 2A h`
//!   (no cross product, and an error of ε·2A|a₀| instead of ε|a₀||a₁||a₂|),
//!   `ψ_t = (Σ_l (a_l·m_l) f_l − |h||Ω|)/4π` written straight into ψ's column, and
//!   `φ_i += (Γ_i(ρ) Ω − h Σ_l (∇Γ_i·m_l) f_l)/4π` with `Γ_i(ρ) = −∇Γ_i·a_{i+1}` (the foot ρ's
//!   barycentric coordinate) and the products `∇Γ_i·m_l/4π` precomputed per face, for corners 0
//!   and 1; corner 2's follow from the partition of unity (`Γ₂ = 1 − Γ₀ − Γ₁`,
//!   `∇Γ₂ = −∇Γ₀ − ∇Γ₁`).
//!
//! The lane arithmetic is a type parameter ([`LaneMath`]), as in MVC's kernel: the baseline is
//! plain IEEE; the AVX2 + FMA tier fuses multiplies and adds; the AVX-512 tier also takes its
//! reciprocals from `vrcp14pd` refined by two Newton steps (about an ulp) instead of dividing.
//! The tiers agree to rounding (1e-13 relative to `1 + |entry|`, tested; a point 1e-7 of an
//! edge's length from an edge, where a solid angle is conditioned to ~ε·size/d, to 1e-9). One
//! machine always runs one tier, so its results are reproducible there. What each choice is
//! worth (fused multiply-adds, the reciprocal, the edges computed ahead of the faces, the triple
//! product as 2A h, the dot products per edge, AVX-512's `vgetmantpd`/`vgetexppd` in the
//! logarithm, corner 2 from the partition of unity): docs/green-measurements.md; together they
//! bind the Arm at 133k vertices in about 100 ms (`green_bind_bench 3`; MVC about 60 ms).
//!
//! A lane is recomputed by the per-point closed forms ([`GreenTriangle::terms`], whole row) when
//! its point lies within [`ON_PLANE`] (relative) of a face's plane or of a cage vertex, where
//! those take their limits; lanes never mix, and flagged lanes may hold NaN before that.

use glam::DVec3;

use super::green_triangle::{GreenTriangle, INV_FOUR_PI, ON_PLANE};
use super::lane_functions::{angle_fraction, ln_of_quotient};
#[cfg(target_arch = "x86_64")]
use super::mvc_lanes::{Avx512Math, FusedMath};
use super::mvc_lanes::{LANES, LaneMath, Lanes, Mask, PlainMath, V8, not, or, per_lane};
use crate::row_blocks::RowBlock;
use crate::simd_dispatch::simd_dispatch;

/// One cage edge as the batch kernel reads it.
#[derive(Debug, Clone, Copy)]
struct PlanEdge {
    /// Cage vertices (a, b), a < b.
    ends: [u32; 2],
    /// Unit direction e = (v_b − v_a)/|v_b − v_a|.
    direction: [f64; 3],
}

/// One non-degenerate cage face (outward, counter-clockwise seen from outside) as the batch
/// kernel reads it; vectors as `[x, y, z]`.
#[derive(Debug, Clone, Copy)]
struct PlanFace {
    /// Its column of ψ (its index among the outward triangles).
    column: u32,
    /// Cage vertices (i₀, i₁, i₂).
    vertices: [u32; 3],
    /// Per local edge l (from corner l to corner l+1): its index in [`GreenBatchPlan::edges`].
    edges: [u32; 3],
    /// Unit outward normal n.
    normal: [f64; 3],
    /// Twice its area, 2A = |(v₁ − v₀) × (v₂ − v₀)|.
    twice_area: f64,
    /// Per local edge l: the outward in-plane normal m_l.
    edge_normals: [[f64; 3]; 3],
    /// Per corner i = 0, 1: −∇Γ_i/4π, with ∇Γ_i the in-plane gradient of its hat function
    /// (corner 2's follows from Σ_i Γ_i = 1).
    scaled_hat_gradients: [[f64; 3]; 2],
    /// `[i][l]` for i = 0, 1: ∇Γ_i · m_l / 4π (corner 2's are minus their sum: Σ_i ∇Γ_i = 0).
    scaled_hat_slopes: [[f64; 3]; 2],
}

/// What the batch kernel needs of a cage, computed once: the faces in cage order, the edges in
/// the order of their first use, and the per-point frames for the recomputed lanes.
#[derive(Debug, Clone)]
pub(crate) struct GreenBatchPlan<'a> {
    positions: &'a [DVec3],
    /// The outward triangles, `#F`.
    triangles: &'a [[u32; 3]],
    /// Per outward triangle: its frame (`None`: degenerate, contributes nothing), `#F`.
    frames: &'a [Option<GreenTriangle>],
    faces: Vec<PlanFace>,
    /// Edges in first-use order.
    edges: Vec<PlanEdge>,
    /// The columns of ψ of the degenerate triangles (always 0).
    degenerate_columns: Vec<u32>,
}

impl<'a> GreenBatchPlan<'a> {
    /// The plan of the cage `positions` with the outward `triangles` and their `frames`
    /// (`GreenTriangle::new` of each).
    pub(crate) fn new(
        positions: &'a [DVec3],
        triangles: &'a [[u32; 3]],
        frames: &'a [Option<GreenTriangle>],
    ) -> Self {
        let mut edge_index = std::collections::HashMap::<[u32; 2], u32>::new();
        let mut edges = Vec::new();
        let mut faces = Vec::with_capacity(triangles.len());
        let mut degenerate_columns = Vec::new();
        for (column, (tri, frame)) in triangles.iter().zip(frames).enumerate() {
            let Some(frame) = frame else {
                degenerate_columns.push(column as u32);
                continue;
            };
            let local_edges = std::array::from_fn(|l| {
                let (a, b) = (tri[l], tri[(l + 1) % 3]);
                let ends = [a.min(b), a.max(b)];
                *edge_index.entry(ends).or_insert_with(|| {
                    let [pa, pb] = ends.map(|v| positions[v as usize]);
                    edges.push(PlanEdge {
                        ends,
                        direction: (pb - pa).normalize_or_zero().to_array(),
                    });
                    (edges.len() - 1) as u32
                })
            });
            faces.push(PlanFace {
                column: column as u32,
                vertices: *tri,
                edges: local_edges,
                normal: frame.normal.to_array(),
                twice_area: frame.twice_area,
                edge_normals: frame.edge_normals.map(|m| m.to_array()),
                scaled_hat_gradients: [0, 1]
                    .map(|i| (-frame.hat_gradients[i] * INV_FOUR_PI).to_array()),
                scaled_hat_slopes: [0, 1].map(|i| {
                    frame
                        .edge_normals
                        .map(|m| frame.hat_gradients[i].dot(m) * INV_FOUR_PI)
                }),
            });
        }
        Self {
            positions,
            triangles,
            frames,
            faces,
            edges,
            degenerate_columns,
        }
    }
}

/// Per-thread buffers of [`evaluate_green_rows`].
#[derive(Debug, Clone)]
pub(crate) struct GreenBatchScratch {
    /// Per cage vertex: a_k = v_k − η (x, y, z) and |a_k|, per lane.
    to_x: Vec<Lanes>,
    to_y: Vec<Lanes>,
    to_z: Vec<Lanes>,
    length: Vec<Lanes>,
    /// Per cage vertex: φ being summed over the faces, per lane.
    vertex_sums: Vec<Lanes>,
    /// Per edge (plan order): ∫_edge ds/R, per lane.
    edge_integrals: Vec<Lanes>,
    /// Per edge (a, b) (plan order): a_a · a_b, per lane.
    edge_dots: Vec<Lanes>,
    /// One row of φ (`#C`) and of ψ (`#F`) for a recomputed lane.
    row_vertex: Vec<f64>,
    row_face: Vec<f64>,
}

impl GreenBatchScratch {
    /// a_k = v_k − η per lane, as (x, y, z).
    #[inline(always)]
    fn to_vertex(&self, k: usize) -> [V8; 3] {
        [V8(self.to_x[k]), V8(self.to_y[k]), V8(self.to_z[k])]
    }

    pub(crate) fn new(plan: &GreenBatchPlan<'_>) -> Self {
        let per_vertex = vec![[0.0; LANES]; plan.positions.len()];
        Self {
            to_x: per_vertex.clone(),
            to_y: per_vertex.clone(),
            to_z: per_vertex.clone(),
            length: per_vertex.clone(),
            vertex_sums: per_vertex,
            edge_integrals: vec![[0.0; LANES]; plan.edges.len()],
            edge_dots: vec![[0.0; LANES]; plan.edges.len()],
            row_vertex: vec![0.0; plan.positions.len()],
            row_face: vec![0.0; plan.triangles.len()],
        }
    }
}

simd_dispatch! {
    /// Green coordinates of `points` (`n`): φ into the rows of `vertex_out` (`n × #C`) and ψ
    /// into the rows of `face_out` (`n × #F`, the plan's triangle order). Every entry of both
    /// is written. Returns the first row (index into `points`) holding a non-finite value, if
    /// any.
    pub(crate) fn evaluate_green_rows(
        plan: &GreenBatchPlan<'_>,
        points: &[DVec3],
        scratch: &mut GreenBatchScratch,
        vertex_out: &mut RowBlock,
        face_out: &mut RowBlock,
    ) -> Option<usize> => evaluate_green_rows_generic::<PlainMath>;
    avx512f: evaluate_green_rows_avx512 => evaluate_green_rows_generic::<Avx512Math>;
    avx2_fma: evaluate_green_rows_avx2 => evaluate_green_rows_generic::<FusedMath>;
}

#[inline(always)]
fn evaluate_green_rows_generic<M: LaneMath>(
    plan: &GreenBatchPlan<'_>,
    points: &[DVec3],
    scratch: &mut GreenBatchScratch,
    vertex_out: &mut RowBlock,
    face_out: &mut RowBlock,
) -> Option<usize> {
    debug_assert_eq!(vertex_out.nrows(), points.len());
    debug_assert_eq!(face_out.nrows(), points.len());
    let mut first_non_finite = None;
    for (batch, chunk) in points.chunks(LANES).enumerate() {
        let start = batch * LANES;
        let count = chunk.len();
        // Pad a short last batch with its last point.
        let lane_point = |l: usize| chunk[l.min(count - 1)];
        let px = V8(std::array::from_fn(|l| lane_point(l).x));
        let py = V8(std::array::from_fn(|l| lane_point(l).y));
        let pz = V8(std::array::from_fn(|l| lane_point(l).z));
        let (recompute, face_check) =
            evaluate_batch::<M>(plan, [px, py, pz], scratch, face_out, start, count);
        // `0·x` is ±0 for a finite x and NaN otherwise: the sums stay 0 iff all are finite.
        let mut check = face_check;
        for (k, sums) in scratch.vertex_sums.iter().enumerate() {
            let value = V8(*sums);
            check = check + value * 0.0;
            vertex_out.write_lanes(start, k, &value.0, count);
        }
        for column in &plan.degenerate_columns {
            face_out.write_lanes(start, *column as usize, &[0.0; LANES], count);
        }
        let mut finite = Mask::from_fn(|l| check.0[l] == 0.0);
        for (l, &point) in chunk.iter().enumerate() {
            if recompute.test(l) {
                let all_finite = evaluate_point(plan, point, scratch);
                for (k, &w) in scratch.row_vertex.iter().enumerate() {
                    vertex_out.write(start + l, k, &[w]);
                }
                for (t, &w) in scratch.row_face.iter().enumerate() {
                    face_out.write(start + l, t, &[w]);
                }
                finite.0[l] = if all_finite { u64::MAX } else { 0 };
            }
        }
        if first_non_finite.is_none() {
            first_non_finite = (0..count).find(|&l| !finite.test(l)).map(|l| start + l);
        }
    }
    first_non_finite
}

/// One row of Green coordinates by the per-point closed forms into `scratch.row_vertex` and
/// `scratch.row_face`; whether every value is finite.
fn evaluate_point(plan: &GreenBatchPlan<'_>, eta: DVec3, scratch: &mut GreenBatchScratch) -> bool {
    let (phi, psi) = (&mut scratch.row_vertex, &mut scratch.row_face);
    phi.fill(0.0);
    for ((t, frame), psi_t) in plan.triangles.iter().zip(plan.frames).zip(psi.iter_mut()) {
        *psi_t = 0.0;
        if let Some(frame) = frame {
            let terms = frame.terms(eta);
            *psi_t = terms.face;
            for (v, part) in t.iter().zip(terms.vertices) {
                phi[*v as usize] += part;
            }
        }
    }
    phi.iter().chain(psi.iter()).all(|w| w.is_finite())
}

/// The lanes of one batch: φ summed into `scratch.vertex_sums`, ψ written into `face_out` (rows
/// `start..start + count`, the columns of the non-degenerate faces). Returns the lanes to
/// recompute per point and, per lane, the sum of `0·ψ` (0 iff every ψ is finite).
#[inline(always)]
fn evaluate_batch<M: LaneMath>(
    plan: &GreenBatchPlan<'_>,
    eta: [V8; 3],
    scratch: &mut GreenBatchScratch,
    face_out: &mut RowBlock,
    start: usize,
    count: usize,
) -> (Mask, V8) {
    let splat = V8::splat;
    for (k, p) in plan.positions.iter().enumerate() {
        let ax = splat(p.x) - eta[0];
        let ay = splat(p.y) - eta[1];
        let az = splat(p.z) - eta[2];
        let length = M::mul_add(ax, ax, M::mul_add(ay, ay, az * az)).sqrt();
        scratch.to_x[k] = ax.0;
        scratch.to_y[k] = ay.0;
        scratch.to_z[k] = az.0;
        scratch.length[k] = length.0;
        scratch.vertex_sums[k] = [0.0; LANES];
    }
    let mut recompute = Mask([0; LANES]);
    let mut check = splat(0.0);
    for (e, edge) in plan.edges.iter().enumerate() {
        let (integral, ends_dot) = edge_integral::<M>(edge, scratch);
        scratch.edge_integrals[e] = integral.0;
        scratch.edge_dots[e] = ends_dot.0;
    }
    for face in &plan.faces {
        let v = face.vertices;
        let idx = [v[0] as usize, v[1] as usize, v[2] as usize];
        // Built element by element (an array `map` here may compile to a memmove).
        let a = [
            scratch.to_vertex(idx[0]),
            scratch.to_vertex(idx[1]),
            scratch.to_vertex(idx[2]),
        ];
        let lengths = [
            V8(scratch.length[idx[0]]),
            V8(scratch.length[idx[1]]),
            V8(scratch.length[idx[2]]),
        ];
        // The per-point code's degenerate positions: at a corner, or on the face's plane.
        let size = lengths[0] + lengths[1] + lengths[2];
        let near_corner = or(
            not(lengths[0].gt(size * ON_PLANE)),
            or(
                not(lengths[1].gt(size * ON_PLANE)),
                not(lengths[2].gt(size * ON_PLANE)),
            ),
        );
        let cube = lengths[0] * lengths[1] * lengths[2];
        let h = dot_constant::<M>(&a[0], &face.normal);
        // Van Oosterom & Strackee: tan(Ω/2) = numerator / denominator, with the triple product
        // a₀·(a₁ × a₂) = a₀·((v₁ − v₀) × (v₂ − v₀)) = 2A h (its error ε·2A|a₀| instead of
        // ε|a₀||a₁||a₂|) and the corners' dot products a_i·a_j from their edges.
        let numerator = h * face.twice_area;
        let dots = [
            V8(scratch.edge_dots[face.edges[0] as usize]),
            V8(scratch.edge_dots[face.edges[1] as usize]),
            V8(scratch.edge_dots[face.edges[2] as usize]),
        ];
        let denominator = M::mul_add(
            dots[0],
            lengths[2],
            M::mul_add(dots[2], lengths[1], M::mul_add(dots[1], lengths[0], cube)),
        );
        let on_plane = not(numerator.abs().gt(cube * ON_PLANE));
        recompute = or(recompute, or(near_corner, on_plane));
        // Both scaled (exactly) to |denominator| ≤ 8 and |numerator| ≤ 2, for the fraction's
        // powers.
        let scale = inverse_power_of_two(cube);
        let (angle_num, angle_den) =
            angle_fraction::<M>(numerator.abs() * scale, denominator * scale);
        let half_solid_angle = angle_num * M::recip(angle_den);
        let solid_angle = V8::select(
            splat(0.0).gt(numerator),
            -(half_solid_angle * 2.0),
            half_solid_angle * 2.0,
        );
        let integrals = [
            V8(scratch.edge_integrals[face.edges[0] as usize]),
            V8(scratch.edge_integrals[face.edges[1] as usize]),
            V8(scratch.edge_integrals[face.edges[2] as usize]),
        ];
        let edge_sum = M::mul_add(
            dot_constant::<M>(&a[0], &face.edge_normals[0]),
            integrals[0],
            M::mul_add(
                dot_constant::<M>(&a[1], &face.edge_normals[1]),
                integrals[1],
                dot_constant::<M>(&a[2], &face.edge_normals[2]) * integrals[2],
            ),
        );
        let psi = M::mul_add(-h.abs(), solid_angle.abs(), edge_sum) * INV_FOUR_PI;
        check = check + psi * 0.0;
        face_out.write_lanes(start, face.column as usize, &psi.0, count);
        // φ_i += (Γ_i(ρ) Ω − h ∇Γ_i·Σ_l m_l f_l)/4π, with Γ_i(ρ) = −∇Γ_i·a_{i+1}; corner 2's
        // terms from the partition of unity (Γ₂ = 1 − Γ₀ − Γ₁, ∇Γ₂ = −∇Γ₀ − ∇Γ₁).
        let hats = [
            dot_constant::<M>(&a[1], &face.scaled_hat_gradients[0]),
            dot_constant::<M>(&a[2], &face.scaled_hat_gradients[1]),
        ];
        let slopes = [
            dot_constant::<M>(&integrals, &face.scaled_hat_slopes[0]),
            dot_constant::<M>(&integrals, &face.scaled_hat_slopes[1]),
        ];
        let minus_h = -h;
        let sums = &mut scratch.vertex_sums;
        let sum = M::mul_add(hats[0], solid_angle, V8(sums[idx[0]]));
        sums[idx[0]] = M::mul_add(minus_h, slopes[0], sum).0;
        let sum = M::mul_add(hats[1], solid_angle, V8(sums[idx[1]]));
        sums[idx[1]] = M::mul_add(minus_h, slopes[1], sum).0;
        let last_hat = (splat(INV_FOUR_PI) - hats[0]) - hats[1];
        let sum = M::mul_add(last_hat, solid_angle, V8(sums[idx[2]]));
        sums[idx[2]] = M::mul_add(h, slopes[0] + slopes[1], sum).0;
    }
    (recompute, check)
}

/// `u · c` per lane for a constant vector `c`.
#[inline(always)]
fn dot_constant<M: LaneMath>(u: &[V8; 3], c: &[f64; 3]) -> V8 {
    M::mul_add(
        u[0],
        V8::splat(c[0]),
        M::mul_add(u[1], V8::splat(c[1]), u[2] * c[2]),
    )
}

/// 2^−e per lane for x = m·2^e (m ∈ [1, 2)), x a positive normal number below 2¹⁰²³ (other
/// lanes give garbage): bit operations only, so that scaling by it is exact.
#[inline(always)]
fn inverse_power_of_two(x: V8) -> V8 {
    // The biased exponent of 2^−e is 2046 − (the biased exponent of x).
    V8(per_lane!(0.0, |l| f64::from_bits(
        (2046u64.wrapping_sub((x.0[l].to_bits() >> 52) & 0x7ff) & 0x7ff) << 52
    )))
}

/// `∫ ds/R` along `edge` for the lanes' points (see `edge_log_integral` in
/// [`super::green_triangle`]): with s₀, s₁ the abscissae of its ends from the foot of η on its
/// line and R₀, R₁ their distances, `ln((R₁ + s₁)/(R₀ + s₀))` if s₀ > 0, `ln((R₀ − s₀)/(R₁ − s₁))`
/// if s₁ < 0, and beside the segment `ln((R₁ + s₁)(R₀ − s₀)/d²)` with d² = |a₀ × e|², the
/// distance² to the line; 0 on the segment itself (d² ≤ the smallest normal).
#[inline(always)]
fn edge_integral<M: LaneMath>(edge: &PlanEdge, scratch: &GreenBatchScratch) -> (V8, V8) {
    let [a, b] = [edge.ends[0] as usize, edge.ends[1] as usize];
    let e = edge.direction;
    let (ax, ay, az) = (
        V8(scratch.to_x[a]),
        V8(scratch.to_y[a]),
        V8(scratch.to_z[a]),
    );
    let (bx, by, bz) = (
        V8(scratch.to_x[b]),
        V8(scratch.to_y[b]),
        V8(scratch.to_z[b]),
    );
    let (r0, r1) = (V8(scratch.length[a]), V8(scratch.length[b]));
    let splat = V8::splat;
    let s0 = M::mul_add(ax, splat(e[0]), M::mul_add(ay, splat(e[1]), az * e[2]));
    let s1 = M::mul_add(bx, splat(e[0]), M::mul_add(by, splat(e[1]), bz * e[2]));
    let cx = M::mul_add(ay, splat(e[2]), -(az * e[1]));
    let cy = M::mul_add(az, splat(e[0]), -(ax * e[2]));
    let cz = M::mul_add(ax, splat(e[1]), -(ay * e[0]));
    let distance_sq = M::mul_add(cx, cx, M::mul_add(cy, cy, cz * cz));
    let zero = V8::splat(0.0);
    let before = s0.gt(zero);
    let after = zero.gt(s1);
    let num = V8::select(
        before,
        r1 + s1,
        V8::select(after, r0 - s0, (r1 + s1) * (r0 - s0)),
    );
    let den = V8::select(before, r0 + s0, V8::select(after, r1 - s1, distance_sq));
    let on_segment = not(or(
        or(before, after),
        distance_sq.gt(V8::splat(f64::MIN_POSITIVE)),
    ));
    let ends_dot = M::mul_add(ax, bx, M::mul_add(ay, by, az * bz));
    (
        V8::select(on_segment, zero, ln_of_quotient::<M>(num, den)),
        ends_dot,
    )
}

#[cfg(test)]
#[path = "green_batch_tests.rs"]
mod tests;
