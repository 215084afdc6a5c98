//! Tests of [`super`] (`skeleton_updater.rs`), kept beside it to hold that file under ~600 lines.

use super::prior::{local_prior, localisation_value};
use super::*;
use crate::coords::mvc::compute_cage_coords;
use crate::subdivide::subdivide_midpoint;

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");

/// Ψ through the local MVC path and through the reference full-MVC path.
fn both_paths(
    levels: usize,
    localisation: JointLocalisation,
) -> (SkeletonUpdater, SkeletonUpdater) {
    let dir = std::path::Path::new(ARM);
    let mesh = crate::io::read_obj(&dir.join("arm.obj")).unwrap();
    let skeleton = crate::io::read_skt(&dir.join("arm.skt")).unwrap();
    let (weights, _) =
        crate::io::read_skw(&dir.join("arm.skw"), mesh.num_vertices(), skeleton.len()).unwrap();
    let cage = crate::io::read_obj(&dir.join("arm_cage.obj")).unwrap();
    let sub = subdivide_midpoint(&mesh, &weights, levels).unwrap();
    let phi = compute_cage_coords(&cage, &sub.mesh.positions, None).unwrap();
    let run = |local| {
        SkeletonUpdater::build(
            &sub.mesh,
            &skeleton,
            &sub.skin_weights,
            (&phi, None),
            &cage.positions,
            localisation,
            local,
        )
        .unwrap()
        .0
    };
    (run(true), run(false))
}

/// How many joints take the local path (no fallback to the full MVC).
fn local_path_joints(levels: usize, localisation: JointLocalisation) -> usize {
    let dir = std::path::Path::new(ARM);
    let mesh = crate::io::read_obj(&dir.join("arm.obj")).unwrap();
    let skeleton = crate::io::read_skt(&dir.join("arm.skt")).unwrap();
    let (weights, _) =
        crate::io::read_skw(&dir.join("arm.skw"), mesh.num_vertices(), skeleton.len()).unwrap();
    let cage = crate::io::read_obj(&dir.join("arm_cage.obj")).unwrap();
    let sub = subdivide_midpoint(&mesh, &weights, levels).unwrap();
    let phi = compute_cage_coords(&cage, &sub.mesh.positions, None).unwrap();
    let local_mvc = LocalMvc::new(&sub.mesh.positions, &sub.mesh.triangles);
    let mut scratch = local_mvc.scratch();
    let inputs = JointInputs {
        rest_mesh: &sub.mesh,
        skeleton: &skeleton,
        skin_weights: &sub.skin_weights,
        cage_coords: &phi,
        face_terms: None,
        rest_cage: &cage.positions,
        localisation,
        reference_floor_power: 0.0,
        candidates: articulation_candidates(&skeleton, &sub.skin_weights),
        local_mvc: None,
    };
    (0..skeleton.len())
        .filter(|&j| local_prior(j, &inputs, &local_mvc, &mut scratch).is_some())
        .count()
}

#[test]
fn the_arm_joints_take_the_local_path() {
    // Every joint of the Arm lies well inside the skin and has a blend region.
    assert_eq!(local_path_joints(0, JointLocalisation::default()), 25);
    assert_eq!(local_path_joints(2, JointLocalisation::default()), 25);
}

fn assert_same_psi(fast: &SkeletonUpdater, reference: &SkeletonUpdater) {
    assert_eq!(fast.num_joints(), reference.num_joints());
    for j in 0..fast.num_joints() {
        let (a, b) = (fast.joint_row(j), reference.joint_row(j));
        let scale = b.iter().map(|w| w.abs()).fold(0.0, f64::max);
        for (k, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                (x - y).abs() <= 1e-9 * scale,
                "joint {j}, cage vertex {k}: {x} vs {y}"
            );
        }
        let (r, s) = (&fast.reports()[j], &reference.reports()[j]);
        assert_eq!(
            (r.joint, r.unlocalised, &r.method),
            (s.joint, s.unlocalised, &s.method)
        );
        assert!(r.residual < 1e-9 && s.residual < 1e-9, "{r:?} {s:?}");
    }
}

#[test]
fn local_mvc_prior_gives_the_full_mvc_psi_on_the_arm() {
    let (fast, reference) = both_paths(0, JointLocalisation::default());
    assert_same_psi(&fast, &reference);
}

#[test]
fn local_mvc_prior_gives_the_full_mvc_psi_on_the_subdivided_arm() {
    let (fast, reference) = both_paths(2, JointLocalisation::default());
    assert_same_psi(&fast, &reference);
    // Another exponent changes the localised regions.
    let (fast, reference) = both_paths(1, JointLocalisation::Articulation { exponent: 0.5 });
    assert_same_psi(&fast, &reference);
}

#[test]
fn reference_tool_mode_is_unchanged_by_the_switch() {
    let (a, b) = both_paths(0, JointLocalisation::reference_tool());
    for j in 0..a.num_joints() {
        assert_eq!(a.joint_row(j), b.joint_row(j));
    }
}

#[test]
fn reference_floor_power_matches_powf() {
    let loc = JointLocalisation::reference_tool();
    let JointLocalisation::ReferenceTool { exponent, epsilon } = loc else {
        unreachable!()
    };
    let floor = epsilon.powf(exponent);
    for own in [0.0f64, 1e-3, 0.01, 0.0100001, 0.3, 1.0] {
        for parent in [None, Some(0.0), Some(0.005), Some(0.7)] {
            let slow = {
                let mut l = -1.0 + own.abs().max(epsilon).powf(exponent);
                if let Some(p) = parent {
                    l += f64::abs(p).max(epsilon).powf(exponent);
                }
                l.max(epsilon)
            };
            assert_eq!(localisation_value(loc, own, parent, floor), slow);
        }
    }
}
