//! The Newton driver shared by the Green-coordinates sync operators (CageUp, CageRev): solves a
//! square system H(x) = 0 over `#C` points with a caller-supplied residual and Jacobian.
//!
//! - **Chord steps.** The factorisation survives between solves, and between the changes of
//!   the caller's system (the Jacobian changes little from one event to the next); it is
//!   recomputed only when a step from stale factors reduces max|H| by less than [`CHORD_RATE`],
//!   or fails to reduce it. The residual is exact, so stale factors change the cost, never the
//!   answer.
//! - **Step halving.** A step that does not reduce max|H| is halved (at most [`MAX_HALVINGS`]
//!   times).
//! - **Stop.** At `tolerance`, after [`MAX_NEWTON_STEPS`] steps, or when a step from fresh
//!   factors no longer reduces max|H| (the round-off floor).

use glam::DVec3;

use super::dense_lu::DenseLu;
use crate::error::RigError;

/// A chord step that leaves more than this fraction of the residual triggers a refactorisation.
///
/// A new Jacobian costs CageRev `3#C × 3#R × 3#C` products (1.3 ms on the Arm's 58-vertex cage,
/// where a residual costs about 25 µs), so chord steps that each cut the residual 4× are the
/// cheaper way to round-off: the factors of the previous grab of a drag, or from across a small
/// skeleton edit, cut it 8–20× (measured, `docs/green-coordinates.md`).
pub const CHORD_RATE: f64 = 0.25;
/// At most this many Newton steps per solve.
pub const MAX_NEWTON_STEPS: usize = 40;
/// At most this many step halvings.
const MAX_HALVINGS: usize = 10;

/// What one solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct NewtonReport {
    /// Newton steps taken.
    pub iterations: usize,
    /// Jacobian factorisations among them.
    pub factorisations: usize,
    /// max_k |H_k| at the end, in scene units.
    pub residual: f64,
}

/// The continuation of the Green sync operators when a direct solve stalls: the change is split
/// into 4, then 16 pieces, solved in turn until one split converges throughout.
pub const CONTINUATION_PIECES: [usize; 2] = [4, 16];

/// Runs the continuation: `piece(a, first)` solves the fraction `a` of the change (`first`: the
/// first piece of a split, which restarts from the unchanged state) and reports it; the reports
/// add up into `total`, whose residual ends as the last piece's. Stops at the first split whose
/// every piece reaches `tolerance`.
pub fn solve_by_continuation(
    tolerance: f64,
    total: &mut NewtonReport,
    mut piece: impl FnMut(f64, bool) -> Result<NewtonReport, RigError>,
) -> Result<(), RigError> {
    for pieces in CONTINUATION_PIECES {
        let mut converged = true;
        for i in 1..=pieces {
            let report = piece(i as f64 / pieces as f64, i == 1)?;
            total.iterations += report.iterations;
            total.factorisations += report.factorisations;
            total.residual = report.residual;
            if report.residual > tolerance {
                converged = false;
                break;
            }
        }
        if converged {
            break;
        }
    }
    Ok(())
}

/// Factors and scratch of one Newton solver over `n` points (`3n` unknowns).
#[derive(Debug, Clone)]
pub struct NewtonSolver {
    lu: DenseLu,
    /// Whether the factors were computed at the current iterate.
    fresh: bool,
    residual: Vec<DVec3>,
    trial: Vec<DVec3>,
    trial_residual: Vec<DVec3>,
    step: Vec<f64>,
}

impl NewtonSolver {
    /// A solver for `n` unknown points.
    pub fn new(n: usize) -> Self {
        Self {
            lu: DenseLu::new(3 * n, "the Green-coordinates reverse Jacobian"),
            fresh: false,
            residual: vec![DVec3::ZERO; n],
            trial: vec![DVec3::ZERO; n],
            trial_residual: vec![DVec3::ZERO; n],
            step: vec![0.0; 3 * n],
        }
    }

    /// Forgets the factors (the next solve starts with a fresh Jacobian).
    pub fn invalidate(&mut self) {
        self.lu.invalidate();
    }

    /// Solves H(x) = 0 from the start `x` (overwritten by the solution).
    ///
    /// `residual(x, out)` writes H(x) (`n` points) and returns max|H| (infinite when not finite);
    /// `jacobian(x, a)` writes ∂H/∂x at x into `a` (`3n × 3n`, column-major, entry (3k+r, 3m+c) =
    /// ∂H_k[r]/∂x_m[c]; `a` holds stale values on entry). No allocation.
    pub fn solve(
        &mut self,
        x: &mut [DVec3],
        tolerance: f64,
        mut residual: impl FnMut(&[DVec3], &mut [DVec3]) -> f64,
        mut jacobian: impl FnMut(&[DVec3], &mut [f64]),
    ) -> Result<NewtonReport, RigError> {
        let mut report = NewtonReport::default();
        let mut norm = residual(x, &mut self.residual);
        self.fresh = false;
        while norm > tolerance && report.iterations < MAX_NEWTON_STEPS {
            if !self.lu.is_factorised() {
                jacobian(x, self.lu.matrix_mut());
                self.lu.factorise()?;
                self.fresh = true;
                report.factorisations += 1;
            }
            for (k, r) in self.residual.iter().enumerate() {
                self.step[3 * k] = -r.x;
                self.step[3 * k + 1] = -r.y;
                self.step[3 * k + 2] = -r.z;
            }
            self.lu.solve(&mut self.step);
            let mut scale = 1.0;
            let mut accepted = None;
            for _ in 0..MAX_HALVINGS {
                for (k, (t, p)) in self.trial.iter_mut().zip(x.iter()).enumerate() {
                    let s =
                        DVec3::new(self.step[3 * k], self.step[3 * k + 1], self.step[3 * k + 2]);
                    *t = *p + scale * s;
                }
                let trial_norm = residual(&self.trial, &mut self.trial_residual);
                if trial_norm < norm {
                    accepted = Some(trial_norm);
                    break;
                }
                scale *= 0.5;
            }
            let Some(trial_norm) = accepted else {
                if self.fresh {
                    break; // the round-off floor: a fresh Newton step no longer helps
                }
                self.lu.invalidate();
                continue;
            };
            report.iterations += 1;
            if !self.fresh && trial_norm > CHORD_RATE * norm {
                self.lu.invalidate();
            }
            self.fresh = false;
            x.copy_from_slice(&self.trial);
            std::mem::swap(&mut self.residual, &mut self.trial_residual);
            norm = trial_norm;
        }
        report.residual = norm;
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_small_nonlinear_system_to_round_off() {
        // H(x) = x + 0.3·(|x|² x) − t, one point.
        let target = [DVec3::new(0.7, -0.2, 0.4)];
        let mut x = [DVec3::ZERO];
        let mut solver = NewtonSolver::new(1);
        let report = solver
            .solve(
                &mut x,
                1e-15,
                |x, out| {
                    out[0] = x[0] + 0.3 * x[0].length_squared() * x[0] - target[0];
                    out[0].abs().max_element()
                },
                |x, a| {
                    let p = x[0];
                    for c in 0..3 {
                        for r in 0..3 {
                            let identity = if r == c { 1.0 } else { 0.0 };
                            a[c * 3 + r] = identity
                                + 0.3 * (identity * p.length_squared() + 2.0 * p[r] * p[c]);
                        }
                    }
                },
            )
            .unwrap();
        assert!(report.residual <= 1e-15, "{report:?}");
        assert!(
            report.iterations <= 20 && report.factorisations <= 3,
            "{report:?}"
        );
    }
}
