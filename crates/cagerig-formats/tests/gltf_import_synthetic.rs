//! glTF features the shared files do not have, built in the test from SimpleSkin (two joints,
//! one rotation channel, 12 keys over 5.5 s): STEP and CUBICSPLINE channels, and a file with
//! two skins. Posed meshes are compared with the independent evaluation of
//! `common::ReferenceGltf` (the specification's interpolation, then LBS).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;
mod synthetic_gltf;

use cagerig_formats::{ImportOptions, import_character};
use common::{ReferenceGltf, data};
use glam::DVec3;
use serde_json::{Value, json};
use synthetic_gltf::{push_view, worst_distance, write_temp};

fn simple_skin() -> Value {
    serde_json::from_slice(&std::fs::read(data("gltf/SimpleSkin/SimpleSkin.gltf")).unwrap())
        .unwrap()
}

/// The key times of SimpleSkin's channel.
fn key_times() -> Vec<f64> {
    let (doc, buffers, _) = gltf::import(data("gltf/SimpleSkin/SimpleSkin.gltf")).unwrap();
    let channel = doc.animations().next().unwrap().channels().next().unwrap();
    let reader = channel.reader(|b| Some(&*buffers[b.index()]));
    reader.read_inputs().unwrap().map(f64::from).collect()
}

/// Midpoints between keys, and times 1 ms after and before each key.
fn probe_times(keys: &[f64]) -> Vec<f64> {
    keys.windows(2)
        .flat_map(|w| [0.5 * (w[0] + w[1]), w[0] + 1e-3, w[1] - 1e-3])
        .collect()
}

#[test]
fn step_channels_hold_each_key_until_the_next() {
    let mut j = simple_skin();
    j["animations"][0]["samplers"][0]["interpolation"] = "STEP".into();
    let path = write_temp("step.gltf", &j);
    let c = import_character(&path, &ImportOptions::default()).unwrap();
    assert!(!c.animations[0].exact, "a STEP channel is marked resampled");
    let keys = key_times();
    // At the keys and everywhere between them except the 1 µs ramp before each key.
    let mut times = keys.clone();
    times.extend(probe_times(&keys));
    let err = worst_distance(&path, &c, 0, &times);
    assert!(err <= 1e-6, "STEP: {err:e} of the diagonal");
    // The pose really steps: just before a key it is the previous key's.
    let reference = ReferenceGltf::load(&path);
    let before = reference.skin(Some(0), keys[2] - 1e-3);
    let at = reference.skin(Some(0), keys[1]);
    assert!(cagerig::mesh::max_distance(&before, &at) < 1e-12);
}

/// SimpleSkin's rotation keys as CUBICSPLINE with non-zero tangents (central differences of
/// the keys): a second buffer (data URI) holds in-tangent, value, out-tangent per key.
fn cubic_spline_document() -> Value {
    let (doc, buffers, _) = gltf::import(data("gltf/SimpleSkin/SimpleSkin.gltf")).unwrap();
    let channel = doc.animations().next().unwrap().channels().next().unwrap();
    let reader = channel.reader(|b| Some(&*buffers[b.index()]));
    let times: Vec<f32> = reader.read_inputs().unwrap().collect();
    let values: Vec<[f32; 4]> = match reader.read_outputs().unwrap() {
        gltf::animation::util::ReadOutputs::Rotations(r) => r.into_f32().collect(),
        _ => panic!("SimpleSkin animates a rotation"),
    };
    let n = times.len();
    let mut floats: Vec<f32> = Vec::with_capacity(n * 12);
    for k in 0..n {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let tangent: Vec<f32> = (0..4)
            .map(|c| (values[b][c] - values[a][c]) / (times[b] - times[a]))
            .collect();
        floats.extend(&tangent);
        floats.extend(values[k]);
        floats.extend(&tangent);
    }
    let bytes: Vec<u8> = floats.iter().flat_map(|x| x.to_le_bytes()).collect();
    let mut j = simple_skin();
    let view = push_view(&mut j, &bytes);
    let accessor = j["accessors"].as_array().unwrap().len();
    j["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": view, "componentType": 5126, "count": 3 * n, "type": "VEC4"}));
    j["animations"][0]["samplers"][0]["output"] = accessor.into();
    j["animations"][0]["samplers"][0]["interpolation"] = "CUBICSPLINE".into();
    j
}

/// Exact at the keys; between them the 60/s resampling (`ImportOptions::resample_fps`) of the
/// Hermite curve stays within 1e-4 of the diagonal (measured 3.6e-5), and gets smaller at a
/// higher rate.
#[test]
fn cubic_spline_channels_match_at_keys_and_resample_between() {
    let path = write_temp("cubic.gltf", &cubic_spline_document());
    let keys = key_times();
    let probes = probe_times(&keys);
    let c = import_character(&path, &ImportOptions::default()).unwrap();
    assert!(!c.animations[0].exact);
    let at_keys = worst_distance(&path, &c, 0, &keys);
    let between = worst_distance(&path, &c, 0, &probes);
    let fine = ImportOptions {
        resample_fps: 240.0,
        ..ImportOptions::default()
    };
    let c240 = import_character(&path, &fine).unwrap();
    let between_240 = worst_distance(&path, &c240, 0, &probes);
    eprintln!(
        "CUBICSPLINE: {at_keys:.1e} at the keys, {between:.1e} between at 60/s, \
         {between_240:.1e} at 240/s (of the diagonal)"
    );
    assert!(at_keys <= 1e-6, "at the keys: {at_keys:e}");
    assert!(between <= 1e-4, "between keys at 60/s: {between:e}");
    assert!(between_240 < between, "{between_240:e} ≥ {between:e}");
    // The tangents matter: the curve is not the LINEAR one.
    let mut linear = cubic_spline_document();
    linear["animations"][0]["samplers"][0] = simple_skin()["animations"][0]["samplers"][0].clone();
    let linear_path = write_temp("cubic_as_linear.gltf", &linear);
    let t = probes[0];
    let curve = ReferenceGltf::load(&path).skin(Some(0), t);
    let straight = ReferenceGltf::load(&linear_path).skin(Some(0), t);
    assert!(cagerig::mesh::max_distance(&curve, &straight) > 1e-4);
}

/// SimpleSkin with a second skin (`"tail"`: the same two joints in the other order, identity
/// inverse bind matrices) on a second node using the same mesh.
fn two_skin_document() -> Value {
    let mut j = simple_skin();
    j["skins"][0]["name"] = "body".into();
    j["skins"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "tail", "joints": [2, 1]}));
    let node = j["nodes"].as_array().unwrap().len();
    j["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"mesh": 0, "skin": 1, "translation": [3.0, 0.0, 0.0]}));
    j["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(node.into());
    j
}

#[test]
fn two_skins_pick_by_name_or_index_and_list_the_others() {
    let path = write_temp("two_skins.gltf", &two_skin_document());
    // Default: the first skin, with a note listing both.
    let first = import_character(&path, &ImportOptions::default()).unwrap();
    assert_eq!(first.summary.chosen_skin, 0);
    assert_eq!(first.summary.skins.len(), 2);
    let notes: Vec<String> = first.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("2 skins") && n.contains("body") && n.contains("tail")),
        "{notes:?}"
    );
    // By name and by index: the second skin, its joints in its own order, no note.
    for selector in ["tail", "1"] {
        let options = ImportOptions {
            skin: Some(selector.into()),
            ..ImportOptions::default()
        };
        let c = import_character(&path, &options).unwrap();
        assert_eq!(c.summary.chosen_skin, 1, "{selector}");
        assert_eq!(c.skeleton.len(), 2);
        assert_eq!(
            c.skeleton.joint(0).parent,
            Some(1),
            "joint 0 is node 2, child of node 1"
        );
        assert_eq!(c.mesh.num_vertices(), 10);
        assert!(!c.warnings.iter().any(|w| w.to_string().contains("2 skins")));
        // Rest: the mesh placed by its node; posed: what a viewer shows for skin 1.
        let (lo, _) = cagerig::mesh::bounding_box(&c.mesh.positions);
        assert!((lo.x - 2.5).abs() < 1e-6, "node translation applied: {lo}");
        let keys = key_times();
        let err = worst_distance(&path, &c, 1, &probe_times(&keys));
        assert!(err <= 1e-6, "skin {selector}: {err:e} of the diagonal");
    }
    // A skin that is not there: an error naming the file and listing the skins.
    let options = ImportOptions {
        skin: Some("wing".into()),
        ..ImportOptions::default()
    };
    let e = import_character(&path, &options).unwrap_err().to_string();
    assert!(
        e.contains("two_skins.gltf")
            && e.contains("wing")
            && e.contains("body")
            && e.contains("tail"),
        "{e}"
    );
}

/// Sparse accessors (glTF 2.0 §3.6.2.3): substitutions over a dense POSITION accessor, and a
/// POSITION accessor made of substitutions alone (no buffer view: zeros, then the values).
#[test]
fn sparse_accessors_are_read() {
    let original = import_character(
        &data("gltf/SimpleSkin/SimpleSkin.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    let rest = original.mesh.positions.clone();
    // Vertices 3 and 7 moved by +0.25 in y over the original data.
    let mut j = simple_skin();
    let indices: Vec<u8> = [3u16, 7].iter().flat_map(|i| i.to_le_bytes()).collect();
    let values: Vec<u8> = [3usize, 7]
        .iter()
        .flat_map(|&v| [rest[v].x as f32, rest[v].y as f32 + 0.25, rest[v].z as f32])
        .flat_map(f32::to_le_bytes)
        .collect();
    let (iv, vv) = (push_view(&mut j, &indices), push_view(&mut j, &values));
    j["accessors"][1]["sparse"] = json!({
        "count": 2,
        "indices": {"bufferView": iv, "componentType": 5123},
        "values": {"bufferView": vv}
    });
    j["accessors"][1]["max"] = json!([0.5, 2.25, 0.0]);
    let c = import_character(&write_temp("sparse.gltf", &j), &ImportOptions::default()).unwrap();
    for (v, (a, b)) in c.mesh.positions.iter().zip(&rest).enumerate() {
        let expected = if v == 3 || v == 7 {
            *b + DVec3::new(0.0, 0.25, 0.0)
        } else {
            *b
        };
        assert!(a.distance(expected) < 1e-7, "vertex {v}: {a} vs {expected}");
    }
    // Every vertex substituted, no buffer view: the same mesh as the original.
    let mut j = simple_skin();
    let indices: Vec<u8> = (0u8..10).collect();
    let values: Vec<u8> = rest
        .iter()
        .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .flat_map(f32::to_le_bytes)
        .collect();
    let (iv, vv) = (push_view(&mut j, &indices), push_view(&mut j, &values));
    j["accessors"][1] = json!({
        "componentType": 5126, "count": 10, "type": "VEC3",
        "max": [0.5, 2.0, 0.0], "min": [-0.5, 0.0, 0.0],
        "sparse": {"count": 10, "indices": {"bufferView": iv, "componentType": 5121},
                   "values": {"bufferView": vv}}
    });
    let c = import_character(
        &write_temp("sparse_only.gltf", &j),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(c.mesh.positions, rest);
    // Indices out of order or out of range are refused, naming the accessor.
    j["accessors"][1]["sparse"]["count"] = 11.into();
    let e = import_character(
        &write_temp("sparse_bad.gltf", &j),
        &ImportOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("accessor 1"), "{e}");
}

/// KHR_mesh_quantization: POSITION as normalised 16-bit integers, the extension required.
#[test]
fn quantized_positions_are_read() {
    let original = import_character(
        &data("gltf/SimpleSkin/SimpleSkin.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    let rest = original.mesh.positions.clone();
    let quantized: Vec<i16> = rest
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .map(|x| (x / 4.0 * 32767.0).round() as i16)
        .collect();
    // VEC3 of 16-bit components: each element padded to 8 bytes (4-byte alignment).
    let bytes: Vec<u8> = quantized
        .chunks(3)
        .flat_map(|c| [c[0], c[1], c[2], 0])
        .flat_map(i16::to_le_bytes)
        .collect();
    let mut j = simple_skin();
    let view = push_view(&mut j, &bytes);
    j["bufferViews"][view]["byteStride"] = 8.into();
    j["accessors"][1] = json!({
        "bufferView": view, "componentType": 5122, "normalized": true, "count": 10,
        "type": "VEC3", "max": [4096, 16384, 0], "min": [-4096, 0, 0]
    });
    j["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    j["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let c = import_character(&write_temp("quantized.gltf", &j), &ImportOptions::default()).unwrap();
    for (k, (a, b)) in c.mesh.positions.iter().zip(&rest).enumerate() {
        let expected = DVec3::new(
            f64::from(quantized[3 * k]) / 32767.0,
            f64::from(quantized[3 * k + 1]) / 32767.0,
            f64::from(quantized[3 * k + 2]) / 32767.0,
        );
        assert_eq!(*a, expected, "vertex {k}");
        assert!(a.distance(*b / 4.0) < 1e-4);
    }
    assert_eq!(c.skeleton.len(), original.skeleton.len());
    // Another required extension is still refused, by name.
    j["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = import_character(&write_temp("draco.gltf", &j), &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("KHR_draco_mesh_compression"), "{e}");
}

/// Required extensions that change only lighting or materials (a Blender level exported with
/// its lamps requires KHR_lights_punctual) are read, with one warning naming them; geometry and
/// animation extensions are still refused by name.
#[test]
fn appearance_only_required_extensions_are_read_with_a_warning() {
    let original = import_character(
        &data("gltf/SimpleSkin/SimpleSkin.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    let mut j = simple_skin();
    let required = ["KHR_lights_punctual", "KHR_materials_clearcoat"];
    j["extensionsUsed"] = json!(required);
    j["extensionsRequired"] = json!(required);
    let c = import_character(&write_temp("lights.gltf", &j), &ImportOptions::default()).unwrap();
    assert_eq!(c.mesh.positions, original.mesh.positions);
    let notes: Vec<String> = c.warnings.iter().map(ToString::to_string).collect();
    let named: Vec<&String> = notes
        .iter()
        .filter(|n| n.contains("KHR_lights_punctual, KHR_materials_clearcoat ignored"))
        .collect();
    assert_eq!(named.len(), 1, "{notes:?}");
    for refused in [
        "EXT_meshopt_compression",
        "EXT_mesh_gpu_instancing",
        "KHR_animation_pointer",
    ] {
        j["extensionsRequired"] = json!(["KHR_lights_punctual", refused]);
        let e = import_character(&write_temp("refused.gltf", &j), &ImportOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(refused) && !e.contains("KHR_lights"), "{e}");
    }
}

/// Two meshes, each with its own skin object over the same joints and bind pose (the second
/// listing the joints in the other order, its JOINTS_0 indices to match): one rig of both
/// meshes, the second mesh's weights on the same joints as the first's.
#[test]
fn skins_sharing_a_skeleton_are_one_rig() {
    let original = import_character(
        &data("gltf/SimpleSkin/SimpleSkin.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    let (doc, buffers, _) = gltf::import(data("gltf/SimpleSkin/SimpleSkin.gltf")).unwrap();
    let skin = doc.skins().next().unwrap();
    let reader = skin.reader(|b| Some(&*buffers[b.index()]));
    let ibms: Vec<[[f32; 4]; 4]> = reader.read_inverse_bind_matrices().unwrap().collect();
    let mut j = simple_skin();
    let joints = j["skins"][0]["joints"].as_array().unwrap().clone();
    // Skin 1: the joints in the other order, their inverse bind matrices too.
    let swapped: Vec<u8> = [ibms[1], ibms[0]]
        .iter()
        .flat_map(|m| {
            m.iter()
                .flatten()
                .flat_map(|x| x.to_le_bytes())
                .collect::<Vec<u8>>()
        })
        .collect();
    let ibm_view = push_view(&mut j, &swapped);
    let ibm_accessor = j["accessors"].as_array().unwrap().len();
    j["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": ibm_view, "componentType": 5126, "count": 2, "type": "MAT4"}));
    j["skins"].as_array_mut().unwrap().push(json!({
        "joints": [joints[1].clone(), joints[0].clone()],
        "inverseBindMatrices": ibm_accessor
    }));
    // Mesh 1: mesh 0 with JOINTS_0 indices swapped (0 ↔ 1).
    let (weights_rows, joint_rows): (Vec<[f32; 4]>, Vec<[u16; 4]>) = {
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let r = prim.reader(|b| Some(&*buffers[b.index()]));
        (
            r.read_weights(0).unwrap().into_f32().collect(),
            r.read_joints(0).unwrap().into_u16().collect(),
        )
    };
    assert_eq!(weights_rows.len(), 10);
    let swapped_joints: Vec<u8> = joint_rows
        .iter()
        .flat_map(|row| {
            row.map(|k| {
                if k == 0 {
                    1
                } else if k == 1 {
                    0
                } else {
                    k
                }
            })
        })
        .flat_map(u16::to_le_bytes)
        .collect();
    let joints_view = push_view(&mut j, &swapped_joints);
    let joints_accessor = j["accessors"].as_array().unwrap().len();
    j["accessors"].as_array_mut().unwrap().push(
        json!({"bufferView": joints_view, "componentType": 5123, "count": 10, "type": "VEC4"}),
    );
    let mut mesh1 = j["meshes"][0].clone();
    mesh1["primitives"][0]["attributes"]["JOINTS_0"] = joints_accessor.into();
    j["meshes"].as_array_mut().unwrap().push(mesh1);
    let node = j["nodes"].as_array().unwrap().len();
    j["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"mesh": 1, "skin": 1}));
    j["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(node.into());
    let c = import_character(
        &write_temp("shared_skins.gltf", &j),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(c.mesh.num_vertices(), 20, "both meshes");
    assert_eq!(c.skeleton.len(), original.skeleton.len());
    for v in 0..10 {
        assert_eq!(c.mesh.positions[v + 10], c.mesh.positions[v]);
        for joint in 0..c.skeleton.len() {
            assert_eq!(
                c.skin_weights.get(v + 10, joint),
                c.skin_weights.get(v, joint),
                "vertex {v} joint {joint}"
            );
        }
    }
    let notes: Vec<String> = c.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        notes.iter().any(|n| n.contains("share one skeleton")),
        "{notes:?}"
    );
}
