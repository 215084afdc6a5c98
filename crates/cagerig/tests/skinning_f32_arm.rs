//! f32 per-frame skinning kernels against the f64 kernels on the 3× subdivided Arm (133 073
//! vertices) at reference step ii (joint 3 rotated by 60° about +X): max |f32 − f64| relative to
//! the bounding-box diagonal of the rest mesh.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;

use cagerig::io::{read_cor_weights, read_obj, read_skt, read_skw};
use cagerig::mesh::{bounding_box, max_distance};
use cagerig::skinning::{
    BlendedF32, BlendedF32Scratch, BlendedSkinning, CorF32, CorF32Scratch, CorScratch, CorSkinning,
    DqsF32, DqsF32Scratch, DqsScratch, DualQuaternionSkinning, LbsF32, LbsF32Scratch,
    LinearBlendSkinning,
};
use cagerig::subdivide::subdivide_midpoint;
use glam::{DAffine3, DVec3, Vec3};

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::{ARM, spread_blend_weights, step2_transforms};

/// Tolerance on max |f32 − f64| / bbox diagonal (measured: LBS 3.1e-7, DQS 4.8e-7, CoR 2.9e-7,
/// blended with `spread_blend_weights` 4.2e-7).
const TOLERANCE: f64 = 2e-6;

struct Rig {
    rest: Vec<DVec3>,
    weights: cagerig::SkinWeights,
    centres: Vec<DVec3>,
    transforms: Vec<DAffine3>,
}

/// The Arm subdivided 3 times; CoR centres = S·M on the original vertices (NaN = no CoR where S
/// has an empty row), midpoints of the parents' centres on new vertices.
fn subdivided_arm() -> Rig {
    let dir = Path::new(ARM);
    let mesh = read_obj(&dir.join("arm.obj")).unwrap();
    let skeleton = read_skt(&dir.join("arm.skt")).unwrap();
    let (weights, _) = read_skw(&dir.join("arm.skw"), mesh.num_vertices(), skeleton.len()).unwrap();
    let s = read_cor_weights(&dir.join("arm_corWeights.txt"), mesh.num_vertices()).unwrap();
    let mut centres: Vec<DVec3> = (0..mesh.num_vertices())
        .map(|i| {
            let (cols, values) = s.row(i);
            if cols.is_empty() {
                return DVec3::NAN;
            }
            cols.iter()
                .zip(values)
                .map(|(&k, &w)| w * mesh.positions[k as usize])
                .sum()
        })
        .collect();
    let sub = subdivide_midpoint(&mesh, &weights, 3).unwrap();
    for &[p, q] in &sub.edge_parents {
        centres.push((centres[p as usize] + centres[q as usize]) * 0.5);
    }
    assert_eq!(sub.mesh.num_vertices(), 133_073);
    assert_eq!(centres.len(), 133_073);
    Rig {
        rest: sub.mesh.positions,
        weights: sub.skin_weights,
        centres,
        transforms: step2_transforms(),
    }
}

fn relative_error(f32_out: &[Vec3], f64_out: &[DVec3], diagonal: f64) -> f64 {
    let widened: Vec<DVec3> = f32_out.iter().map(|p| p.as_dvec3()).collect();
    max_distance(&widened, f64_out) / diagonal
}

#[test]
fn f32_kernels_match_f64_on_subdivided_arm_step2() {
    let rig = subdivided_arm();
    let (lo, hi) = bounding_box(&rig.rest);
    let diagonal = lo.distance(hi);
    let n = rig.rest.len();
    let num_joints = rig.transforms.len();
    let mut exact = vec![DVec3::ZERO; n];
    let mut approx = vec![Vec3::ZERO; n];

    LinearBlendSkinning::new(&rig.weights).apply(&rig.transforms, &rig.rest, &mut exact);
    LbsF32::new(&rig.weights, &rig.rest).unwrap().apply(
        &rig.transforms,
        &mut LbsF32Scratch::new(num_joints),
        &mut approx,
    );
    let lbs_error = relative_error(&approx, &exact, diagonal);

    DualQuaternionSkinning::new(&rig.weights).apply(
        &rig.transforms,
        &rig.rest,
        &mut DqsScratch::new(num_joints),
        &mut exact,
    );
    DqsF32::new(&rig.weights, &rig.rest).unwrap().apply(
        &rig.transforms,
        &mut DqsF32Scratch::new(num_joints),
        &mut approx,
    );
    let dqs_error = relative_error(&approx, &exact, diagonal);

    CorSkinning::new(&rig.weights).apply(
        &rig.transforms,
        &rig.rest,
        &rig.centres,
        &mut CorScratch::new(num_joints),
        &mut exact,
    );
    CorF32::new(&rig.weights, &rig.rest, &rig.centres)
        .unwrap()
        .apply(
            &rig.transforms,
            &mut CorF32Scratch::new(num_joints),
            &mut approx,
        );
    let cor_error = relative_error(&approx, &exact, diagonal);

    let blend = spread_blend_weights(n);
    BlendedSkinning::new(&rig.weights, &blend).unwrap().apply(
        &rig.transforms,
        &rig.rest,
        &mut DqsScratch::new(num_joints),
        &mut exact,
    );
    BlendedF32::new(&rig.weights, &blend, &rig.rest)
        .unwrap()
        .apply(
            &rig.transforms,
            &mut BlendedF32Scratch::new(num_joints),
            &mut approx,
        );
    let blended_error = relative_error(&approx, &exact, diagonal);

    println!(
        "subdivided Arm ({n} v, bbox diagonal {diagonal:.3}), step ii, max |f32 - f64| / diagonal: \
         LBS {lbs_error:.3e}, DQS {dqs_error:.3e}, CoR {cor_error:.3e}, blended {blended_error:.3e}"
    );
    assert!(lbs_error <= TOLERANCE, "LBS {lbs_error:e}");
    assert!(dqs_error <= TOLERANCE, "DQS {dqs_error:e}");
    assert!(cor_error <= TOLERANCE, "CoR {cor_error:e}");
    assert!(blended_error <= TOLERANCE, "blended {blended_error:e}");
}

#[test]
fn f32_set_rest_positions_follows_an_edit() {
    // Translating the rest mesh and centres by d moves the identity-pose output by d.
    let rig = subdivided_arm();
    let num_joints = rig.transforms.len();
    let d = DVec3::new(3.0, -2.0, 1.0);
    let moved: Vec<DVec3> = rig.rest.iter().map(|p| *p + d).collect();
    let moved_centres: Vec<DVec3> = rig.centres.iter().map(|p| *p + d).collect();
    let identity = vec![DAffine3::IDENTITY; num_joints];
    let mut out = vec![Vec3::ZERO; rig.rest.len()];
    let expected: Vec<DVec3> = moved.clone();
    let (lo, hi) = bounding_box(&rig.rest);
    let tolerance = 1e-6 * lo.distance(hi);

    let mut lbs = LbsF32::new(&rig.weights, &rig.rest).unwrap();
    lbs.set_rest_positions(&moved).unwrap();
    lbs.apply(&identity, &mut LbsF32Scratch::new(num_joints), &mut out);
    assert!(relative_error(&out, &expected, 1.0) < tolerance);

    let mut dqs = DqsF32::new(&rig.weights, &rig.rest).unwrap();
    dqs.set_rest_positions(&moved).unwrap();
    dqs.apply(&identity, &mut DqsF32Scratch::new(num_joints), &mut out);
    assert!(relative_error(&out, &expected, 1.0) < tolerance);

    let mut cor = CorF32::new(&rig.weights, &rig.rest, &rig.centres).unwrap();
    cor.set_rest_positions(&moved, &moved_centres).unwrap();
    cor.apply(&identity, &mut CorF32Scratch::new(num_joints), &mut out);
    assert!(relative_error(&out, &expected, 1.0) < tolerance);

    // Wrong sizes are errors, not panics.
    assert!(lbs.set_rest_positions(&moved[1..]).is_err());
    assert!(cor.set_rest_positions(&moved, &moved_centres[1..]).is_err());
}
