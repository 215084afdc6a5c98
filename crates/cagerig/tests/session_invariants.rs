//! Invariants of the coupled rig on built-in rigs under interleaved events:
//! identity pose gives the rest mesh, the loop C' → C → S → S' → C' is exact under LBS (and with
//! the ghost fit for DQS/CoR/blended), M = ΦC and A = ΨC hold after any number of events (no
//! drift). Every rig carries random DQ blend weights, so the blended method runs everywhere.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::cage_coords::CoordsPrecision;
use cagerig::demo;
use cagerig::mesh::max_distance;
use cagerig::session::{CageFitSource, RigParts, RigSession, SessionOptions};
use cagerig::skinning::{DqBlendWeights, SkinningMethod};
use cagerig::sync::cage_reverser::ReverserMethod;
use glam::DVec3;

fn session(name: &str) -> RigSession {
    session_with(name, SessionOptions::default())
}

fn session_with(name: &str, options: SessionOptions) -> RigSession {
    let rig = demo::builtin(name, None).unwrap();
    let blend = random_blend_weights(rig.mesh.num_vertices(), 11);
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage)
        .with_dq_blend_weights(Some(blend));
    RigSession::new(parts, options).unwrap().0
}

/// Random DQ blend weights (`#V`): uniform in [0, 1], with every fifth vertex at 0 or 1.
fn random_blend_weights(num_vertices: usize, seed: u64) -> DqBlendWeights {
    let mut rng = Lcg(seed);
    let values = (0..num_vertices)
        .map(|v| match v % 10 {
            0 => 0.0,
            5 => 1.0,
            _ => rng.next(),
        })
        .collect();
    DqBlendWeights::new(values).unwrap()
}

/// Scale of the rig, for relative tolerances.
fn scale(s: &RigSession) -> f64 {
    let (lo, hi) = cagerig::mesh::bounding_box(s.rest_cage());
    (hi - lo).length()
}

fn check_consensus(s: &RigSession, tol: f64) {
    let mut m = vec![DVec3::ZERO; s.rest_mesh().len()];
    s.cage_coords().apply(s.rest_cage(), &mut m);
    assert!(max_distance(&m, s.rest_mesh()) < tol, "M != ΦC");
    let mut a = vec![DVec3::ZERO; s.skeleton().len()];
    s.skeleton_updater()
        .apply(s.rest_cage(), s.rest_cage_terms(), &mut a);
    let rest: Vec<DVec3> = s.rest_joints().collect();
    assert!(max_distance(&a, &rest) < tol, "A != ΨC");
}

/// Deterministic pseudo-random numbers (no extra dependency).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
    fn index(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
    fn vec(&mut self, r: f64) -> DVec3 {
        DVec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * 2.0 * r
    }
}

#[test]
fn identity_pose_gives_rest_structures() {
    for name in ["bar", "bar_irregular", "snake"] {
        let s = session(name);
        let tol = 1e-12 * scale(&s);
        assert!(max_distance(s.posed_mesh(), s.rest_mesh()) < tol, "{name}");
        assert!(
            max_distance(s.posed_cage(), s.rest_cage()) < 1e3 * tol,
            "{name}"
        );
        let rest: Vec<DVec3> = s.skeleton().rest_positions();
        let psi: Vec<DVec3> = s.rest_joints().collect();
        assert!(
            max_distance(&rest, &psi) < 1e-9 * scale(&s),
            "{name}: ΨC != rest joints"
        );
    }
}

fn grab_lands_exactly(s: &mut RigSession, vertices: &[usize], offset: DVec3, tol: f64) {
    let before = s.posed_cage().to_vec();
    s.move_posed_cage(vertices, &[offset]).unwrap();
    for (k, (after, b)) in s.posed_cage().iter().zip(&before).enumerate() {
        let expect = if vertices.contains(&k) {
            *b + offset
        } else {
            *b
        };
        assert!(
            after.distance(expect) < tol,
            "cage vertex {k}: {after} vs {expect} ({})",
            after.distance(expect)
        );
    }
}

#[test]
fn loop_is_exact_under_lbs_and_ghost_fit() {
    for method in SkinningMethod::ALL {
        let mut s = session("bar");
        s.set_skinning(method).unwrap();
        assert_eq!(s.fit_source(), CageFitSource::GhostLbs);
        let tol = 1e-9 * scale(&s).max(1.0);
        s.rotate_joint(1, DVec3::Z, 0.8).unwrap();
        grab_lands_exactly(&mut s, &[3, 5], DVec3::new(0.3, -0.2, 0.4), tol);
        s.move_rest_cage(&[0, 1], &[DVec3::new(0.0, 0.5, 0.0)])
            .unwrap();
        s.rotate_joint(2, DVec3::Y, -0.5).unwrap();
        grab_lands_exactly(&mut s, &[7], DVec3::new(-0.5, 0.1, 0.2), tol);
        grab_lands_exactly(&mut s, &[2, 7, 9], DVec3::new(0.1, 0.1, -0.3), tol);
        check_consensus(&s, tol);
    }
}

#[test]
fn thousand_interleaved_events_keep_consensus_and_do_not_drift() {
    interleaved_events_keep_consensus(session("bar_irregular"), 1000);
}

#[test]
fn f32_coordinates_keep_every_invariant() {
    let options = SessionOptions {
        cage_coords_precision: CoordsPrecision::F32,
        ..SessionOptions::default()
    };
    let s = session_with("bar_irregular", options.clone());
    assert_eq!(s.cage_coords().precision(), CoordsPrecision::F32);
    let sc = scale(&s);
    // The rest mesh became ΦC of the rounded Φ: within f32 rounding of the f64 rig's.
    let exact = session("bar_irregular");
    let moved = max_distance(s.rest_mesh(), exact.rest_mesh());
    assert!(
        moved > 0.0 && moved < 1e-6 * sc,
        "rest mesh moved by {moved}"
    );
    assert!(max_distance(s.posed_mesh(), s.rest_mesh()) < 1e-12 * sc);
    check_consensus(&s, 1e-12 * sc);
    interleaved_events_keep_consensus(s, 300);
    // CoR centres (Λ rounded too) and the exact loop with the ghost fit.
    let mut s = session_with("bar", options);
    s.set_skinning(SkinningMethod::Cor).unwrap();
    let tol = 1e-9 * scale(&s);
    s.rotate_joint(1, DVec3::Z, 0.8).unwrap();
    grab_lands_exactly(&mut s, &[3, 5], DVec3::new(0.3, -0.2, 0.4), tol);
    check_consensus(&s, tol);
}

/// Random rotations, rest-cage drags, grabs (checked to land) and skinning switches; M = ΦC and
/// A = ΨC checked every 50 events and at the end, then C' = C after a pose reset.
fn interleaved_events_keep_consensus(mut s: RigSession, events: usize) {
    let mut rng = Lcg(7);
    let nc = s.rest_cage().len();
    let nj = s.skeleton().len();
    let sc = scale(&s);
    let tol = 1e-9 * sc;
    for event in 0..events {
        match rng.index(5) {
            0 | 1 => {
                let axis = rng.vec(1.0) + DVec3::splat(1e-3);
                s.rotate_joint(rng.index(nj), axis, (rng.next() - 0.5) * 0.4)
                    .unwrap();
            }
            2 => {
                let v = [rng.index(nc), rng.index(nc)];
                s.move_rest_cage(&v, &[rng.vec(0.02 * sc)]).unwrap();
            }
            3 => {
                let v = [rng.index(nc)];
                grab_lands_exactly(&mut s, &v, rng.vec(0.02 * sc), tol);
            }
            _ => {
                let m = SkinningMethod::ALL[rng.index(SkinningMethod::ALL.len())];
                s.set_skinning(m).unwrap();
            }
        }
        if event % 50 == 0 {
            check_consensus(&s, tol);
        }
    }
    check_consensus(&s, tol);
    // Back at rest pose, C' fits M = ΦC again: C' = C up to round-off.
    s.reset_pose();
    assert!(max_distance(s.posed_cage(), s.rest_cage()) < tol);
}

#[test]
fn bad_edits_are_errors_not_panics() {
    let mut s = session("bar");
    assert!(s.rotate_joint(99, DVec3::X, 1.0).is_err());
    assert!(s.rotate_joint(0, DVec3::ZERO, 1.0).is_err());
    assert!(s.rotate_joint(0, DVec3::X, f64::NAN).is_err());
    assert!(s.move_rest_cage(&[999], &[DVec3::X]).is_err());
    assert!(
        s.move_posed_cage(&[0, 1], &[DVec3::X, DVec3::Y, DVec3::Z])
            .is_err()
    );
    assert!(
        s.move_posed_cage(&[0], &[DVec3::new(f64::INFINITY, 0.0, 0.0)])
            .is_err()
    );
    // State unchanged by rejected edits.
    assert!(max_distance(s.posed_mesh(), s.rest_mesh()) < 1e-12);
}

#[test]
fn low_rank_and_dense_reverse_deformers_agree() {
    // The low-rank factorisation is the paper's square fit's (the regularised fit is dense).
    let paper = || SessionOptions {
        cage_fit: cagerig::CageFitKind::Paper,
        ..SessionOptions::default()
    };
    for name in ["bar", "snake"] {
        let mut fast = session_with(name, paper());
        let mut dense = session_with(name, paper());
        dense.set_reverser_method(ReverserMethod::Dense);
        let nj = fast.skeleton().len();
        for s in [&mut fast, &mut dense] {
            // One rotated joint (rank-3 update), then several (rank 3·#active).
            s.rotate_joint(nj / 2, DVec3::Z, 0.7).unwrap();
            s.move_posed_cage(&[3], &[DVec3::new(0.2, 0.3, -0.1)])
                .unwrap();
            s.rotate_joint(1, DVec3::new(1.0, 1.0, 0.0), -0.4).unwrap();
            s.rotate_joint(nj - 1, DVec3::Y, 0.3).unwrap();
            s.move_posed_cage(&[1, 6], &[DVec3::new(-0.1, 0.05, 0.2)])
                .unwrap();
        }
        assert!(fast.reverser_is_low_rank(), "{name}");
        assert!(!dense.reverser_is_low_rank(), "{name}");
        let tol = 1e-10 * scale(&fast);
        assert!(
            max_distance(fast.rest_cage(), dense.rest_cage()) < tol,
            "{name}"
        );
        assert!(
            max_distance(fast.posed_cage(), dense.posed_cage()) < tol,
            "{name}"
        );
    }
}

#[test]
fn cached_keyframe_playback_equals_full_recompute() {
    use cagerig::animation::{CageTrack, SkeletonTrack};
    use cagerig::playback::AnimationPlayer;
    use glam::{DAffine3, DQuat};
    let base = session("snake");
    let nc = base.rest_cage().len();
    let skeleton = base.skeleton().clone();
    let mut locals = vec![DAffine3::IDENTITY; skeleton.len()];
    skeleton.locals_from_worlds(&skeleton.rest_world_from_joint(), &mut locals);
    let keys: Vec<Vec<DAffine3>> = (0..3)
        .map(|k| {
            locals
                .iter()
                .map(|l| *l * DAffine3::from_quat(DQuat::from_rotation_z(0.1 * k as f64)))
                .collect()
        })
        .collect();
    let offsets: Vec<Vec<DVec3>> = (0..2)
        .map(|k| {
            (0..nc)
                .map(|c| DVec3::new(0.0, 0.02 * (c % 3) as f64, 0.01) * k as f64)
                .collect()
        })
        .collect();
    let skel = SkeletonTrack::new(vec![0.0, 1.0, 2.0], keys).unwrap();
    let cage = CageTrack::new(vec![0.0, 1.5], offsets).unwrap();
    let mut player = AnimationPlayer::new(&base, Some(skel.clone()), Some(cage.clone())).unwrap();
    let mut cached = base.clone();
    let mut full = base;
    let mut sampled_offsets = vec![DVec3::ZERO; nc];
    let mut sampled_locals = locals.clone();
    for t in [0.3, 0.75, 1.2, 1.9, 2.5] {
        player.apply(t, &mut cached).unwrap();
        cage.sample(t, &mut sampled_offsets);
        skel.sample(t, &mut sampled_locals);
        let rotations: Vec<DQuat> = sampled_locals
            .iter()
            .map(|l| DQuat::from_mat3(&l.matrix3))
            .collect();
        let motion: Vec<DVec3> = sampled_locals
            .iter()
            .zip(skeleton.joints())
            .map(|(l, j)| match j.parent {
                None => l.translation - j.rest_world_from_joint.translation,
                Some(_) => DVec3::ZERO,
            })
            .collect();
        full.set_animation_sample(Some(&sampled_offsets), &rotations, &motion)
            .unwrap();
        let tol = 1e-10 * scale(&full);
        assert!(
            max_distance(cached.rest_mesh(), full.rest_mesh()) < tol,
            "t = {t}"
        );
        assert!(
            max_distance(cached.posed_mesh(), full.posed_mesh()) < tol,
            "t = {t}"
        );
        assert!(
            max_distance(cached.posed_cage(), full.posed_cage()) < tol,
            "t = {t}"
        );
    }
}

#[test]
fn cor_centres_catch_up_after_cage_edits_under_other_methods() {
    let mut always_cor = session("bar");
    always_cor.set_skinning(SkinningMethod::Cor).unwrap();
    let mut switched = session("bar");
    switched.set_skinning(SkinningMethod::Cor).unwrap();
    switched.set_skinning(SkinningMethod::Lbs).unwrap();
    for s in [&mut always_cor, &mut switched] {
        s.rotate_joint(1, DVec3::Z, 0.6).unwrap();
        s.move_rest_cage(&[0, 4], &[DVec3::new(0.2, -0.3, 0.1)])
            .unwrap();
        s.move_posed_cage(&[7], &[DVec3::new(0.0, 0.2, 0.3)])
            .unwrap();
    }
    switched.set_skinning(SkinningMethod::Cor).unwrap();
    let tol = 1e-10 * scale(&switched);
    let (a, b) = (
        always_cor.cor_centres().unwrap(),
        switched.cor_centres().unwrap(),
    );
    assert!(max_distance(a, b) < tol);
    assert!(max_distance(always_cor.posed_mesh(), switched.posed_mesh()) < tol);
}
