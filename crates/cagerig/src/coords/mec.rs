//! Maximum-entropy coordinates with a prior (Hormann & Sukumar 2008; paper Eq. 11), used by
//! SkelUp to express each rest joint as a combination of rest-cage vertices (one row of Ψ).
//!
//! Given points c_k (`#C`), prior masses m_k > 0 and a target a, find b (`#C`) maximising
//! `Σ_k −b_k ln(b_k / m_k)` subject to `Σ_k b_k c_k = a` and `Σ_k b_k = 1`.
//!
//! **Solver.** The dual: `b_k(λ) = m_k exp(−λ·x_k) / Z(λ)` with `x_k = (c_k − a) / s`
//! (s = max_k |c_k − a|, for conditioning), minimise the convex `F(λ) = ln Σ_k m_k exp(−λ·x_k)`
//! over λ ∈ R³. ∇F = −Σ b_k x_k (the scaled linear-precision residual), ∇²F = covariance of x
//! under b. Newton steps with an Armijo backtracking line search on F (log-sum-exp evaluated with
//! a max shift), until `|Σ b_k x_k| ≤ 1e-14` or no further decrease is possible. Partition of
//! unity holds by construction and every b_k > 0.
//!
//! **Invalid priors.** Non-positive masses (SkelUp's projected priors μ = Φᵀπ can be slightly
//! negative) are clamped to `1e-10 · max_k m_k` before solving; the number clamped is reported.
//! If no mass is positive and finite, or any mass is non-finite, the uniform prior is used for
//! the fallback below (MEC is not attempted).
//!
//! **Fallback.** A positive solution exists only when a is strictly inside the convex hull of the
//! c_k. When Newton does not reach `|Σ b c − a| ≤ 1e-10 · s` (a outside the hull or on its
//! boundary, where λ diverges), the result is the least-squares projection of the normalised prior
//! q = m / Σm onto the constraints: `min ‖b − q‖²` s.t. `Σ b_k c_k = a`, `Σ b_k = 1`, in closed
//! form `b = q + Aᵀ (A Aᵀ)⁺ (r − A q)` with the 4 × #C matrix A = [x_kᵀ; 1] and r = [0; 1]. It
//! satisfies both constraints exactly (to rounding) whenever the c_k are affinely independent
//! enough to span R³ (≥ 4 non-coplanar points), but weights may be negative. The report says so.

use faer::Mat;
use glam::DVec3;

/// Which method produced the coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MecMethod {
    /// Converged maximum-entropy coordinates (all weights positive).
    MaxEntropy,
    /// Least-squares projection of the prior onto the constraints (see module docs).
    LeastSquaresFallback,
}

/// Outcome of [`max_entropy_coordinates`].
#[derive(Debug, Clone, PartialEq)]
pub struct MecReport {
    /// Which method produced the coordinates.
    pub method: MecMethod,
    /// Newton iterations performed (also when the method then fell back).
    pub iterations: usize,
    /// Linear-precision residual `|Σ_k b_k c_k − a|` of the returned coordinates.
    pub residual: f64,
    /// Partition-of-unity residual `|Σ_k b_k − 1|` of the returned coordinates.
    pub sum_residual: f64,
    /// Masses that were ≤ 0 and were clamped to a positive floor before solving.
    pub clamped_masses: usize,
    /// Why MEC was not used (only for [`MecMethod::LeastSquaresFallback`]).
    pub fallback_reason: Option<String>,
}

/// Relative clamp floor for non-positive prior masses.
const MASS_FLOOR: f64 = 1e-10;
/// Newton stops when the scaled residual |Σ b x| reaches this.
const GRADIENT_TOL: f64 = 1e-14;
/// MEC is accepted when the scaled residual is at most this.
const ACCEPT_TOL: f64 = 1e-10;
const MAX_ITERATIONS: usize = 200;
/// |λ| (scaled units) beyond which the dual is considered divergent (a not inside the hull).
const MAX_LAMBDA: f64 = 1e6;

/// The largest distance from `target` to `points` (0 for none): the scale of both solvers'
/// dual variables.
pub(super) fn farthest_distance(points: &[DVec3], target: DVec3) -> f64 {
    points
        .iter()
        .map(|c| c.distance(target))
        .fold(0.0, f64::max)
}

/// Max-entropy coordinates of `target` w.r.t. `points` (`#C`) with prior masses `prior` (`#C`),
/// written into `out` (`#C`). See the module docs for the solver, clamping and fallback.
/// Allocates only on the fallback path.
pub fn max_entropy_coordinates(
    points: &[DVec3],
    prior: &[f64],
    target: DVec3,
    out: &mut [f64],
) -> MecReport {
    let n = points.len();
    debug_assert_eq!(prior.len(), n);
    debug_assert_eq!(out.len(), n);
    let scale = farthest_distance(points, target);
    if n == 0 || !target.is_finite() || !scale.is_finite() {
        out.iter_mut().for_each(|b| *b = f64::NAN);
        return MecReport {
            method: MecMethod::LeastSquaresFallback,
            iterations: 0,
            residual: f64::NAN,
            sum_residual: f64::NAN,
            clamped_masses: 0,
            fallback_reason: Some("no points, or non-finite points/target".into()),
        };
    }
    if scale == 0.0 {
        // Every point coincides with the target: the prior itself is a solution.
        let total: f64 = prior.iter().filter(|m| m.is_finite() && **m > 0.0).sum();
        for (b, m) in out.iter_mut().zip(prior) {
            *b = if total > 0.0 && m.is_finite() && *m > 0.0 {
                m / total
            } else {
                1.0 / n as f64
            };
        }
        return finish(points, target, out, MecMethod::MaxEntropy, 0, 0, None);
    }
    let max_mass = prior.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if prior.iter().any(|m| !m.is_finite()) || max_mass <= 0.0 {
        let uniform = 1.0 / n as f64;
        out.iter_mut().for_each(|b| *b = uniform);
        let reason =
            "prior masses are non-finite or none is positive; projecting the uniform prior";
        return least_squares_fallback(points, target, scale, out, 0, 0, reason.into());
    }
    let floor = MASS_FLOOR * max_mass;
    let clamped_masses = prior.iter().filter(|m| **m <= 0.0).count();
    let mass = |k: usize| prior[k].max(floor);
    let log_mass = |k: usize| mass(k).ln();
    let x = |k: usize| (points[k] - target) / scale;

    // F(λ) = ln Σ m_k exp(−λ·x_k), evaluated with a max shift.
    let objective = |lambda: DVec3| -> f64 {
        let shift = (0..n)
            .map(|k| log_mass(k) - lambda.dot(x(k)))
            .fold(f64::NEG_INFINITY, f64::max);
        let sum: f64 = (0..n)
            .map(|k| (log_mass(k) - lambda.dot(x(k)) - shift).exp())
            .sum();
        shift + sum.ln()
    };
    // Writes b(λ) into out; returns (Σ b x, covariance rows).
    let weights = |lambda: DVec3, out: &mut [f64]| -> (DVec3, [DVec3; 3]) {
        let shift = (0..n)
            .map(|k| log_mass(k) - lambda.dot(x(k)))
            .fold(f64::NEG_INFINITY, f64::max);
        let mut total = 0.0;
        for (k, b) in out.iter_mut().enumerate() {
            *b = (log_mass(k) - lambda.dot(x(k)) - shift).exp();
            total += *b;
        }
        let mut mean = DVec3::ZERO;
        let mut second = [DVec3::ZERO; 3];
        for (k, b) in out.iter_mut().enumerate() {
            *b /= total;
            let xk = x(k);
            mean += *b * xk;
            for (row, xi) in second.iter_mut().zip(xk.to_array()) {
                *row += (*b * xi) * xk;
            }
        }
        let cov = [
            second[0] - mean.x * mean,
            second[1] - mean.y * mean,
            second[2] - mean.z * mean,
        ];
        (mean, cov)
    };

    let mut lambda = DVec3::ZERO;
    let mut value = objective(lambda);
    let mut iterations = 0;
    let mut failure: Option<String> = None;
    let mut previous_gradient = f64::INFINITY;
    loop {
        let (mean, cov) = weights(lambda, out);
        let gradient = -mean;
        let gradient_norm = gradient.length();
        // Converged, or stagnating at rounding level (quadratic convergence has stopped).
        if gradient_norm <= GRADIENT_TOL
            || (gradient_norm <= 1e-2 * ACCEPT_TOL && gradient_norm > 0.5 * previous_gradient)
        {
            break;
        }
        previous_gradient = gradient_norm;
        if iterations >= MAX_ITERATIONS {
            failure = Some(format!(
                "Newton did not converge in {MAX_ITERATIONS} iterations"
            ));
            break;
        }
        iterations += 1;
        let step = match solve_spd3(cov, -gradient) {
            Some(step) => step,
            None => {
                failure = Some("the dual Hessian is singular".into());
                break;
            }
        };
        let slope = gradient.dot(step);
        if slope >= 0.0 {
            failure = Some("Newton direction is not a descent direction".into());
            break;
        }
        // Armijo backtracking. Once the predicted decrease is below the resolution of F the
        // test is meaningless (rounding noise); we are then in Newton's quadratic region and
        // take the full step.
        let mut t = 1.0;
        let mut accepted = None;
        if -slope <= 1e-13 * (1.0 + value.abs()) {
            let candidate = lambda + step;
            accepted = Some((candidate, objective(candidate)));
        }
        for _ in 0..60 {
            if accepted.is_some() {
                break;
            }
            let candidate = lambda + t * step;
            let candidate_value = objective(candidate);
            if candidate_value.is_finite() && candidate_value <= value + 1e-4 * t * slope {
                accepted = Some((candidate, candidate_value));
                break;
            }
            t *= 0.5;
        }
        match accepted {
            Some((candidate, candidate_value)) => {
                lambda = candidate;
                value = candidate_value;
            }
            None => {
                // No decrease possible at this precision: keep the current iterate.
                weights(lambda, out);
                break;
            }
        }
        if lambda.length() > MAX_LAMBDA {
            failure = Some(format!(
                "the dual variable diverges (|λ| > {MAX_LAMBDA:e}): the target is not strictly inside the convex hull"
            ));
            break;
        }
    }
    let residual = scaled_residual(points, target, scale, out);
    let valid = out.iter().all(|b| b.is_finite());
    if failure.is_none() && valid && residual <= ACCEPT_TOL {
        return finish(
            points,
            target,
            out,
            MecMethod::MaxEntropy,
            iterations,
            clamped_masses,
            None,
        );
    }
    let reason = failure.unwrap_or_else(|| {
        format!("Newton stalled with scaled linear-precision residual {residual:e}")
    });
    let total: f64 = (0..n).map(mass).sum();
    for (k, b) in out.iter_mut().enumerate() {
        *b = mass(k) / total;
    }
    least_squares_fallback(
        points,
        target,
        scale,
        out,
        iterations,
        clamped_masses,
        reason,
    )
}

/// |Σ b x| with x = (c − a)/s.
fn scaled_residual(points: &[DVec3], target: DVec3, scale: f64, b: &[f64]) -> f64 {
    let mean: DVec3 = points
        .iter()
        .zip(b)
        .map(|(c, w)| *w * ((*c - target) / scale))
        .sum();
    let sum: f64 = b.iter().sum();
    mean.length().max((sum - 1.0).abs())
}

fn finish(
    points: &[DVec3],
    target: DVec3,
    out: &[f64],
    method: MecMethod,
    iterations: usize,
    clamped_masses: usize,
    fallback_reason: Option<String>,
) -> MecReport {
    let combo: DVec3 = points.iter().zip(out).map(|(c, b)| *b * *c).sum();
    let sum: f64 = out.iter().sum();
    MecReport {
        method,
        iterations,
        residual: combo.distance(target),
        sum_residual: (sum - 1.0).abs(),
        clamped_masses,
        fallback_reason,
    }
}

/// Least-squares projection of `out` (holding the normalised prior q on entry) onto
/// {b : Σ b x = 0, Σ b = 1}: b = q + Aᵀ (A Aᵀ)⁺ (r − A q), plus one refinement step.
fn least_squares_fallback(
    points: &[DVec3],
    target: DVec3,
    scale: f64,
    out: &mut [f64],
    iterations: usize,
    clamped_masses: usize,
    reason: String,
) -> MecReport {
    let n = points.len();
    let row = |k: usize| -> [f64; 4] {
        let xk = (points[k] - target) / scale;
        [xk.x, xk.y, xk.z, 1.0]
    };
    let mut gram = Mat::<f64>::zeros(4, 4);
    for k in 0..n {
        let a = row(k);
        for i in 0..4 {
            for j in 0..4 {
                gram[(i, j)] += a[i] * a[j];
            }
        }
    }
    let pseudo_inverse = gram.thin_svd().ok().map(|svd| {
        let s = svd.S().column_vector();
        let largest = (0..4).map(|i| s[i]).fold(0.0, f64::max);
        let u = svd.U();
        let v = svd.V();
        Mat::<f64>::from_fn(4, 4, |i, j| {
            (0..4)
                .filter(|&l| s[l] > 1e-13 * largest)
                .map(|l| v[(i, l)] * u[(j, l)] / s[l])
                .sum()
        })
    });
    crate::vector_registers::clear_upper_halves();
    let report = |out: &[f64], reason: String| {
        finish(
            points,
            target,
            out,
            MecMethod::LeastSquaresFallback,
            iterations,
            clamped_masses,
            Some(reason),
        )
    };
    let Some(pinv) = pseudo_inverse else {
        return report(
            out,
            format!("{reason}; the least-squares system could not be factorised"),
        );
    };
    for _ in 0..2 {
        let mut residual = [0.0, 0.0, 0.0, 1.0];
        for (k, b) in out.iter().enumerate() {
            let a = row(k);
            for i in 0..4 {
                residual[i] -= a[i] * b;
            }
        }
        let mut multiplier = [0.0; 4];
        for (i, m) in multiplier.iter_mut().enumerate() {
            *m = (0..4).map(|j| pinv[(i, j)] * residual[j]).sum();
        }
        for (k, b) in out.iter_mut().enumerate() {
            let a = row(k);
            *b += (0..4).map(|i| a[i] * multiplier[i]).sum::<f64>();
        }
    }
    report(out, reason)
}

/// Solves the symmetric positive semi-definite 3 × 3 system `h · s = rhs` (Cholesky with a tiny
/// relative ridge); `None` if h is not positive definite even with the ridge.
fn solve_spd3(h: [DVec3; 3], rhs: DVec3) -> Option<DVec3> {
    let trace = h[0].x + h[1].y + h[2].z;
    if trace.is_nan() || trace <= 0.0 || !trace.is_finite() {
        return None;
    }
    let ridge = 1e-15 * trace;
    let a = [
        [h[0].x + ridge, h[0].y, h[0].z],
        [h[1].x, h[1].y + ridge, h[1].z],
        [h[2].x, h[2].y, h[2].z + ridge],
    ];
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let mut sum = 0.5 * (a[i][j] + a[j][i]);
            sum -= (0..j).map(|p| l[i][p] * l[j][p]).sum::<f64>();
            if i == j {
                if sum.is_nan() || sum <= 0.0 {
                    return None;
                }
                l[i][i] = sum.sqrt();
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    let r = rhs.to_array();
    let mut y = [0.0; 3];
    for i in 0..3 {
        y[i] = (r[i] - (0..i).map(|p| l[i][p] * y[p]).sum::<f64>()) / l[i][i];
    }
    let mut s = [0.0; 3];
    for i in (0..3).rev() {
        s[i] = (y[i] - (i + 1..3).map(|p| l[p][i] * s[p]).sum::<f64>()) / l[i][i];
    }
    let s = DVec3::from_array(s);
    s.is_finite().then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn constraint_errors(points: &[DVec3], b: &[f64], a: DVec3) -> (f64, f64) {
        let combo: DVec3 = points.iter().zip(b).map(|(c, w)| *w * *c).sum();
        (combo.distance(a), (b.iter().sum::<f64>() - 1.0).abs())
    }

    fn tetra() -> Vec<DVec3> {
        vec![
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ]
    }

    #[test]
    fn simplex_recovers_barycentric() {
        let c = tetra();
        let bary = [0.1, 0.2, 0.3, 0.4];
        let a: DVec3 = c.iter().zip(bary).map(|(p, w)| w * *p).sum();
        for prior in [[1.0; 4], [5.0, 0.1, 2.0, 7.0]] {
            let mut b = [0.0; 4];
            let report = max_entropy_coordinates(&c, &prior, a, &mut b);
            assert_eq!(report.method, MecMethod::MaxEntropy, "{report:?}");
            for (x, y) in b.iter().zip(bary) {
                assert!((x - y).abs() < 1e-12, "{b:?}");
            }
        }
    }

    #[test]
    fn prior_at_target_is_returned_unchanged() {
        // Octahedron vertices; the prior's own centroid is the target ⇒ b = normalised prior.
        let (c, _) = crate::coords::mvc::tests::octahedron([1.0; 6]);
        let prior = [3.0, 1.0, 2.0, 2.0, 0.5, 0.5];
        let a: DVec3 = c.iter().zip(prior).map(|(p, m)| m / 9.0 * *p).sum();
        let mut b = [0.0; 6];
        let report = max_entropy_coordinates(&c, &prior, a, &mut b);
        assert_eq!(report.method, MecMethod::MaxEntropy);
        for (x, m) in b.iter().zip(prior) {
            assert!((x - m / 9.0).abs() < 1e-12);
        }
        // A concentrated prior pulls the weights towards its vertex, constraints still hold.
        let concentrated = [1e6, 1.0, 1.0, 1.0, 1.0, 1.0];
        let mut b2 = [0.0; 6];
        let report = max_entropy_coordinates(&c, &concentrated, DVec3::ZERO, &mut b2);
        assert_eq!(report.method, MecMethod::MaxEntropy);
        let (lin, sum) = constraint_errors(&c, &b2, DVec3::ZERO);
        assert!(lin < 1e-12 && sum < 1e-12);
        assert!(b2[0] > b2[2] && (b2[0] - b2[1]).abs() < 1e-12, "{b2:?}");
        let mut uniform = [0.0; 6];
        max_entropy_coordinates(&c, &[1.0; 6], DVec3::new(0.1, 0.2, 0.3), &mut uniform);
        max_entropy_coordinates(&c, &concentrated, DVec3::new(0.1, 0.2, 0.3), &mut b2);
        assert!(b2[0] > uniform[0]);
    }

    #[test]
    fn outside_hull_falls_back_and_satisfies_constraints() {
        let c = tetra();
        for a in [
            DVec3::new(3.0, -2.0, 5.0),
            // On a face of the hull: no strictly positive solution.
            (c[0] + c[1] + c[2]) / 3.0,
        ] {
            let mut b = [0.0; 4];
            let report = max_entropy_coordinates(&c, &[1.0, 2.0, 3.0, 4.0], a, &mut b);
            let (lin, sum) = constraint_errors(&c, &b, a);
            assert!(lin < 1e-10 && sum < 1e-10, "{report:?}");
            assert!((report.residual - lin).abs() < 1e-15);
            if a.x == 3.0 {
                assert_eq!(report.method, MecMethod::LeastSquaresFallback);
                assert!(report.fallback_reason.is_some());
            }
        }
        // Many points, target outside.
        let cloud: Vec<DVec3> = (0..30)
            .map(|i| {
                let f = i as f64;
                DVec3::new((f * 1.3).sin(), (f * 0.7).cos(), (f * 2.1).sin())
            })
            .collect();
        let mut b = vec![0.0; 30];
        let a = DVec3::new(4.0, 4.0, -4.0);
        let report = max_entropy_coordinates(&cloud, &[1.0; 30], a, &mut b);
        assert_eq!(report.method, MecMethod::LeastSquaresFallback);
        let (lin, sum) = constraint_errors(&cloud, &b, a);
        assert!(lin < 1e-10 && sum < 1e-10);
    }

    #[test]
    fn non_positive_masses_are_clamped() {
        let (c, _) = crate::coords::mvc::tests::octahedron([1.0; 6]);
        let a = DVec3::new(0.1, -0.2, 0.05);
        let mut b = [0.0; 6];
        let report = max_entropy_coordinates(&c, &[1.0, -0.5, 2.0, 0.0, 1.0, 1.0], a, &mut b);
        assert_eq!(report.method, MecMethod::MaxEntropy);
        assert_eq!(report.clamped_masses, 2);
        let (lin, sum) = constraint_errors(&c, &b, a);
        assert!(lin < 1e-12 && sum < 1e-12);
        assert!(b.iter().all(|w| *w > 0.0));
        // Invalid priors: least squares on the uniform prior.
        for prior in [[f64::NAN, 1.0, 1.0, 1.0, 1.0, 1.0], [-1.0; 6]] {
            let report = max_entropy_coordinates(&c, &prior, a, &mut b);
            assert_eq!(report.method, MecMethod::LeastSquaresFallback);
            let (lin, sum) = constraint_errors(&c, &b, a);
            assert!(lin < 1e-12 && sum < 1e-12);
        }
    }

    proptest! {
        #[test]
        fn constraints_hold_inside_hull(
            cloud in proptest::collection::vec((-10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0), 4..40),
            mix in proptest::collection::vec(0.05f64..1.0, 40),
            masses in proptest::collection::vec(1e-3f64..1e3, 40),
        ) {
            let points: Vec<DVec3> = cloud.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            let n = points.len();
            let total: f64 = mix[..n].iter().sum::<f64>();
            let a: DVec3 = points.iter().zip(&mix[..n]).map(|(p, w)| *w / total * *p).sum::<DVec3>();
            let mut b = vec![0.0; n];
            let report = max_entropy_coordinates(&points, &masses[..n], a, &mut b);
            let (lin, sum) = constraint_errors(&points, &b, a);
            prop_assert!(lin <= 1e-10, "{report:?}");
            prop_assert!(sum <= 1e-10);
            prop_assert_eq!(report.method, MecMethod::MaxEntropy, "{:?}", report);
            prop_assert!(b.iter().all(|w| *w >= 0.0));
        }
    }
}
