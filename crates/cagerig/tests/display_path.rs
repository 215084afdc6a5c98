//! The f32 display path (`DisplayPrecision::F32`): the drawn M' is within 2e-6 of the bounding-box
//! diagonal of the exact one, and everything else — C', C, the joints, and the exact M' the
//! session still hands out — is bit-identical to a session on the exact path given the same
//! events, under LBS, DQS, CoR and the LBS/DQS blend. The drawn rest mesh M (Φ̃·C after a
//! current-cage edit, with Φ rounded to f32) is within 2e-6 of the diagonal of the exact M. The
//! same holds for a rig bound with Green coordinates (M̃ = [φ̃ ψ̃]·[C; g(C)], the exact M on
//! CageUp's rows).

#![expect(clippy::unwrap_used, clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::pose::LocalPose;
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig::{CoordsKind, demo};
use glam::{DQuat, DVec3};

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

fn session(coords: CoordsKind) -> RigSession {
    // MVC: 20k vertices, three chunks of the count-sorted kernels. Green: the default snake,
    // whose Green CageUp follows these events (tests/green_session.rs plays 200 random ones).
    let resolution = match coords {
        CoordsKind::Mvc => Some(20_000),
        CoordsKind::Green => None,
    };
    let rig = demo::builtin("snake", resolution).unwrap();
    let blend = support::spread_blend_weights(rig.mesh.num_vertices());
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage)
        .with_dq_blend_weights(Some(blend));
    let options = SessionOptions {
        coords,
        ..SessionOptions::default()
    };
    RigSession::new(parts, options).unwrap().0
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
    check_display_path(CoordsKind::Mvc);
}

#[test]
fn display_path_matches_the_exact_path_under_green_coordinates() {
    check_display_path(CoordsKind::Green);
}

/// Runs `event` on both sessions: both apply it, or both refuse it with the same error (a Green
/// CageUp that does not converge refuses the event and leaves the rig as it was). Returns 1 for
/// a refusal.
fn both(
    exact: &mut RigSession,
    display: &mut RigSession,
    event: impl Fn(&mut RigSession) -> Result<(), cagerig::RigError>,
) -> usize {
    let (a, b) = (event(exact), event(display));
    match (a, b) {
        (Ok(()), Ok(())) => 0,
        (Err(a), Err(b)) => {
            assert_eq!(a.to_string(), b.to_string());
            1
        }
        (a, b) => panic!("exact path: {a:?}, display path: {b:?}"),
    }
}

fn check_display_path(coords: CoordsKind) {
    let mut refused = 0;
    let mut exact = session(coords);
    let mut display = session(coords);
    // Green CageUp refuses poses whose fitted cage folds (docs/green-coordinates.md): smaller
    // bends for Green rigs.
    let bend = match coords {
        CoordsKind::Mvc => 1.0,
        CoordsKind::Green => 0.1,
    };
    display
        .set_display_precision(DisplayPrecision::F32)
        .unwrap();
    // The same call on the exact session (it re-skins and re-fits, as the switch does): a Green
    // CageUp's warm starts then follow the same history on both.
    exact
        .set_display_precision(DisplayPrecision::Exact)
        .unwrap();
    assert_eq!(display.display_precision(), DisplayPrecision::F32);
    assert_same_state(&exact, &display, "switching the display path on");
    let offset = DVec3::new(0.02, -0.01, 0.015) * bend;
    for method in SkinningMethod::ALL {
        refused += both(&mut exact, &mut display, |s| s.set_skinning(method));
        assert_same_state(&exact, &display, &format!("{method:?}"));
        refused += both(&mut exact, &mut display, |s| {
            s.rotate_joint(5, DVec3::new(0.3, 1.0, 0.2).normalize(), 0.7 * bend)
        });
        assert_same_state(
            &exact,
            &display,
            &format!("a joint rotation under {method:?}"),
        );
        refused += both(&mut exact, &mut display, |s| {
            s.move_rest_cage(&[0, 3, 7], &[offset])
        });
        assert_same_state(
            &exact,
            &display,
            &format!("a rest-cage edit under {method:?}"),
        );
        refused += both(&mut exact, &mut display, |s| {
            s.move_posed_cage(&[9, 10], &[offset])
        });
        assert_same_state(
            &exact,
            &display,
            &format!("a current-cage grab under {method:?}"),
        );
        // Grab, rotate and edit the rest cage without reading M in between: the rest-cage
        // edit computes the exact M itself before its increment.
        refused += both(&mut exact, &mut display, |s| {
            s.move_posed_cage(&[2, 4], &[-offset])
        });
        refused += both(&mut exact, &mut display, |s| {
            s.rotate_joint(3, DVec3::Y, -0.4 * bend)
        });
        refused += both(&mut exact, &mut display, |s| {
            s.move_posed_cage(&[1], &[offset])
        });
        refused += both(&mut exact, &mut display, |s| {
            s.move_rest_cage(&[5], &[offset])
        });
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
    refused += both(&mut exact, &mut display, |s| {
        s.set_animation_sample_local(Some(&offsets), &pose)
    });
    refused += both(&mut exact, &mut display, |s| {
        s.rotate_joint(2, DVec3::X, 0.1)
    });
    assert_same_state(&exact, &display, "an animation sample with cage offsets");
    // Switching back after a grab (M kept on the MaxVol rows) restores the whole exact M.
    refused += both(&mut exact, &mut display, |s| {
        s.move_posed_cage(&[0], &[offset])
    });
    for s in [&mut exact, &mut display] {
        s.set_display_precision(DisplayPrecision::Exact).unwrap();
    }
    assert!(display.display_mesh().is_none());
    assert_eq!(exact.posed_mesh(), display.posed_mesh());
    assert_eq!(exact.rest_mesh(), display.rest_mesh());
    refused += both(&mut exact, &mut display, |s| {
        s.rotate_joint(5, DVec3::X, 0.2)
    });
    assert_eq!(exact.posed_mesh(), display.posed_mesh());
    match coords {
        CoordsKind::Mvc => assert_eq!(refused, 0, "MVC refuses none of these events"),
        // Refusals are compared above; most events must have been applied.
        CoordsKind::Green => assert!(refused <= 6, "{refused} events refused"),
    }
}
