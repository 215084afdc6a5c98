//! Conformance with the paper tool's outputs on the Arm (`data/arm/reference`, see its
//! README.txt): the scripted scenario s0 (load), s2 (skeleton edit), s3 (rest-cage edit),
//! s4 (current-cage grab), the DQS/CoR variants of step ii and the animation samples, all with
//! the shipped Φ and MaxVol files and renormalised weights.
//!
//! Known defects of the reference that these tests allow for (and check that we do not share):
//! its joint 2 ("upperarm02.R") is 0.41 off Ψ·C = rest position; its animation root motion
//! depends on the previously played sample.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::{Path, PathBuf};

use cagerig::mesh::max_distance;
use cagerig::playback::AnimationPlayer;
use cagerig::rig_files::load_rig_files;
use cagerig::session::{CageFitSource, GivenCageCoords, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig::sync::skeleton_updater::JointLocalisation;
use glam::DVec3;

fn arm_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm")
}

fn reference(name: &str) -> PathBuf {
    arm_dir().join("reference").join(name)
}

fn obj(name: &str) -> Vec<DVec3> {
    cagerig::io::read_obj(&reference(name)).unwrap().positions
}

/// `index name father x y z` lines.
fn joints(name: &str) -> Vec<DVec3> {
    std::fs::read_to_string(reference(name))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            // `index name father x y z` or `index x y z`: the position is the last 3 numbers.
            let t: Vec<f64> = l
                .split_whitespace()
                .rev()
                .take(3)
                .map(|x| x.parse().unwrap())
                .collect();
            DVec3::new(t[2], t[1], t[0])
        })
        .collect()
}

fn session(localisation: JointLocalisation) -> RigSession {
    let files = load_rig_files(&arm_dir().join("arm.obj"), None).unwrap();
    assert!(files.parts.cage_coords.is_some() && files.parts.maxvol_rows.is_some());
    // The tool's own Φ (6 decimals), kept even though it reproduces M only to 9.6e-4: the
    // conformance is with the tool's numbers (the default recomputes such a Φ).
    // The paper's CageUp (`--cage-fit paper`): the tool's C' interpolates the MaxVol rows.
    let options = SessionOptions {
        localisation,
        cage_fit: cagerig::CageFitKind::Paper,
        given_cage_coords: GivenCageCoords::Keep,
        ..SessionOptions::default()
    };
    RigSession::new(files.parts, options).unwrap().0
}

const JOINT2: usize = 2;

fn assert_joints_match_except_2(ours: &[DVec3], theirs: &[DVec3], tol: f64, what: &str) {
    assert_eq!(ours.len(), 25);
    for (j, (a, b)) in ours.iter().zip(theirs).enumerate() {
        if j != JOINT2 {
            assert!(
                a.distance(*b) <= tol,
                "{what}: joint {j} off by {}",
                a.distance(*b)
            );
        }
    }
}

fn rotate_step2(s: &mut RigSession) {
    let j = s.skeleton().find("lowerarm01.R").unwrap();
    assert_eq!(j, 3);
    s.rotate_joint(j, DVec3::X, 60f64.to_radians()).unwrap();
}

const STEP3_VERTICES: [usize; 5] = [0, 2, 4, 5, 6];
const STEP3_OFFSET: DVec3 = DVec3::new(2.0, -1.0, 1.5);
const STEP4_VERTICES: [usize; 3] = [20, 23, 25];
const STEP4_OFFSET: DVec3 = DVec3::new(-1.5, 2.0, 0.5);

#[test]
fn scenario_matches_the_reference_tool() {
    let mut s = session(JointLocalisation::reference_tool());
    // s0: loaded state; Ψ·C reproduces every rest joint (the tool's misses joint 2 by 0.41).
    assert!(max_distance(s.rest_mesh(), &obj("s0_M_rest.obj")) == 0.0);
    assert!(max_distance(s.rest_cage(), &obj("s0_C_rest.obj")) == 0.0);
    let rest: Vec<DVec3> = s.rest_joints().collect();
    assert!(max_distance(&rest, &joints("s0_joints_rest.txt")) == 0.0);
    let mut psi_c = vec![DVec3::ZERO; 25];
    s.skeleton_updater()
        .apply(s.rest_cage(), s.rest_cage_terms(), &mut psi_c);
    assert!(
        max_distance(&psi_c, &rest) < 1e-9,
        "Ψ·C must equal the rest joints"
    );
    let tool_psi_c = joints("s0_joints_PsiC.txt");
    assert!(
        tool_psi_c[JOINT2].distance(rest[JOINT2]) > 0.4,
        "the reference's defect"
    );
    assert!(max_distance(s.posed_mesh(), s.rest_mesh()) < 1e-12);

    // s2: skeleton edit.
    rotate_step2(&mut s);
    assert!(max_distance(s.posed_mesh(), &obj("s2_Mdef.obj")) < 1e-6);
    assert!(max_distance(s.posed_cage(), &obj("s2_Cdef.obj")) < 1e-6);
    let posed: Vec<DVec3> = s.posed_joints().collect();
    assert!(max_distance(&posed, &joints("s2_joints_current.txt")) < 1e-6);

    // s3: rest-cage edit. M = ΦC exactly; joints (but 2) as the tool's.
    s.move_rest_cage(&STEP3_VERTICES, &[STEP3_OFFSET]).unwrap();
    assert!(max_distance(s.rest_cage(), &obj("s3_C_rest.obj")) < 1e-12);
    let mut phi_c = vec![DVec3::ZERO; s.rest_mesh().len()];
    s.cage_coords().apply(s.rest_cage(), &mut phi_c);
    assert!(max_distance(&phi_c, s.rest_mesh()) < 1e-9);
    assert!(max_distance(s.rest_mesh(), &obj("s3_M_rest.obj")) < 1e-9);
    let rest: Vec<DVec3> = s.rest_joints().collect();
    assert_joints_match_except_2(&rest, &joints("s3_joints_rest.txt"), 1e-6, "s3 rest");
    let posed: Vec<DVec3> = s.posed_joints().collect();
    assert_joints_match_except_2(&posed, &joints("s3_joints_current.txt"), 1e-6, "s3 current");

    // s4: current-cage grab through CageRev: grabbed land, others do not move.
    let before = s.posed_cage().to_vec();
    s.move_posed_cage(&STEP4_VERTICES, &[STEP4_OFFSET]).unwrap();
    for (k, (after, b)) in s.posed_cage().iter().zip(&before).enumerate() {
        let expect = if STEP4_VERTICES.contains(&k) {
            *b + STEP4_OFFSET
        } else {
            *b
        };
        assert!(after.distance(expect) < 1e-9, "cage vertex {k}");
    }
    assert!(max_distance(s.posed_cage(), &obj("s4_Cdef_grabbed_before_update.obj")) < 1e-9);
    s.cage_coords().apply(s.rest_cage(), &mut phi_c);
    assert!(max_distance(&phi_c, s.rest_mesh()) < 1e-9);
    // Joint 2's Ψ row does not enter Eq. 19 here (its bone and its parents are unrotated), so
    // the rest-cage solution matches the tool's too.
    assert!(max_distance(s.rest_cage(), &obj("s4_C_rest.obj")) < 1e-6);
    let rest: Vec<DVec3> = s.rest_joints().collect();
    assert_joints_match_except_2(&rest, &joints("s4_joints_rest.txt"), 1e-6, "s4 rest");
    let posed: Vec<DVec3> = s.posed_joints().collect();
    assert_joints_match_except_2(&posed, &joints("s4_joints_current.txt"), 1e-6, "s4 current");
}

#[test]
fn default_localisation_keeps_the_loop_exact_on_the_arm() {
    let mut s = session(JointLocalisation::default());
    let rest: Vec<DVec3> = s.rest_joints().collect();
    let mut psi_c = vec![DVec3::ZERO; 25];
    s.skeleton_updater()
        .apply(s.rest_cage(), s.rest_cage_terms(), &mut psi_c);
    assert!(max_distance(&psi_c, &rest) < 1e-9);
    assert!(
        s.skeleton_updater()
            .reports()
            .iter()
            .all(|r| r.method == "max_entropy")
    );
    rotate_step2(&mut s);
    // Step ii does not involve Ψ: identical to the reference whatever the localisation.
    assert!(max_distance(s.posed_mesh(), &obj("s2_Mdef.obj")) < 1e-6);
    s.move_rest_cage(&STEP3_VERTICES, &[STEP3_OFFSET]).unwrap();
    let before = s.posed_cage().to_vec();
    s.move_posed_cage(&STEP4_VERTICES, &[STEP4_OFFSET]).unwrap();
    for (k, (after, b)) in s.posed_cage().iter().zip(&before).enumerate() {
        let expect = if STEP4_VERTICES.contains(&k) {
            *b + STEP4_OFFSET
        } else {
            *b
        };
        assert!(after.distance(expect) < 1e-9, "cage vertex {k}");
    }
}

#[test]
fn dqs_and_cor_step2_match_the_reference() {
    for (method, mesh, cage) in [
        (
            SkinningMethod::Dqs,
            "x_step2_DQS_Mdef.obj",
            "x_step2_DQS_Cdef.obj",
        ),
        (
            SkinningMethod::Cor,
            "x_step2_CoR_Mdef.obj",
            "x_step2_CoR_Cdef.obj",
        ),
        (
            SkinningMethod::Lbs,
            "x_step2_LBS_Mdef.obj",
            "x_step2_LBS_Cdef.obj",
        ),
    ] {
        let mut s = session(JointLocalisation::reference_tool());
        s.set_skinning(method).unwrap();
        // The tool fits C' to the displayed mesh; our default fits an LBS ghost instead.
        s.set_fit_source(CageFitSource::DisplayedMesh);
        rotate_step2(&mut s);
        let m = max_distance(s.posed_mesh(), &obj(&format!("extras/{mesh}")));
        let c = max_distance(s.posed_cage(), &obj(&format!("extras/{cage}")));
        assert!(m < 1e-6 && c < 1e-6, "{method:?}: M' off by {m}, C' by {c}");
        if method != SkinningMethod::Lbs {
            // The ghost fit gives the LBS cage (exact loop) instead.
            s.set_fit_source(CageFitSource::GhostLbs);
            let lbs_cage = obj("extras/x_step2_LBS_Cdef.obj");
            assert!(max_distance(s.posed_cage(), &lbs_cage) < 1e-6);
        }
    }
}

#[test]
fn animation_samples_match_up_to_the_reference_root_motion_defect() {
    let s = session(JointLocalisation::reference_tool());
    let skeleton = s.skeleton().clone();
    let (skel_track, _) = cagerig::io::skeleton_animation::read_skeleton_animation(
        &arm_dir().join("arm_skelAnim.txt"),
        &skeleton,
    )
    .unwrap();
    let cage_track =
        cagerig::io::read_cage_animation(&arm_dir().join("arm_cageAnim.txt"), 58).unwrap();
    let mut player = AnimationPlayer::new(&s, Some(skel_track), Some(cage_track)).unwrap();
    let mut s = s;
    let original_root = skeleton.joint(0).rest_world_from_joint.translation;
    // The tool's root motion is measured from the rest root of the PREVIOUS sample.
    let mut previous_rest_root = original_root;
    for t in ["0.75", "2.25", "4.00"] {
        player.apply(t.parse().unwrap(), &mut s).unwrap();
        let prefix = format!("extras/x_anim_t{t}_");
        assert!(max_distance(s.rest_cage(), &obj(&format!("{prefix}C_rest.obj"))) < 1e-9);
        assert!(max_distance(s.rest_mesh(), &obj(&format!("{prefix}LBS_Mrest.obj"))) < 1e-9);
        let rest: Vec<DVec3> = s.rest_joints().collect();
        assert_joints_match_except_2(&rest, &joints(&format!("{prefix}joints_rest.txt")), 1e-6, t);
        // Ours is history-free; the tool's is shifted by (original − previous) rest root.
        let shift = previous_rest_root - original_root;
        let posed: Vec<DVec3> = s.posed_joints().map(|p| p - shift).collect();
        assert_joints_match_except_2(
            &posed,
            &joints(&format!("{prefix}joints_current.txt")),
            1e-6,
            t,
        );
        let shifted: Vec<DVec3> = s.posed_mesh().iter().map(|p| *p - shift).collect();
        assert!(max_distance(&shifted, &obj(&format!("{prefix}LBS_Mdef.obj"))) < 1e-6);
        previous_rest_root = rest[0];
    }
}
