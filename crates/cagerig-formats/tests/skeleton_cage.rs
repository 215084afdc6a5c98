//! The skeleton layout of cage generation on CesiumMan (Khronos sample): the generated cage
//! keeps the legs apart, where the offset layout webs them together, and passes every check of
//! the validator.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use cagerig::cage_gen::{
    CageLayout, CageOptions, CageRig, GeneratedCage, check_coordinates, generate_rig_cage,
};
use cagerig::mesh::winding_number;
use cagerig_formats::{ImportOptions, ImportedCharacter, import_character};
use common::data;

fn cage(character: &ImportedCharacter, layout: CageLayout) -> GeneratedCage {
    let options = CageOptions {
        layout,
        ..CageOptions::default()
    };
    let rig = CageRig {
        skeleton: &character.skeleton,
        weights: Some(&character.skin_weights),
    };
    let mut generated = generate_rig_cage(&character.mesh, &options, Some(rig)).unwrap();
    check_coordinates(&generated.cage, &character.mesh, &mut generated.report);
    assert!(
        generated.report.passed(),
        "{layout}: {:?}",
        generated.report.failures()
    );
    assert_eq!(generated.stats.layout, layout);
    generated
}

#[test]
fn cesium_mans_skeleton_cage_keeps_the_legs_apart() {
    let character = import_character(
        &data("gltf/CesiumMan/CesiumMan.glb"),
        &ImportOptions::default(),
    )
    .unwrap();
    let skeleton = &character.skeleton;
    let joint = |name: &str| skeleton.find(name).unwrap();
    let rest = skeleton.rest_positions();
    // Midway between the two thighs, knees and shins: outside the skin.
    let between: Vec<_> = ["1", "2", "3"]
        .iter()
        .map(|k| {
            let left = rest[joint(&format!("leg_joint_L_{k}"))];
            let right = rest[joint(&format!("leg_joint_R_{k}"))];
            0.5 * (left + right)
        })
        .collect();
    let inside = |generated: &GeneratedCage, p| {
        winding_number(&generated.cage.positions, &generated.cage.triangles, p) > 0.5
    };
    let offset = cage(&character, CageLayout::Offset);
    assert!(
        between[1..].iter().all(|&p| inside(&offset, p)),
        "the offset cage webs the legs"
    );
    let by_skeleton = cage(&character, CageLayout::Skeleton);
    assert!(by_skeleton.stats.cut_points > 0);
    assert_eq!(by_skeleton.stats.body_parts, 19);
    // The knees and shins are apart; the thighs' midpoint is in the crotch, under the cut's end.
    for &p in &between[1..] {
        assert!(
            !inside(&by_skeleton, p),
            "the skeleton cage holds {p} between the legs"
        );
    }
}
