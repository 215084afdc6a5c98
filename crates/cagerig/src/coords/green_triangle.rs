//! One cage triangle's closed-form contribution to the Green coordinates of one point
//! (Lipman, Levin & Cohen-Or, "Green Coordinates", SIGGRAPH 2008, Sec. 3–4).
//!
//! For a point η inside a closed cage with outward normals, Green's third identity applied to the
//! linear functions gives `η = Σ_i φ_i(η) v_i + Σ_t ψ_t(η) n_t` with
//!
//! - `ψ_t(η) = (1/4π) ∫_t 1/R dσ` (the single-layer potential of the face, R = |ξ − η|), and
//! - `φ_i(η) = (1/4π) Σ_{t ∋ i} ∫_t Γ_i(ξ) (ξ − η)·n_t / R³ dσ` (the double-layer potential of the
//!   hat function Γ_i, linear on each face).
//!
//! Both integrals have closed forms in the face's plane frame (h: signed height of the plane
//! above η along n; ρ: the foot of η on the plane; for each edge l: its outward in-plane normal
//! m_l, the signed distance t_l = (a_l − ρ)·m_l from ρ to the edge line, the endpoint abscissae
//! s_l^± and distances R_l^±, and f_l = ∫_edge 1/R ds = ln((R_l^+ + s_l^+)/(R_l^- + s_l^-))):
//!
//! - `∫_t 1/R = Σ_l t_l f_l − |h| |Ω|`, with Ω the solid angle of t seen from η;
//! - `∫_t Γ_i h/R³ = Γ_i(ρ) Ω − h ∇Γ_i · Σ_l m_l f_l` (Ω signed like h; by the divergence
//!   theorem in the plane, `∫_t (ξ − ρ)/R³ = −Σ_l m_l f_l`).
//!
//! This replaces Lipman et al.'s `GCTriInt` angle recursion by the equivalent edge form (the
//! boundary-element formulas of Graglia 1993), which stays finite in every degenerate position:
//! η on a face's plane (h = 0: Ω is 0 outside the face, and the interior limit 2π on it), on an
//! edge's line (R₀ = 0: the log term is multiplied by t_l = 0 and h = 0) or at a vertex.

use std::f64::consts::PI;

use glam::DVec3;

/// 1/(4π).
pub(super) const INV_FOUR_PI: f64 = 0.25 / PI;

/// The contribution of one triangle (v₀, v₁, v₂), counter-clockwise seen from outside, to the
/// Green coordinates of the point `eta`: the face coordinate ψ_t and the three vertex
/// coordinates φ added to v₀, v₁, v₂.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleGreenTerms {
    /// ψ_t(η) ≥ 0.
    pub face: f64,
    /// The parts of φ_{v₀}, φ_{v₁}, φ_{v₂} carried by this triangle.
    pub vertices: [f64; 3],
}

/// A cage triangle's plane frame, computed once for all points: corners (counter-clockwise seen
/// from outside), unit normal n, twice the area, per edge l (from corner l to l+1) its unit
/// direction e_l and outward in-plane normal m_l = e_l × n, and the in-plane gradients ∇Γ_i of
/// the three hat functions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GreenTriangle {
    corners: [DVec3; 3],
    pub(super) normal: DVec3,
    pub(super) twice_area: f64,
    edge_directions: [DVec3; 3],
    pub(super) edge_normals: [DVec3; 3],
    pub(super) hat_gradients: [DVec3; 3],
}

impl GreenTriangle {
    /// The frame of triangle `corners`; `None` for a degenerate (zero-area) triangle, which
    /// contributes nothing.
    pub fn new(corners: [DVec3; 3]) -> Option<Self> {
        let cross = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let twice_area = cross.length();
        if twice_area <= f64::MIN_POSITIVE || !twice_area.is_finite() {
            return None;
        }
        let normal = cross / twice_area;
        let edge_directions: [DVec3; 3] = std::array::from_fn(|l| {
            (corners[(l + 1) % 3] - corners[l])
                .try_normalize()
                .unwrap_or(DVec3::ZERO)
        });
        Some(Self {
            corners,
            normal,
            twice_area,
            edge_directions,
            edge_normals: edge_directions.map(|e| e.cross(normal)),
            hat_gradients: std::array::from_fn(|i| {
                normal.cross(corners[(i + 2) % 3] - corners[(i + 1) % 3]) / twice_area
            }),
        })
    }

    /// The triangle's Green terms for the point `eta`.
    pub fn terms(&self, eta: DVec3) -> TriangleGreenTerms {
        let corners = &self.corners;
        let n = self.normal;
        let a = [corners[0] - eta, corners[1] - eta, corners[2] - eta];
        let lengths = [a[0].length(), a[1].length(), a[2].length()];
        let height = a[0].dot(n);
        let (omega, on_plane) = signed_solid_angle(a, lengths, self.twice_area * height);
        let h = if on_plane { 0.0 } else { height };
        // Σ_l t_l f_l and Σ_l m_l f_l over the three edges.
        let mut edge_sum = 0.0;
        let mut normal_sum = DVec3::ZERO;
        for l in 0..3 {
            let next = (l + 1) % 3;
            let e = self.edge_directions[l];
            let m = self.edge_normals[l];
            let f = edge_log_integral(a[l].dot(e), a[next].dot(e), lengths[l], lengths[next]);
            edge_sum += a[l].dot(m) * f;
            normal_sum += m * f;
        }
        let face = INV_FOUR_PI * (edge_sum - h.abs() * omega.abs());
        let vertices = std::array::from_fn(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            // Barycentric Γ_i at the foot ρ of η on the plane.
            let hat_at_foot = a[j].cross(a[k]).dot(n) / self.twice_area;
            INV_FOUR_PI * (hat_at_foot * omega - h * self.hat_gradients[i].dot(normal_sum))
        });
        TriangleGreenTerms { face, vertices }
    }
}

/// Green terms of triangle `corners` (counter-clockwise seen from outside) for the point `eta`.
/// A degenerate triangle (zero area) contributes nothing.
#[cfg(test)]
pub fn triangle_green_terms(corners: [DVec3; 3], eta: DVec3) -> TriangleGreenTerms {
    match GreenTriangle::new(corners) {
        Some(triangle) => triangle.terms(eta),
        None => TriangleGreenTerms {
            face: 0.0,
            vertices: [0.0; 3],
        },
    }
}

/// Points closer to a face's plane than this fraction of their distances to its corners are
/// taken to lie on it (and get the limits from behind the face, i.e. from inside the cage).
pub(super) const ON_PLANE: f64 = 1e-12;

/// Solid angle of the triangle with corners `a` (relative to the point), signed like the triple
/// product `numerator` = a₀·(a₁×a₂) (positive when the point is behind the face, i.e. inside a
/// cage with outward normals; Van Oosterom & Strackee 1983), and whether the point lies on the
/// face's plane. On the plane, the limit from behind: 0 outside the triangle, 2π inside, π on an
/// edge, the corner's angle at a corner. The caller passes the triple product as 2A h (twice the
/// area times the height a₀·n, equal to it since a₁ − a₀ and a₂ − a₀ are the triangle's edges),
/// whose error is ε·2A|a₀| where the product's own is ε|a₀||a₁||a₂|; the batch kernel does the
/// same.
fn signed_solid_angle(a: [DVec3; 3], lengths: [f64; 3], numerator: f64) -> (f64, bool) {
    let denominator = lengths[0] * lengths[1] * lengths[2]
        + a[0].dot(a[1]) * lengths[2]
        + a[0].dot(a[2]) * lengths[1]
        + a[1].dot(a[2]) * lengths[0];
    let size = lengths[0] + lengths[1] + lengths[2];
    let cube = lengths[0] * lengths[1] * lengths[2];
    if let Some(l) = lengths.iter().position(|&r| r <= ON_PLANE * size) {
        // At corner l: the corner's angle.
        return (a[(l + 1) % 3].angle_between(a[(l + 2) % 3]), true);
    }
    if numerator.abs() <= ON_PLANE * cube {
        let omega = if denominator < -ON_PLANE * cube {
            2.0 * PI // inside the triangle
        } else if denominator <= ON_PLANE * cube {
            PI // on an edge
        } else {
            0.0
        };
        return (omega, true);
    }
    (2.0 * numerator.atan2(denominator), false)
}

/// `∫ ds / R` along an edge from abscissa `s0` to `s1` (relative to the foot of the point on the
/// edge's line), the endpoints being at distances `r0`, `r1` from the point:
/// `ln((r1 + s1)/(r0 + s0))`, in whichever of its equivalent forms has no cancellation. Zero when
/// the point lies on the edge segment itself (where every use multiplies it by zero).
fn edge_log_integral(s0: f64, s1: f64, r0: f64, r1: f64) -> f64 {
    if s0 > 0.0 {
        ((r1 + s1) / (r0 + s0)).ln()
    } else if s1 < 0.0 {
        ((r0 - s0) / (r1 - s1)).ln()
    } else {
        // s0 ≤ 0 ≤ s1: (r0 + s0) = (r0² − s0²)/(r0 − s0) = d²/(r0 − s0), d the distance to the
        // line, computed from the endpoint with the smaller |s| for accuracy.
        let d2 = if -s0 < s1 {
            (r0 - s0) * (r0 + s0)
        } else {
            (r1 - s1) * (r1 + s1)
        };
        if d2 <= f64::MIN_POSITIVE {
            return 0.0;
        }
        ((r1 + s1) * (r0 - s0) / d2).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the integrals on a fine subdivision of the triangle, 7-point Gauss rule on
    /// each piece.
    fn quadrature(corners: [DVec3; 3], eta: DVec3, levels: u32) -> TriangleGreenTerms {
        let cross = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let n = cross.normalize();
        let steps = 1usize << levels;
        let mut face = 0.0;
        let mut vertices = [0.0; 3];
        // Dunavant degree-5 rule (barycentric, weights sum to 1).
        let a1 = 0.059_715_871_789_770;
        let b1 = 0.470_142_064_105_115;
        let a2 = 0.797_426_985_353_087;
        let b2 = 0.101_286_507_323_456;
        let rule: [([f64; 3], f64); 7] = [
            ([1.0 / 3.0; 3], 0.225),
            ([a1, b1, b1], 0.132_394_152_788_506),
            ([b1, a1, b1], 0.132_394_152_788_506),
            ([b1, b1, a1], 0.132_394_152_788_506),
            ([a2, b2, b2], 0.125_939_180_544_827),
            ([b2, a2, b2], 0.125_939_180_544_827),
            ([b2, b2, a2], 0.125_939_180_544_827),
        ];
        let point = |u: f64, v: f64| [1.0 - u - v, u, v];
        let sub_area = cross.length() / 2.0 / (steps * steps) as f64;
        for i in 0..steps {
            for j in 0..steps - i {
                let s = steps as f64;
                let mut pieces = vec![[
                    point(i as f64 / s, j as f64 / s),
                    point((i + 1) as f64 / s, j as f64 / s),
                    point(i as f64 / s, (j + 1) as f64 / s),
                ]];
                if i + j + 1 < steps {
                    pieces.push([
                        point((i + 1) as f64 / s, j as f64 / s),
                        point((i + 1) as f64 / s, (j + 1) as f64 / s),
                        point(i as f64 / s, (j + 1) as f64 / s),
                    ]);
                }
                for piece in pieces {
                    for (w, weight) in rule {
                        let bary: [f64; 3] =
                            std::array::from_fn(|c| (0..3).map(|p| w[p] * piece[p][c]).sum());
                        let xi = corners[0] * bary[0] + corners[1] * bary[1] + corners[2] * bary[2];
                        let r = xi - eta;
                        let len = r.length();
                        face += weight * sub_area / len;
                        let kernel = r.dot(n) / (len * len * len);
                        for (v, b) in vertices.iter_mut().zip(bary) {
                            *v += weight * sub_area * b * kernel;
                        }
                    }
                }
            }
        }
        TriangleGreenTerms {
            face: face * INV_FOUR_PI,
            vertices: vertices.map(|v| v * INV_FOUR_PI),
        }
    }

    #[test]
    fn matches_brute_force_quadrature() {
        let corners = [
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(1.3, 0.1, 0.2),
            DVec3::new(0.4, 1.1, 0.6),
        ];
        // Above, below, beside, and far from the triangle.
        let points = [
            DVec3::new(0.5, 0.4, -0.6),
            DVec3::new(0.5, 0.3, 1.5),
            DVec3::new(2.0, 2.0, 0.1),
            DVec3::new(-1.0, 0.5, 0.9),
            DVec3::new(6.0, -4.0, 3.0),
        ];
        for eta in points {
            let exact = triangle_green_terms(corners, eta);
            let brute = quadrature(corners, eta, 6);
            assert!(
                (exact.face - brute.face).abs() < 1e-9,
                "{eta}: {} vs {}",
                exact.face,
                brute.face
            );
            for (e, b) in exact.vertices.iter().zip(brute.vertices) {
                assert!((e - b).abs() < 1e-9, "{eta}: {e} vs {b}");
            }
        }
    }

    #[test]
    fn close_to_a_face_and_an_edge_matches_quadrature_and_stays_finite() {
        let corners = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // 1e-2 above the face (the quadrature needs a fine grid there), on the plane outside, on
        // the plane inside (interior limit), on an edge, at a vertex, on an edge's line.
        let near = DVec3::new(0.3, 0.3, -1e-2);
        let exact = triangle_green_terms(corners, near);
        let brute = quadrature(corners, near, 8);
        assert!((exact.face - brute.face).abs() < 1e-7);
        for (e, b) in exact.vertices.iter().zip(brute.vertices) {
            assert!((e - b).abs() < 1e-5, "{e} vs {b}");
        }
        for eta in [
            DVec3::new(2.0, 2.0, 0.0),
            DVec3::new(0.2, 0.2, 0.0),
            DVec3::new(0.5, 0.0, 0.0),
            DVec3::ZERO,
            DVec3::new(-1.0, 0.0, 0.0),
        ] {
            let t = triangle_green_terms(corners, eta);
            assert!(t.face.is_finite() && t.vertices.iter().all(|v| v.is_finite()));
        }
        // On the plane inside the face: φ is the interior limit Γ_i(ρ)/2.
        let t = triangle_green_terms(corners, DVec3::new(0.2, 0.3, 0.0));
        for (v, hat) in t.vertices.iter().zip([0.5, 0.2, 0.3]) {
            assert!((v - hat / 2.0).abs() < 1e-12, "{v} vs {}", hat / 2.0);
        }
        // Just below vs on the plane: continuous from the inside.
        let below = triangle_green_terms(corners, DVec3::new(0.2, 0.3, -1e-12));
        assert!((below.face - t.face).abs() < 1e-10);
    }

    #[test]
    fn degenerate_triangle_contributes_nothing() {
        let t = triangle_green_terms([DVec3::ZERO, DVec3::X, DVec3::X * 2.0], DVec3::Y);
        assert_eq!(t.face, 0.0);
        assert_eq!(t.vertices, [0.0; 3]);
    }
}
