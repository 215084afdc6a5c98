//! Max-entropy-style coordinates with a **signed** prior: the paper tool's variant, kept to
//! reproduce its Ψ (SkelUp with its localisation produces cage masses μ of both signs).
//!
//! Same exponential family as [`super::mec`]: `b_k(λ) = μ_k exp(−λ·x_k) / Σ_l μ_l exp(−λ·x_l)`
//! with `x_k = (c_k − a)/s`, which sums to one for any λ; λ ∈ R³ solves the linear-precision
//! equations `g(λ) = Σ_k b_k(λ) x_k = 0`. With signed masses the dual is not convex, so we use
//! Newton on g with the exact Jacobian `J = −(Σ b x xᵀ − (Σ b x)(Σ b x)ᵀ)` and a backtracking
//! line search on |g|. If it does not converge (or a denominator vanishes) we fall back to the
//! positive solver of [`super::mec`], which clamps the masses and guarantees both constraints.

use glam::{DMat3, DVec3};

use super::mec::{MecReport, farthest_distance, max_entropy_coordinates};

const MAX_ITERATIONS: usize = 100;
const TOLERANCE: f64 = 1e-14;

/// Coordinates of `target` w.r.t. `points` with signed prior masses `prior`; see module docs.
pub fn max_entropy_coordinates_signed(
    points: &[DVec3],
    prior: &[f64],
    target: DVec3,
    out: &mut [f64],
) -> MecReport {
    let n = points.len();
    let scale = farthest_distance(points, target);
    if n == 0
        || scale.is_nan()
        || scale <= 0.0
        || !scale.is_finite()
        || prior.iter().any(|m| !m.is_finite())
    {
        return max_entropy_coordinates(points, prior, target, out);
    }
    let x = |k: usize| (points[k] - target) / scale;
    // Evaluates b(λ) into out; returns (g, J) or None if the normaliser vanishes.
    let eval = |lambda: DVec3, out: &mut [f64]| -> Option<(DVec3, DMat3)> {
        let mut total = 0.0;
        for (k, b) in out.iter_mut().enumerate() {
            *b = prior[k] * (-lambda.dot(x(k))).exp();
            total += *b;
        }
        if total.is_nan() || total.abs() <= 1e-300 || !total.is_finite() {
            return None;
        }
        let mut g = DVec3::ZERO;
        let mut second = DMat3::ZERO;
        for (k, b) in out.iter_mut().enumerate() {
            *b /= total;
            let xk = x(k);
            g += *b * xk;
            second += DMat3::from_cols(xk * xk.x, xk * xk.y, xk * xk.z) * *b;
        }
        let outer = DMat3::from_cols(g * g.x, g * g.y, g * g.z);
        Some((g, -(second - outer)))
    };
    let mut lambda = DVec3::ZERO;
    let mut iterations = 0;
    let mut converged = false;
    if let Some((mut g, mut jac)) = eval(lambda, out) {
        while iterations < MAX_ITERATIONS {
            if g.length() <= TOLERANCE {
                converged = true;
                break;
            }
            iterations += 1;
            if jac.determinant().abs() < 1e-300 {
                break;
            }
            let step = -(jac.inverse() * g);
            let mut t = 1.0;
            let mut accepted = false;
            while t > 1e-12 {
                let trial = lambda + t * step;
                if let Some((g2, j2)) = eval(trial, out)
                    && g2.length() < g.length()
                {
                    lambda = trial;
                    g = g2;
                    jac = j2;
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                converged = g.length() <= 1e-12;
                break;
            }
        }
        if !converged {
            converged = g.length() <= 1e-12;
        }
        // Make `out` hold b(λ) for the final λ.
        let _ = eval(lambda, out);
    }
    if !converged {
        return max_entropy_coordinates(points, prior, target, out);
    }
    let reached = out
        .iter()
        .zip(points)
        .fold(DVec3::ZERO, |acc, (&b, c)| acc + b * *c);
    MecReport {
        method: super::mec::MecMethod::MaxEntropy,
        iterations,
        residual: reached.distance(target),
        sum_residual: (out.iter().sum::<f64>() - 1.0).abs(),
        clamped_masses: 0,
        fallback_reason: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_prior_solution_satisfies_constraints() {
        let points = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 1.0, 1.0),
        ];
        let prior = [0.3, 0.3, 0.3, 0.3, -0.01];
        let target = DVec3::new(0.3, 0.25, 0.2);
        let mut b = [0.0; 5];
        let r = max_entropy_coordinates_signed(&points, &prior, target, &mut b);
        assert!(r.residual < 1e-12, "{r:?}");
        assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(b[4] < 0.0, "the negative mass keeps its sign: {b:?}");
    }
}
