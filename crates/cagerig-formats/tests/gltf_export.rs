//! Export → Khronos validator (when installed: .ci/run puts it in .ci/gltf-validator) →
//! reimport round trip: the reimported rest mesh, rest joints and the pose stored in the nodes
//! give cagerig's own M and M' to ≤ 1e-5 of the bounding-box diagonal (the file is f32).

#![expect(clippy::unwrap_used, clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use std::path::{Path, PathBuf};

use cagerig::TriMesh;
use cagerig::animation::SkeletonTrack;
use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig_formats::gltf::export::{session_to_gltf, write_glb};
use cagerig_formats::{ImportOptions, import_character};
use common::data;
use glam::DVec3;
use proptest::prelude::*;

fn temp_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cagerig-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write(session: &RigSession, path: &Path) {
    let (doc, bin) = session_to_gltf(session, "character").unwrap();
    let mut bytes = Vec::new();
    write_glb(&mut bytes, &doc, &bin).unwrap();
    std::fs::write(path, bytes).unwrap();
}

/// Validator summary, or None when the validator is not installed.
fn validate(path: &Path) -> Option<serde_json::Value> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::var_os("GLTF_VALIDATOR_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".ci/gltf-validator"));
    if !dir.join("node_modules/gltf-validator").is_dir() {
        eprintln!(
            "gltf-validator not installed in {}: validation skipped",
            dir.display()
        );
        return None;
    }
    let out = std::process::Command::new("node")
        .arg(root.join("tools/gltf-validate.js"))
        .arg(path)
        .env("GLTF_VALIDATOR_DIR", &dir)
        .output()
        .expect("running node");
    assert!(
        out.status.success(),
        "validator failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

/// Reimports `path` and checks M, the rest joints and M' under the file's node pose.
fn check_round_trip(session: &RigSession, path: &Path) -> f64 {
    let c = import_character(path, &ImportOptions::default()).unwrap();
    let (lo, hi) = cagerig::mesh::bounding_box(session.rest_mesh());
    let diag = (hi - lo).length();
    let rest_err = cagerig::mesh::max_distance(&c.mesh.positions, session.rest_mesh()) / diag;
    let joints: Vec<DVec3> = session.rest_joints().collect();
    let joint_err = cagerig::mesh::max_distance(&c.skeleton.rest_positions(), &joints) / diag;
    let cage = TriMesh::new(
        session.rest_cage().to_vec(),
        session.cage_triangles().to_vec(),
    )
    .unwrap();
    let parts = RigParts::new(
        c.mesh.clone(),
        c.skeleton.clone(),
        c.skin_weights.clone(),
        cage,
    );
    let mut again = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    let track = SkeletonTrack::new(vec![0.0], vec![c.node_pose.clone()]).unwrap();
    let mut player =
        AnimationPlayer::with_channels(&again, Some(track), None, PoseChannels::Full).unwrap();
    player.apply(0.0, &mut again).unwrap();
    let posed_err = cagerig::mesh::max_distance(again.posed_mesh(), session.posed_mesh()) / diag;
    assert!(
        rest_err <= 1e-5 && joint_err <= 1e-5 && posed_err <= 1e-5,
        "rest {rest_err:e}, joints {joint_err:e}, posed {posed_err:e}"
    );
    rest_err.max(joint_err).max(posed_err)
}

#[test]
fn edited_fox_exports_validates_and_round_trips() {
    let c = import_character(&data("fox/Fox.glb"), &ImportOptions::default()).unwrap();
    let cage = cagerig::io::obj::read_obj(&data("fox/Fox_cage.obj")).unwrap();
    let parts = RigParts::new(c.mesh, c.skeleton, c.skin_weights, cage);
    let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    let neck = s.skeleton().find("b_Neck_04").unwrap();
    s.rotate_joint(neck, DVec3::X, 0.5).unwrap();
    s.move_rest_cage(&[0, 1, 2], &[DVec3::new(0.0, 5.0, 0.0)])
        .unwrap();
    s.move_posed_cage(&[10], &[DVec3::new(0.0, 0.0, 4.0)])
        .unwrap();
    let path = temp_file("fox_edited.glb");
    write(&s, &path);
    if let Some(report) = validate(&path) {
        assert_eq!(report["errors"], 0, "{report}");
        assert_eq!(report["warnings"], 0, "{report}");
    }
    let err = check_round_trip(&s, &path);
    eprintln!("fox round trip: {err:e} of the diagonal");
}

/// The same character as glTF text: `.gltf` (JSON naming its buffer) + `.bin` beside it,
/// valid, and reimported to the same structures as the binary file.
#[test]
fn text_gltf_export_writes_json_and_bin_that_validate_and_round_trip() {
    let rig = cagerig::demo::builtin("bar", None).unwrap();
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    s.rotate_joint(1, DVec3::Z, 0.6).unwrap();
    s.move_rest_cage(&[2], &[DVec3::new(0.0, 0.2, 0.0)])
        .unwrap();
    let path = temp_file("bar_text.gltf");
    cagerig_formats::gltf::export::export_glb(&s, &path, "bar").unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let uri = json["buffers"][0]["uri"].as_str().unwrap().to_owned();
    assert!(
        uri.starts_with("bar_text-") && uri.ends_with(".bin") && uri.len() == 29,
        "{uri}"
    );
    let bin = path.with_file_name(&uri);
    assert!(bin.is_file());
    // Exporting a changed state replaces the buffer file: the earlier one is removed, and the
    // .gltf refers to the new one.
    let rig = cagerig::demo::builtin("bar", None).unwrap();
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    let mut changed = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    changed.rotate_joint(1, DVec3::Z, 0.1).unwrap();
    cagerig_formats::gltf::export::export_glb(&changed, &path, "bar").unwrap();
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let new_uri = again["buffers"][0]["uri"].as_str().unwrap().to_owned();
    assert_ne!(new_uri, uri);
    assert!(!bin.exists() && path.with_file_name(&new_uri).is_file());
    cagerig_formats::gltf::export::export_glb(&s, &path, "bar").unwrap();
    assert_eq!(
        json["buffers"][0]["byteLength"].as_u64().unwrap(),
        std::fs::metadata(&bin).unwrap().len()
    );
    if let Some(report) = validate(&path) {
        assert_eq!(report["errors"], 0, "{report}");
        assert_eq!(report["warnings"], 0, "{report}");
    }
    check_round_trip(&s, &path);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]
    #[test]
    fn random_edits_of_the_bar_round_trip(
        joint in 0usize..3,
        angle in -1.5f64..1.5,
        axis in prop::array::uniform3(-1.0f64..1.0),
        cage_vertex in 0usize..8,
        offset in prop::array::uniform3(-0.3f64..0.3),
    ) {
        let rig = cagerig::demo::builtin("bar", None).unwrap();
        let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
        let joint = joint % s.skeleton().len();
        let axis = DVec3::from(axis);
        prop_assume!(axis.length() > 0.1);
        s.rotate_joint(joint, axis, angle).unwrap();
        let v = cage_vertex % s.rest_cage().len();
        s.move_rest_cage(&[v], &[DVec3::from(offset)]).unwrap();
        let path = temp_file(&format!("bar_{joint}_{v}_{}.glb", angle.to_bits()));
        write(&s, &path);
        check_round_trip(&s, &path);
        let _ = std::fs::remove_file(&path);
    }
}

#[test]
fn hybrid_animation_exports_with_cage_keys_as_morph_targets() {
    use cagerig::animation::CageTrack;
    use cagerig_formats::gltf::export_animation::{animation_to_gltf, sample_times};
    let c = import_character(&data("fox/Fox.glb"), &ImportOptions::default()).unwrap();
    let walk = c.find_animation("Walk").unwrap().track.clone();
    let cage = cagerig::io::obj::read_obj(&data("fox/Fox_cage.obj")).unwrap();
    let nc = cage.num_vertices();
    let parts = RigParts::new(c.mesh, c.skeleton, c.skin_weights, cage);
    let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    let key = |k: usize| -> Vec<DVec3> {
        (0..nc)
            .map(|i| DVec3::new(0.0, ((i * 7 + k * 3) % 5) as f64 * 0.8, (k as f64) * 1.5))
            .collect()
    };
    let cage_track = CageTrack::new(
        vec![0.0, 0.3, 0.7],
        vec![vec![DVec3::ZERO; nc], key(1), key(2)],
    )
    .unwrap();
    let mut player = AnimationPlayer::with_channels(
        &s,
        Some(walk.clone()),
        Some(cage_track.clone()),
        PoseChannels::Full,
    )
    .unwrap();
    let keys: Vec<f64> = walk
        .times()
        .iter()
        .chain(cage_track.times())
        .copied()
        .collect();
    let times = sample_times(player.duration(), 30.0, &keys);
    let (doc, bin, _) = animation_to_gltf(
        &mut s,
        &mut player,
        Some(&cage_track),
        &times,
        "arm",
        "walk",
        false,
    )
    .unwrap();
    let path = temp_file("fox_hybrid.glb");
    let mut bytes = Vec::new();
    write_glb(&mut bytes, &doc, &bin).unwrap();
    std::fs::write(&path, bytes).unwrap();
    if let Some(report) = validate(&path) {
        assert_eq!(report["errors"], 0, "{report}");
        assert_eq!(report["warnings"], 0, "{report}");
    }
    let (lo, hi) = cagerig::mesh::bounding_box(s.rest_mesh());
    let diag = (hi - lo).length();
    let mut worst: f64 = 0.0;
    for &t in times.iter().step_by(3).chain([0.3, 0.7].iter()) {
        player.apply(t, &mut s).unwrap();
        let viewer = common::reference_skinning(&path, Some(0), t);
        let err = cagerig::mesh::max_distance(&viewer, s.posed_mesh()) / diag;
        worst = worst.max(err);
        assert!(
            err <= 1e-5,
            "t = {t}: the file shows {err:e} of the diagonal away from cagerig"
        );
    }
    eprintln!("hybrid animation export: worst {worst:e} of the diagonal at the sample times");
}
