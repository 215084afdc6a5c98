//! The face terms of a Green-coordinates deformation: g_t(C') = s_t(C') · n_t(C') for every cage
//! triangle t (Lipman et al. 2008, Sec. 4), with n_t the unit normal of the deformed triangle and
//! s_t its stretch factor relative to the binding cage:
//!
//! `s_t = √(|u'|²|v|² − 2(u'·v')(u·v) + |v'|²|u|²) / (√8 · area(t))`
//!
//! (u, v: the edges v₁ − v₀, v₂ − v₀ of the binding triangle; u', v' of the deformed one). A
//! similarity x ↦ λRx + b of the cage gives s_t = λ and g_t = λ R n_t, so the deformed points move
//! by the same similarity; at the binding cage g_t = n_t.
//!
//! [`StretchedNormals::face_jacobian`] gives ∂g_t/∂v'_a (three 3×3 blocks), which the Green
//! CageUp and CageRev Newton iterations use:
//! `∂g/∂u' = n ⊗ ∂s/∂u' − (s/|c'|)(I − n nᵀ)[v']×`, `∂g/∂v' = n ⊗ ∂s/∂v' + (s/|c'|)(I − n nᵀ)[u']×`
//! with c' = u' × v', `∂s/∂u' = (|v|² u' − (u·v) v') s/σ`, `∂s/∂v' = (|u|² v' − (u·v) u') s/σ`
//! and σ the radicand.

use glam::{DMat3, DVec3};

/// The binding triangle's quadratic form: |u|², |v|², u·v and 1/(√8 · area).
#[derive(Debug, Clone, Copy, PartialEq)]
struct BindingFace {
    uu: f64,
    vv: f64,
    uv: f64,
    inverse_scale: f64,
}

/// g_t(C') = s_t n_t for every cage triangle (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct StretchedNormals {
    triangles: Vec<[u32; 3]>,
    binding: Vec<BindingFace>,
}

impl StretchedNormals {
    /// From the binding cage (the cage the Green coordinates were computed for) and its
    /// outward-oriented triangles (`#F`). A degenerate binding triangle gets g = 0 (its Green
    /// face coordinates are zero too).
    pub fn new(binding_cage: &[DVec3], triangles: Vec<[u32; 3]>) -> Self {
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
        Self { triangles, binding }
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
        let length = cross.length();
        if length <= f64::MIN_POSITIVE {
            return DVec3::ZERO;
        }
        let sigma = radicand(f, u, v);
        cross * (sigma.max(0.0).sqrt() * f.inverse_scale / length)
    }

    /// ∂g_t/∂v'_a for the three corners a of face t (3×3 each, columns: d/dx, d/dy, d/dz), at
    /// `cage`. Zero for a degenerate deformed or binding triangle.
    pub fn face_jacobian(&self, cage: &[DVec3], t: usize) -> [DMat3; 3] {
        self.face_jacobian_at(t, self.triangles[t].map(|v| cage[v as usize]))
    }

    /// [`Self::face_jacobian`] of face t with its corners at `corners`.
    pub fn face_jacobian_at(&self, t: usize, corners: [DVec3; 3]) -> [DMat3; 3] {
        let f = &self.binding[t];
        let [a, b, c] = corners;
        let (u, v) = (b - a, c - a);
        let cross = u.cross(v);
        let length = cross.length();
        let sigma = radicand(f, u, v);
        if length <= f64::MIN_POSITIVE || sigma <= f64::MIN_POSITIVE || f.inverse_scale == 0.0 {
            return [DMat3::ZERO; 3];
        }
        let s = sigma.sqrt() * f.inverse_scale;
        let n = cross / length;
        let ds_du = (f.vv * u - f.uv * v) * (s / sigma);
        let ds_dv = (f.uu * v - f.uv * u) * (s / sigma);
        let project = DMat3::IDENTITY - outer(n, n);
        let k = s / length;
        let dg_du = outer(n, ds_du) - project * cross_matrix(v) * k;
        let dg_dv = outer(n, ds_dv) + project * cross_matrix(u) * k;
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

    #[test]
    fn unit_normals_at_binding_and_similarity_equivariance() {
        let (p, t) = cage();
        let normals = StretchedNormals::new(&p, t.clone());
        let mut g = vec![DVec3::ZERO; t.len()];
        normals.apply(&p, &mut g);
        for (gt, tri) in g.iter().zip(&t) {
            let [a, b, c] = tri.map(|v| p[v as usize]);
            let n = (b - a).cross(c - a).normalize();
            assert!(gt.distance(n) < 1e-15);
        }
        let rotation = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.8);
        let moved: Vec<DVec3> = p
            .iter()
            .map(|x| rotation * (*x * 1.7) + DVec3::new(3.0, -1.0, 2.0))
            .collect();
        let mut h = vec![DVec3::ZERO; t.len()];
        normals.apply(&moved, &mut h);
        for (ht, gt) in h.iter().zip(&g) {
            assert!(ht.distance(rotation * (*gt * 1.7)) < 1e-14);
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let (p, t) = cage();
        let normals = StretchedNormals::new(&p, t.clone());
        let deformed: Vec<DVec3> = p
            .iter()
            .enumerate()
            .map(|(i, x)| *x * DVec3::new(1.3, 0.8, 1.1) + DVec3::splat(0.1 * i as f64))
            .collect();
        let step = 1e-6;
        for face in 0..t.len() {
            let jac = normals.face_jacobian(&deformed, face);
            for (corner, block) in jac.iter().enumerate() {
                for axis in 0..3 {
                    let mut plus = deformed.clone();
                    let mut minus = deformed.clone();
                    plus[t[face][corner] as usize][axis] += step;
                    minus[t[face][corner] as usize][axis] -= step;
                    let fd =
                        (normals.face(&plus, face) - normals.face(&minus, face)) / (2.0 * step);
                    let analytic = block.col(axis);
                    assert!(fd.distance(analytic) < 1e-8, "{fd} vs {analytic}");
                }
            }
        }
    }

    #[test]
    fn degenerate_faces_give_zero() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        let normals = StretchedNormals::new(&p, vec![[0, 1, 2]]);
        assert_eq!(normals.face(&p, 0), DVec3::ZERO);
        assert_eq!(normals.face_jacobian(&p, 0), [DMat3::ZERO; 3]);
    }
}
