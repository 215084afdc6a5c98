//! CageUp for Green coordinates (S'→C'): the current cage C' whose Green deformation fits the
//! skinned fitting rows M'_R, by Gauss–Newton.
//!
//! With Green coordinates the fitting rows are `F_R(C') = φ_R C' + ψ_R g(C')` (g the face terms,
//! see [`crate::coords::stretched_normals`]), non-linear in C'. An exact interpolation of #C rows (the
//! MVC CageUp) has no solution once the skinned rows leave what a Green cage can produce (a
//! strong bend folds the interpolation map), so CageUp is the least-squares fit
//!
//! `C' = argmin ½ ‖F_R(C') − M'_R‖² + ½ Σ_axes (C' − P)ᵀ W (C' − P)`  over the rows R (MaxVol
//! rows of [φ ψ], #C + #F of them, or all rows), the second term when the fit is regularised
//! towards the carried cage P ([`prior`]; W = λ(LᵀL + εI), `#C × #C`),
//!
//! solved by Newton's method on the gradient Jᵀr, with the analytic Jacobian
//! `J = φ_R ⊗ I₃ + ψ_R ∂g/∂C'` (`3#R × 3#C`) and the Hessian `JᵀJ + Σ_f ∇²(u_f·g_f)` (+ W ⊗ I₃;
//! u = ψ_Rᵀr; the second-order term by differences of the analytic ∂g, as the fitted rows are not all
//! reachable and Gauss–Newton alone converges slowly on such large-residual fits). Where that
//! Hessian is not positive definite, or its quadratic model predicts the decrease of ½‖r‖² badly,
//! the step is damped (Levenberg–Marquardt on the full Hessian, i.e. a trust region whose damping
//! shrinks to 0 — pure Newton — as the iterate converges). Warm-started from the previous C'
//! moved by the change of the skinning transforms (done by the session); the first steps of an
//! event reuse the previous event's undamped Hessian factors (chord steps) while each halves the
//! gradient. The fit is converged when the
//! gradient Jᵀr is below [`GRADIENT_TOLERANCE`] of the cage size: C' is then a stationary point
//! to round-off, which is what CageRev inverts exactly ([`reverser`]). A large
//! change of pose in one event is split into pieces (continuation) when the direct solve stalls.

use faer::Mat;
use glam::{DMat3, DVec3};

use crate::coords::stretched_normals::StretchedNormals;
use crate::error::RigError;
use crate::sync::dense_lu::DenseLu;
use crate::sync::newton::{NewtonReport, solve_by_continuation};

mod budget;
mod damping;
mod evaluation;
mod gram;
mod objective;
mod prediction;
pub mod prior;
pub mod reverser;
mod rows;
#[cfg(test)]
mod tests;

pub use budget::{AfterDirectSolve, FitBudget, UNFITTED_STEPS};
use damping::{damping_scale, lower_damping, raise_damping};
use evaluation::{Evaluation, FaceScratch};
use gram::gram_matrices;
pub use prior::FitPrior;
pub(crate) use rows::{rows_jacobian_into, rows_of};

/// Converged when max |Jᵀr| is at most this fraction of the cage size.
pub const GRADIENT_TOLERANCE: f64 = 1e-13;
/// A fit whose gradient stops falling above [`GRADIENT_TOLERANCE`] (the round-off floor of
/// Jᵀr: on cages with large face coordinates it lies near 1.4e-13 of the cage size) is accepted
/// when max |Jᵀr| is at most this fraction of the cage size; a continuation piece too. The
/// session refuses an event whose CageUp ends above it.
pub const ACCEPTED_GRADIENT: f64 = 1e-10;
/// At the round-off floor: the quadratic model predicts a decrease of the energy by at most
/// this fraction of it.
const FLOOR_ENERGY_CHANGE: f64 = 1e-12;
/// Steps at the round-off floor that do not halve the gradient before the solve stops there.
const FLOOR_STALLS: usize = 3;
/// A chord step (stale Hessian) is kept only when it leaves at most this fraction of the
/// gradient.
pub const CHORD_RATE: f64 = 0.5;
/// The last factors serve chord steps when their damping is at most this fraction of the
/// Hessian's scale (a converged solve ends with a damping far below it).
pub const CHORD_DAMPING: f64 = 1e-3;
/// At most this many steps for the direct solve of an event.
pub const MAX_STEPS: usize = 60;
/// At most this many steps per piece of a continuation.
pub const MAX_PIECE_STEPS: usize = 20;

/// Precomputed Green CageUp (see the module docs).
#[derive(Debug, Clone)]
pub struct GreenCageFit {
    num_cage: usize,
    /// φ_R, `#R × #C`.
    vertex_rows: Mat<f64>,
    /// ψ_R, `#R × #F`.
    face_rows: Mat<f64>,
    /// φ_Rᵀ (`#C × #R`) and ψ_Rᵀ (`#F × #R`): the gradient's φ_Rᵀr and ψ_Rᵀr read their
    /// contiguous columns ([`rows::transposed_times_points`]).
    vertex_rows_transposed: Mat<f64>,
    face_rows_transposed: Mat<f64>,
    normals: StretchedNormals,
    /// The binding cage (the start when a warm start is not finite).
    binding_cage: Vec<DVec3>,
    lu: DenseLu,
    /// The Levenberg–Marquardt damping the last solve ended with (the next one starts there).
    damping: f64,
    /// The damping of the factors in `lu` (0: an undamped Hessian, usable for chord steps).
    factor_damping: f64,
    tolerance: f64,
    /// [`ACCEPTED_GRADIENT`] × the cage size.
    accepted: f64,
    /// The Gram matrices of the fitting rows, constant: φ_Rᵀφ_R (`#C × #C`), φ_Rᵀψ_R
    /// (`#C × #F`) and ψ_Rᵀψ_R (`#F × #F`). JᵀJ is assembled from them and the sparse ∂g/∂C in
    /// O(#F²) block operations per step instead of the O(#R·#C²) product of J with itself.
    vertex_gram: Mat<f64>,
    vertex_face_gram: Mat<f64>,
    face_gram: Mat<f64>,
    /// Scratch: ∂g_f/∂(corners of f) (`#F`), (ψ_Rᵀψ_R ⊗ I₃)·∂g/∂C as `#F × #C` blocks, and
    /// JᵀJ as `#C × #C` blocks (row-major).
    face_blocks: Vec<[DMat3; 3]>,
    face_gram_blocks: Vec<DMat3>,
    hessian_blocks: Vec<DMat3>,
    /// Scratch: ψ_Rᵀr, the weights of the faces' second-order terms in the Hessian (`#F`).
    hessian_face_weights: Vec<DVec3>,
    /// The Hessian of the fit (`3#C × 3#C`), refreshed with the factors.
    normal_matrix: Mat<f64>,
    /// Scratch of the objective's evaluations: the face terms, and the residual and gradient at
    /// the current point and at a trial point.
    faces: FaceScratch,
    current: Evaluation,
    trial_evaluation: Evaluation,
    trial: Vec<DVec3>,
    step: Vec<f64>,
    /// The rows the last converged solution was fitted to, and that solution (the start of a
    /// continuation).
    last_target: Vec<DVec3>,
    has_last_target: bool,
    last_solution: Vec<DVec3>,
    piece_target: Vec<DVec3>,
    /// The direct solve's cage while a retry runs (`#C`).
    retry_cage: Vec<DVec3>,
    last: NewtonReport,
    /// The regulariser towards the carried cage ([`prior`]), when the fit has one, and a prior
    /// kept aside while the fit is not regularised.
    prior: Option<FitPrior>,
    prior_aside: Option<FitPrior>,
}

impl GreenCageFit {
    /// From φ_R (`#R × #C`) and ψ_R (`#R × #F`) of the fitting rows, the binding cage (`#C`) and
    /// its stretched normals.
    pub fn new(
        vertex_rows: Mat<f64>,
        face_rows: Mat<f64>,
        binding_cage: &[DVec3],
        normals: StretchedNormals,
    ) -> Result<Self, RigError> {
        let (lo, hi) = crate::mesh::bounding_box(binding_cage);
        let cage_size = (hi - lo).length();
        let num_rows = vertex_rows.nrows();
        if face_rows.nrows() != num_rows || face_rows.ncols() != normals.len() {
            return Err(RigError::SizeMismatch {
                what: "Green CageUp: fitting rows of ψ (#R × #F)",
                expected: num_rows * normals.len(),
                actual: face_rows.nrows() * face_rows.ncols(),
            });
        }
        let num_cage = vertex_rows.ncols();
        if num_rows < num_cage {
            return Err(RigError::SizeMismatch {
                what: "Green CageUp: fitting rows (at least one per cage vertex)",
                expected: num_cage,
                actual: num_rows,
            });
        }
        if binding_cage.len() != num_cage {
            return Err(RigError::SizeMismatch {
                what: "Green CageUp: binding cage vertices",
                expected: num_cage,
                actual: binding_cage.len(),
            });
        }
        let num_faces = normals.len();
        let (vertex_gram, vertex_face_gram, face_gram) = gram_matrices(&vertex_rows, &face_rows);
        Ok(Self {
            num_cage,
            vertex_rows_transposed: vertex_rows.transpose().to_owned(),
            face_rows_transposed: face_rows.transpose().to_owned(),
            vertex_rows,
            face_rows,
            normals,
            binding_cage: binding_cage.to_vec(),
            lu: DenseLu::new(3 * num_cage, "the Green-coordinates Hessian"),
            damping: 0.0,
            factor_damping: f64::INFINITY,
            tolerance: GRADIENT_TOLERANCE * cage_size.max(f64::MIN_POSITIVE),
            accepted: ACCEPTED_GRADIENT * cage_size.max(f64::MIN_POSITIVE),
            vertex_gram,
            vertex_face_gram,
            face_gram,
            face_blocks: vec![[DMat3::ZERO; 3]; num_faces],
            face_gram_blocks: vec![DMat3::ZERO; num_faces * num_cage],
            hessian_blocks: vec![DMat3::ZERO; num_cage * num_cage],
            hessian_face_weights: vec![DVec3::ZERO; num_faces],
            normal_matrix: Mat::zeros(3 * num_cage, 3 * num_cage),
            faces: FaceScratch::new(num_cage, num_faces),
            current: Evaluation::new(num_rows, num_cage),
            trial_evaluation: Evaluation::new(num_rows, num_cage),
            trial: vec![DVec3::ZERO; num_cage],
            step: vec![0.0; 3 * num_cage],
            last_target: vec![DVec3::ZERO; num_rows],
            has_last_target: false,
            last_solution: vec![DVec3::ZERO; num_cage],
            piece_target: vec![DVec3::ZERO; num_rows],
            retry_cage: vec![DVec3::ZERO; num_cage],
            last: NewtonReport::default(),
            prior: None,
            prior_aside: None,
        })
    }

    /// The stretched normals g of the binding cage.
    pub fn normals(&self) -> &StretchedNormals {
        &self.normals
    }

    /// φ_R, `#R × #C`.
    pub fn vertex_rows(&self) -> &Mat<f64> {
        &self.vertex_rows
    }

    /// ψ_R, `#R × #F`.
    pub fn face_rows(&self) -> &Mat<f64> {
        &self.face_rows
    }

    /// Forgets what earlier solves left (their factors and solution) and takes `cage` (`#C`) as
    /// the last converged solution, for its own rows F_R(cage): the next [`GreenCageFit::apply`]
    /// that stalls continues from there to its rows in pieces. No allocation.
    pub fn restart_from(&mut self, cage: &[DVec3]) {
        let mut g = std::mem::take(&mut self.faces.g);
        let mut rows = std::mem::take(&mut self.last_target);
        self.rows_of(cage, &mut g, &mut rows);
        self.faces.g = g;
        self.last_target = rows;
        self.last_solution.copy_from_slice(cage);
        self.restart_prior_from(cage);
        self.has_last_target = true;
        self.lu.invalidate();
        self.factor_damping = f64::INFINITY;
        self.damping = 0.0;
    }

    /// The report of the last [`GreenCageFit::apply`] (`residual` is max |Jᵀr|).
    pub fn last_report(&self) -> NewtonReport {
        self.last
    }

    /// The convergence tolerance on max |Jᵀr|, in scene units.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// ½‖F_R(x) − target‖² plus the prior's ½ Σ_axes (x − P)ᵀW(x − P) (the fit's energy at x).
    /// No allocation.
    pub fn energy(&mut self, target: &[DVec3], x: &[DVec3]) -> f64 {
        let mut g = std::mem::take(&mut self.faces.g);
        let mut pulls = std::mem::take(&mut self.faces.pulls);
        let mut rows = std::mem::take(&mut self.trial_evaluation.residual);
        self.rows_of(x, &mut g, &mut rows);
        let energy = rows
            .iter()
            .zip(target)
            .map(|(r, t)| 0.5 * r.distance_squared(*t))
            .sum::<f64>()
            + self.prior_energy(x, &mut pulls);
        self.faces.g = g;
        self.faces.pulls = pulls;
        self.trial_evaluation.residual = rows;
        if energy.is_finite() {
            energy
        } else {
            f64::INFINITY
        }
    }

    /// F_R(x) = φ_R x + ψ_R g(x) into `out` (`#R`), with g(x) into `g`.
    pub fn rows_of(&self, x: &[DVec3], g: &mut [DVec3], out: &mut [DVec3]) {
        self.normals.apply(x, g);
        rows_of(&self.vertex_rows, &self.face_rows, x, g, out);
    }

    /// Fits C' (`posed_cage`, `#C`; on entry the warm start, normally the previous C'; a
    /// non-finite start is replaced by the binding cage) to the rows `target` (M'_R, `#R`). Errors when JᵀJ is singular; a fit
    /// that stops above the tolerance is reported in [`NewtonReport::residual`] (the caller
    /// decides). No allocation (a refactorisation reuses the stored matrices).
    pub fn apply(
        &mut self,
        target: &[DVec3],
        posed_cage: &mut [DVec3],
    ) -> Result<NewtonReport, RigError> {
        self.apply_within(target, posed_cage, FitBudget::FULL)
    }

    /// [`GreenCageFit::apply`] within `budget`.
    pub fn apply_within(
        &mut self,
        target: &[DVec3],
        posed_cage: &mut [DVec3],
        budget: FitBudget,
    ) -> Result<NewtonReport, RigError> {
        debug_assert_eq!(target.len(), self.current.residual.len());
        if posed_cage.iter().any(|p| !p.is_finite()) {
            posed_cage.copy_from_slice(&self.binding_cage);
            self.has_last_target = false;
        }
        self.predict_from_last_solution(target, posed_cage);
        let mut total = self.solve_for(target, posed_cage, budget.steps)?;
        // A direct solve that stopped at the round-off floor below the accepted gradient is
        // done; one that ran out of steps above it continues in pieces, each accepted there.
        if total.residual > self.accepted
            && self.has_last_target
            && budget.then == AfterDirectSolve::RetryFromLastSolution
        {
            self.retry_cage.copy_from_slice(posed_cage);
            posed_cage.copy_from_slice(&self.last_solution);
            let retry = self.solve_for(target, posed_cage, budget.steps)?;
            total.iterations += retry.iterations;
            total.factorisations += retry.factorisations;
            if retry.residual <= self.accepted {
                total.residual = retry.residual;
            } else {
                posed_cage.copy_from_slice(&self.retry_cage);
            }
        }
        if total.residual > self.accepted
            && self.has_last_target
            && budget.then == AfterDirectSolve::Continuation
        {
            let accepted = self.accepted;
            solve_by_continuation(accepted, &mut total, |a, first| {
                if first {
                    posed_cage.copy_from_slice(&self.last_solution);
                }
                let mut piece_target = std::mem::take(&mut self.piece_target);
                for ((p, last), t) in piece_target.iter_mut().zip(&self.last_target).zip(target) {
                    *p = last.lerp(*t, a);
                }
                self.blend_prior(a);
                let report = self.solve_for(&piece_target, posed_cage, MAX_PIECE_STEPS);
                self.piece_target = piece_target;
                report
            })?;
            self.blend_prior(1.0);
        }
        if total.residual <= self.accepted {
            self.last_target.copy_from_slice(target);
            self.last_solution.copy_from_slice(posed_cage);
            self.keep_prior_as_last();
            self.has_last_target = true;
        }
        self.last = total;
        Ok(total)
    }

    /// J = φ_R ⊗ I₃ + ψ_R ∂g/∂x at x into `out` (`3#R × 3#C`).
    pub fn jacobian_into(&self, x: &[DVec3], out: &mut Mat<f64>) {
        rows_jacobian_into(&self.vertex_rows, &self.face_rows, &self.normals, x, out);
    }

    /// Factorises the stored Hessian plus `damping`·I.
    fn factorise_damped(&mut self, damping: f64) -> Result<(), RigError> {
        self.factor_damping = damping;
        let n = 3 * self.num_cage;
        let a = self.lu.matrix_mut();
        for c in 0..n {
            let column = self.normal_matrix.col(c);
            for r in 0..n {
                a[c * n + r] = column[r];
            }
            a[c * n + c] += damping;
        }
        self.lu.factorise()
    }

    /// One Gauss–Newton solve for the rows `target` from `posed_cage`.
    fn solve_for(
        &mut self,
        target: &[DVec3],
        posed_cage: &mut [DVec3],
        max_steps: usize,
    ) -> Result<NewtonReport, RigError> {
        let mut faces = std::mem::take(&mut self.faces);
        let mut current = std::mem::take(&mut self.current);
        let mut trial_evaluation = std::mem::take(&mut self.trial_evaluation);
        let mut trial = std::mem::take(&mut self.trial);
        let mut report = NewtonReport::default();
        #[expect(clippy::redundant_closure_call)] // the loop's `?` stays inside, scratch goes back
        let outcome = (|| {
            let (mut energy, mut norm) =
                self.evaluate(posed_cage, target, &mut faces, &mut current);
            // Chord steps first: the last solve's undamped Hessian factors (the previous event's
            // solution is close), as long as each step at least halves the gradient.
            if self.lu.is_factorised()
                && self.factor_damping <= CHORD_DAMPING * damping_scale(&self.normal_matrix)
            {
                while norm > self.tolerance && report.iterations < max_steps {
                    self.newton_step(&current.gradient, posed_cage, &mut trial);
                    let (trial_energy, trial_norm) =
                        self.evaluate(&trial, target, &mut faces, &mut trial_evaluation);
                    if !(trial_energy <= energy && trial_norm <= CHORD_RATE * norm) {
                        break;
                    }
                    report.iterations += 1;
                    posed_cage.copy_from_slice(&trial);
                    std::mem::swap(&mut current, &mut trial_evaluation);
                    energy = trial_energy;
                    norm = trial_norm;
                }
            }
            // Levenberg–Marquardt on the full Hessian (a trust region): the damping μ grows when
            // the quadratic model predicts badly and shrinks (to 0: Newton) when it predicts well.
            let mut damping = self.damping;
            let mut hessian_current = false;
            // Steps in a row at the round-off floor (the model predicts an energy change below
            // FLOOR_ENERGY_CHANGE of it) that did not halve the gradient; at FLOOR_STALLS the
            // solve stops there.
            let mut floor_stalls = 0;
            // The damping of the last step that made real progress (not at the floor).
            let mut accepted_damping = damping;
            while norm > self.tolerance && report.iterations < max_steps {
                if floor_stalls >= FLOOR_STALLS {
                    break;
                }
                if !hessian_current {
                    self.hessian_at(posed_cage, &current.residual);
                    hessian_current = true;
                    report.factorisations += 1;
                }
                if self.factorise_damped(damping).is_err() {
                    damping = raise_damping(damping, &self.normal_matrix, 10.0);
                    if !damping.is_finite() {
                        break;
                    }
                    continue;
                }
                self.newton_step(&current.gradient, posed_cage, &mut trial);
                let slope: f64 = current
                    .gradient
                    .iter()
                    .enumerate()
                    .map(|(k, d)| {
                        d.dot(DVec3::new(
                            self.step[3 * k],
                            self.step[3 * k + 1],
                            self.step[3 * k + 2],
                        ))
                    })
                    .sum();
                if slope.is_nan() || slope >= 0.0 {
                    damping = raise_damping(damping, &self.normal_matrix, 10.0);
                    if !damping.is_finite() {
                        break;
                    }
                    continue;
                }
                let step_squared: f64 = self.step.iter().map(|v| v * v).sum();
                let predicted = -0.5 * slope + 0.5 * damping * step_squared;
                let (trial_energy, trial_norm) =
                    self.evaluate(&trial, target, &mut faces, &mut trial_evaluation);
                let ratio = (energy - trial_energy) / predicted;
                // At the round-off floor the model predicts a change of ½‖r‖² below its
                // resolution: accept a step that still reduces the gradient, and count the steps
                // that do not halve it.
                let at_floor = predicted <= FLOOR_ENERGY_CHANGE * energy;
                if at_floor && trial_norm > 0.5 * norm {
                    floor_stalls += 1;
                } else {
                    floor_stalls = 0;
                }
                let floor =
                    trial_energy <= energy * (1.0 + FLOOR_ENERGY_CHANGE) && trial_norm < norm;
                if !(ratio > 1e-4 || floor) {
                    damping = raise_damping(damping, &self.normal_matrix, 4.0);
                    if !damping.is_finite() {
                        break;
                    }
                    continue;
                }
                report.iterations += 1;
                if !at_floor {
                    accepted_damping = damping;
                }
                if ratio > 0.75 {
                    damping = lower_damping(damping, &self.normal_matrix);
                } else if ratio < 0.25 {
                    damping = raise_damping(damping, &self.normal_matrix, 2.0);
                }
                posed_cage.copy_from_slice(&trial);
                std::mem::swap(&mut current, &mut trial_evaluation);
                energy = trial_energy;
                norm = trial_norm;
                hessian_current = false;
            }
            if floor_stalls >= FLOOR_STALLS {
                // Stopped at the round-off floor, where the damping was raised on noise: the
                // next event starts from the damping of the last real progress, and its
                // prediction and chord steps get undamped factors at this solution.
                damping = accepted_damping;
                if !hessian_current {
                    self.hessian_at(posed_cage, &current.residual);
                    report.factorisations += 1;
                }
                if self.factorise_damped(0.0).is_err() {
                    self.lu.invalidate();
                }
            }
            self.damping = if damping.is_finite() { damping } else { 0.0 };
            report.residual = norm;
            Ok(())
        })();
        self.faces = faces;
        self.current = current;
        self.trial_evaluation = trial_evaluation;
        self.trial = trial;
        outcome.map(|()| report)
    }
}
