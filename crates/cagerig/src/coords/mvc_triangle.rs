//! The per-triangle step of the mean value coordinates ([`super::mvc`]): unit vectors and
//! distances to the corners of one triangle, its edge terms (one arctangent per edge, table
//! based) and its contribution to the weights, with the degenerate cases (on an edge, on the
//! triangle) and the helpers that write their exact limits.

use glam::DVec3;

use super::mvc::EPS;

/// What one triangle does to the MVC of `point` ([`triangle_weights`]).
pub(crate) enum TriangleWeights {
    /// Unnormalised weights of the three corners, in triangle order.
    Add([f64; 3]),
    /// The point lies on the triangle's plane outside it: no contribution.
    Skip,
    /// The point lies on the edge (a, b), at distances `dist_a`, `dist_b` from its ends.
    OnEdge {
        a: usize,
        b: usize,
        dist_a: f64,
        dist_b: f64,
    },
    /// The point lies inside the triangle.
    OnTriangle,
}

/// The per-triangle step of [`mean_value_coordinates`] (Ju et al. 2005) for triangle `tri`:
/// unit vectors and distances to the corners, the edge terms (edge j is opposite corner j:
/// (j+1, j+2)), then the triangle's contribution. Summing a vertex's `Add` weights over its
/// incident triangles in ascending order gives bitwise that function's weight before
/// normalisation. Does not handle the snapped-vertex case.
pub(crate) fn triangle_weights(
    positions: &[DVec3],
    tri: [u32; 3],
    point: DVec3,
) -> TriangleWeights {
    let idx = tri.map(|i| i as usize);
    let mut unit = [DVec3::ZERO; 3];
    let mut dist = [0.0; 3];
    for j in 0..3 {
        let v = positions[idx[j]] - point;
        dist[j] = v.length();
        unit[j] = v / dist[j];
    }
    let mut cross = [DVec3::ZERO; 3];
    let mut half_angle_over_sin = [0.0; 3];
    let mut theta = [0.0; 3];
    for j in 0..3 {
        let (a, b) = ((j + 1) % 3, (j + 2) % 3);
        match edge_terms(unit[a], unit[b]) {
            EdgeTerms::Regular { c, k, angle } => {
                cross[j] = c;
                half_angle_over_sin[j] = k;
                theta[j] = angle;
            }
            EdgeTerms::OnEdge => {
                return TriangleWeights::OnEdge {
                    a: idx[a],
                    b: idx[b],
                    dist_a: dist[a],
                    dist_b: dist[b],
                };
            }
        }
    }
    match triangle_contribution(&unit, &dist, &cross, &half_angle_over_sin, &theta) {
        Contribution::Add(w) => TriangleWeights::Add(w),
        Contribution::Skip => TriangleWeights::Skip,
        Contribution::OnTriangle => TriangleWeights::OnTriangle,
    }
}

/// The cage vertex `point` coincides with (within `EPS · max distance`), if any.
pub(super) fn snapped_vertex(positions: &[DVec3], point: DVec3) -> Option<usize> {
    let mut nearest = (usize::MAX, f64::INFINITY);
    let mut farthest: f64 = 0.0;
    for (k, p) in positions.iter().enumerate() {
        let d = p.distance(point);
        if d < nearest.1 {
            nearest = (k, d);
        }
        farthest = farthest.max(d);
    }
    (nearest.0 != usize::MAX && nearest.1 <= EPS * farthest).then_some(nearest.0)
}

pub(super) enum EdgeTerms {
    /// `c = u_a × u_b`, `k = θ / (2 |c|)`, `angle = θ` (the edge's arc length on the sphere).
    Regular { c: DVec3, k: f64, angle: f64 },
    /// The point lies on the edge segment.
    OnEdge,
}

#[inline]
pub(super) fn edge_terms(ua: DVec3, ub: DVec3) -> EdgeTerms {
    let c = ua.cross(ub);
    let sin = c.length();
    let cos = ua.dot(ub);
    if sin < EPS && cos < 0.0 {
        return EdgeTerms::OnEdge;
    }
    let angle = fast_angle(sin, cos);
    // θ / sin θ → 1 as θ → 0 (coincident directions).
    let k = if sin > 1e-300 { 0.5 * angle / sin } else { 0.5 };
    EdgeTerms::Regular { c, k, angle }
}

/// atan((k + ½) / 8) for k = 0..8 (nodes of the table-based arctangent).
const ATAN_NODES: [f64; 8] = [
    0.06241880999595735,
    0.18534794999569476,
    0.3028848683749714,
    0.4124104415973873,
    0.5123894603107377,
    0.6022873461349642,
    0.6823165548747481,
    0.7531512809621944,
];

/// `atan2(sin, cos)` for `sin ≥ 0` (result in [0, π]), accurate to a few ulp and several times
/// faster than libm: octant reduction to t ∈ [0, 1], table node c = (k + ½)/8 and
/// atan t = atan c + atan((t − c)/(1 + t c)) with |argument| ≤ 1/16, degree-13 Taylor series.
#[inline]
pub(crate) fn fast_angle(sin: f64, cos: f64) -> f64 {
    let abs_cos = cos.abs();
    let swap = sin > abs_cos;
    let (num, den) = if swap { (abs_cos, sin) } else { (sin, abs_cos) };
    if den == 0.0 {
        return 0.0;
    }
    let t = num / den;
    let k = ((t * 8.0) as usize).min(7);
    let node = (k as f64 + 0.5) / 8.0;
    let z = (t - node) / (1.0 + t * node);
    let z2 = z * z;
    let series = z
        * (1.0
            + z2 * (-1.0 / 3.0
                + z2 * (1.0 / 5.0
                    + z2 * (-1.0 / 7.0 + z2 * (1.0 / 9.0 + z2 * (-1.0 / 11.0 + z2 / 13.0))))));
    let mut angle = ATAN_NODES[k] + series;
    if swap {
        angle = std::f64::consts::FRAC_PI_2 - angle;
    }
    if cos < 0.0 {
        angle = std::f64::consts::PI - angle;
    }
    angle
}

pub(super) enum Contribution {
    Add([f64; 3]),
    Skip,
    OnTriangle,
}

/// Unnormalised MVC weights of one triangle. `cross[j] = u_{j+1} × u_{j+2}` (triangle order),
/// `k[j] = θ_j / (2 |cross[j]|)`, `theta[j]` the arc opposite corner j.
#[inline]
pub(super) fn triangle_contribution(
    unit: &[DVec3; 3],
    dist: &[f64; 3],
    cross: &[DVec3; 3],
    k: &[f64; 3],
    theta: &[f64; 3],
) -> Contribution {
    let det = unit[0].dot(cross[0]);
    if det.abs() < EPS {
        // On the triangle's plane: inside iff the spherical perimeter is 2π.
        let perimeter = theta[0] + theta[1] + theta[2];
        return if 2.0 * std::f64::consts::PI - perimeter < EPS {
            Contribution::OnTriangle
        } else {
            Contribution::Skip
        };
    }
    let mean = k[0] * cross[0] + k[1] * cross[1] + k[2] * cross[2];
    let inv_det = 1.0 / det;
    Contribution::Add([
        cross[0].dot(mean) * inv_det / dist[0],
        cross[1].dot(mean) * inv_det / dist[1],
        cross[2].dot(mean) * inv_det / dist[2],
    ])
}

/// Linear interpolation along edge (a, b) for a point on it.
pub(super) fn write_on_edge(a: usize, b: usize, da: f64, db: f64, out: &mut [f64]) {
    out.iter_mut().for_each(|w| *w = 0.0);
    let total = da + db;
    out[a] = db / total;
    out[b] = da / total;
}

/// Planar barycentric coordinates of the projection of `point` on triangle `idx`.
pub(super) fn write_on_triangle(
    positions: &[DVec3],
    idx: [usize; 3],
    point: DVec3,
    out: &mut [f64],
) {
    out.iter_mut().for_each(|w| *w = 0.0);
    let [p0, p1, p2] = idx.map(|i| positions[i]);
    let normal = (p1 - p0).cross(p2 - p0);
    let areas = [
        (p1 - point).cross(p2 - point).dot(normal),
        (p2 - point).cross(p0 - point).dot(normal),
        (p0 - point).cross(p1 - point).dot(normal),
    ];
    let total = areas[0] + areas[1] + areas[2];
    for j in 0..3 {
        out[idx[j]] = areas[j] / total;
    }
}

pub(super) fn normalise(out: &mut [f64]) {
    let total: f64 = out.iter().sum();
    if total != 0.0 && total.is_finite() {
        let inv = 1.0 / total;
        out.iter_mut().for_each(|w| *w *= inv);
    } else {
        out.iter_mut().for_each(|w| *w = f64::NAN);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_angle_matches_libm() {
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let theta = std::f64::consts::PI * i as f64 / 200_000.0;
            for scale in [1.0, 0.3, 7.0] {
                let (s, c) = (theta.sin().abs() * scale, theta.cos() * scale);
                let err = (fast_angle(s, c) - s.atan2(c)).abs();
                worst = worst.max(err);
            }
        }
        assert!(worst < 1e-15, "worst {worst:e}");
        assert_eq!(fast_angle(0.0, 1.0), 0.0);
        assert_eq!(fast_angle(0.0, -1.0), std::f64::consts::PI);
        assert_eq!(fast_angle(0.0, 0.0), 0.0);
    }
}
