//! Property tests of the f32 skinning kernels (LbsF32, DqsF32, CorF32, BlendedF32): the properties of the f64
//! kernels within f32 tolerance, and agreement with the f64 kernels. Coordinates and translations
//! are in [-10, 10]; the tolerance 1e-4 is ≈ 2e-6 of the scale (f32 ε ≈ 6e-8).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::SkinWeights;
use cagerig::skinning::{
    BlendedF32, BlendedF32Scratch, BlendedSkinning, CorF32, CorF32Scratch, CorScratch, CorSkinning,
    DqsF32, DqsF32Scratch, DqsScratch, DualQuaternionSkinning, LbsF32, LbsF32Scratch,
    LinearBlendSkinning,
};
use glam::{DAffine3, DVec3, Vec3};
use proptest::prelude::*;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::{point, rigid, skin_weights, spread_blend_weights, weight_rows};

const NUM_JOINTS: usize = 6;
const TOLERANCE: f64 = 1e-4;

/// f32 LBS, DQS, CoR and the blend (with [`spread_blend_weights`]) of the same input, widened
/// to f64.
fn skin_all_f32(
    w: &SkinWeights,
    t: &[DAffine3],
    rest: &[DVec3],
    centres: &[DVec3],
) -> [Vec<DVec3>; 4] {
    let n = rest.len();
    let widen = |v: Vec<Vec3>| v.iter().map(|p| p.as_dvec3()).collect::<Vec<_>>();
    let mut lbs = vec![Vec3::ZERO; n];
    LbsF32::new(w, rest)
        .unwrap()
        .apply(t, &mut LbsF32Scratch::new(t.len()), &mut lbs);
    let mut dqs = vec![Vec3::ZERO; n];
    DqsF32::new(w, rest)
        .unwrap()
        .apply(t, &mut DqsF32Scratch::new(t.len()), &mut dqs);
    let mut cor = vec![Vec3::ZERO; n];
    CorF32::new(w, rest, centres)
        .unwrap()
        .apply(t, &mut CorF32Scratch::new(t.len()), &mut cor);
    let mut blended = vec![Vec3::ZERO; n];
    BlendedF32::new(w, &spread_blend_weights(n), rest)
        .unwrap()
        .apply(t, &mut BlendedF32Scratch::new(t.len()), &mut blended);
    [widen(lbs), widen(dqs), widen(cor), widen(blended)]
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
        for (method, out) in skin_all_f32(&w, &t, &rest, &centres).iter().enumerate() {
            for (a, b) in out.iter().zip(&rest) {
                prop_assert!(a.abs_diff_eq(*b, TOLERANCE), "method {}: {} vs {}", method, a, b);
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
        let [lbs, dqs, cor, blended] = skin_all_f32(&w, &transforms, &rest, &centres);
        for i in 0..rest.len() {
            let expected = transforms[joint].transform_point3(rest[i]);
            prop_assert!(blended[i].abs_diff_eq(expected, TOLERANCE), "{} vs {}", blended[i], expected);
            prop_assert!(lbs[i].abs_diff_eq(expected, TOLERANCE), "{} vs {}", lbs[i], expected);
            prop_assert!(dqs[i].abs_diff_eq(expected, TOLERANCE), "{} vs {}", dqs[i], expected);
            prop_assert!(cor[i].abs_diff_eq(expected, TOLERANCE), "{} vs {}", cor[i], expected);
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
        for (method, out) in skin_all_f32(&w, &t, &rest, &centres).iter().enumerate() {
            for (a, b) in out.iter().zip(&rest) {
                let expected = transform.transform_point3(*b);
                prop_assert!(a.abs_diff_eq(expected, TOLERANCE), "method {}: {} vs {}", method, a, expected);
            }
        }
    }

    /// Random rigs and poses (rotations up to any angle, pivots included): f32 ≈ f64.
    #[test]
    fn f32_kernels_match_f64_kernels(
        (rows, rest, centres) in (1..40usize).prop_flat_map(|n| (
            weight_rows(n, NUM_JOINTS),
            proptest::collection::vec(point(), n),
            proptest::collection::vec(point(), n),
        )),
        transforms in proptest::collection::vec(rigid(), NUM_JOINTS),
    ) {
        let w = skin_weights(&rows, NUM_JOINTS);
        let n = rest.len();
        let mut lbs = vec![DVec3::ZERO; n];
        LinearBlendSkinning::new(&w).apply(&transforms, &rest, &mut lbs);
        let mut dqs = vec![DVec3::ZERO; n];
        DualQuaternionSkinning::new(&w).apply(&transforms, &rest, &mut DqsScratch::new(NUM_JOINTS), &mut dqs);
        let mut cor = vec![DVec3::ZERO; n];
        CorSkinning::new(&w).apply(&transforms, &rest, &centres, &mut CorScratch::new(NUM_JOINTS), &mut cor);
        let mut blended = vec![DVec3::ZERO; n];
        BlendedSkinning::new(&w, &spread_blend_weights(n))
            .unwrap()
            .apply(&transforms, &rest, &mut DqsScratch::new(NUM_JOINTS), &mut blended);
        let approx = skin_all_f32(&w, &transforms, &rest, &centres);
        for (method, (exact, approx)) in [lbs, dqs, cor, blended].iter().zip(&approx).enumerate() {
            for (a, b) in approx.iter().zip(exact) {
                // DQS/CoR normalise a blended quaternion; its conditioning is bounded because the
                // pivot term has weight ≥ 1/#J, so the error stays at a few f32 ulps of the scale.
                prop_assert!(a.abs_diff_eq(*b, TOLERANCE), "method {}: {} vs {}", method, a, b);
            }
        }
    }
}
