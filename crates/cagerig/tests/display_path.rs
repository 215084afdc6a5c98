//! The f32 display path (`DisplayPrecision::F32`): the drawn M' is within 2e-6 of the bounding-box
//! diagonal of the exact one, and everything else — C', C, the joints, and the exact M' the
//! session still hands out — is bit-identical to a session on the exact path given the same
//! events, under LBS, DQS, CoR and the LBS/DQS blend. The drawn rest mesh M (Φ̃·C after a current-cage edit, with
//! Φ rounded to f32) is within 2e-6 of the diagonal of the exact M.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::demo;
use cagerig::pose::LocalPose;
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use glam::{DQuat, DVec3};

mod support;

fn session() -> RigSession {
    // 20k vertices: three chunks of the count-sorted kernels.
    let rig = demo::builtin("snake", Some(20_000)).unwrap();
    let blend = support::spread_blend_weights(rig.mesh.num_vertices());
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage)
        .with_dq_blend_weights(Some(blend));
    RigSession::new(parts, SessionOptions::default()).unwrap().0
}

fn diagonal(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = points.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    (hi - lo).length()
}

fn assert_same_state(exact: &RigSession, display: &RigSession, step: &str) {
    assert_eq!(exact.posed_cage(), display.posed_cage(), "C' after {step}");
    assert_eq!(exact.rest_cage(), display.rest_cage(), "C after {step}");
    assert_eq!(exact.rest_mesh(), display.rest_mesh(), "M after {step}");
    assert_eq!(
        exact.posed_world_from_joint(),
        display.posed_world_from_joint(),
        "S' after {step}"
    );
    assert_eq!(
        exact.posed_mesh(),
        display.posed_mesh(),
        "exact M' after {step}"
    );
    assert!(exact.display_mesh().is_none() && exact.display_rest_mesh().is_none());
    let shown = display.display_mesh().expect("display path is on");
    assert_drawn_close(shown, exact.posed_mesh(), &format!("M' after {step}"));
    let shown = display.display_rest_mesh().expect("display path is on");
    assert_drawn_close(shown, exact.rest_mesh(), &format!("M after {step}"));
}

/// The drawn f32 points are within 2e-6 of the diagonal of the exact ones.
fn assert_drawn_close(shown: &[glam::Vec3], exact: &[DVec3], what: &str) {
    let tolerance = 2e-6 * diagonal(exact);
    let worst = shown
        .iter()
        .zip(exact)
        .map(|(a, b)| a.as_dvec3().distance(*b))
        .fold(0.0, f64::max);
    assert!(
        worst <= tolerance,
        "displayed {what}: max error {worst:e} > {tolerance:e}"
    );
}

#[test]
fn display_path_matches_the_exact_path() {
    let mut exact = session();
    let mut display = session();
    display
        .set_display_precision(DisplayPrecision::F32)
        .unwrap();
    assert_eq!(display.display_precision(), DisplayPrecision::F32);
    assert_same_state(&exact, &display, "switching the display path on");
    let offset = DVec3::new(0.02, -0.01, 0.015);
    for method in SkinningMethod::ALL {
        for s in [&mut exact, &mut display] {
            s.set_skinning(method).unwrap();
        }
        assert_same_state(&exact, &display, &format!("{method:?}"));
        for s in [&mut exact, &mut display] {
            s.rotate_joint(5, DVec3::new(0.3, 1.0, 0.2).normalize(), 0.7)
                .unwrap();
        }
        assert_same_state(
            &exact,
            &display,
            &format!("a joint rotation under {method:?}"),
        );
        for s in [&mut exact, &mut display] {
            s.move_rest_cage(&[0, 3, 7], &[offset]).unwrap();
        }
        assert_same_state(
            &exact,
            &display,
            &format!("a rest-cage edit under {method:?}"),
        );
        for s in [&mut exact, &mut display] {
            s.move_posed_cage(&[9, 10], &[offset]).unwrap();
        }
        assert_same_state(
            &exact,
            &display,
            &format!("a current-cage grab under {method:?}"),
        );
        // Grab, rotate and edit the rest cage without reading M in between: the rest-cage
        // edit computes the exact M itself before its increment.
        for s in [&mut exact, &mut display] {
            s.move_posed_cage(&[2, 4], &[-offset]).unwrap();
            s.rotate_joint(3, DVec3::Y, -0.4).unwrap();
            s.move_posed_cage(&[1], &[offset]).unwrap();
            s.move_rest_cage(&[5], &[offset]).unwrap();
        }
        assert_same_state(
            &exact,
            &display,
            &format!("grab, rotate, grab, rest-cage edit under {method:?}"),
        );
    }
    // An animation sample with cage offsets (playback of a cage track) takes the same path as
    // a grab on the display path.
    let nc = exact.rest_cage().len();
    let nj = exact.skeleton().len();
    let offsets: Vec<DVec3> = (0..nc)
        .map(|k| DVec3::new(0.01 * (k % 3) as f64, -0.005, 0.002 * k as f64))
        .collect();
    let rotations: Vec<DQuat> = (0..nj)
        .map(|j| DQuat::from_rotation_z(0.05 * j as f64))
        .collect();
    let translation_offsets = vec![DVec3::ZERO; nj];
    let pose = LocalPose {
        rotations: &rotations,
        scales: None,
        translation_offsets: &translation_offsets,
        roots_only: true,
    };
    for s in [&mut exact, &mut display] {
        s.set_animation_sample_local(Some(&offsets), &pose).unwrap();
        s.rotate_joint(2, DVec3::X, 0.1).unwrap();
    }
    assert_same_state(&exact, &display, "an animation sample with cage offsets");
    // Switching back after a grab (M kept on the MaxVol rows) restores the whole exact M.
    for s in [&mut exact, &mut display] {
        s.move_posed_cage(&[0], &[offset]).unwrap();
    }
    display
        .set_display_precision(DisplayPrecision::Exact)
        .unwrap();
    assert!(display.display_mesh().is_none());
    assert_eq!(exact.posed_mesh(), display.posed_mesh());
    assert_eq!(exact.rest_mesh(), display.rest_mesh());
    for s in [&mut exact, &mut display] {
        s.rotate_joint(5, DVec3::X, 0.2).unwrap();
    }
    assert_eq!(exact.posed_mesh(), display.posed_mesh());
}
