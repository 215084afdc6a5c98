//! Tests of [`super::GreenCageFit`]: the fit recovers a cage from its own Green deformation,
//! and its Newton matrix is the fit's Hessian.

use glam::DQuat;

use super::*;
use crate::coords::green::compute_green_coords;
use crate::coords::green::tests::{random_inside, test_cage};

/// The fit of all rows of `points` inside the test cage (and the cage).
fn fit_of(points: &[DVec3]) -> (GreenCageFit, crate::mesh::TriMesh) {
    let cage = test_cage();
    let coords = compute_green_coords(&cage, points, None).unwrap();
    let normals = StretchedNormals::new(&cage.positions, coords.triangles.clone());
    let fit = GreenCageFit::new(
        coords.vertex.matrix().clone(),
        coords.face.matrix().clone(),
        &cage.positions,
        normals,
    )
    .unwrap();
    (fit, cage)
}

#[test]
fn recovers_a_deformed_cage_from_its_green_deformation() {
    let points = random_inside(5, 60);
    let (mut fit, cage) = fit_of(&points);
    let rotation = DQuat::from_axis_angle(DVec3::new(0.3, 1.0, 0.2).normalize(), 0.9);
    let deformed: Vec<DVec3> = cage
        .positions
        .iter()
        .enumerate()
        .map(|(i, c)| rotation * (*c * DVec3::new(1.4, 0.9, 1.0)) + DVec3::splat(0.05 * i as f64))
        .collect();
    let mut g = vec![DVec3::ZERO; fit.normals().len()];
    let mut rows = vec![DVec3::ZERO; points.len()];
    fit.rows_of(&deformed, &mut g, &mut rows);
    let mut solved = cage.positions.clone();
    let report = fit.apply(&rows, &mut solved).unwrap();
    assert!(report.residual <= fit.tolerance(), "{report:?}");
    for (s, d) in solved.iter().zip(&deformed) {
        assert!(s.distance(*d) < 1e-11, "{s} vs {d}");
    }
    // Warm start at the solution: nothing to do.
    let again = fit.apply(&rows, &mut solved).unwrap();
    assert_eq!(again.iterations, 0);
}

#[test]
fn newton_matrix_is_the_hessian_of_the_fit() {
    let points = random_inside(9, 40);
    let (mut fit, cage) = fit_of(&points);
    // A target no cage reaches: the rest rows pushed around (large residual).
    let target: Vec<DVec3> = points
        .iter()
        .enumerate()
        .map(|(i, p)| *p * 1.2 + DVec3::new(0.1 * (i % 3) as f64, 0.05, -0.1 * (i % 5) as f64))
        .collect();
    let x: Vec<DVec3> = cage
        .positions
        .iter()
        .enumerate()
        .map(|(i, c)| *c + DVec3::splat(0.03 * i as f64))
        .collect();
    let nr = points.len();
    let nf = fit.normals().len();
    let gradient_at = |fit: &GreenCageFit, x: &[DVec3]| {
        let mut faces = FaceScratch::new(x.len(), nf);
        let mut out = Evaluation::new(nr, x.len());
        fit.evaluate(x, &target, &mut faces, &mut out);
        (out.gradient, out.residual)
    };
    let (_, residual) = gradient_at(&fit, &x);
    fit.hessian_at(&x, &residual);
    let n = 3 * x.len();
    let h = 1e-6;
    for q in 0..n {
        let mut plus = x.clone();
        let mut minus = x.clone();
        plus[q / 3][q % 3] += h;
        minus[q / 3][q % 3] -= h;
        let (gp, _) = gradient_at(&fit, &plus);
        let (gm, _) = gradient_at(&fit, &minus);
        for p in 0..n {
            let fd = (gp[p / 3][p % 3] - gm[p / 3][p % 3]) / (2.0 * h);
            let analytic = fit.normal_matrix[(p, q)];
            assert!(
                (fd - analytic).abs() < 1e-5 * (1.0 + fd.abs()),
                "({p}, {q}): {fd} vs {analytic}"
            );
        }
    }
}

#[test]
fn gauss_newton_matrix_from_the_gram_matrices_is_j_transpose_j() {
    let points = random_inside(11, 50);
    let (mut fit, cage) = fit_of(&points);
    let x: Vec<DVec3> = cage
        .positions
        .iter()
        .enumerate()
        .map(|(i, c)| *c * 1.1 + DVec3::new(0.02 * i as f64, -0.01, 0.03 * (i % 3) as f64))
        .collect();
    let n = 3 * x.len();
    let mut jacobian = Mat::<f64>::zeros(3 * points.len(), n);
    fit.jacobian_into(&x, &mut jacobian);
    let explicit = jacobian.transpose() * &jacobian;
    fit.gauss_newton_matrix_at(&x);
    let scale = (0..n).map(|i| explicit[(i, i)].abs()).fold(0.0, f64::max);
    for p in 0..n {
        for q in 0..n {
            let (a, b) = (fit.normal_matrix[(p, q)], explicit[(p, q)]);
            assert!((a - b).abs() <= 1e-12 * scale, "({p}, {q}): {a} vs {b}");
        }
    }
}

/// A sequence of nearby large-residual targets (an animation): after the first fit, each starts
/// from the first-order prediction off the last solution (one chord step on its factors) and
/// converges in a few steps; the warm start the caller passes in is a poor one on
/// purpose (the binding cage), so the prediction is what makes them few (at most two Hessians
/// per target, the other steps chord steps on the last factors). Each solution is the
/// same stationary point a cold solve from the previous solution finds.
#[test]
fn nearby_targets_start_from_the_prediction_off_the_last_solution() {
    let points = random_inside(13, 60);
    let (mut fit, cage) = fit_of(&points);
    let target_at = |t: f64| -> Vec<DVec3> {
        let rotation = DQuat::from_axis_angle(DVec3::new(0.2, 1.0, 0.4).normalize(), t);
        points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                // Rows no Green cage reaches exactly: a point-dependent push.
                rotation * *p + DVec3::new(0.02 * (i % 3) as f64, 0.01 * t, -0.015 * (i % 4) as f64)
            })
            .collect()
    };
    let mut solution = cage.positions.clone();
    let first = fit.apply(&target_at(0.10), &mut solution).unwrap();
    assert!(first.residual <= fit.tolerance(), "{first:?}");
    for k in 1..6 {
        let target = target_at(0.10 + 0.01 * k as f64);
        let mut cold = solution.clone();
        let mut reference = fit.clone();
        reference.has_last_target = false;
        let cold_report = reference.apply(&target, &mut cold).unwrap();
        let mut warm = cage.positions.clone();
        let report = fit.apply(&target, &mut warm).unwrap();
        assert!(report.residual <= fit.tolerance(), "{report:?}");
        assert!(cold_report.residual <= fit.tolerance(), "{cold_report:?}");
        assert!(
            report.factorisations <= 2 && report.iterations <= 8,
            "target {k}: {report:?} (from the previous solution: {cold_report:?})"
        );
        for (a, b) in warm.iter().zip(&cold) {
            assert!(a.distance(*b) < 1e-10, "{a} vs {b}");
        }
        solution = warm;
    }
}

/// A cage far from the origin: the rounding of the rows (eps × |x|) puts the round-off floor of
/// Jᵀr above GRADIENT_TOLERANCE × size. The fit stops at that floor (it used to spend all its
/// steps there with the damping raised on noise, and hand the next event damped factors, so no
/// prediction) and accepts it below ACCEPTED_GRADIENT; the next, nearby target then starts from
/// the prediction on undamped factors.
#[test]
fn a_fit_whose_round_off_floor_is_above_the_tolerance_stops_there() {
    let offset = DVec3::new(3.0e4, -2.0e4, 1.0e4);
    let points: Vec<DVec3> = random_inside(9, 40).iter().map(|p| *p + offset).collect();
    let mut cage = test_cage();
    cage.positions.iter_mut().for_each(|c| *c += offset);
    let coords = compute_green_coords(&cage, &points, None).unwrap();
    let normals = StretchedNormals::new(&cage.positions, coords.triangles.clone());
    let mut fit = GreenCageFit::new(
        coords.vertex.matrix().clone(),
        coords.face.matrix().clone(),
        &cage.positions,
        normals,
    )
    .unwrap();
    // Unreachable rows (a large residual), then the same rows moved a little.
    let target = |shift: f64| -> Vec<DVec3> {
        points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                offset
                    + (*p - offset) * 1.1
                    + DVec3::new(0.05 * (i % 3) as f64 + shift, 0.02, -0.04 * (i % 5) as f64)
            })
            .collect()
    };
    let mut solved = cage.positions.clone();
    let first = fit.apply(&target(0.0), &mut solved).unwrap();
    // The floor: 7.7e-12 against a tolerance of 3.6e-13 (1e-13 of the cage size).
    assert!(
        first.residual > fit.tolerance() && first.residual <= fit.accepted,
        "{first:?}"
    );
    assert!(first.iterations < MAX_STEPS / 2, "{first:?}");
    // The fix itself: the kept factors are undamped (they serve the next event's prediction and
    // chord steps), not damped on the floor's noise.
    assert!(
        fit.factor_damping <= CHORD_DAMPING * damping_scale(&fit.normal_matrix),
        "kept damping {} of a scale {}",
        fit.factor_damping,
        damping_scale(&fit.normal_matrix)
    );
    // Undamped kept factors: 1 step and 2 Hessians, or 2 and 3 where the floor's round-off takes
    // one more step to recognise (the last bits of the binding kernel's coordinates decide);
    // damped factors would take 3 steps and 4 Hessians.
    let second = fit.apply(&target(1e-3), &mut solved).unwrap();
    assert!(second.residual <= fit.accepted, "{second:?}");
    assert!(
        second.iterations <= 2 && second.factorisations <= 3,
        "{second:?}"
    );
}

/// The fit of all rows of `points` regularised towards the carried cage, with two joints
/// splitting the points by x (the test cage and the points' φ for the prior).
fn regularised_fit_of(points: &[DVec3]) -> (GreenCageFit, crate::mesh::TriMesh) {
    let (fit, cage) = fit_of(points);
    let coords = compute_green_coords(&cage, points, None).unwrap();
    let (lo, hi) = crate::mesh::bounding_box(points);
    let (omega, _) = crate::skin_weights::SkinWeights::from_triplets(
        points.len(),
        2,
        points.iter().enumerate().flat_map(|(i, p)| {
            let t = ((p.x - lo.x) / (hi.x - lo.x)).clamp(0.0, 1.0);
            [(i, 0, 1.0 - t), (i, 1, t)]
        }),
    )
    .unwrap();
    let rows: Vec<usize> = (0..points.len()).collect();
    let mut fit = fit;
    let rows_scale = fit.binding_rows_scale();
    let prior = FitPrior::for_binding(
        &coords.vertex,
        &rows,
        &cage.positions,
        fit.normals().triangles(),
        points,
        &omega,
        &crate::sync::cage_prior::BindingJoints::two_joint_chain(
            DVec3::new(lo.x, 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)),
            0.5 * (lo + hi),
        ),
        rows_scale,
    )
    .unwrap();
    (fit.with_prior(prior, true), cage)
}

/// At the rest pose the carried cage is the rest cage, so the regularised fit of the rest rows
/// returns the rest cage (from a perturbed start); a rigid motion of both joints moves the
/// answer rigidly.
#[test]
fn a_regularised_fit_keeps_the_rest_cage_and_follows_rigid_motions() {
    let points = random_inside(17, 80);
    let (mut fit, cage) = regularised_fit_of(&points);
    fit.carry_prior(&[glam::DAffine3::IDENTITY; 2], &cage.positions);
    for (p, c) in fit.prior_target().unwrap().iter().zip(&cage.positions) {
        assert!(p.distance(*c) < 1e-13, "P {p} vs C {c}");
    }
    let mut g = vec![DVec3::ZERO; fit.normals().len()];
    let mut rows = vec![DVec3::ZERO; points.len()];
    fit.rows_of(&cage.positions, &mut g, &mut rows);
    let mut solved: Vec<DVec3> = cage
        .positions
        .iter()
        .enumerate()
        .map(|(i, c)| *c + DVec3::new(0.02, -0.01 * (i % 3) as f64, 0.015))
        .collect();
    let report = fit.apply(&rows, &mut solved).unwrap();
    assert!(report.residual <= fit.tolerance(), "{report:?}");
    for (s, c) in solved.iter().zip(&cage.positions) {
        assert!(s.distance(*c) < 1e-11, "{s} vs {c}");
    }
    let motion = glam::DAffine3::from_rotation_translation(
        DQuat::from_axis_angle(DVec3::new(0.2, 1.0, -0.4).normalize(), 0.7),
        DVec3::new(0.3, -0.2, 0.5),
    );
    fit.carry_prior(&[motion; 2], &cage.positions);
    let moved_rows: Vec<DVec3> = rows.iter().map(|r| motion.transform_point3(*r)).collect();
    let report = fit.apply(&moved_rows, &mut solved).unwrap();
    assert!(report.residual <= fit.tolerance(), "{report:?}");
    for (s, c) in solved.iter().zip(&cage.positions) {
        let expected = motion.transform_point3(*c);
        assert!(s.distance(expected) < 1e-10, "{s} vs {expected}");
    }
}

/// With a prior, the gradient is the derivative of the energy and the Newton matrix the
/// derivative of the gradient (central differences), at a large-residual state.
#[test]
fn a_regularised_fits_gradient_and_newton_matrix_are_its_derivatives() {
    let points = random_inside(19, 50);
    let (mut fit, cage) = regularised_fit_of(&points);
    let turn = glam::DAffine3::from_rotation_translation(
        DQuat::from_axis_angle(DVec3::X, 0.5),
        DVec3::new(0.0, 0.1, 0.0),
    );
    fit.carry_prior(&[glam::DAffine3::IDENTITY, turn], &cage.positions);
    let target: Vec<DVec3> = points
        .iter()
        .enumerate()
        .map(|(i, p)| *p * 1.1 + DVec3::new(0.05 * (i % 4) as f64, -0.03, 0.02))
        .collect();
    let x: Vec<DVec3> = cage
        .positions
        .iter()
        .enumerate()
        .map(|(i, c)| *c + DVec3::new(0.02 * i as f64, 0.01, -0.015 * (i % 3) as f64))
        .collect();
    let (nr, nf) = (points.len(), fit.normals().len());
    let evaluate = |fit: &GreenCageFit, x: &[DVec3]| {
        let mut faces = FaceScratch::new(x.len(), nf);
        let mut out = Evaluation::new(nr, x.len());
        let (energy, _) = fit.evaluate(x, &target, &mut faces, &mut out);
        (energy, out.gradient, out.residual)
    };
    let (energy, gradient, residual) = evaluate(&fit, &x);
    assert!((fit.energy(&target, &x) - energy).abs() <= 1e-14 * energy);
    fit.hessian_at(&x, &residual);
    let n = 3 * x.len();
    let h = 1e-6;
    for q in 0..n {
        let mut plus = x.clone();
        let mut minus = x.clone();
        plus[q / 3][q % 3] += h;
        minus[q / 3][q % 3] -= h;
        let (ep, gp, _) = evaluate(&fit, &plus);
        let (em, gm, _) = evaluate(&fit, &minus);
        let slope = (ep - em) / (2.0 * h);
        let analytic = gradient[q / 3][q % 3];
        assert!(
            (slope - analytic).abs() < 1e-6 * (1.0 + slope.abs()),
            "gradient {q}: {slope} vs {analytic}"
        );
        for p in 0..n {
            let fd = (gp[p / 3][p % 3] - gm[p / 3][p % 3]) / (2.0 * h);
            let analytic = fit.normal_matrix[(p, q)];
            assert!(
                (fd - analytic).abs() < 1e-5 * (1.0 + fd.abs()),
                "({p}, {q}): {fd} vs {analytic}"
            );
        }
    }
}
