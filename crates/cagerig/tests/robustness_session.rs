//! Malformed input, library side: events are all-or-nothing, and the constructors apply the one
//! cage validation.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::error::RigError;
use cagerig::session::{MAX_STATE_MAGNITUDE, RigParts, RigSession, SessionOptions};
use glam::{DQuat, DVec3};

fn bar_parts() -> RigParts {
    let rig = cagerig::demo::builtin("bar", Some(8)).unwrap();
    RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage)
}

fn snapshot(s: &RigSession) -> Vec<Vec<DVec3>> {
    vec![
        s.rest_mesh().to_vec(),
        s.posed_mesh().to_vec(),
        s.rest_cage().to_vec(),
        s.posed_cage().to_vec(),
        s.rest_joints().collect(),
        s.posed_joints().collect(),
    ]
}

fn close(a: &[Vec<DVec3>], b: &[Vec<DVec3>], tol: f64) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| x.iter().zip(y).all(|(p, q)| p.distance(*q) <= tol))
}

#[test]
fn an_event_that_would_overflow_is_refused_and_the_rig_stays_as_it_was() {
    let (mut s, _) = RigSession::new(bar_parts(), SessionOptions::default()).unwrap();
    s.rotate_joint(2, DVec3::Z, 0.7).unwrap();
    s.move_rest_cage(&[3], &[DVec3::new(0.0, 0.2, 0.0)])
        .unwrap();
    let before = snapshot(&s);
    // Finite offsets whose sum leaves the bound: refused, nothing moved.
    let huge = DVec3::new(MAX_STATE_MAGNITUDE * 0.75, 0.0, 0.0);
    s.move_rest_cage(&[5], &[huge]).unwrap();
    let after_first = snapshot(&s);
    let e = s.move_rest_cage(&[5], &[huge]).unwrap_err();
    assert!(matches!(e, RigError::EventRefused { .. }), "{e}");
    assert!(e.to_string().contains("rest cage vertex 5"), "{e}");
    assert!(close(
        &snapshot(&s),
        &after_first,
        1e-9 * MAX_STATE_MAGNITUDE
    ));
    // (Moving back by −huge would lose the small offsets to cancellation: start afresh.)
    let (mut s, _) = RigSession::new(bar_parts(), SessionOptions::default()).unwrap();
    s.rotate_joint(2, DVec3::Z, 0.7).unwrap();
    assert!(close(&before[..0], &[], 0.0));
    // A grab of that size is refused too, and a pose with a huge root motion.
    let before = snapshot(&s);
    assert!(s.move_posed_cage(&[1], &[huge * 2.0]).is_err());
    assert!(close(&snapshot(&s), &before, 1e-9));
    let rotations: Vec<DQuat> = vec![DQuat::IDENTITY; s.skeleton().len()];
    let mut motion = vec![DVec3::ZERO; s.skeleton().len()];
    motion[0] = huge * 2.0;
    assert!(s.set_pose(&rotations, &motion).is_err());
    assert!(close(&snapshot(&s), &before, 1e-9));
    for v in snapshot(&s).iter().flatten() {
        assert!(v.is_finite());
    }
}

#[test]
fn constructors_refuse_a_cage_that_does_not_enclose_the_mesh() {
    let mut parts = bar_parts();
    for p in &mut parts.cage.positions {
        *p *= 0.5;
    }
    let e = RigSession::new(parts.clone(), SessionOptions::default()).unwrap_err();
    assert!(matches!(e, RigError::MeshOutsideCage { .. }), "{e}");
    let options = SessionOptions {
        allow_mesh_outside_cage: true,
        ..SessionOptions::default()
    };
    let (_, warnings) = RigSession::new(parts, options).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.to_string().contains("outside the cage"))
    );
    // A mesh without faces.
    let mut faceless = bar_parts();
    faceless.mesh.triangles.clear();
    let e = RigSession::new(faceless, SessionOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no triangle"), "{e}");
}
