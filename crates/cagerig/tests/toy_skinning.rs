//! A skinning method from outside the library, bound as `docs/architecture.md` ("A skinning
//! method", from another crate) says: a `SkinningBackend` passed in
//! `SessionOptions::external_skinning` binds to the rig, and `SkinningMethod::External` selects
//! it. The session's couplings do not depend on it: CageUp fits the ghost LBS of its rows, as
//! for every method but LBS.
//!
//! The toy method is *rigid nearest-bone skinning*: at binding, each rest vertex is given to the
//! bone (parent joint → joint) nearest to it, and M'_v = T_b(v)·M_v with that bone's parent
//! transform — Ω is not read.

#![expect(clippy::unwrap_used)]

use std::sync::Arc;

use cagerig::RigError;
use cagerig::demo;
use cagerig::session::{
    BoundSkinning, CageFitSource, DisplayPrecision, RigParts, RigSession, SessionOptions,
    SkinningBackend, SkinningBindInput,
};
use cagerig::skinning::SkinningMethod;
use glam::{DAffine3, DVec3};

/// Rigid nearest-bone skinning (the backend: it binds per rig).
#[derive(Debug)]
struct RigidBones;

/// Rigid nearest-bone skinning bound to one rig: the joint each vertex follows (`#V`).
#[derive(Debug)]
struct BoundRigidBones {
    joint_of_vertex: Vec<usize>,
}

/// Distance from `p` to the segment `a`–`b`.
fn distance_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.distance(a + t * ab)
}

impl SkinningBackend for RigidBones {
    fn name(&self) -> &str {
        "rigid"
    }

    fn bind(&self, rig: &SkinningBindInput<'_>) -> Result<Arc<dyn BoundSkinning>, String> {
        let joints = rig.skeleton.rest_positions();
        // Bone (p → j) moves with its parent joint p.
        let bones: Vec<(usize, DVec3, DVec3)> = (0..joints.len())
            .filter_map(|j| {
                let p = rig.skeleton.parent(j)?;
                Some((p, joints[p], joints[j]))
            })
            .collect();
        if bones.is_empty() {
            return Err(format!(
                "the skeleton has {} joint(s) and no bone: expected a joint with a parent",
                joints.len()
            ));
        }
        let joint_of_vertex = rig
            .rest_mesh
            .iter()
            .map(|&x| {
                bones
                    .iter()
                    .map(|&(p, a, b)| (p, distance_to_segment(x, a, b)))
                    .min_by(|l, r| l.1.total_cmp(&r.1))
                    .map_or(0, |(p, _)| p)
            })
            .collect();
        Ok(Arc::new(BoundRigidBones { joint_of_vertex }))
    }
}

impl BoundSkinning for BoundRigidBones {
    fn apply(&self, posed_from_rest: &[DAffine3], rest_mesh: &[DVec3], out: &mut [DVec3]) {
        for ((o, &x), &j) in out.iter_mut().zip(rest_mesh).zip(&self.joint_of_vertex) {
            *o = posed_from_rest[j].transform_point3(x);
        }
    }
}

/// A method that binds no rig.
#[derive(Debug)]
struct Refusing;

impl SkinningBackend for Refusing {
    fn name(&self) -> &str {
        "refusing"
    }

    fn bind(&self, _rig: &SkinningBindInput<'_>) -> Result<Arc<dyn BoundSkinning>, String> {
        Err("expected nothing it can bind".into())
    }
}

/// The built-in bar bound with `options`.
fn bar(options: SessionOptions) -> Result<RigSession, RigError> {
    let rig = demo::builtin("bar", None).unwrap();
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    RigSession::new(parts, options).map(|(session, _)| session)
}

/// The bar under rigid skinning from the start.
fn rigid_bar() -> RigSession {
    bar(SessionOptions {
        skinning: SkinningMethod::External,
        external_skinning: Some(Arc::new(RigidBones)),
        ..SessionOptions::default()
    })
    .unwrap()
}

/// The bounding-box diagonal of M.
fn diagonal(session: &RigSession) -> f64 {
    let points = session.rest_mesh();
    let lo = points.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = points.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    (hi - lo).length()
}

/// M' of the toy, computed here from the session's M and T (bound to the rig as it is now).
fn rigid_posed_mesh(session: &RigSession) -> Vec<DVec3> {
    let bound = RigidBones
        .bind(&SkinningBindInput {
            rest_mesh: session.rest_mesh(),
            triangles: session.mesh_triangles(),
            skeleton: session.skeleton(),
            skin_weights: session.skin_weights(),
        })
        .unwrap();
    let mut out = vec![DVec3::ZERO; session.rest_mesh().len()];
    bound.apply(session.posed_from_rest(), session.rest_mesh(), &mut out);
    out
}

fn worst_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}

#[test]
fn rigid_skinning_binds_poses_and_keeps_the_couplings_exact() {
    let mut session = rigid_bar();
    let mut lbs = bar(SessionOptions::default()).unwrap();
    assert_eq!(session.skinning(), SkinningMethod::External);
    let diagonal = diagonal(&session);
    for s in [&mut session, &mut lbs] {
        s.rotate_joint(1, DVec3::Z, 40f64.to_radians()).unwrap();
    }
    // M' is the toy's, not LBS's; C' is the fit of the ghost LBS, the LBS rig's to the bit.
    assert_eq!(session.posed_mesh(), &rigid_posed_mesh(&session)[..]);
    assert!(
        worst_distance(session.posed_mesh(), lbs.posed_mesh()) > 1e-3 * diagonal,
        "rigid skinning differs from LBS where the weights blend"
    );
    assert_eq!(session.posed_cage(), lbs.posed_cage());

    // Grab the current cage: the grabbed vertex lands, the others stay.
    let before = session.posed_cage().to_vec();
    let offset = DVec3::new(0.0, 0.05, 0.02) * diagonal;
    session.move_posed_cage(&[3], &[offset]).unwrap();
    for (k, (now, was)) in session.posed_cage().iter().zip(&before).enumerate() {
        let expected = if k == 3 { *was + offset } else { *was };
        assert!(
            now.distance(expected) <= 1e-9 * diagonal,
            "C'[{k}] {now} against {expected}"
        );
    }
    // CageRev moved the rest cage; the rest skin is its map M = ΦC, and M' the toy's of it.
    let mut phi_c = vec![DVec3::ZERO; session.rest_mesh().len()];
    session.cage_coords().apply(session.rest_cage(), &mut phi_c);
    let worst = worst_distance(&phi_c, session.rest_mesh());
    assert!(worst <= 1e-9 * diagonal, "M = ΦC to {worst:e}");
    assert_ne!(session.rest_cage(), session.original_rest_cage());
    let mut expected = vec![DVec3::ZERO; phi_c.len()];
    let at_binding = rigid_bar();
    let bound = RigidBones
        .bind(&SkinningBindInput {
            rest_mesh: at_binding.rest_mesh(),
            triangles: at_binding.mesh_triangles(),
            skeleton: at_binding.skeleton(),
            skin_weights: at_binding.skin_weights(),
        })
        .unwrap();
    bound.apply(
        session.posed_from_rest(),
        session.rest_mesh(),
        &mut expected,
    );
    assert_eq!(
        session.posed_mesh(),
        &expected[..],
        "bound once, applied to M"
    );
}

#[test]
fn a_session_switches_away_from_the_external_method_and_back() {
    let mut session = rigid_bar();
    session
        .rotate_joint(1, DVec3::Z, 30f64.to_radians())
        .unwrap();
    let (posed_mesh, posed_cage) = (session.posed_mesh().to_vec(), session.posed_cage().to_vec());
    session.set_skinning(SkinningMethod::Dqs).unwrap();
    assert_ne!(session.posed_mesh(), &posed_mesh[..]);
    session.set_skinning(SkinningMethod::External).unwrap();
    assert_eq!(session.posed_mesh(), &posed_mesh[..]);
    assert_eq!(session.posed_cage(), &posed_cage[..]);
    // A rebind keeps the method: the backend binds the new rig.
    let (rebound, _) = session.rebound(cagerig::CoordsKind::Green).unwrap();
    assert_eq!(rebound.skinning(), SkinningMethod::External);
}

#[test]
fn the_display_path_draws_the_external_method_rounded() {
    let mut session = rigid_bar();
    session
        .rotate_joint(1, DVec3::Z, 30f64.to_radians())
        .unwrap();
    let offset = DVec3::new(0.0, 0.1, 0.0);
    let mut exact = session.clone();
    session
        .set_display_precision(DisplayPrecision::F32)
        .unwrap();
    for s in [&mut session, &mut exact] {
        s.set_fit_source(CageFitSource::DisplayedMesh);
        s.move_posed_cage(&[3], &[offset]).unwrap();
    }
    // CageUp read the toy's exact rows on both paths.
    assert_eq!(session.posed_cage(), exact.posed_cage());
    assert_eq!(session.posed_mesh(), exact.posed_mesh());
    let drawn = session.display_mesh().unwrap();
    for (d, p) in drawn.iter().zip(exact.posed_mesh()) {
        assert_eq!(*d, p.as_vec3());
    }
}

#[test]
fn a_session_without_an_external_method_refuses_it() {
    let mut session = bar(SessionOptions::default()).unwrap();
    session
        .rotate_joint(1, DVec3::Z, 30f64.to_radians())
        .unwrap();
    let posed_mesh = session.posed_mesh().to_vec();
    assert_eq!(
        session.set_skinning(SkinningMethod::External),
        Err(RigError::NoExternalSkinning)
    );
    assert_eq!(session.skinning(), SkinningMethod::Lbs);
    assert_eq!(session.posed_mesh(), &posed_mesh[..]);
}

#[test]
fn a_method_that_cannot_bind_the_rig_fails_the_binding_with_its_words() {
    let err = bar(SessionOptions {
        external_skinning: Some(Arc::new(Refusing)),
        ..SessionOptions::default()
    })
    .unwrap_err();
    assert_eq!(
        err,
        RigError::ExternalSkinning {
            name: "refusing".into(),
            message: "expected nothing it can bind".into()
        }
    );
}

#[test]
fn a_saved_state_with_the_external_method_reopens_where_the_method_is_passed_in() {
    let mut session = rigid_bar();
    session
        .rotate_joint(1, DVec3::Z, 30f64.to_radians())
        .unwrap();
    session
        .move_posed_cage(&[3], &[DVec3::new(0.0, 0.1, 0.0)])
        .unwrap();
    let text = serde_json::to_string(&session.editable_state()).unwrap();
    assert!(text.contains("\"skinning\":\"external\""), "{text}");
    let state: cagerig::session::EditableState = serde_json::from_str(&text).unwrap();
    assert_eq!(state.skinning, SkinningMethod::External);
    // A session with the method passed in takes the state back (C to the bit; M' and C' to
    // round-off, since the restore re-derives them from the state's C and pose).
    let mut reopened = rigid_bar();
    reopened.restore_editable_state(&state).unwrap();
    assert_eq!(reopened.skinning(), SkinningMethod::External);
    assert_eq!(reopened.rest_cage(), session.rest_cage());
    let size = diagonal(&session);
    for (what, a, b) in [
        ("M'", reopened.posed_mesh(), session.posed_mesh()),
        ("C'", reopened.posed_cage(), session.posed_cage()),
    ] {
        let worst = worst_distance(a, b);
        assert!(worst <= 1e-9 * size, "{what}: {worst}");
    }
    // One without it refuses the state in words and stays as it was.
    let mut plain = bar(SessionOptions::default()).unwrap();
    let before = plain.posed_mesh().to_vec();
    assert_eq!(
        plain.restore_editable_state(&state),
        Err(RigError::NoExternalSkinning)
    );
    assert_eq!(plain.skinning(), SkinningMethod::Lbs);
    assert_eq!(plain.posed_mesh(), &before[..]);
}
