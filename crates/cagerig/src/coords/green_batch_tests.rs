//! Tests of [`super`] (`green_batch.rs`), kept beside it to hold that file under ~600 lines.

#![expect(
    unsafe_code,
    reason = "tests call the #[target_feature] tiers after detecting them"
)]

use super::*;
use crate::coords::green::outward_triangles;
use crate::coords::green::tests::{random_inside, test_cage};

/// φ and ψ (column-major, `n × #C` and `n × #F`) of `points` by the given tier: 0 the
/// baseline body, 1 AVX2, 2 AVX-512; `None` if the CPU lacks the tier.
fn run_tier(
    tier: u8,
    plan: &GreenBatchPlan<'_>,
    points: &[DVec3],
) -> Option<(Vec<f64>, Vec<f64>, Option<usize>)> {
    let (n, c, f) = (points.len(), plan.positions.len(), plan.triangles.len());
    let mut phi = vec![f64::NAN; n * c];
    let mut psi = vec![f64::NAN; n * f];
    let mut scratch = GreenBatchScratch::new(plan);
    // SAFETY: `phi` is n × c and `psi` n × f column-major, owned here.
    let (mut vertex_out, mut face_out) = unsafe {
        (
            RowBlock::new(phi.as_mut_ptr(), n, n, c),
            RowBlock::new(psi.as_mut_ptr(), n, n, f),
        )
    };
    let (v, o) = (&mut vertex_out, &mut face_out);
    let bad = match tier {
        0 => evaluate_green_rows_generic::<PlainMath>(plan, points, &mut scratch, v, o),
        #[cfg(target_arch = "x86_64")]
        1 if crate::simd_dispatch::cpu().avx2() =>
        // SAFETY: feature checked.
        unsafe { evaluate_green_rows_avx2(plan, points, &mut scratch, v, o) },
        #[cfg(target_arch = "x86_64")]
        2 if crate::simd_dispatch::cpu().avx512f() =>
        // SAFETY: feature checked.
        unsafe { evaluate_green_rows_avx512(plan, points, &mut scratch, v, o) },
        _ => return None,
    };
    Some((phi, psi, bad))
}

/// Regular points inside, points on a face, next to an edge and on a cage vertex (recomputed
/// lanes), and a short last batch.
fn mixed_points(cage: &crate::mesh::TriMesh) -> Vec<DVec3> {
    let p = &cage.positions;
    let mut points = random_inside(11, 37);
    points[3] = p[2];
    points[9] = (p[0] + p[2] + p[4]) / 3.0;
    points[17] = (p[0] + p[2]) / 2.0 * (1.0 - 1e-7);
    points[18] = (p[1] + p[4]) / 2.0 * (1.0 - 1e-3);
    points
}

/// The largest difference between two tiers' entries, relative to `1 + |entry|`.
fn tier_difference(tier: &[f64], baseline: &[f64]) -> f64 {
    tier.iter()
        .zip(baseline)
        .map(|(a, b)| (a - b).abs() / (1.0 + b.abs()))
        .fold(0.0, f64::max)
}

/// The wide tiers fuse multiplies and adds and take the AVX-512 reciprocal estimate refined to
/// about an ulp, so they agree with the plain IEEE baseline to rounding: within 1e-13 (relative
/// to 1 + |entry|) everywhere but the point 1e-7 of an edge's length from an edge (row 17), where
/// a face's solid angle is only conditioned to ~ε·size/d (the recomputed lanes, on a face, an edge
/// or a corner, take the same per-point code on every tier).
#[test]
fn every_tier_agrees_with_the_baseline_to_rounding() {
    let cage = test_cage();
    let triangles = outward_triangles(&cage);
    let frames: Vec<_> = triangles
        .iter()
        .map(|t| GreenTriangle::new(t.map(|v| cage.positions[v as usize])))
        .collect();
    let plan = GreenBatchPlan::new(&cage.positions, &triangles, &frames);
    let points = mixed_points(&cage);
    let Some((phi, psi, bad)) = run_tier(0, &plan, &points) else {
        unreachable!("the baseline always runs")
    };
    assert_eq!(bad, None);
    let n = points.len();
    let without_row_17 = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .enumerate()
            .filter(|(k, _)| k % n != 17)
            .map(|(_, &w)| w)
            .collect()
    };
    for tier in [1, 2] {
        if let Some((tier_phi, tier_psi, tier_bad)) = run_tier(tier, &plan, &points) {
            assert_eq!(tier_bad, None);
            for (name, got, expected) in [("φ", &tier_phi, &phi), ("ψ", &tier_psi, &psi)] {
                let all = tier_difference(got, expected);
                let regular = tier_difference(&without_row_17(got), &without_row_17(expected));
                assert!(regular < 1e-13, "{name} of tier {tier}: {regular:e}");
                assert!(all < 1e-9, "{name} of tier {tier} beside an edge: {all:e}");
            }
        }
    }
}

#[test]
fn batches_match_the_per_point_closed_forms() {
    let cage = test_cage();
    let triangles = outward_triangles(&cage);
    let frames: Vec<_> = triangles
        .iter()
        .map(|t| GreenTriangle::new(t.map(|v| cage.positions[v as usize])))
        .collect();
    let plan = GreenBatchPlan::new(&cage.positions, &triangles, &frames);
    let points = mixed_points(&cage);
    let Some((phi, psi, _)) = run_tier(0, &plan, &points) else {
        unreachable!("the baseline always runs")
    };
    let (n, c, f) = (points.len(), cage.positions.len(), triangles.len());
    let mut scratch = GreenBatchScratch::new(&plan);
    for (i, &eta) in points.iter().enumerate() {
        assert!(evaluate_point(&plan, eta, &mut scratch));
        // Within d of an edge each face's solid angle is only known to ~ε·size/d (the
        // conditioning of its arctangent's arguments there), in either form.
        let tolerance = match i {
            17 => 1e-9,
            18 => 1e-12,
            _ => 1e-14,
        };
        for k in 0..c {
            let (got, expected) = (phi[k * n + i], scratch.row_vertex[k]);
            assert!(
                (got - expected).abs() < tolerance,
                "φ row {i} col {k}: {got} vs {expected}"
            );
        }
        for t in 0..f {
            let (got, expected) = (psi[t * n + i], scratch.row_face[t]);
            assert!(
                (got - expected).abs() < tolerance,
                "ψ row {i} col {t}: {got} vs {expected}"
            );
        }
    }
}

proptest::proptest! {
    /// On an icosphere cage with random radii at any scale, the batches reproduce every
    /// interior point and sum φ to 1, and every tier agrees with the baseline to rounding.
    #[test]
    fn batches_reproduce_and_sum_to_one_on_any_star_cage(
        radii in proptest::collection::vec(0.8f64..1.6, 42),
        scale in 0.01f64..100.0,
        seed in 0u64..1000,
    ) {
        let (positions, triangles) = crate::coords::mvc::tests::icosphere(&radii);
        let positions: Vec<DVec3> = positions.iter().map(|p| *p * scale).collect();
        let frames: Vec<_> = triangles
            .iter()
            .map(|t| GreenTriangle::new(t.map(|v| positions[v as usize])))
            .collect();
        let plan = GreenBatchPlan::new(&positions, &triangles, &frames);
        // Points within 0.4 of the centre (`random_inside` gives |x|₁ < 0.8): the face planes
        // pass at ≥ 0.6 with corner radii in [0.8, 1.6] and 32–36° between neighbours.
        let points: Vec<DVec3> =
            random_inside(seed, 21).iter().map(|p| *p * (0.5 * scale)).collect();
        let Some((phi, psi, bad)) = run_tier(0, &plan, &points) else {
            unreachable!("the baseline always runs")
        };
        proptest::prop_assert_eq!(bad, None);
        let mut normals = vec![DVec3::ZERO; triangles.len()];
        crate::coords::green::face_normals(&positions, &triangles, &mut normals);
        let n = points.len();
        for (i, eta) in points.iter().enumerate() {
            let sum: f64 = (0..positions.len()).map(|k| phi[k * n + i]).sum();
            let image: DVec3 = positions
                .iter()
                .enumerate()
                .map(|(k, v)| phi[k * n + i] * *v)
                .chain(normals.iter().enumerate().map(|(t, m)| psi[t * n + i] * *m))
                .sum();
            proptest::prop_assert!((sum - 1.0).abs() < 1e-13, "Σφ = {}", sum);
            proptest::prop_assert!(
                image.distance(*eta) < 1e-13 * scale,
                "{} vs {}", image, eta
            );
        }
        for tier in [1, 2] {
            if let Some((tier_phi, tier_psi, _)) = run_tier(tier, &plan, &points) {
                // ψ has the units of length: compared at the cage's scale.
                let unit_psi = |v: &[f64]| v.iter().map(|w| w / scale).collect::<Vec<_>>();
                let phi_difference = tier_difference(&tier_phi, &phi);
                let psi_difference = tier_difference(&unit_psi(&tier_psi), &unit_psi(&psi));
                proptest::prop_assert!(phi_difference < 1e-13, "φ: {:e}", phi_difference);
                proptest::prop_assert!(psi_difference < 1e-13, "ψ: {:e}", psi_difference);
            }
        }
    }
}

#[test]
fn degenerate_triangle_gets_a_zero_column_and_is_skipped() {
    let mut cage = test_cage();
    // A zero-area triangle (a repeated corner) appended to the closed cage.
    cage.triangles.push([0, 2, 2]);
    let triangles = outward_triangles(&cage);
    let frames: Vec<_> = triangles
        .iter()
        .map(|t| GreenTriangle::new(t.map(|v| cage.positions[v as usize])))
        .collect();
    assert!(frames[8].is_none());
    let plan = GreenBatchPlan::new(&cage.positions, &triangles, &frames);
    let points = random_inside(5, 10);
    let Some((_, psi, bad)) = run_tier(0, &plan, &points) else {
        unreachable!("the baseline always runs")
    };
    assert_eq!(bad, None);
    assert!(psi[8 * points.len()..].iter().all(|&w| w == 0.0));
}
