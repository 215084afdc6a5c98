//! Helpers of the tests that build glTF files: embedded buffers, a temporary file, and the
//! distance of an imported animation from the independent evaluation.

use std::path::{Path, PathBuf};

use base64::Engine;
use cagerig_formats::ImportedCharacter;
use glam::{DAffine3, DVec3};
use serde_json::{Value, json};

use crate::common::ReferenceGltf;

/// Writes `document` as `name` in this process's temporary folder; returns its path.
pub fn write_temp(name: &str, document: &Value) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cagerig-synthetic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(document).unwrap()).unwrap();
    path
}

/// Largest distance over `times` between the imported character posed by its animation 0 and
/// the reference evaluation of `path` (skin `skin`), as a fraction of the rest bounding-box
/// diagonal. The skeleton is posed directly, without a cage (SimpleSkin is a flat strip, for
/// which Φ is rank deficient for any cage): track locals → FK → `T_j = posed · rest⁻¹` →
/// cagerig's LBS of M.
pub fn worst_distance(path: &Path, c: &ImportedCharacter, skin: usize, times: &[f64]) -> f64 {
    let reference = ReferenceGltf::load(path).with_skin(skin);
    let (lo, hi) = cagerig::mesh::bounding_box(&c.mesh.positions);
    let diag = (hi - lo).length();
    let rest_frames = c.skeleton.rest_world_from_joint();
    let lbs = cagerig::skinning::lbs::LinearBlendSkinning::new(&c.skin_weights);
    let nj = c.skeleton.len();
    let mut locals = vec![DAffine3::IDENTITY; nj];
    let mut world = vec![DAffine3::IDENTITY; nj];
    let mut transforms = vec![DAffine3::IDENTITY; nj];
    let mut posed = vec![DVec3::ZERO; c.mesh.num_vertices()];
    times
        .iter()
        .map(|&t| {
            c.animations[0].track.sample(t, &mut locals);
            c.skeleton.forward_kinematics(&locals, &mut world);
            cagerig::Skeleton::skinning_transforms(&rest_frames, &world, &mut transforms);
            lbs.apply(&transforms, &c.mesh.positions, &mut posed);
            cagerig::mesh::max_distance(&reference.skin(Some(0), t), &posed) / diag
        })
        .fold(0.0, f64::max)
}

/// Appends `bytes` as a new embedded buffer with one buffer view; returns the view's index.
pub fn push_view(j: &mut Value, bytes: &[u8]) -> usize {
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    );
    let buffer = j["buffers"].as_array().unwrap().len();
    j["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({"uri": uri, "byteLength": bytes.len()}));
    let view = j["bufferViews"].as_array().unwrap().len();
    j["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": buffer, "byteLength": bytes.len()}));
    view
}
