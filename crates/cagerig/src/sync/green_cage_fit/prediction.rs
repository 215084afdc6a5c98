//! The warm start of [`super::GreenCageFit`] from its last converged solution, and the Newton
//! step on the stored factors that it, the chord steps and the damped steps share.

use glam::DVec3;

use super::{CHORD_DAMPING, GreenCageFit, damping_scale};

impl GreenCageFit {
    /// Replaces the warm start `posed_cage` by the first-order prediction from the last converged
    /// solution x₀ (fitted to the rows t₀), when the fit likes it better: by the implicit
    /// function theorem the solution for the rows t moves by H⁻¹J(x₀)ᵀ(t − t₀) = −H⁻¹∇E(x₀; t),
    /// one chord step from x₀ on the last factors (taken at x₀ to round-off when that solve
    /// converged). It follows the fit's flat directions, which a warm start moved with the bones
    /// does not know about. With a prior, the carried cage P is tried as a start as well. No
    /// allocation.
    pub(super) fn predict_from_last_solution(
        &mut self,
        target: &[DVec3],
        posed_cage: &mut [DVec3],
    ) {
        let predict = self.has_last_target
            && self.lu.is_factorised()
            && self.factor_damping <= CHORD_DAMPING * damping_scale(&self.normal_matrix);
        if !predict && self.prior.is_none() {
            return;
        }
        let mut faces = std::mem::take(&mut self.faces);
        let mut evaluation = std::mem::take(&mut self.trial_evaluation);
        let mut trial = std::mem::take(&mut self.trial);
        let (mut start_energy, start_norm) =
            self.evaluate(posed_cage, target, &mut faces, &mut evaluation);
        // A warm start that is already the answer (after a grab: CageRev made it one) stays.
        if start_norm > self.tolerance {
            // With a prior, the carried cage P is a start too.
            if let Some(p) = &self.prior {
                trial.copy_from_slice(p.target());
                let (carried_energy, _) =
                    self.evaluate(&trial, target, &mut faces, &mut evaluation);
                if carried_energy < start_energy {
                    posed_cage.copy_from_slice(&trial);
                    start_energy = carried_energy;
                }
            }
            if predict {
                let _ = self.evaluate(&self.last_solution, target, &mut faces, &mut evaluation);
                let from = std::mem::take(&mut self.last_solution);
                self.newton_step(&evaluation.gradient, &from, &mut trial);
                self.last_solution = from;
                let (predicted_energy, _) =
                    self.evaluate(&trial, target, &mut faces, &mut evaluation);
                if predicted_energy < start_energy {
                    posed_cage.copy_from_slice(&trial);
                }
            }
        }
        self.faces = faces;
        self.trial_evaluation = evaluation;
        self.trial = trial;
    }

    /// The step −H⁻¹·`gradient` on the current factors into `self.step` (`3#C`), and
    /// `trial` = `from` + step (`#C`).
    pub(super) fn newton_step(&mut self, gradient: &[DVec3], from: &[DVec3], trial: &mut [DVec3]) {
        for (k, d) in gradient.iter().enumerate() {
            self.step[3 * k] = -d.x;
            self.step[3 * k + 1] = -d.y;
            self.step[3 * k + 2] = -d.z;
        }
        self.lu.solve(&mut self.step);
        for (k, (t, p)) in trial.iter_mut().zip(from).enumerate() {
            *t = *p + DVec3::new(self.step[3 * k], self.step[3 * k + 1], self.step[3 * k + 2]);
        }
    }
}
