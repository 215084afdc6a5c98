//! The fit's objective ½‖r‖² (r = F_R(x) − M'_R) for [`super::GreenCageFit`]: its value and
//! gradient Jᵀr, and its full Hessian JᵀJ + Σ_f ∇²((ψ_Rᵀr)_f · g_f) (see the module docs of
//! [`super`]).

use glam::DVec3;

use super::{GreenCageFit, rows_of};

impl GreenCageFit {
    /// ½‖r‖² and Jᵀr at x (r = F_R(x) − target into `residual`, Jᵀr into `gradient`); returns
    /// (½‖r‖², max |Jᵀr|), infinite when not finite.
    pub(super) fn evaluate(
        &self,
        x: &[DVec3],
        target: &[DVec3],
        g: &mut [DVec3],
        face_sums: &mut [DVec3],
        residual: &mut [DVec3],
        gradient: &mut [DVec3],
    ) -> (f64, f64) {
        self.normals.apply(x, g);
        rows_of(&self.vertex_rows, &self.face_rows, x, g, residual);
        let mut energy = 0.0;
        for (r, t) in residual.iter_mut().zip(target) {
            *r -= *t;
            energy += 0.5 * r.length_squared();
        }
        // Jᵀr = φ_Rᵀ r + Σ_f (∂g_f/∂x)ᵀ (ψ_Rᵀ r)_f.
        for (k, out) in gradient.iter_mut().enumerate() {
            let column = self.vertex_rows.col(k);
            *out = residual
                .iter()
                .enumerate()
                .fold(DVec3::ZERO, |acc, (i, r)| acc + column[i] * *r);
        }
        for (f, sum) in face_sums.iter_mut().enumerate() {
            let column = self.face_rows.col(f);
            *sum = residual
                .iter()
                .enumerate()
                .fold(DVec3::ZERO, |acc, (i, r)| acc + column[i] * *r);
        }
        for (f, triangle) in self.normals.triangles().iter().enumerate() {
            let blocks = self.normals.face_jacobian(x, f);
            for (corner, block) in triangle.iter().zip(blocks) {
                gradient[*corner as usize] += block.transpose() * face_sums[f];
            }
        }
        let largest = gradient
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
        if energy.is_finite() && largest.is_finite() {
            (energy, largest)
        } else {
            (f64::INFINITY, f64::INFINITY)
        }
    }

    /// The Hessian of ½‖r‖² at x into `self.normal_matrix`: JᵀJ + Σ_f ∇²((ψ_Rᵀr)_f · g_f), with r
    /// the residual rows at x (`residual`, `#R`).
    pub(super) fn hessian_at(&mut self, x: &[DVec3], residual: &[DVec3]) {
        self.gauss_newton_matrix_at(x);
        for (f, triangle) in self.normals.triangles().iter().enumerate() {
            let column = self.face_rows.col(f);
            let weight = residual
                .iter()
                .enumerate()
                .fold(DVec3::ZERO, |acc, (i, r)| acc + column[i] * *r);
            let corners = triangle.map(|v| x[v as usize]);
            let scale = (corners[1] - corners[0])
                .length()
                .max((corners[2] - corners[0]).length());
            let step = 1e-6 * scale.max(f64::MIN_POSITIVE);
            let hessian = self.normals.weighted_face_hessian(f, corners, weight, step);
            for (p, row) in hessian.iter().enumerate() {
                let i = 3 * triangle[p / 3] as usize + p % 3;
                for (q, value) in row.iter().enumerate() {
                    let j = 3 * triangle[q / 3] as usize + q % 3;
                    self.normal_matrix[(i, j)] += value;
                }
            }
        }
    }
}
