//! The face terms of a Green-coordinates deformation: one vector g_t(C') per cage triangle t, so
//! that a point moves to `Σ φ_i v'_i + Σ ψ_t g_t(C')` (Lipman et al. 2008, Eq. 4).
//!
//! Two face terms, equal whenever a face moves by a similarity (x ↦ λRx + b gives g_t = λ R n_t,
//! so the deformed points move by the same similarity; at the binding cage g_t = n_t):
//!
//! - [`FaceTermKind::FoldSafe`] (the default): `ĝ_t = √2 · c' / √σ`, with c' = u' × v' the
//!   deformed triangle's area vector (|c'| twice its area) and
//!   `σ = |u'|²|v|² − 2(u'·v')(u·v) + |v'|²|u|²`
//!   (u, v: the edges v₁ − v₀, v₂ − v₀ of the binding triangle; u', v' of the deformed one). Since
//!   Lipman's stretch factor is s = √σ / (√8 · area), ĝ = c' / (2 A s) with A the binding area:
//!   the deformed area vector divided by the rest area and the stretch. σ is a positive definite
//!   quadratic form in (u', v') (its determinant is |u × v|⁴), so ĝ is smooth (real-analytic)
//!   everywhere but at a triangle collapsed to a point: it passes through zero when the deformed
//!   triangle folds (c' → 0) instead of jumping from n to −n. Its length is the area ratio over
//!   the stretch, A'/(A s) = σ₁σ₂/√((σ₁² + σ₂²)/2) for the singular values σ₁, σ₂ of the face's
//!   linear map, against Lipman's √((σ₁² + σ₂²)/2): the two agree to second order in the
//!   anisotropy ε of a near-conformal map (σ₁,₂ = λ(1 ± ε): λ(1 − 3ε²/2) against λ(1 + ε²/2)).
//! - [`FaceTermKind::Lipman`]: Lipman et al.'s `g_t = s_t · n_t` with n_t = c'/|c'| the unit
//!   normal, which jumps from n to −n when the deformed triangle folds.
//!
//! [`StretchedNormals::face_jacobian`] gives ∂g_t/∂v'_a (three 3×3 blocks), which the Green
//! CageUp and CageRev Newton iterations use. For ĝ, with ∂c'/∂u' = −[v']×, ∂c'/∂v' = [u']×,
//! ∂σ/∂u' = 2(|v|² u' − (u·v) v') and ∂σ/∂v' = 2(|u|² v' − (u·v) u'):
//! `∂ĝ/∂u' = √(2/σ) (−[v']× − c' ⊗ (|v|² u' − (u·v) v')/σ)`,
//! `∂ĝ/∂v' = √(2/σ) ([u']× − c' ⊗ (|u|² v' − (u·v) u')/σ)`.
//! For Lipman's g:
//! `∂g/∂u' = n ⊗ ∂s/∂u' − (s/|c'|)(I − n nᵀ)[v']×`, `∂g/∂v' = n ⊗ ∂s/∂v' + (s/|c'|)(I − n nᵀ)[u']×`
//! with `∂s/∂u' = (|v|² u' − (u·v) v') s/σ`, `∂s/∂v' = (|u|² v' − (u·v) u') s/σ`.

use glam::{DMat3, DVec3};

/// The binding triangle's quadratic form: |u|², |v|², u·v and 1/(√8 · area).
#[derive(Debug, Clone, Copy, PartialEq)]
struct BindingFace {
    uu: f64,
    vv: f64,
    uv: f64,
    inverse_scale: f64,
}

/// Which face term g_t a Green deformation uses (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaceTermKind {
    /// ĝ_t = √2 c'/√σ = c'/(2 A s): smooth through folds (the default).
    #[default]
    FoldSafe,
    /// Lipman et al.'s g_t = s_t n_t: jumps when a deformed triangle folds.
    Lipman,
}

/// A face-term name that [`FaceTermKind::from_str`] does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown Green face term {found:?}: expected {}",
    FaceTermKind::names_text()
)]
pub struct UnknownFaceTermKind {
    /// The name as given.
    pub found: String,
}

impl FaceTermKind {
    /// Every kind, in the order front ends list them.
    pub const ALL: [FaceTermKind; 2] = [Self::FoldSafe, Self::Lipman];

    /// The name in options and files: `"fold-safe"` or `"lipman"`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::FoldSafe => "fold-safe",
            Self::Lipman => "lipman",
        }
    }

    /// One line of help for option lists.
    pub const fn help(self) -> &'static str {
        match self {
            Self::FoldSafe => {
                "c'/(2·A·s): Lipman's s·n' under similarities, smooth when a current-cage \
                 triangle folds (the default)"
            }
            Self::Lipman => "Lipman et al.'s stretched normal s·n', which jumps at a fold",
        }
    }
}

crate::named_kind::named_kind!(FaceTermKind, UnknownFaceTermKind, FaceTermKind::help);

/// g_t(C') for every cage triangle (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct StretchedNormals {
    triangles: Vec<[u32; 3]>,
    binding: Vec<BindingFace>,
    kind: FaceTermKind,
}

impl StretchedNormals {
    /// From the binding cage (the cage the Green coordinates were computed for) and its
    /// outward-oriented triangles (`#F`), with the default face term
    /// ([`FaceTermKind::FoldSafe`]). A degenerate binding triangle gets g = 0 (its Green face
    /// coordinates are zero too).
    pub fn new(binding_cage: &[DVec3], triangles: Vec<[u32; 3]>) -> Self {
        Self::with_kind(binding_cage, triangles, FaceTermKind::default())
    }

    /// [`Self::new`] with the face term `kind`.
    pub fn with_kind(binding_cage: &[DVec3], triangles: Vec<[u32; 3]>, kind: FaceTermKind) -> Self {
        let binding = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| binding_cage[v as usize]);
                let (u, v) = (b - a, c - a);
                let twice_area = u.cross(v).length();
                BindingFace {
                    uu: u.length_squared(),
                    vv: v.length_squared(),
                    uv: u.dot(v),
                    inverse_scale: if twice_area > f64::MIN_POSITIVE {
                        // √8 · area = √2 · |u × v|.
                        1.0 / (std::f64::consts::SQRT_2 * twice_area)
                    } else {
                        0.0
                    },
                }
            })
            .collect();
        Self {
            triangles,
            binding,
            kind,
        }
    }

    /// The face term these normals evaluate.
    pub fn kind(&self) -> FaceTermKind {
        self.kind
    }

    /// The outward-oriented triangles, `#F`.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of faces `#F`.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True when the cage has no face.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// g_t(cage) for every face into `out` (`#F`). No allocation.
    pub fn apply(&self, cage: &[DVec3], out: &mut [DVec3]) {
        for (t, g) in out.iter_mut().enumerate() {
            *g = self.face(cage, t);
        }
    }

    /// g_t(cage) of face t.
    #[inline]
    pub fn face(&self, cage: &[DVec3], t: usize) -> DVec3 {
        let f = &self.binding[t];
        let [a, b, c] = self.triangles[t].map(|v| cage[v as usize]);
        let (u, v) = (b - a, c - a);
        let cross = u.cross(v);
        let sigma = radicand(f, u, v);
        match self.kind {
            FaceTermKind::FoldSafe => {
                // ĝ = √2 c'/√σ; c' and σ vanish together only when u' = v' = 0.
                if sigma <= f64::MIN_POSITIVE || f.inverse_scale == 0.0 {
                    return DVec3::ZERO;
                }
                cross * (std::f64::consts::SQRT_2 / sigma.sqrt())
            }
            FaceTermKind::Lipman => {
                let length = cross.length();
                if length <= f64::MIN_POSITIVE {
                    return DVec3::ZERO;
                }
                cross * (sigma.max(0.0).sqrt() * f.inverse_scale / length)
            }
        }
    }

    /// ∂g_t/∂v'_a for the three corners a of face t (3×3 each, columns: d/dx, d/dy, d/dz), at
    /// `cage`. Zero for a degenerate binding triangle, a triangle collapsed to a point, and
    /// (Lipman's term) a deformed triangle of zero area.
    pub fn face_jacobian(&self, cage: &[DVec3], t: usize) -> [DMat3; 3] {
        self.face_jacobian_at(t, self.triangles[t].map(|v| cage[v as usize]))
    }

    /// [`Self::face_jacobian`] of face t with its corners at `corners`.
    pub fn face_jacobian_at(&self, t: usize, corners: [DVec3; 3]) -> [DMat3; 3] {
        let f = &self.binding[t];
        let [a, b, c] = corners;
        let (u, v) = (b - a, c - a);
        let cross = u.cross(v);
        let sigma = radicand(f, u, v);
        if sigma <= f64::MIN_POSITIVE || f.inverse_scale == 0.0 {
            return [DMat3::ZERO; 3];
        }
        let half_ds_du = f.vv * u - f.uv * v;
        let half_ds_dv = f.uu * v - f.uv * u;
        let (dg_du, dg_dv) = match self.kind {
            FaceTermKind::FoldSafe => {
                let k = (2.0 / sigma).sqrt();
                (
                    (-cross_matrix(v) - outer(cross, half_ds_du / sigma)) * k,
                    (cross_matrix(u) - outer(cross, half_ds_dv / sigma)) * k,
                )
            }
            FaceTermKind::Lipman => {
                let length = cross.length();
                if length <= f64::MIN_POSITIVE {
                    return [DMat3::ZERO; 3];
                }
                let s = sigma.sqrt() * f.inverse_scale;
                let n = cross / length;
                let project = DMat3::IDENTITY - outer(n, n);
                let k = s / length;
                (
                    outer(n, half_ds_du * (s / sigma)) - project * cross_matrix(v) * k,
                    outer(n, half_ds_dv * (s / sigma)) + project * cross_matrix(u) * k,
                )
            }
        };
        [-(dg_du + dg_dv), dg_du, dg_dv]
    }
}

impl StretchedNormals {
    /// The Hessian (9 × 9, symmetric, over the corners' coordinates, index 3·corner + axis) of
    /// x ↦ w·g_t(x) for a fixed vector `w`, at `corners`, by central differences of its analytic
    /// gradient (∂g_t/∂x)ᵀw with steps of `step`. Used by the Newton CageUp's second-order term,
    /// where its error only slows convergence, not the solution.
    pub fn weighted_face_hessian(
        &self,
        t: usize,
        corners: [DVec3; 3],
        w: DVec3,
        step: f64,
    ) -> [[f64; 9]; 9] {
        let mut hessian = [[0.0; 9]; 9];
        for q in 0..9 {
            let mut plus = corners;
            let mut minus = corners;
            plus[q / 3][q % 3] += step;
            minus[q / 3][q % 3] -= step;
            let (jp, jm) = (
                self.face_jacobian_at(t, plus),
                self.face_jacobian_at(t, minus),
            );
            for corner in 0..3 {
                let difference =
                    (jp[corner].transpose() * w - jm[corner].transpose() * w) / (2.0 * step);
                for axis in 0..3 {
                    hessian[3 * corner + axis][q] = difference[axis];
                }
            }
        }
        let unsymmetric = hessian;
        for (i, row) in hessian.iter_mut().enumerate() {
            for (j, value) in row.iter_mut().enumerate() {
                *value = 0.5 * (unsymmetric[i][j] + unsymmetric[j][i]);
            }
        }
        hessian
    }
}

/// σ = |u'|²|v|² − 2(u'·v')(u·v) + |v'|²|u|².
#[inline]
fn radicand(f: &BindingFace, u: DVec3, v: DVec3) -> f64 {
    u.length_squared() * f.vv - 2.0 * u.dot(v) * f.uv + v.length_squared() * f.uu
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// [a]×, with [a]× b = a × b.
fn cross_matrix(a: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, a.z, -a.y),
        DVec3::new(-a.z, 0.0, a.x),
        DVec3::new(a.y, -a.x, 0.0),
    )
}

#[cfg(test)]
mod tests {
    use glam::DQuat;

    use super::*;

    fn cage() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.1, 0.0),
                DVec3::new(0.2, 0.9, 0.1),
                DVec3::new(0.3, 0.2, 1.1),
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
    }

    const KINDS: [FaceTermKind; 2] = [FaceTermKind::FoldSafe, FaceTermKind::Lipman];

    #[test]
    fn unit_normals_at_binding_and_similarity_equivariance() {
        let (p, t) = cage();
        for kind in KINDS {
            let normals = StretchedNormals::with_kind(&p, t.clone(), kind);
            let mut g = vec![DVec3::ZERO; t.len()];
            normals.apply(&p, &mut g);
            for (gt, tri) in g.iter().zip(&t) {
                let [a, b, c] = tri.map(|v| p[v as usize]);
                let n = (b - a).cross(c - a).normalize();
                assert!(gt.distance(n) < 1e-15, "{kind:?}");
            }
            let rotation = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.8);
            let moved: Vec<DVec3> = p
                .iter()
                .map(|x| rotation * (*x * 1.7) + DVec3::new(3.0, -1.0, 2.0))
                .collect();
            let mut h = vec![DVec3::ZERO; t.len()];
            normals.apply(&moved, &mut h);
            for (ht, gt) in h.iter().zip(&g) {
                assert!(ht.distance(rotation * (*gt * 1.7)) < 1e-14, "{kind:?}");
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let (p, t) = cage();
        // A deformation that also folds face 0 (its corner 2 pushed through the opposite edge).
        let stretched: Vec<DVec3> = p
            .iter()
            .enumerate()
            .map(|(i, x)| *x * DVec3::new(1.3, 0.8, 1.1) + DVec3::splat(0.1 * i as f64))
            .collect();
        let mut folded = p.clone();
        folded[2] = DVec3::new(0.6, -0.4, 0.05);
        for kind in KINDS {
            let normals = StretchedNormals::with_kind(&p, t.clone(), kind);
            for deformed in [&stretched, &folded] {
                let step = 1e-6;
                for face in 0..t.len() {
                    let jac = normals.face_jacobian(deformed, face);
                    for (corner, block) in jac.iter().enumerate() {
                        for axis in 0..3 {
                            let mut plus = deformed.clone();
                            let mut minus = deformed.clone();
                            plus[t[face][corner] as usize][axis] += step;
                            minus[t[face][corner] as usize][axis] -= step;
                            let fd = (normals.face(&plus, face) - normals.face(&minus, face))
                                / (2.0 * step);
                            let analytic = block.col(axis);
                            assert!(fd.distance(analytic) < 1e-8, "{kind:?}: {fd} vs {analytic}");
                        }
                    }
                }
            }
        }
    }

    /// A triangle in the xy plane with its third corner moved along y through the opposite
    /// edge: ĝ is the signed area ratio over the stretch times +z, continuous through zero;
    /// Lipman's term keeps length s and jumps from +z·s to −z·s.
    #[test]
    fn the_fold_safe_term_passes_through_a_fold_and_lipmans_jumps() {
        let rest = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let triangle = vec![[0u32, 1, 2]];
        let fold_safe =
            StretchedNormals::with_kind(&rest, triangle.clone(), FaceTermKind::FoldSafe);
        let lipman = StretchedNormals::with_kind(&rest, triangle, FaceTermKind::Lipman);
        let at = |h: f64| [DVec3::ZERO, DVec3::X, DVec3::new(0.0, h, 0.0)];
        // u' = x, v' = h·y against u = x, v = y: σ = 1 + h², s = √((1 + h²)/2), A'/A = h.
        for h in [0.5f64, 1e-3, 1e-9, 0.0, -1e-9, -1e-3, -0.5] {
            let expected = h * (2.0 / (1.0 + h * h)).sqrt();
            let g = fold_safe.face(&at(h), 0);
            assert!(g.distance(DVec3::Z * expected) < 1e-15, "h = {h}: {g}");
            let s = ((1.0 + h * h) / 2.0).sqrt();
            let l = lipman.face(&at(h), 0);
            if h != 0.0 {
                assert!(
                    l.distance(DVec3::Z * s * h.signum()) < 1e-15,
                    "h = {h}: {l}"
                );
            }
        }
        // The fold-safe Jacobian at the fold itself is finite and gives the slope √2 along y.
        let jac = fold_safe.face_jacobian_at(0, at(0.0));
        assert!(jac[2].col(1).distance(DVec3::Z * std::f64::consts::SQRT_2) < 1e-15);
    }

    /// A near-conformal face map with singular values λ(1 ± ε): both terms have length λ to
    /// first order, ĝ = λ(1 − ε²)/√(1 + ε²) and Lipman's λ√(1 + ε²) exactly.
    #[test]
    fn both_terms_agree_to_second_order_on_near_conformal_maps() {
        let rest = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let triangle = vec![[0u32, 1, 2]];
        let (lambda, epsilon) = (1.3, 1e-3);
        let rotation = DQuat::from_axis_angle(DVec3::new(0.3, -1.0, 0.4).normalize(), 1.1);
        let map = |x: DVec3| {
            rotation
                * DVec3::new(
                    lambda * (1.0 + epsilon) * x.x,
                    lambda * (1.0 - epsilon) * x.y,
                    0.0,
                )
        };
        let deformed = rest.map(map);
        let normal = rotation * DVec3::Z;
        for (kind, length) in [
            (
                FaceTermKind::FoldSafe,
                lambda * (1.0 - epsilon * epsilon) / (1.0 + epsilon * epsilon).sqrt(),
            ),
            (
                FaceTermKind::Lipman,
                lambda * (1.0 + epsilon * epsilon).sqrt(),
            ),
        ] {
            let normals = StretchedNormals::with_kind(&rest, triangle.clone(), kind);
            let g = normals.face(&deformed, 0);
            assert!(g.distance(normal * length) < 1e-14, "{kind:?}: {g}");
            assert!((g.length() - lambda).abs() < 2.0 * lambda * epsilon * epsilon);
        }
    }

    #[test]
    fn face_term_names_parse_back() {
        for k in FaceTermKind::ALL {
            assert_eq!(k.name().parse::<FaceTermKind>(), Ok(k));
            assert_eq!(k.to_string(), k.name());
        }
        assert_eq!(
            "Fold_Safe".parse::<FaceTermKind>(),
            Ok(FaceTermKind::FoldSafe)
        );
        assert_eq!(
            "lipmann".parse::<FaceTermKind>().unwrap_err().to_string(),
            "unknown Green face term \"lipmann\": expected fold-safe or lipman"
        );
    }

    #[test]
    fn degenerate_faces_give_zero() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        let normals = StretchedNormals::new(&p, vec![[0, 1, 2]]);
        assert_eq!(normals.face(&p, 0), DVec3::ZERO);
        assert_eq!(normals.face_jacobian(&p, 0), [DMat3::ZERO; 3]);
    }
}
