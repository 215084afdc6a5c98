//! FBX import against the reference meshes of ufbx's own test suite (Blender 2.79 sausage: the
//! skin at given takes and times).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig_formats::{ImportOptions, SpaceSummary, import_character};
use common::{box_cage, data};
use glam::{DMat3, DVec3};

/// The conversion to right-handed, +Y up, +Z front, metres, built from the file's stated axes
/// and unit alone: the file's right/up/front axes go to +X/+Y/+Z, scaled to metres.
fn expected_world_from_file(space: &SpaceSummary) -> DMat3 {
    let direction = |axis: &str| match axis {
        "+X" => DVec3::X,
        "-X" => -DVec3::X,
        "+Y" => DVec3::Y,
        "-Y" => -DVec3::Y,
        "+Z" => DVec3::Z,
        "-Z" => -DVec3::Z,
        other => panic!("axis {other}"),
    };
    // Columns: the file coordinates of the right, up and front directions; K·F = unit·I.
    let file_axes = DMat3::from_cols(
        direction(&space.file_right),
        direction(&space.file_up),
        direction(&space.file_front),
    );
    file_axes.transpose() * space.file_unit_meters
}

#[test]
fn sausage_posed_at_the_reference_times_matches_ufbx_meshes() {
    let space = check_against_references(&data("fbx/blender_279_sausage_7400_binary.fbx"));
    // Blender wrote this file in glTF's convention already: nothing to convert.
    assert!(
        space.describe().contains("none needed"),
        "{}",
        space.describe()
    );
}

/// Finds `S<len>name` + the property's type strings in a binary FBX and overwrites the value
/// that follows (same size: the file stays valid).
fn patch_property(bytes: &mut [u8], name: &str, types: &[u8], value: &[u8]) {
    let mut pattern = vec![b'S'];
    pattern.extend((name.len() as u32).to_le_bytes());
    pattern.extend(name.as_bytes());
    pattern.extend(types);
    let at = bytes
        .windows(pattern.len())
        .position(|w| w == pattern.as_slice())
        .unwrap_or_else(|| panic!("no property {name}"))
        + pattern.len();
    bytes[at..at + value.len()].copy_from_slice(value);
}

/// The same sausage with its global settings rewritten to Z up (right +X, up +Z, front −Y,
/// as 3ds Max and Blender scenes are) and inches: the coordinates in the file are unchanged,
/// so the reference meshes hold in the file's space and the import must convert them.
#[test]
fn z_up_inch_fbx_is_converted_to_y_up_metres() {
    let mut bytes = std::fs::read(data("fbx/blender_279_sausage_7400_binary.fbx")).unwrap();
    let int = b"S\x03\x00\x00\x00intS\x07\x00\x00\x00IntegerS\x00\x00\x00\x00I";
    let double = b"S\x06\x00\x00\x00doubleS\x06\x00\x00\x00NumberS\x00\x00\x00\x00D";
    for (name, value) in [
        ("UpAxis", 2i32),
        ("UpAxisSign", 1),
        ("FrontAxis", 1),
        ("FrontAxisSign", -1),
        ("CoordAxis", 0),
        ("CoordAxisSign", 1),
    ] {
        patch_property(&mut bytes, name, int, &value.to_le_bytes());
    }
    patch_property(
        &mut bytes,
        "UnitScaleFactor",
        double,
        &2.54f64.to_le_bytes(),
    );
    let dir = std::env::temp_dir().join(format!("cagerig-fbx-axes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sausage_z_up_inches.fbx");
    std::fs::write(&path, bytes).unwrap();
    let space = check_against_references(&path);
    assert!(
        space.file_up == "+Z" && (space.file_unit_meters - 0.0254).abs() < 1e-12,
        "{}",
        space.describe()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Left-handed axes (right −X): the conversion mirrors, positions still match the references
/// through it, and the triangle winding is reversed (outward faces stay outward).
#[test]
fn left_handed_fbx_is_mirrored_with_its_winding_reversed() {
    let original = std::fs::read(data("fbx/blender_279_sausage_7400_binary.fbx")).unwrap();
    let mut bytes = original.clone();
    let int = b"S\x03\x00\x00\x00intS\x07\x00\x00\x00IntegerS\x00\x00\x00\x00I";
    patch_property(&mut bytes, "CoordAxisSign", int, &(-1i32).to_le_bytes());
    let dir = std::env::temp_dir().join(format!("cagerig-fbx-left-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sausage_left_handed.fbx");
    std::fs::write(&path, bytes).unwrap();
    let space = check_against_references(&path);
    assert_eq!(space.file_right, "-X", "{}", space.describe());
    let mirrored = import_character(&path, &ImportOptions::default()).unwrap();
    let kept = import_character(
        &data("fbx/blender_279_sausage_7400_binary.fbx"),
        &ImportOptions::default(),
    )
    .unwrap();
    for (a, b) in mirrored.mesh.triangles.iter().zip(&kept.mesh.triangles) {
        assert_eq!(*a, [b[0], b[2], b[1]]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Imports `path` (the sausage, possibly with other global settings), checks the stated
/// conversion against one built from the stated axes and unit, and the skin posed at the
/// reference times against ufbx's reference meshes carried through that conversion.
fn check_against_references(path: &std::path::Path) -> SpaceSummary {
    let c = import_character(path, &ImportOptions::default()).unwrap();
    // Blender skins linearly, and the file says so: the front ends pose it with LBS.
    assert_eq!(
        c.skinning,
        Some(cagerig::skinning::SkinningMethod::Lbs),
        "the file's skinning method"
    );
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
    // Converted to glTF's convention; the reference meshes are in the file's own space.
    let space = &c.summary.space;
    eprintln!("space: {}", space.describe());
    assert!(space.converted);
    let world_from_file = expected_world_from_file(space);
    let stated = glam::DAffine3::from_cols_array(&space.world_from_file);
    assert!(
        (stated.matrix3 - world_from_file)
            .abs()
            .to_cols_array()
            .iter()
            .all(|d| *d < 1e-12)
            && stated.translation.length() < 1e-12,
        "stated conversion {stated:?}, expected {world_from_file:?}"
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
        let mut reference = cagerig::io::obj::read_obj(&data(file)).unwrap();
        for p in &mut reference.positions {
            *p = world_from_file * *p;
        }
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
        // The reference OBJs carry 6 decimals (≈ 1.3e-7 of the file-space diagonal).
        assert!(err < 1e-6, "{take} at t = {t}: {err:e} of the diagonal");
    }
    c.summary.space
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

/// An FBX character is every skinned mesh as one rig: a skin choice is refused, not ignored.
#[test]
fn a_skin_choice_on_an_fbx_file_is_refused_with_the_reason() {
    let path = data("fbx/blender_279_sausage_7400_binary.fbx");
    let options = ImportOptions {
        skin: Some("1".into()),
        ..ImportOptions::default()
    };
    let message = import_character(&path, &options).unwrap_err().to_string();
    assert!(
        message.contains("blender_279_sausage_7400_binary.fbx")
            && message.contains("--skin \"1\" chooses among a glTF file's skins"),
        "{message}"
    );
    assert!(import_character(&path, &ImportOptions::default()).is_ok());
}
