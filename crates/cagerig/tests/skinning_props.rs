//! Property tests shared by the four skinning kernels (LBS, DQS, CoR, the LBS/DQS blend).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::SkinWeights;
use cagerig::skinning::{
    BlendedSkinning, CorScratch, CorSkinning, DqBlendWeights, DqsScratch, DualQuaternionSkinning,
    LinearBlendSkinning,
};
use glam::{DAffine3, DVec3};
use proptest::prelude::*;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::{point, rigid, skin_weights, spread_blend_weights, weight_rows};

const NUM_JOINTS: usize = 6;

/// LBS, DQS, CoR and the blend (with [`spread_blend_weights`]) of the same input.
fn skin_all(w: &SkinWeights, t: &[DAffine3], rest: &[DVec3], centres: &[DVec3]) -> [Vec<DVec3>; 4] {
    let n = rest.len();
    let mut lbs = vec![DVec3::ZERO; n];
    LinearBlendSkinning::new(w).apply(t, rest, &mut lbs);
    let mut dqs = vec![DVec3::ZERO; n];
    DualQuaternionSkinning::new(w).apply(t, rest, &mut DqsScratch::new(t.len()), &mut dqs);
    let mut cor = vec![DVec3::ZERO; n];
    CorSkinning::new(w).apply(t, rest, centres, &mut CorScratch::new(t.len()), &mut cor);
    let blend = spread_blend_weights(n);
    [lbs, dqs, cor, skin_blended(w, &blend, t, rest)]
}

/// The blended kernel with blend weights `blend` (`#V`).
fn skin_blended(
    w: &SkinWeights,
    blend: &DqBlendWeights,
    t: &[DAffine3],
    rest: &[DVec3],
) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; rest.len()];
    BlendedSkinning::new(w, blend)
        .unwrap()
        .apply(t, rest, &mut DqsScratch::new(t.len()), &mut out);
    out
}

proptest! {
    #[test]
    fn identity_transforms_give_the_rest_mesh(
        (rows, rest, centres) in (1..40usize).prop_flat_map(|n| (
            weight_rows(n, NUM_JOINTS),
            proptest::collection::vec(point(), n),
            proptest::collection::vec(point(), n),
        ))
    ) {
        let w = skin_weights(&rows, NUM_JOINTS);
        let t = vec![DAffine3::IDENTITY; NUM_JOINTS];
        for (method, out) in skin_all(&w, &t, &rest, &centres).iter().enumerate() {
            for (a, b) in out.iter().zip(&rest) {
                prop_assert!(a.abs_diff_eq(*b, 1e-14 * (1.0 + b.length())), "method {}: {} vs {}", method, a, b);
            }
        }
    }

    #[test]
    fn single_bone_methods_agree(
        joint in 0..NUM_JOINTS,
        transforms in proptest::collection::vec(rigid(), NUM_JOINTS),
        rest in proptest::collection::vec(point(), 1..30),
        centre in point(),
    ) {
        let rows: Vec<Vec<(usize, f64)>> = rest.iter().map(|_| vec![(joint, 1.0)]).collect();
        let w = skin_weights(&rows, NUM_JOINTS);
        let centres = vec![centre; rest.len()];
        let [lbs, dqs, cor, blended] = skin_all(&w, &transforms, &rest, &centres);
        for i in 0..rest.len() {
            let expected = transforms[joint].transform_point3(rest[i]);
            prop_assert!(lbs[i].abs_diff_eq(expected, 1e-10));
            prop_assert!(blended[i].abs_diff_eq(expected, 1e-10), "{} vs {}", blended[i], expected);
            prop_assert!(dqs[i].abs_diff_eq(expected, 1e-10), "{} vs {}", dqs[i], expected);
            prop_assert!(cor[i].abs_diff_eq(expected, 1e-10), "{} vs {}", cor[i], expected);
        }
    }

    #[test]
    fn common_rigid_transform_moves_the_mesh_rigidly(
        (rows, rest, centres) in (1..40usize).prop_flat_map(|n| (
            weight_rows(n, NUM_JOINTS),
            proptest::collection::vec(point(), n),
            proptest::collection::vec(point(), n),
        )),
        transform in rigid(),
    ) {
        let w = skin_weights(&rows, NUM_JOINTS);
        let t = vec![transform; NUM_JOINTS];
        for (method, out) in skin_all(&w, &t, &rest, &centres).iter().enumerate() {
            for (a, b) in out.iter().zip(&rest) {
                let expected = transform.transform_point3(*b);
                prop_assert!(a.abs_diff_eq(expected, 1e-10), "method {}: {} vs {}", method, a, expected);
            }
        }
    }

    /// The blend is the convex combination `(1 − b)·LBS + b·DQS` of the two kernels' points,
    /// for any blend weights in [0, 1].
    #[test]
    fn blended_is_the_convex_combination_of_lbs_and_dqs(
        (rows, rest, blend) in (1..40usize).prop_flat_map(|n| (
            weight_rows(n, NUM_JOINTS),
            proptest::collection::vec(point(), n),
            proptest::collection::vec(0.0..=1.0f64, n),
        )),
        transforms in proptest::collection::vec(rigid(), NUM_JOINTS),
    ) {
        let w = skin_weights(&rows, NUM_JOINTS);
        let [lbs, dqs, ..] = skin_all(&w, &transforms, &rest, &rest);
        let blended = skin_blended(&w, &DqBlendWeights::new(blend.clone()).unwrap(), &transforms, &rest);
        for i in 0..rest.len() {
            let expected = lbs[i] * (1.0 - blend[i]) + dqs[i] * blend[i];
            prop_assert!(blended[i].abs_diff_eq(expected, 1e-10), "vertex {}: {} vs {}", i, blended[i], expected);
        }
    }

    /// Rotations by ±θ (θ near 180°) about the same axis have nearly antipodal quaternions; the
    /// blend must go the short way, through 180°, not collapse towards the identity.
    #[test]
    fn dqs_and_cor_blend_near_antipodal_rotations_the_short_way(
        axis in point().prop_filter("zero axis", |a| a.length() > 0.1),
        theta_deg in 150.0..179.9f64,
        first_weight in 0.05..0.95f64,
        p in point(),
    ) {
        let axis = axis.normalize();
        let theta = theta_deg.to_radians();
        let t = [
            DAffine3::from_axis_angle(axis, theta),
            DAffine3::from_axis_angle(axis, -theta),
        ];
        let w = SkinWeights::from_triplets(1, 2, [(0, 0, first_weight), (0, 1, 1.0 - first_weight)])
            .unwrap()
            .0;
        let mut dqs = [DVec3::ZERO];
        DualQuaternionSkinning::new(&w).apply(&t, &[p], &mut DqsScratch::new(2), &mut dqs);
        let mut cor = [DVec3::ZERO];
        CorSkinning::new(&w).apply(&t, &[p], &[DVec3::ZERO], &mut CorScratch::new(2), &mut cor);
        let along = axis * p.dot(axis);
        let radial = p - along;
        for out in [dqs[0], cor[0]] {
            // A rotation about `axis`: axial component and radius kept.
            prop_assert!((out.dot(axis) - p.dot(axis)).abs() < 1e-10);
            let out_radial = out - axis * out.dot(axis);
            prop_assert!((out_radial.length() - radial.length()).abs() < 1e-10);
            // Angle between θ and 360° − θ (through 180°): cos ≤ cos θ.
            if radial.length() > 1e-3 {
                let cos = out_radial.dot(radial) / radial.length_squared();
                prop_assert!(cos <= theta.cos() + 1e-9, "cos {} vs {}", cos, theta.cos());
            }
        }
    }
}
