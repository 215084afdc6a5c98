//! The regularised CageUp (the default `CageFitKind`) on the paper's Arm and the built-in rigs:
//! the paper's guarantees hold (a grab lands exactly and nothing else moves, the loop
//! C' → C → S → S' → C' is a fixed point, the skin is the paper fit's bit for bit), and the
//! current cage stays near the body where the paper's fit leaves it.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::PathBuf;

use cagerig::CageFitKind;
use cagerig::cage_quality::{CageQualityProbe, joint_bends};
use cagerig::mesh::max_distance;
use cagerig::rig_files::load_rig_files;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use glam::DVec3;

/// The paper's Arm as its files give it.
fn arm_parts() -> RigParts {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
    load_rig_files(&dir.join("arm.obj"), None).unwrap().parts
}

fn arm(cage_fit: CageFitKind) -> RigSession {
    let options = SessionOptions {
        cage_fit,
        ..SessionOptions::default()
    };
    RigSession::new(arm_parts(), options).unwrap().0
}

fn builtin(name: &str, cage_fit: CageFitKind) -> RigSession {
    let rig = cagerig::demo::builtin(name, None).unwrap();
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    let options = SessionOptions {
        cage_fit,
        ..SessionOptions::default()
    };
    RigSession::new(parts, options).unwrap().0
}

fn diagonal(s: &RigSession) -> f64 {
    let (lo, hi) = cagerig::mesh::bounding_box(s.rest_mesh());
    (hi - lo).length()
}

/// C' of the state (C, S') recomputed from scratch: the loop's fixed point.
fn refitted_posed_cage(s: &RigSession) -> Vec<DVec3> {
    let mut fresh = s.clone();
    let state = fresh.editable_state();
    fresh.restore_editable_state(&state).unwrap();
    fresh.posed_cage().to_vec()
}

#[test]
fn the_default_is_regularised_and_the_rest_pose_keeps_the_rest_cage() {
    let s = arm(CageFitKind::default());
    assert_eq!(s.cage_fit(), CageFitKind::Regularised);
    let tol = 1e-12 * diagonal(&s);
    assert!(max_distance(s.posed_cage(), s.rest_cage()) < tol);
}

#[test]
fn grabs_land_exactly_and_nothing_else_moves_under_every_method() {
    for method in [
        SkinningMethod::Lbs,
        SkinningMethod::Dqs,
        SkinningMethod::Cor,
    ] {
        let mut s = arm(CageFitKind::Regularised);
        s.set_skinning(method).unwrap();
        let elbow = s.skeleton().find("lowerarm01.R").unwrap();
        s.rotate_joint(elbow, DVec3::X, 60f64.to_radians()).unwrap();
        s.rotate_joint(1, DVec3::Z, 0.3).unwrap();
        let tol = 1e-9 * diagonal(&s);
        for (vertices, offset) in [
            (vec![10usize], DVec3::new(0.3, -0.2, 0.5)),
            (vec![3, 40, 50], DVec3::new(-0.4, 0.1, 0.2)),
        ] {
            let before = s.posed_cage().to_vec();
            s.move_posed_cage(&vertices, &[offset]).unwrap();
            for (k, (now, was)) in s.posed_cage().iter().zip(&before).enumerate() {
                let expected = if vertices.contains(&k) {
                    *was + offset
                } else {
                    *was
                };
                assert!(
                    now.distance(expected) < tol,
                    "{method:?}: C' vertex {k} is {:.3e} from its target",
                    now.distance(expected)
                );
            }
            // The loop: C' is what CageUp fits for the new (C, S').
            let refit = refitted_posed_cage(&s);
            assert!(max_distance(&refit, s.posed_cage()) < tol, "{method:?}");
        }
    }
}

#[test]
fn the_skin_is_the_paper_fits_bit_for_bit_and_only_the_handle_differs() {
    let mut paper = arm(CageFitKind::Paper);
    let mut regularised = arm(CageFitKind::Regularised);
    for s in [&mut paper, &mut regularised] {
        s.rotate_joint(3, DVec3::X, 1.0).unwrap();
        s.rotate_joint(8, DVec3::Y, -0.7).unwrap();
        s.move_rest_cage(&[5, 6], &[DVec3::new(0.2, 0.1, 0.0)])
            .unwrap();
    }
    assert_eq!(paper.posed_mesh(), regularised.posed_mesh());
    assert_eq!(paper.rest_mesh(), regularised.rest_mesh());
    assert_ne!(paper.posed_cage(), regularised.posed_cage());
}

#[test]
fn switching_the_fit_refits_the_handle_and_an_undo_restores_it() {
    let mut s = arm(CageFitKind::Regularised);
    s.rotate_joint(3, DVec3::X, 1.0).unwrap();
    let regularised_state = s.editable_state();
    let regularised_cage = s.posed_cage().to_vec();
    s.set_cage_fit(CageFitKind::Paper).unwrap();
    assert_eq!(s.cage_fit(), CageFitKind::Paper);
    let paper = {
        let mut p = arm(CageFitKind::Paper);
        p.rotate_joint(3, DVec3::X, 1.0).unwrap();
        p
    };
    let tol = 1e-12 * diagonal(&s);
    assert!(max_distance(s.posed_cage(), paper.posed_cage()) < tol);
    // A grab under the switched fit lands exactly too.
    s.move_posed_cage(&[12], &[DVec3::new(0.0, 0.5, 0.0)])
        .unwrap();
    // Undo: the saved state names its fit.
    s.restore_editable_state(&regularised_state).unwrap();
    assert_eq!(s.cage_fit(), CageFitKind::Regularised);
    assert!(max_distance(s.posed_cage(), &regularised_cage) < tol);
}

/// The elbow bent in steps of 15° to 135° on the Arm, and the bar and the snake bent at their
/// middle joint: the regularised handle stays near the body (spread ≤ 1.5, deviation ≤ 0.06 of
/// the diagonal, no triangle turned over) and never strays further than the paper's.
#[test]
fn the_handle_follows_large_bends() {
    for name in ["arm", "bar", "snake"] {
        let rig = |fit| match name {
            "arm" => arm(fit),
            _ => builtin(name, fit),
        };
        let (mut regularised, mut paper) = (rig(CageFitKind::Regularised), rig(CageFitKind::Paper));
        let probe = CageQualityProbe::of_session(&regularised).unwrap();
        let joint = match name {
            "arm" => regularised.skeleton().find("lowerarm01.R").unwrap(),
            _ => regularised.skeleton().len() / 2,
        };
        for step in 1..=9 {
            let mut quality = Vec::new();
            for s in [&mut regularised, &mut paper] {
                s.rotate_joint(joint, DVec3::X, 15f64.to_radians()).unwrap();
                quality.push(probe.measure_session(s));
            }
            let (r, p) = (quality[0], quality[1]);
            let at = format!("{name} at {}°: {r} (paper: {p})", 15 * step);
            assert!(r.spread <= 1.5 && r.deviation <= 0.06, "{at}");
            assert_eq!(r.flipped, 0.0, "{at}");
            assert!(
                r.spread <= p.spread.max(1.05) && r.deviation <= p.deviation + 1e-9,
                "{at}"
            );
        }
    }
}

/// Every joint of the Arm bent by 45° about x, y and z from rest: the regularised handle is
/// no further from the body than the paper's (deviation; spread within 5 % of rest), close to it everywhere
/// (spread ≤ 1.5, deviation ≤ 0.06 of the diagonal), and flips fewer cage triangles at worst.
/// On the hand, whose coarse cage spans several fingers, a few triangles still turn against
/// the rigid reference (3.6 % at worst, the paper's fit 15 %).
#[test]
fn the_arms_joint_bends_keep_the_handle_on_the_body() {
    let mut regularised = arm(CageFitKind::Regularised);
    let mut paper = arm(CageFitKind::Paper);
    let r = joint_bends(&mut regularised, 45f64.to_radians()).unwrap();
    let p = joint_bends(&mut paper, 45f64.to_radians()).unwrap();
    let (mut worst_r, mut worst_p) = (0.0f64, 0.0f64);
    for (r, p) in r.iter().zip(&p) {
        let (name, r, p) = (&r.name, r.quality.unwrap(), p.quality.unwrap());
        assert!(r.spread <= 1.5 && r.deviation <= 0.06, "{name}: {r}");
        assert!(
            r.spread <= p.spread.max(1.05) && r.deviation <= p.deviation + 1e-9,
            "{name}: {r} against the paper's {p}"
        );
        worst_r = worst_r.max(r.flipped);
        worst_p = worst_p.max(p.flipped);
    }
    assert!(
        worst_r < 0.5 * worst_p,
        "flipped {worst_r} against the paper's {worst_p}"
    );
}

/// The Arm with its generated 58-vertex cage (the skeleton layout, as `cagerig cage --vertices
/// 58`): every joint turned about x, y and z to 15°, 30°, 45°, 60° and 90°, each angle from rest
/// and as a continuation of the previous one. The handle stays near the body (spread ≤ 1.5) for
/// every joint and angle: beyond 45° the metacarpals carry a finger out of the palm that the
/// coarse cage wraps in one part with its neighbours, and the reach limit keeps the cage vertex
/// the finger's rows pull on within reach of its skin (2.68 without it). A grab after each
/// joint's sweep lands exactly and leaves the other cage vertices still.
#[test]
fn the_arms_single_joint_sweep_keeps_a_generated_handle_on_the_body() {
    use cagerig::cage_gen::{CageOptions, CageRig, CageTarget, generate_rig_cage};
    let mut parts = arm_parts();
    let options = CageOptions {
        target: CageTarget::Vertices(58),
        ..CageOptions::default()
    };
    let rig = CageRig {
        skeleton: &parts.skeleton,
        weights: Some(&parts.skin_weights),
    };
    parts.cage = generate_rig_cage(&parts.mesh, &options, Some(rig))
        .unwrap()
        .cage;
    let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    let probe = CageQualityProbe::of_session(&s).unwrap();
    let tol = 1e-9 * diagonal(&s);
    let angles = [15.0f64, 30.0, 45.0, 60.0, 90.0];
    // The worst spread up to 45° and beyond.
    let mut worst = [(0.0f64, String::new()), (0.0f64, String::new())];
    let mut note = |s: &RigSession, angle: f64, what: String| {
        let spread = probe.measure_session(s).spread;
        let slot = &mut worst[usize::from(angle > 45.0)];
        if spread > slot.0 {
            *slot = (spread, what);
        }
    };
    for joint in 0..s.skeleton().len() {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            for angle in angles {
                s.reset_pose();
                s.rotate_joint(joint, axis, angle.to_radians()).unwrap();
                note(
                    &s,
                    angle,
                    format!("joint {joint} about {axis} to {angle}° from rest"),
                );
            }
            s.reset_pose();
            let mut at = 0.0;
            for angle in angles {
                s.rotate_joint(joint, axis, (angle - at).to_radians())
                    .unwrap();
                at = angle;
                note(
                    &s,
                    angle,
                    format!("joint {joint} about {axis} to {angle}° in steps"),
                );
            }
        }
        let vertex = joint % s.rest_cage().len();
        let target = s.posed_cage()[vertex] + DVec3::new(0.0, 0.4, -0.2);
        let others = s.posed_cage().to_vec();
        s.move_posed_cage(&[vertex], &[DVec3::new(0.0, 0.4, -0.2)])
            .unwrap();
        assert!(
            s.posed_cage()[vertex].distance(target) < tol,
            "joint {joint}"
        );
        for (k, (now, before)) in s.posed_cage().iter().zip(&others).enumerate() {
            if k != vertex {
                assert!(
                    now.distance(*before) < tol,
                    "joint {joint}: vertex {k} moved"
                );
            }
        }
        s.reset_pose();
    }
    let [(up_to_45, at), (beyond, beyond_at)] = worst;
    println!("worst spread up to 45°: {up_to_45:.3} ({at}); beyond: {beyond:.3} ({beyond_at})");
    assert!(up_to_45 <= 1.5, "spread {up_to_45:.3}: {at}");
    assert!(beyond <= 1.5, "spread {beyond:.3}: {beyond_at}");
}

/// The bar (2 segments: a mirror-symmetric skin and cage) bent about z, bound once with its own
/// Φ and once with every entry of Φ moved by a few units of round-off (what another SIMD tier's
/// M = ΦC gives): the two agree to round-off, before and after a grab, and the prior P is
/// mirror-symmetric in z. Before, a neighbourhood of the prior cut through a tie of equal
/// distances and a cage vertex exactly at the rest reach was kept or dropped by the last bits:
/// C' moved by 0.1 (the bar is 2.6 wide) from one CPU to another. (C' itself is not symmetric:
/// the MaxVol rows it fits are not.)
#[test]
fn a_symmetric_rigs_prior_is_symmetric_and_its_handle_does_not_hang_on_the_last_bits() {
    let rig = cagerig::demo::builtin("bar", Some(2)).unwrap();
    let bind = |relative: f64| {
        let mut parts = RigParts::new(
            rig.mesh.clone(),
            rig.skeleton.clone(),
            rig.skin_weights.clone(),
            rig.cage.clone(),
        );
        let phi =
            cagerig::coords::mvc::compute_cage_coords(&parts.cage, &parts.mesh.positions, None)
                .unwrap();
        let mut matrix = phi.matrix().clone();
        let mut state = 0x5eed_u64;
        for j in 0..matrix.ncols() {
            for i in 0..matrix.nrows() {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let unit = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                matrix[(i, j)] *= 1.0 + relative * unit;
            }
        }
        parts.cage_coords = Some(cagerig::cage_coords::CageCoords::from_matrix(matrix).unwrap());
        let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
        s.rotate_joint(1, DVec3::Z, 0.5).unwrap();
        let bent = s.posed_cage().to_vec();
        let carried = s.cage_updater().prior().unwrap().carried_cage().to_vec();
        s.move_posed_cage(&[3], &[DVec3::new(0.0, 0.2, 0.0)])
            .unwrap();
        (bent, carried, s.rest_cage().to_vec())
    };
    let (bent, carried, grabbed) = bind(0.0);
    let (bent_other, _, grabbed_other) = bind(4e-16);
    let tol = 1e-9 * diagonal(&builtin("bar", CageFitKind::default()));
    assert!(
        max_distance(&bent, &bent_other) < tol,
        "{}",
        max_distance(&bent, &bent_other)
    );
    assert!(max_distance(&grabbed, &grabbed_other) < tol);
    let cage = &rig.cage.positions;
    for (k, c) in cage.iter().enumerate() {
        let mirror = cage
            .iter()
            .position(|m| (*m - DVec3::new(c.x, c.y, -c.z)).length() < 1e-12)
            .unwrap();
        let image = carried[mirror] * DVec3::new(1.0, 1.0, -1.0);
        assert!(
            (carried[k] - image).length() < tol,
            "the prior at cage vertex {k} and at its mirror {mirror}"
        );
    }
}

/// On a skin larger than 16,384 vertices the prior's neighbourhoods are the measure's (both
/// searched over the whole skin): the Arm subdivided twice (33k vertices) through the bench's
/// synthetic animation turns no cage triangle against the measure's reference. When the prior
/// searched a regular subsample of 16,384 vertices, its fold guard kept triangles facing its own
/// wider patches, and 0.9–1.8 % of them turned over at these frames (deviation up to 0.054).
#[test]
fn a_large_skins_handle_keeps_its_triangles_against_the_measures_reference() {
    let arm = arm_parts();
    let sub = cagerig::subdivide::subdivide_midpoint(&arm.mesh, &arm.skin_weights, 2).unwrap();
    assert!(sub.mesh.num_vertices() > 16_384);
    let parts = RigParts::new(sub.mesh, arm.skeleton, sub.skin_weights, arm.cage);
    let (mut s, _) = RigSession::new(parts, SessionOptions::default()).unwrap();
    let (skeleton_track, cage_track) =
        cagerig::demo::bench_tracks::synthetic_tracks(s.skeleton(), s.rest_cage()).unwrap();
    let mut player =
        cagerig::playback::AnimationPlayer::new(&s, Some(skeleton_track), Some(cage_track))
            .unwrap();
    let probe = CageQualityProbe::of_session(&s).unwrap();
    for t in [6.0, 6.5, 7.0, 8.5, 9.0, 9.5] {
        player.apply(t, &mut s).unwrap();
        let q = probe.measure_session(&s);
        assert_eq!(q.flipped, 0.0, "t = {t}: {q}");
        assert!(q.deviation <= 0.035 && q.spread <= 1.15, "t = {t}: {q}");
    }
}
