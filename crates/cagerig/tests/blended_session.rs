//! The blended LBS/DQS method in a session: its blend weights at the boundary, its limits
//! (b ≡ 0 is LBS and b ≡ 1 is DQS, bit for bit, through every event), CageUp's ghost fit (C' is
//! the LBS cage whatever b is), and the paths that rebuild a rig (rebind, new skeleton).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::demo;
use cagerig::mesh::max_distance;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skinning::{DqBlendWeights, SkinningMethod};
use cagerig::{CoordsKind, RigError};
use glam::DVec3;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

fn parts(blend: Option<DqBlendWeights>) -> RigParts {
    let rig = demo::builtin("bar", None).unwrap();
    RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage).with_dq_blend_weights(blend)
}

fn session(blend: Option<DqBlendWeights>) -> RigSession {
    RigSession::new(parts(blend), SessionOptions::default())
        .unwrap()
        .0
}

fn num_vertices() -> usize {
    demo::builtin("bar", None).unwrap().mesh.num_vertices()
}

/// A pose, a rest-cage edit, a grab and another pose.
fn events(s: &mut RigSession) {
    s.rotate_joint(1, DVec3::Z, 0.8).unwrap();
    s.move_rest_cage(&[0, 1], &[DVec3::new(0.0, 0.3, 0.1)])
        .unwrap();
    s.move_posed_cage(&[3, 5], &[DVec3::new(0.2, -0.1, 0.3)])
        .unwrap();
    s.rotate_joint(2, DVec3::Y, -0.6).unwrap();
}

#[test]
fn a_rig_without_blend_weights_refuses_blended_and_stays_as_it_was() {
    let mut s = session(None);
    s.rotate_joint(1, DVec3::Z, 0.5).unwrap();
    let before = s.posed_mesh().to_vec();
    let err = s.set_skinning(SkinningMethod::Blended).unwrap_err();
    assert_eq!(err, RigError::NoDqBlendWeights);
    assert!(err.to_string().contains("DQ blend weights"), "{err}");
    assert_eq!(s.skinning(), SkinningMethod::Lbs);
    assert_eq!(s.posed_mesh(), &before[..]);
    // Asked for at construction: the same error.
    let options = SessionOptions {
        skinning: SkinningMethod::Blended,
        ..SessionOptions::default()
    };
    assert_eq!(
        RigSession::new(parts(None), options).unwrap_err(),
        RigError::NoDqBlendWeights
    );
}

#[test]
fn blend_weights_of_the_wrong_length_are_refused() {
    let n = num_vertices();
    let err = RigSession::new(
        parts(Some(DqBlendWeights::uniform(n - 1, 0.5).unwrap())),
        SessionOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        err,
        RigError::SizeMismatch {
            what: "DQ blend weights (one per mesh vertex)",
            expected: n,
            actual: n - 1,
        }
    );
}

#[test]
fn zero_is_lbs_and_one_is_dqs_bit_for_bit_through_events() {
    let n = num_vertices();
    for (b, method) in [(0.0, SkinningMethod::Lbs), (1.0, SkinningMethod::Dqs)] {
        let mut blended = session(Some(DqBlendWeights::uniform(n, b).unwrap()));
        blended.set_skinning(SkinningMethod::Blended).unwrap();
        let mut reference = session(None);
        reference.set_skinning(method).unwrap();
        for s in [&mut blended, &mut reference] {
            events(s);
        }
        assert_eq!(blended.posed_mesh(), reference.posed_mesh(), "b = {b}");
        assert_eq!(blended.posed_cage(), reference.posed_cage(), "b = {b}");
        assert_eq!(blended.rest_cage(), reference.rest_cage(), "b = {b}");
    }
}

#[test]
fn ghost_fit_gives_the_lbs_cage_and_the_blend_lies_between_lbs_and_dqs() {
    let blend = support::spread_blend_weights(num_vertices());
    let mut s = session(Some(blend.clone()));
    s.set_skinning(SkinningMethod::Blended).unwrap();
    events(&mut s);
    let blended_mesh = s.posed_mesh().to_vec();
    let blended_cage = s.posed_cage().to_vec();
    s.set_skinning(SkinningMethod::Lbs).unwrap();
    let lbs = s.posed_mesh().to_vec();
    // CageUp fits the ghost LBS under the blend: C' is the LBS cage.
    assert!(max_distance(&blended_cage, s.posed_cage()) < 1e-12);
    s.set_skinning(SkinningMethod::Dqs).unwrap();
    let dqs = s.posed_mesh().to_vec();
    for (v, &b) in blend.values().iter().enumerate() {
        let expected = lbs[v] * (1.0 - b) + dqs[v] * b;
        assert!(
            blended_mesh[v].distance(expected) < 1e-12,
            "vertex {v}: {} vs {expected}",
            blended_mesh[v]
        );
    }
    // The blend matters on this pose: it is neither the LBS nor the DQS mesh.
    assert!(max_distance(&blended_mesh, &lbs) > 1e-3);
    assert!(max_distance(&blended_mesh, &dqs) > 1e-3);
}

#[test]
fn rebinding_and_a_new_skeleton_keep_the_blend_weights() {
    let blend = support::spread_blend_weights(num_vertices());
    let mut s = session(Some(blend.clone()));
    s.set_skinning(SkinningMethod::Blended).unwrap();
    events(&mut s);
    let (rebound, _) = s.rebound(CoordsKind::Mvc).unwrap();
    assert_eq!(rebound.skinning(), SkinningMethod::Blended);
    assert_eq!(rebound.dq_blend_weights(), Some(&blend));
    let parts = s.parts_with_skeleton(s.skeleton().clone(), s.skin_weights().clone());
    assert_eq!(parts.dq_blend_weights.as_ref(), Some(&blend));
    let (rebound, _) = RigSession::new(parts, s.rebinding_options()).unwrap();
    assert_eq!(rebound.skinning(), SkinningMethod::Blended);
}
