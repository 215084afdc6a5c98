//! The reach of a Green rig's handle on CesiumMan (Khronos sample) with its default automatic
//! cage: in the walk's pose at t = 0.7 s the fit would leave the body, so the regulariser
//! pulls some current-cage vertices back (reach weights β_k > 0), and anchors one whose carried
//! vertex is itself off the body on its skinned vertex. Grabs of such vertices still land
//! exactly and move nothing else: CageRev inverts the fit with its pose's reach terms.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use cagerig::CoordsKind;
use cagerig::cage_gen::{CageOptions, CageRig, generate_rig_cage};
use cagerig::playback::{AnimationPlayer, PoseChannels};
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig_formats::{ImportOptions, import_character};
use common::data;
use glam::DVec3;

fn diagonal(p: &[DVec3]) -> f64 {
    let (lo, hi) = cagerig::mesh::bounding_box(p);
    (hi - lo).length()
}

#[test]
fn grabs_of_a_green_handle_held_within_reach_land_exactly() {
    let character = import_character(
        &data("gltf/CesiumMan/CesiumMan.glb"),
        &ImportOptions::default(),
    )
    .unwrap();
    let rig = CageRig {
        skeleton: &character.skeleton,
        weights: Some(&character.skin_weights),
    };
    let cage = generate_rig_cage(&character.mesh, &CageOptions::default(), Some(rig))
        .unwrap()
        .cage;
    let parts = RigParts::new(
        character.mesh.clone(),
        character.skeleton.clone(),
        character.skin_weights.clone(),
        cage,
    );
    let options = SessionOptions {
        coords: CoordsKind::Green,
        ..SessionOptions::default()
    };
    let mut s = RigSession::new(parts, options).unwrap().0;
    let track = character.animations[0].track.clone();
    let mut player =
        AnimationPlayer::with_channels(&s, Some(track), None, PoseChannels::Full).unwrap();
    player.apply(0.7, &mut s).unwrap();

    let (weights, anchored) = s.green_reach().unwrap();
    let (weights, anchored) = (weights.to_vec(), anchored.to_vec());
    let held: Vec<usize> = (0..weights.len())
        .filter(|&k| weights[k] > 0.0 && !anchored[k])
        .collect();
    let anchors: Vec<usize> = (0..weights.len())
        .filter(|&k| weights[k] > 0.0 && anchored[k])
        .collect();
    let free = (0..weights.len()).find(|&k| weights[k] == 0.0).unwrap();
    assert!(!held.is_empty(), "no vertex held within reach at t = 0.7");
    assert!(!anchors.is_empty(), "no vertex anchored at t = 0.7");

    let d = diagonal(s.rest_cage());
    let tol = 1e-9 * d;
    for k in [anchors[0], held[0], free] {
        let offset = DVec3::new(0.3, -0.5, 0.8).normalize() * (0.01 * d);
        let before = s.posed_cage().to_vec();
        s.move_posed_cage(&[k], &[offset]).unwrap();
        for (m, (after, b)) in s.posed_cage().iter().zip(&before).enumerate() {
            let expect = if m == k { *b + offset } else { *b };
            let off = after.distance(expect);
            assert!(off < tol, "grab of vertex {k}: vertex {m} is {off:e} off");
        }
        // The pose's reach terms are the pose's alone: the grab left them as they were.
        let (after_weights, after_anchored) = s.green_reach().unwrap();
        assert_eq!(after_weights, &weights[..]);
        assert_eq!(after_anchored, &anchored[..]);
    }
}
