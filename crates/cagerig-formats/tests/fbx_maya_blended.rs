//! Maya's "weight blended" skinning (a per-vertex blend of linear and dual-quaternion
//! skinning) against the reference meshes of ufbx's own test suite: `maya_dq_weights` posed at
//! frames 10 and 18 (24 frames/s) of its animation, as ufbx's `test_skin.h` checks it
//! (`ufbxt_check_frame(scene, …, "maya_dq_weights_10", NULL, 10.0/24.0)`).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skinning::SkinningMethod;
use cagerig_formats::{ImportOptions, import_character};
use common::{box_cage, data};
use glam::DAffine3;

const FILE: &str = "fbx/maya_dq_weights_7500_binary.fbx";

/// Max distance to the reference meshes at both frames, over the rest mesh's bounding-box
/// diagonal, with the skin posed by `method` (`None`: the file's method).
fn error_against_references(method: Option<SkinningMethod>) -> f64 {
    let c = import_character(&data(FILE), &ImportOptions::default()).unwrap();
    let world_from_file = DAffine3::from_cols_array(&c.summary.space.world_from_file);
    let (lo, hi) = cagerig::mesh::bounding_box(&c.mesh.positions);
    let diag = (hi - lo).length();
    let parts = RigParts::new(
        c.mesh.clone(),
        c.skeleton.clone(),
        c.skin_weights.clone(),
        box_cage(&c.mesh.positions, 0.05),
    )
    .with_dq_blend_weights(c.dq_blend_weights.clone());
    let options = SessionOptions {
        skinning: method.or(c.skinning).unwrap(),
        ..SessionOptions::default()
    };
    let mut s = RigSession::new(parts, options).unwrap().0;
    assert_eq!(c.animations.len(), 1, "one animation stack");
    let track = c.animations[0].track.clone();
    let mut worst = 0.0f64;
    for (frame, file) in [
        (10.0, "fbx/maya_dq_weights_10.obj"),
        (18.0, "fbx/maya_dq_weights_18.obj"),
    ] {
        let mut reference = cagerig::io::obj::read_obj(&data(file)).unwrap();
        assert_eq!(reference.num_vertices(), s.num_vertices(), "{file}");
        for p in &mut reference.positions {
            *p = world_from_file.transform_point3(*p);
        }
        let mut player =
            AnimationPlayer::with_channels(&s, Some(track.clone()), None, PoseChannels::Full)
                .unwrap();
        player.apply(frame / 24.0, &mut s).unwrap();
        let err = cagerig::mesh::max_distance(s.posed_mesh(), &reference.positions) / diag;
        eprintln!(
            "{} frame {frame}: {err:.3e} of the diagonal ({diag:.4} m)",
            s.skinning().label()
        );
        worst = worst.max(err);
    }
    worst
}

#[test]
fn the_file_imports_as_blended_with_its_per_vertex_weights() {
    let c = import_character(&data(FILE), &ImportOptions::default()).unwrap();
    assert_eq!(c.skinning, Some(SkinningMethod::Blended));
    let b = c.dq_blend_weights.as_ref().unwrap();
    assert_eq!(b.len(), c.mesh.num_vertices());
    // Painted weights: some vertices fully linear, some fully DQ, some in between.
    let values = b.values();
    assert!(values.contains(&0.0) || values.iter().any(|&x| x < 0.1));
    assert!(values.iter().any(|&x| x > 0.9));
    assert!(values.iter().any(|&x| x > 0.1 && x < 0.9));
    // The method is the file's: no note says otherwise any more.
    assert!(
        !c.warnings.iter().any(|w| w.to_string().contains("blend")),
        "{:?}",
        c.warnings
    );
}

#[test]
fn weight_blended_maya_skin_poses_as_in_maya() {
    let blended = error_against_references(None);
    let lbs = error_against_references(Some(SkinningMethod::Lbs));
    let dqs = error_against_references(Some(SkinningMethod::Dqs));
    eprintln!("max error / diagonal: blended {blended:.3e}, LBS {lbs:.3e}, DQS {dqs:.3e}");
    assert!(blended < 1e-5, "blended: {blended:e} of the diagonal");
    // The blend matters: neither pure method reproduces Maya's pose.
    assert!(lbs > 1e-3 && dqs > 1e-3, "LBS {lbs:e}, DQS {dqs:e}");
}
