//! Malformed and hostile glTF files give clear errors naming the file and the element, never a
//! panic nor a huge allocation.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use std::path::{Path, PathBuf};

use base64::Engine;
use cagerig_formats::gltf::import_gltf_bytes;
use cagerig_formats::{ImportOptions, import_character};
use common::data;

fn err_of(bytes: &[u8], path: &Path) -> String {
    match import_gltf_bytes(bytes, path, &ImportOptions::default()) {
        Ok(_) => panic!("{} was accepted", path.display()),
        Err(e) => e.to_string(),
    }
}

fn simple_skin() -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(data("gltf/SimpleSkin/SimpleSkin.gltf")).unwrap())
        .unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cagerig-formats-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn every_truncation_of_the_fox_is_an_error_not_a_panic() {
    let bytes = std::fs::read(data("fox/Fox.glb")).unwrap();
    let path = Path::new("truncated/Fox.glb");
    let n = bytes.len();
    for k in (0..64)
        .map(|i| i * n / 64)
        .chain([1, 11, 12, 19, 20, n - 1])
    {
        let e = err_of(&bytes[..k], path);
        assert!(e.contains("truncated/Fox.glb"), "{k}: {e}");
        // Past the magic, the message says the file is cut short and how long it should be.
        if k >= 4 {
            assert!(e.contains("the file looks truncated"), "{k}: {e}");
            assert!(e.contains(&format!("found {k}")), "{k}: {e}");
        }
    }
    let e = err_of(&bytes[..n / 2], path);
    assert!(
        e.contains(&format!("its GLB header says {n} bytes, found {}", n / 2)),
        "{e}"
    );
}

#[test]
fn bad_accessor_indices_are_reported() {
    let mut j = simple_skin();
    j["meshes"][0]["primitives"][0]["indices"] = 99.into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("bad.gltf"));
    assert!(
        e.contains("bad.gltf") && e.contains("not a valid glTF"),
        "{e}"
    );
    let mut j = simple_skin();
    j["skins"][0]["joints"][1] = 57.into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("bad.gltf"));
    assert!(e.contains("bad.gltf"), "{e}");
}

/// Regression (found by the `gltf_import` fuzz target): the `gltf` crate's validation indexed
/// the accessors with a primitive's POSITION index before checking it and panicked.
#[test]
fn a_position_accessor_index_out_of_range_is_an_error_not_a_panic() {
    for index in [99usize, u32::MAX as usize] {
        let mut j = simple_skin();
        j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = index.into();
        let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("bad.gltf"));
        assert!(
            e.contains("bad.gltf") && e.contains("POSITION") && e.contains(&index.to_string()),
            "{e}"
        );
    }
    let mut j = simple_skin();
    j["accessors"] = serde_json::json!([]);
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("empty.gltf"));
    assert!(e.contains("has 0 accessors"), "{e}");
}

/// Regression (found by the `gltf_import` fuzz target): animation channel targets are not
/// validated by the `gltf` crate, whose accessors unwrap them.
#[test]
fn bad_animation_channel_targets_are_errors_not_panics() {
    let mut j = simple_skin();
    j["animations"][0]["channels"][0]["target"]["path"] = "translationx".into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("path.gltf"));
    assert!(e.contains("path.gltf") && e.contains("target.path"), "{e}");
    let mut j = simple_skin();
    j["animations"][0]["channels"][0]["target"]["node"] = 1000.into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("node.gltf"));
    assert!(e.contains("target.node is 1000"), "{e}");
}

#[test]
fn accessor_larger_than_its_bytes_is_refused_before_allocation() {
    // A ~1 kB file claiming 10¹² vertices.
    let mut j = simple_skin();
    let pos = j["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    j["accessors"][pos]["count"] = 1_000_000_000_000u64.into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("huge.gltf"));
    assert!(
        e.contains("huge.gltf") && e.contains(&format!("accessor {pos}")),
        "{e}"
    );
    // A joint index past the skin's joints.
    let mut j = simple_skin();
    let view = j["accessors"][pos]["bufferView"].as_u64().unwrap() as usize;
    j["bufferViews"][view]["byteLength"] = 4.into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("short.gltf"));
    assert!(e.contains("short.gltf") && e.contains("accessor"), "{e}");
}

#[test]
fn nan_positions_are_refused_with_the_element() {
    let mut j = simple_skin();
    let pos = j["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let view = j["accessors"][pos]["bufferView"].as_u64().unwrap() as usize;
    let offset = j["bufferViews"][view]["byteOffset"].as_u64().unwrap_or(0) as usize
        + j["accessors"][pos]["byteOffset"].as_u64().unwrap_or(0) as usize;
    let buffer = j["bufferViews"][view]["buffer"].as_u64().unwrap() as usize;
    let uri = j["buffers"][buffer]["uri"].as_str().unwrap().to_owned();
    let (head, payload) = uri.split_once(";base64,").unwrap();
    let engine = base64::engine::general_purpose::STANDARD;
    let mut bytes = engine.decode(payload).unwrap();
    bytes[offset + 4..offset + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    j["buffers"][buffer]["uri"] = format!("{head};base64,{}", engine.encode(&bytes)).into();
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("nan.gltf"));
    assert!(
        e.contains("nan.gltf") && e.contains("POSITION") && e.contains("not finite"),
        "{e}"
    );
}

#[test]
fn missing_and_escaping_buffers_are_refused() {
    let dir = temp_dir("uris");
    let mut j = simple_skin();
    j["buffers"][0]["uri"] = "missing.bin".into();
    let file = dir.join("missing.gltf");
    std::fs::write(&file, serde_json::to_vec(&j).unwrap()).unwrap();
    let e = import_character(&file, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.bin") && e.contains("buffer 0"), "{e}");
    for uri in ["../outside.bin", "/etc/passwd", "https://example.com/x.bin"] {
        j["buffers"][0]["uri"] = uri.into();
        std::fs::write(&file, serde_json::to_vec(&j).unwrap()).unwrap();
        let e = import_character(&file, &ImportOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("refused") && e.contains("missing.gltf"),
            "{uri}: {e}"
        );
    }
    // A buffer shorter than its byteLength.
    j["buffers"][0]["uri"] = "short.bin".into();
    std::fs::write(dir.join("short.bin"), [0u8; 3]).unwrap();
    std::fs::write(&file, serde_json::to_vec(&j).unwrap()).unwrap();
    let e = import_character(&file, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("declares") && e.contains("buffer 0"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_without_a_skin_says_what_is_needed() {
    let mut j = simple_skin();
    j.as_object_mut().unwrap().remove("skins");
    j["nodes"][0].as_object_mut().unwrap().remove("skin");
    let e = err_of(&serde_json::to_vec(&j).unwrap(), Path::new("noskin.gltf"));
    assert!(e.contains("no skin"), "{e}");
}
