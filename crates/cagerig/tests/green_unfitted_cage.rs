//! Green rigs past the fold limit under `UnfittedCagePolicy::KeepEvent`: the event is kept with
//! the skin and skeletons exact, C' reported unfitted, grabs refused until a pose fits again
//! (`session/unfitted_cage.rs`). On the Arm with Lipman's stretched normal and the fit on the
//! rows alone, the rig that still has such poses.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;

use cagerig::coords::stretched_normals::FaceTermKind;
use cagerig::mesh::max_distance;
use cagerig::rig_files::load_rig_files;
use cagerig::session::{RigSession, SessionOptions, UnfittedCagePolicy};
use cagerig::skinning::LinearBlendSkinning;
use cagerig::{CageFitKind, CoordsKind, RigError};
use glam::DVec3;

fn arm(coords: CoordsKind, unfitted_cage: UnfittedCagePolicy) -> RigSession {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
    let files = load_rig_files(&dir.join("arm.obj"), None).unwrap();
    // Lipman's stretched normal and the fit on the rows alone: the Green rig that still finds
    // no current cage past a fold (the default rig follows these poses).
    let options = SessionOptions {
        coords,
        unfitted_cage,
        green_face_term: FaceTermKind::Lipman,
        cage_fit: CageFitKind::Paper,
        ..SessionOptions::default()
    };
    RigSession::new(files.parts, options).unwrap().0
}

fn diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = cagerig::mesh::bounding_box(points);
    (hi - lo).length()
}

/// M' skinned from the session's own M and pose, from scratch.
fn skinned_from_scratch(s: &RigSession) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; s.num_vertices()];
    LinearBlendSkinning::new(s.skin_weights()).apply(s.posed_from_rest(), s.rest_mesh(), &mut out);
    out
}

/// The elbow (joint 3) bent in 6° steps, 25 steps (150°): far past the Green fold limit
/// (about 66°, `a_bend_past_the_fold_is_refused_with_a_clear_error_and_nothing_moves`).
const STEPS: usize = 25;

#[test]
fn past_the_fold_the_pose_is_kept_exact_and_the_current_cage_reported_unfitted() {
    let mut refused = arm(CoordsKind::Green, UnfittedCagePolicy::Refuse);
    let mut kept = arm(CoordsKind::Green, UnfittedCagePolicy::KeepEvent);
    let mut mvc = arm(CoordsKind::Mvc, UnfittedCagePolicy::Refuse);
    let tol = 1e-9 * diagonal(kept.rest_mesh());
    let mut refusals = 0;
    let mut first_unfitted = None;
    for step in 0..STEPS {
        let angle = 6f64.to_radians();
        match refused.rotate_joint(3, DVec3::X, angle) {
            Ok(()) => {}
            Err(RigError::GreenFitFailed { .. }) => refusals += 1,
            Err(e) => panic!("{e}"),
        }
        kept.rotate_joint(3, DVec3::X, angle).unwrap();
        mvc.rotate_joint(3, DVec3::X, angle).unwrap();
        if first_unfitted.is_none() && kept.posed_cage_unfitted().is_some() {
            first_unfitted = Some(step);
        }
        // The pose and the skin are the mean value rig's: skinning never reads C'.
        let off = max_distance(kept.posed_mesh(), mvc.posed_mesh());
        assert!(off < tol, "step {step}: M' off the MVC rig's by {off:e}");
        let joints: Vec<DVec3> = kept.posed_joints().collect();
        let mvc_joints: Vec<DVec3> = mvc.posed_joints().collect();
        assert!(max_distance(&joints, &mvc_joints) < tol, "step {step}: S'");
        assert!(kept.posed_cage().iter().all(|p| p.is_finite()));
    }
    let first = first_unfitted.expect("the bend reaches the fold limit");
    eprintln!(
        "unfitted from {}° on; the default policy refused {refusals} of {STEPS} steps",
        6 * (first + 1)
    );
    assert!(first >= 10, "unfitted already at step {first}");
    assert!(refusals > 0, "the default policy refuses past the fold");
    assert!(refused.posed_cage_unfitted().is_none());
    let unfitted = kept.posed_cage_unfitted().expect("150° is past the fold");
    assert!(unfitted.residual > unfitted.limit, "{unfitted:?}");

    // A grab of the unfitted C' is refused, and nothing moves.
    let before = (kept.rest_cage().to_vec(), kept.posed_cage().to_vec());
    let error = kept
        .move_posed_cage(&[7], &[DVec3::new(0.0, 1.0, 0.0)])
        .unwrap_err();
    assert!(matches!(error, RigError::PosedCageUnfitted(_)), "{error:?}");
    let message = error.to_string();
    assert!(
        message.contains("cannot be grabbed") && message.contains("mean value coordinates"),
        "{message}"
    );
    assert_eq!(
        before,
        (kept.rest_cage().to_vec(), kept.posed_cage().to_vec())
    );
}

#[test]
fn rest_cage_edits_in_an_unfitted_pose_move_the_skin_as_at_rest() {
    let mut kept = arm(CoordsKind::Green, UnfittedCagePolicy::KeepEvent);
    let mut at_rest = arm(CoordsKind::Green, UnfittedCagePolicy::Refuse);
    let tol = 1e-9 * diagonal(kept.rest_mesh());
    for _ in 0..STEPS {
        kept.rotate_joint(3, DVec3::X, 6f64.to_radians()).unwrap();
    }
    assert!(kept.posed_cage_unfitted().is_some());
    // Inflate: the rest-cage vertices of the upper half pushed out from the cage's centre.
    let cage = kept.rest_cage().to_vec();
    let centre = cage.iter().copied().sum::<DVec3>() / cage.len() as f64;
    let vertices: Vec<usize> = (0..cage.len()).filter(|&k| cage[k].y > centre.y).collect();
    let offsets: Vec<DVec3> = vertices
        .iter()
        .map(|&k| 0.05 * (cage[k] - centre))
        .collect();
    kept.move_rest_cage(&vertices, &offsets).unwrap();
    at_rest.move_rest_cage(&vertices, &offsets).unwrap();
    // The rest skin and skeleton are those of the same edit at the rest pose (Green map, SkelUp).
    let off = max_distance(kept.rest_mesh(), at_rest.rest_mesh());
    assert!(off < tol, "M off by {off:e}");
    assert!(off > 0.0 || kept.rest_mesh() == at_rest.rest_mesh());
    let moved = max_distance(
        kept.rest_mesh(),
        arm(CoordsKind::Green, UnfittedCagePolicy::Refuse).rest_mesh(),
    );
    assert!(
        moved > 1e-3 * diagonal(kept.rest_mesh()),
        "the edit moved M by {moved:e}"
    );
    let joints: Vec<DVec3> = kept.rest_joints().collect();
    let rest_joints: Vec<DVec3> = at_rest.rest_joints().collect();
    assert!(max_distance(&joints, &rest_joints) < tol, "S");
    // And the current skin is that M skinned by the pose.
    let off = max_distance(kept.posed_mesh(), &skinned_from_scratch(&kept));
    assert!(off < tol, "M' off by {off:e}");
}

#[test]
fn back_in_a_pose_the_cage_follows_it_is_fitted_and_grabs_land_again() {
    let mut kept = arm(CoordsKind::Green, UnfittedCagePolicy::KeepEvent);
    let tol = 1e-9 * diagonal(kept.rest_mesh());
    for _ in 0..STEPS {
        kept.rotate_joint(3, DVec3::X, 6f64.to_radians()).unwrap();
    }
    assert!(kept.posed_cage_unfitted().is_some());
    // Straighten back in the same steps: the fit comes back before the rest pose.
    let mut fitted_at = None;
    for step in 0..STEPS {
        kept.rotate_joint(3, DVec3::X, -6f64.to_radians()).unwrap();
        if kept.posed_cage_unfitted().is_none() {
            fitted_at = Some(step);
            break;
        }
    }
    let fitted_at = fitted_at.expect("never fitted again on the way back");
    let fitted_degrees = 6 * (STEPS - fitted_at - 1);
    eprintln!("fitted again at {fitted_degrees}°");
    // Where it was last fitted on the way out: the streak's retry from the last fitted cage
    // finds it (its direct solve alone, from the folded closest cage, only at the rest pose).
    assert!(
        fitted_degrees >= 60,
        "fitted again only at {fitted_degrees}°"
    );
    let before = kept.posed_cage().to_vec();
    let offset = DVec3::new(0.0, 0.5, 0.0);
    kept.move_posed_cage(&[7], &[offset]).unwrap();
    for (k, (after, b)) in kept.posed_cage().iter().zip(&before).enumerate() {
        let expect = if k == 7 { *b + offset } else { *b };
        assert!(after.distance(expect) < tol, "cage vertex {k}");
    }
    // The rest pose always fits.
    let mut kept = arm(CoordsKind::Green, UnfittedCagePolicy::KeepEvent);
    for _ in 0..STEPS {
        kept.rotate_joint(3, DVec3::X, 6f64.to_radians()).unwrap();
    }
    kept.reset_pose();
    assert!(kept.posed_cage_unfitted().is_none());
    assert!(max_distance(kept.posed_cage(), kept.rest_cage()) < tol);
}

#[test]
fn policy_names_parse_and_print() {
    for policy in UnfittedCagePolicy::ALL {
        assert_eq!(policy.name().parse::<UnfittedCagePolicy>().unwrap(), policy);
        assert_eq!(policy.to_string(), policy.name());
    }
    let error = "sometimes".parse::<UnfittedCagePolicy>().unwrap_err();
    assert_eq!(
        error.to_string(),
        "unknown unfitted-cage policy \"sometimes\": expected refuse or keep"
    );
    assert_eq!(UnfittedCagePolicy::default(), UnfittedCagePolicy::Refuse);
}

#[test]
fn an_unfitted_state_restores_exactly_with_its_policy() {
    let mut kept = arm(CoordsKind::Green, UnfittedCagePolicy::KeepEvent);
    kept.rotate_joint(3, DVec3::X, 120f64.to_radians()).unwrap();
    assert!(kept.posed_cage_unfitted().is_some());
    let state = kept.editable_state();
    assert_eq!(state.unfitted_cage, UnfittedCagePolicy::KeepEvent);
    assert_eq!(state.posed_cage.as_deref(), Some(kept.posed_cage()));
    // A session with the default policy takes the state's (an undo, a session file).
    let mut fresh = arm(CoordsKind::Green, UnfittedCagePolicy::Refuse);
    fresh.restore_editable_state(&state).unwrap();
    assert_eq!(fresh.unfitted_cage_policy(), UnfittedCagePolicy::KeepEvent);
    assert!(fresh.posed_cage_unfitted().is_some());
    assert_eq!(fresh.editable_state(), state);
    let tol = 1e-12 * diagonal(kept.rest_mesh());
    assert!(max_distance(fresh.posed_mesh(), kept.posed_mesh()) < tol);
    // Back to the rest state, with its policy.
    let rest = arm(CoordsKind::Green, UnfittedCagePolicy::Refuse).editable_state();
    fresh.restore_editable_state(&rest).unwrap();
    assert_eq!(fresh.unfitted_cage_policy(), UnfittedCagePolicy::Refuse);
    assert!(fresh.posed_cage_unfitted().is_none());
    // Under it, the unfitted state is refused: nothing changes.
    let mut strict = state.clone();
    strict.unfitted_cage = UnfittedCagePolicy::Refuse;
    let error = fresh.restore_editable_state(&strict).unwrap_err();
    assert!(
        matches!(error, RigError::GreenFitFailed { .. }),
        "{error:?}"
    );
    assert_eq!(fresh.editable_state(), rest);
}
