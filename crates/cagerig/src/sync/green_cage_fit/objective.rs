//! The fit's objective ½‖r‖² (r = F_R(x) − M'_R) for [`super::GreenCageFit`]: its value and
//! gradient Jᵀr, and its full Hessian JᵀJ + Σ_f ∇²((ψ_Rᵀr)_f · g_f) (see the module docs of
//! [`super`]); with a prior ([`super::prior`]) plus ½ Σ_axes (x − P)ᵀW(x − P), W(x − P) and
//! W ⊗ I₃.

use glam::{DAffine3, DVec3};

use super::evaluation::{Evaluation, FaceScratch};
use super::prior::FitPrior;
use super::rows::transposed_times_points;
use super::{GreenCageFit, rows_of};

impl GreenCageFit {
    /// ½‖r‖² and Jᵀr at x (r = F_R(x) − target and Jᵀr into `out`, with `faces` as scratch);
    /// returns (½‖r‖², max |Jᵀr|), infinite when not finite.
    pub(super) fn evaluate(
        &self,
        x: &[DVec3],
        target: &[DVec3],
        faces: &mut FaceScratch,
        out: &mut Evaluation,
    ) -> (f64, f64) {
        let FaceScratch {
            g,
            face_sums,
            pulls,
        } = faces;
        let Evaluation { residual, gradient } = out;
        self.normals.apply(x, g);
        rows_of(&self.vertex_rows, &self.face_rows, x, g, residual);
        let mut energy = 0.0;
        for (r, t) in residual.iter_mut().zip(target) {
            *r -= *t;
            energy += 0.5 * r.length_squared();
        }
        // Jᵀr = φ_Rᵀ r + Σ_f (∂g_f/∂x)ᵀ (ψ_Rᵀ r)_f.
        transposed_times_points(&self.vertex_rows_transposed, residual, gradient);
        transposed_times_points(&self.face_rows_transposed, residual, face_sums);
        for (f, triangle) in self.normals.triangles().iter().enumerate() {
            let blocks = self.normals.face_jacobian(x, f);
            for (corner, block) in triangle.iter().zip(blocks) {
                gradient[*corner as usize] += block.transpose() * face_sums[f];
            }
        }
        energy += self.add_prior_gradient(x, gradient, pulls);
        let largest = gradient
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
        if energy.is_finite() && largest.is_finite() {
            (energy, largest)
        } else {
            (f64::INFINITY, f64::INFINITY)
        }
    }

    /// The Hessian of the fit's energy at x into `self.normal_matrix`:
    /// JᵀJ + Σ_f ∇²((ψ_Rᵀr)_f · g_f) (+ W ⊗ I₃ with a prior), with r the residual rows at x
    /// (`residual`, `#R`).
    pub(super) fn hessian_at(&mut self, x: &[DVec3], residual: &[DVec3]) {
        self.gauss_newton_matrix_at(x);
        let mut weights = std::mem::take(&mut self.hessian_face_weights);
        transposed_times_points(&self.face_rows_transposed, residual, &mut weights);
        for (f, (triangle, &weight)) in self.normals.triangles().iter().zip(&weights).enumerate() {
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
        self.hessian_face_weights = weights;
        self.add_prior_hessian();
    }
}

impl GreenCageFit {
    /// Regularises the fit with `prior` (see [`FitPrior`]), or keeps it aside for
    /// [`Self::set_regularised`] when `on` is false.
    pub fn with_prior(mut self, prior: FitPrior, on: bool) -> Self {
        if on {
            self.prior = Some(prior);
        } else {
            self.prior_aside = Some(prior);
        }
        self
    }

    /// The regulariser, when the fit has one.
    pub fn prior(&self) -> Option<&FitPrior> {
        self.prior.as_ref()
    }

    /// Turns the regulariser on or off (kept aside while off); returns whether the fit is now
    /// regularised (false when asked on without a prior given to [`Self::with_prior`]).
    /// Forgets the last solution, as the energy changed.
    pub fn set_regularised(&mut self, on: bool) -> bool {
        if on && self.prior.is_none() {
            self.prior = self.prior_aside.take();
        } else if !on && self.prior.is_some() {
            self.prior_aside = self.prior.take();
        }
        self.has_last_target = false;
        self.lu.invalidate();
        self.factor_damping = f64::INFINITY;
        self.prior.is_some()
    }

    /// Sets P for the next [`GreenCageFit::apply`]: `rest_cage` (`#C`) carried by the skinning
    /// transforms `posed_from_rest` (`#J`, the LBS transforms also under DQS and CoR, as the
    /// fitting rows' ghost). No allocation once the prior's moments are computed for `rest_cage`.
    pub fn carry_prior(&mut self, posed_from_rest: &[DAffine3], rest_cage: &[DVec3]) {
        if let Some(p) = &mut self.prior {
            p.carry(posed_from_rest, rest_cage);
        }
    }

    /// P of the current event, when the fit has a prior (`#C`).
    pub fn prior_target(&self) -> Option<&[DVec3]> {
        self.prior.as_ref().map(FitPrior::target)
    }

    /// The prior's energy at x added to the returned value and its gradient to `gradient` (0
    /// without a prior).
    pub(super) fn add_prior_gradient(
        &self,
        x: &[DVec3],
        gradient: &mut [DVec3],
        pulls: &mut [DVec3],
    ) -> f64 {
        self.prior
            .as_ref()
            .map_or(0.0, |p| p.add_to_gradient(x, gradient, pulls))
    }

    /// The prior's energy ½ Σ_axes (x − P)ᵀW(x − P) at x (0 without a prior). No allocation.
    pub(super) fn prior_energy(&self, x: &[DVec3], pulls: &mut [DVec3]) -> f64 {
        self.prior.as_ref().map_or(0.0, |p| p.energy(x, pulls))
    }

    /// normal_matrix += W ⊗ I₃ (nothing without a prior).
    pub(super) fn add_prior_hessian(&mut self) {
        if let Some(p) = &self.prior {
            p.add_to_hessian(&mut self.normal_matrix);
        }
    }

    /// P of the current solve: the blend (1 − a)·P_last + a·P_target (a continuation's piece).
    pub(super) fn blend_prior(&mut self, a: f64) {
        if let Some(p) = &mut self.prior {
            p.blend(a);
        }
    }

    /// After a converged solve: the current P becomes the last solution's.
    pub(super) fn keep_prior_as_last(&mut self) {
        if let Some(p) = &mut self.prior {
            p.keep_as_last();
        }
    }

    /// `cage` (`#C`) becomes the last solution's P.
    pub(super) fn restart_prior_from(&mut self, cage: &[DVec3]) {
        if let Some(p) = &mut self.prior {
            p.restart_from(cage);
        }
    }
}
