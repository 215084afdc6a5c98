//! How far a viewer's LBS of an exported rig is from cagerig's own DQS / CoR M' (glTF skins
//! with LBS only; the export carries the rig and the pose, see the README's Export bullet).
//!
//! The session is posed (Fox: its Walk and Run animations at a few times; Arm: the elbow bent,
//! and bent and twisted), exported with `session_to_gltf`, and the file is evaluated by the
//! independent glTF skinning of `common::reference_skinning` (node TRS, IBM, LBS). The
//! distance to the session's M' under DQS and CoR is measured as max and RMS over the
//! vertices, divided by the bounding-box diagonal of the rest mesh, and checked against the
//! bounds the README states (`GAP_BOUNDS`). Under LBS the same path gives ≤ 1e-5 (control).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use std::path::PathBuf;

use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig_formats::gltf::export::{session_to_gltf, write_glb};
use cagerig_formats::{ImportOptions, import_character};
use common::data;
use glam::DVec3;

/// The README's statement: (rig, method, largest max distance, largest RMS), fractions of the
/// bounding-box diagonal, over the poses below.
const GAP_BOUNDS: [(&str, SkinningMethod, f64, f64); 4] = [
    ("fox", SkinningMethod::Dqs, 3.1e-2, 4.6e-3),
    ("fox", SkinningMethod::Cor, 1.8e-2, 3.4e-3),
    ("arm", SkinningMethod::Dqs, 2.6e-2, 4.1e-3),
    ("arm", SkinningMethod::Cor, 2.7e-2, 4.1e-3),
];

/// Fox animation times, as fractions of each animation's duration.
const FOX_PHASES: [f64; 3] = [0.25, 0.5, 0.75];

fn temp_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cagerig-dqs-cor-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// (max, RMS) distance between what a viewer shows for the exported session and the
/// session's own M', as fractions of the rest bounding-box diagonal.
fn viewer_gap(session: &RigSession, file_name: &str) -> (f64, f64) {
    let (doc, bin) = session_to_gltf(session, "character").unwrap();
    let mut bytes = Vec::new();
    write_glb(&mut bytes, &doc, &bin).unwrap();
    let path = temp_file(file_name);
    std::fs::write(&path, bytes).unwrap();
    let viewer = common::reference_skinning(&path, None, 0.0);
    let _ = std::fs::remove_file(&path);
    let (lo, hi) = cagerig::mesh::bounding_box(session.rest_mesh());
    let diag = (hi - lo).length();
    let posed = session.posed_mesh();
    assert_eq!(viewer.len(), posed.len());
    let squares: Vec<f64> = viewer
        .iter()
        .zip(posed)
        .map(|(a, b)| a.distance_squared(*b))
        .collect();
    let max = squares.iter().copied().fold(0.0f64, f64::max).sqrt();
    let rms = (squares.iter().sum::<f64>() / squares.len() as f64).sqrt();
    (max / diag, rms / diag)
}

/// The Fox at every (animation, phase) pose under `method`: the gap at each pose.
fn fox_gaps(method: SkinningMethod) -> Vec<(String, f64, f64)> {
    let c = import_character(&data("fox/Fox.glb"), &ImportOptions::default()).unwrap();
    let cage = cagerig::io::obj::read_obj(&data("fox/Fox_cage.obj")).unwrap();
    let animations = c.animations.clone();
    let parts = RigParts::new(c.mesh, c.skeleton, c.skin_weights, cage);
    let options = SessionOptions {
        skinning: method,
        ..SessionOptions::default()
    };
    let mut s = RigSession::new(parts, options).unwrap().0;
    let mut gaps = Vec::new();
    for name in ["Walk", "Run"] {
        let animation = animations.iter().find(|a| a.name == name).unwrap();
        let mut player = AnimationPlayer::with_channels(
            &s,
            Some(animation.track.clone()),
            None,
            PoseChannels::Full,
        )
        .unwrap();
        for phase in FOX_PHASES {
            let t = phase * animation.duration;
            player.apply(t, &mut s).unwrap();
            let (max, rms) = viewer_gap(&s, &format!("fox_{name}_{method:?}_{phase}.glb"));
            gaps.push((format!("{name} t={t:.3}"), max, rms));
        }
    }
    gaps
}

/// The Arm bent at the elbow (90°), and bent and twisted (forearm 60° about its bone).
fn arm_gaps(method: SkinningMethod) -> Vec<(String, f64, f64)> {
    let files = cagerig::rig_files::load_rig_files(&data("arm/arm.obj"), None).unwrap();
    let options = SessionOptions {
        skinning: method,
        ..SessionOptions::default()
    };
    let mut s = RigSession::new(files.parts, options).unwrap().0;
    let elbow = s.skeleton().find("lowerarm01.R").unwrap();
    let forearm = s.skeleton().find("lowerarm02.R").unwrap();
    let wrist = s.skeleton().find("wrist.R").unwrap();
    let mut gaps = Vec::new();
    s.rotate_joint(elbow, DVec3::X, 90f64.to_radians()).unwrap();
    let (max, rms) = viewer_gap(&s, &format!("arm_bent_{method:?}.glb"));
    gaps.push(("elbow 90°".to_string(), max, rms));
    let joints: Vec<DVec3> = s.posed_joints().collect();
    let bone = (joints[wrist] - joints[forearm]).normalize();
    s.rotate_joint(forearm, bone, 60f64.to_radians()).unwrap();
    let (max, rms) = viewer_gap(&s, &format!("arm_twisted_{method:?}.glb"));
    gaps.push(("elbow 90° + twist 60°".to_string(), max, rms));
    gaps
}

fn gaps_of(rig: &str, method: SkinningMethod) -> Vec<(String, f64, f64)> {
    match rig {
        "fox" => fox_gaps(method),
        _ => arm_gaps(method),
    }
}

#[test]
fn viewer_lbs_of_the_export_is_within_the_stated_distance_of_dqs_and_cor() {
    for (rig, method, max_bound, rms_bound) in GAP_BOUNDS {
        let gaps = gaps_of(rig, method);
        for (pose, max, rms) in &gaps {
            eprintln!("{rig} {method:?} {pose}: max {max:.3e}, RMS {rms:.3e} of the diagonal");
        }
        let worst_max = gaps.iter().map(|g| g.1).fold(0.0f64, f64::max);
        let worst_rms = gaps.iter().map(|g| g.2).fold(0.0f64, f64::max);
        assert!(
            worst_max <= max_bound && worst_rms <= rms_bound,
            "{rig} {method:?}: max {worst_max:e} (README: ≤ {max_bound:e}), RMS {worst_rms:e} \
             (README: ≤ {rms_bound:e}) of the diagonal"
        );
        // The gap is real (DQS/CoR differ from LBS at these poses): the statement is not vacuous.
        assert!(
            worst_max > 1e-4,
            "{rig} {method:?}: gap {worst_max:e}: no longer differs from LBS"
        );
    }
}

/// Control: under LBS a viewer shows cagerig's M' at the same poses (f32 rounding only).
#[test]
fn viewer_lbs_of_the_export_matches_cagerig_lbs_at_the_same_poses() {
    for rig in ["fox", "arm"] {
        for (pose, max, _) in gaps_of(rig, SkinningMethod::Lbs) {
            assert!(max <= 1e-5, "{rig} LBS {pose}: {max:e} of the diagonal");
        }
    }
}

/// The one-state bake (`export_character_baked`, Python's `Rig.export_gltf(..., bake=True)`):
/// the same posed Arm under DQS, CoR and the blended method, exported with the bake, shows
/// cagerig's M' in the viewer — its default morph weight is 1, nothing is played — to 1e-5 of
/// the diagonal, where the plain export is the gap above; and cagerig reads the file back with
/// the baked target left out (the rest skin is the plain export's).
#[test]
fn a_baked_state_shows_cagerigs_skin_in_the_viewer() {
    let files = cagerig::rig_files::load_rig_files(&data("arm/arm.obj"), None).unwrap();
    let nv = files.parts.mesh.num_vertices();
    let blend =
        cagerig::skinning::DqBlendWeights::new((0..nv).map(|v| (v % 5) as f64 / 4.0).collect())
            .unwrap();
    for method in [
        SkinningMethod::Dqs,
        SkinningMethod::Cor,
        SkinningMethod::Blended,
    ] {
        let options = SessionOptions {
            skinning: method,
            ..SessionOptions::default()
        };
        let parts = files
            .parts
            .clone()
            .with_dq_blend_weights(Some(blend.clone()));
        let mut s = RigSession::new(parts, options).unwrap().0;
        let elbow = s.skeleton().find("lowerarm01.R").unwrap();
        s.rotate_joint(elbow, DVec3::X, 90f64.to_radians()).unwrap();
        s.move_rest_cage(&[0, 2, 4], &[DVec3::new(0.5, -0.2, 0.3)])
            .unwrap();
        let path = temp_file(&format!("arm_baked_{method:?}.glb"));
        let report = cagerig_formats::export_character_baked(&s, &path, "arm").unwrap();
        let viewer = common::reference_skinning(&path, None, 0.0);
        let (lo, hi) = cagerig::mesh::bounding_box(s.rest_mesh());
        let diag = (hi - lo).length();
        let off = cagerig::mesh::max_distance(&viewer, s.posed_mesh()) / diag;
        eprintln!(
            "{method:?}: baked {off:.2e} of the diagonal (the correction reached {:.2e})",
            report.largest_correction / diag
        );
        assert!(off <= 1e-5, "{method:?}: {off:e}");
        assert!(report.largest_correction / diag > 1e-4, "{report:?}");
        let again = import_character(&path, &ImportOptions::default()).unwrap();
        let rest_off = cagerig::mesh::max_distance(&again.mesh.positions, s.rest_mesh()) / diag;
        assert!(
            rest_off <= 1e-6,
            "{method:?}: rest skin read back {rest_off:e} off"
        );
        let _ = std::fs::remove_file(&path);
    }
}
