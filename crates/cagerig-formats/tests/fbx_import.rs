//! FBX import against the reference meshes of ufbx's own test suite (Blender 2.79 sausage: the
//! skin at given takes and times).

mod common;

use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig_formats::{ImportOptions, import_character};
use common::{box_cage, data};

#[test]
fn sausage_posed_at_the_reference_times_matches_ufbx_meshes() {
    let c = import_character(
        &data("fbx/blender_279_sausage_7400_binary.fbx"),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(c.mesh.num_vertices(), 290);
    assert_eq!(c.skeleton.len(), 3);
    let names: Vec<&str> = c.animations.iter().map(|a| a.name.as_str()).collect();
    eprintln!(
        "animations {names:?} joints {:?}",
        c.skeleton
            .joints()
            .iter()
            .map(|j| &j.name)
            .collect::<Vec<_>>()
    );
    let (lo, hi) = cagerig::mesh::bounding_box(&c.mesh.positions);
    let diag = (hi - lo).length();
    let parts = RigParts::new(
        c.mesh.clone(),
        c.skeleton.clone(),
        c.skin_weights.clone(),
        box_cage(&c.mesh.positions, 0.05),
    );
    let mut s = RigSession::new(parts, SessionOptions::default()).unwrap().0;
    for (take, t, file) in [
        ("Base", 0.0, "fbx/blender_279_sausage_base_0.obj"),
        ("Spin", 15.0 / 24.0, "fbx/blender_279_sausage_spin_15.obj"),
        (
            "Wiggle",
            20.0 / 24.0,
            "fbx/blender_279_sausage_wiggle_20.obj",
        ),
    ] {
        let reference = cagerig::io::obj::read_obj(&data(file)).unwrap();
        let a = c
            .animations
            .iter()
            .find(|a| a.name.contains(take))
            .unwrap_or_else(|| panic!("no take {take} in {names:?}"));
        let mut player =
            AnimationPlayer::with_channels(&s, Some(a.track.clone()), None, PoseChannels::Full)
                .unwrap();
        player.apply(t, &mut s).unwrap();
        let err = cagerig::mesh::max_distance(s.posed_mesh(), &reference.positions) / diag;
        eprintln!("{take} t={t}: {err:e} of the diagonal ({diag})");
        // The reference OBJs carry 6 decimals (≈ 1.3e-7 of this diagonal).
        assert!(err < 1e-6, "{take} at t = {t}: {err:e} of the diagonal");
    }
}

#[test]
fn truncated_fbx_files_are_errors_naming_the_file() {
    let bytes = std::fs::read(data("fbx/blender_279_sausage_7400_binary.fbx")).unwrap();
    let dir = std::env::temp_dir().join(format!("cagerig-fbx-trunc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("cut.fbx");
    for k in (0..16).map(|i| i * bytes.len() / 16) {
        std::fs::write(&file, &bytes[..k]).unwrap();
        match import_character(&file, &ImportOptions::default()) {
            Err(e) => assert!(e.to_string().contains("cut.fbx"), "{k}: {e}"),
            // ufbx may recover a prefix that still holds a whole skinned mesh; it must be valid.
            Ok(c) => assert_eq!(c.mesh.num_vertices(), 290, "{k}"),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
