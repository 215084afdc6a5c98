//! Skeletons nested in other skeletons, built in the test after the Khronos sample
//! RecursiveSkeletons (whose binary buffer could not be obtained here: its README describes one
//! mesh reused by 84 skins over chains of 10 joints, chains attached to the joints of other
//! chains, and an animation in which each column twists about its own axis, carrying the chains
//! attached to it).
//!
//! Here: one square column (10 rings of 4 vertices, each ring bound with weight 1 to one joint,
//! the sample's 40 vertices and 228 indices), three chains of 10 joints — B hangs from joint 5
//! of A, C from joint 4 of B, each 20 units off its parent's axis — and one skin per chain over
//! that same mesh, with the sample's inverse bind matrices (pure translations along y), so the
//! file's node pose is not its bind pose. Every joint turns LINEAR over three keys about its
//! chain's axis. The skinned nodes sit under joints of other skins (a skinned node's own
//! transform is ignored). Each skin is imported and compared with the independent evaluation of
//! `common::ReferenceGltf` between the keys, where the root of B and C is carried along an arc
//! by the turning joints above it.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

mod common;
mod synthetic_gltf;

use std::path::Path;

use cagerig_formats::{ImportOptions, ImportedCharacter, import_character};
use glam::{DQuat, DVec3};
use serde_json::{Value, json};
use synthetic_gltf::{push_view, worst_distance, write_temp};

/// Joints per chain (and rings of the column), as in the sample.
const CHAIN: usize = 10;
/// Spacing of the rings and of the joints along a chain.
const SPACING: f32 = 10.0;
/// The angle each joint turns to at the middle key, radians (the sample's 0.2).
const TURN: f32 = 0.2;

/// Appends `bytes` as an embedded buffer with one view and one accessor; returns the accessor.
fn push_accessor(j: &mut Value, bytes: &[u8], mut accessor: Value) -> usize {
    accessor["bufferView"] = push_view(j, bytes).into();
    let index = j["accessors"].as_array().unwrap().len();
    j["accessors"].as_array_mut().unwrap().push(accessor);
    index
}

fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// The column of `n` rings: ring k at y = 10k, corners (±5, ±5) in x and z, bound to joint k.
fn push_column_mesh(j: &mut Value, n: usize) {
    let corners = [(-5.0f32, -5.0f32), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)];
    let positions: Vec<f32> = (0..n)
        .flat_map(|k| {
            corners
                .iter()
                .flat_map(move |&(x, z)| [x, SPACING * k as f32, z])
        })
        .collect();
    let top = SPACING * (n - 1) as f32;
    let position = push_accessor(
        j,
        &f32_bytes(positions),
        json!({"componentType": 5126, "count": 4 * n, "type": "VEC3",
               "min": [-5.0, 0.0, -5.0], "max": [5.0, top, 5.0]}),
    );
    let joints: Vec<u8> = (0..n)
        .flat_map(|k| (0..4).flat_map(move |_| [k as u8, 0, 0, 0]))
        .collect();
    let joints = push_accessor(
        j,
        &joints,
        json!({"componentType": 5121, "count": 4 * n, "type": "VEC4"}),
    );
    let weights = push_accessor(
        j,
        &f32_bytes((0..4 * n).flat_map(|_| [1.0, 0.0, 0.0, 0.0])),
        json!({"componentType": 5126, "count": 4 * n, "type": "VEC4"}),
    );
    let mut triangles: Vec<u16> = vec![0, 2, 1, 0, 3, 2];
    for k in 0..n - 1 {
        for c in 0..4 {
            let (a, b) = ((4 * k + c) as u16, (4 * k + (c + 1) % 4) as u16);
            triangles.extend([a, b, b + 4, a, b + 4, a + 4]);
        }
    }
    let last = (4 * (n - 1)) as u16;
    triangles.extend([last, last + 1, last + 2, last, last + 2, last + 3]);
    assert_eq!(triangles.len(), 24 * n - 12);
    let indices = push_accessor(
        j,
        &triangles
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect::<Vec<u8>>(),
        json!({"componentType": 5123, "count": triangles.len(), "type": "SCALAR"}),
    );
    j["meshes"] = json!([{"primitives": [{
        "attributes": {"POSITION": position, "JOINTS_0": joints, "WEIGHTS_0": weights},
        "indices": indices
    }]}]);
}

/// A chain of `n` joint nodes under `parent` (or at the top), its root at `offset` from the
/// parent turned by `root_rotation`; returns the joint nodes.
fn push_chain(
    j: &mut Value,
    n: usize,
    parent: Option<usize>,
    offset: [f32; 3],
    root_rotation: DQuat,
) -> Vec<usize> {
    let mut nodes = Vec::with_capacity(n);
    for k in 0..n {
        let node = j["nodes"].as_array().unwrap().len();
        let mut n = if k == 0 {
            let q = root_rotation.as_quat();
            json!({"translation": offset, "rotation": [q.x, q.y, q.z, q.w]})
        } else {
            json!({"translation": [0.0, SPACING, 0.0]})
        };
        n["name"] = format!("joint{node}").into();
        j["nodes"].as_array_mut().unwrap().push(n);
        let above = if k == 0 { parent } else { Some(nodes[k - 1]) };
        match above {
            Some(p) => {
                let children = j["nodes"][p]
                    .as_object_mut()
                    .unwrap()
                    .entry("children")
                    .or_insert_with(|| json!([]));
                children.as_array_mut().unwrap().push(node.into());
            }
            None => j["scenes"][0]["nodes"]
                .as_array_mut()
                .unwrap()
                .push(node.into()),
        }
        nodes.push(node);
    }
    nodes
}

/// One skin over `joints` with the sample's inverse bind matrices (translations by −10k along
/// y), and a node of the column mesh with that skin under `parent`.
fn push_skin(j: &mut Value, name: &str, joints: &[usize], parent: usize) {
    let matrices = f32_bytes((0..joints.len()).flat_map(|k| {
        let mut m = [0.0f32; 16];
        (m[0], m[5], m[10], m[15]) = (1.0, 1.0, 1.0, 1.0);
        m[13] = -SPACING * k as f32;
        m
    }));
    let ibm = push_accessor(
        j,
        &matrices,
        json!({"componentType": 5126, "count": joints.len(), "type": "MAT4"}),
    );
    let skin = j["skins"].as_array().unwrap().len();
    j["skins"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": name, "joints": joints, "inverseBindMatrices": ibm}));
    let node = j["nodes"].as_array().unwrap().len();
    // A transform the viewer must ignore: the node of a skinned mesh does not place it.
    j["nodes"].as_array_mut().unwrap().push(
        json!({"name": format!("{name} mesh"), "mesh": 0, "skin": skin, "translation": [3.0, 7.0, -2.0]}),
    );
    j["nodes"][parent]
        .as_object_mut()
        .unwrap()
        .entry("children")
        .or_insert_with(|| json!([]))
        .as_array_mut()
        .unwrap()
        .push(node.into());
}

/// One animation: every joint of each chain turns LINEAR from rest to [`TURN`] about the chain's
/// axis and back over the keys 0, 1, 2 s, after its rest rotation.
fn push_twist_animation(j: &mut Value, chains: &[(&[usize], DVec3)]) {
    let times = push_accessor(
        j,
        &f32_bytes([0.0, 1.0, 2.0]),
        json!({"componentType": 5126, "count": 3, "type": "SCALAR", "min": [0.0], "max": [2.0]}),
    );
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    for &(joints, axis) in chains {
        for &node in joints {
            let rest = j["nodes"][node]["rotation"]
                .as_array()
                .map(|q| {
                    let v: Vec<f64> = q.iter().map(|x| x.as_f64().unwrap()).collect();
                    DQuat::from_xyzw(v[0], v[1], v[2], v[3])
                })
                .unwrap_or(DQuat::IDENTITY);
            let turned = rest * DQuat::from_axis_angle(axis, f64::from(TURN));
            let keys = f32_bytes(
                [rest, turned, rest]
                    .iter()
                    .flat_map(|q| q.as_quat().to_array()),
            );
            let output = push_accessor(
                j,
                &keys,
                json!({"componentType": 5126, "count": 3, "type": "VEC4"}),
            );
            channels.push(
                json!({"sampler": samplers.len(), "target": {"node": node, "path": "rotation"}}),
            );
            samplers.push(json!({"input": times, "output": output, "interpolation": "LINEAR"}));
        }
    }
    j["animations"] = json!([{"name": "twist", "samplers": samplers, "channels": channels}]);
}

/// The document with chains of `n` joints: A (at the top, turning about x), B (under A's joint
/// n/2, 20 units off its axis, turned 90° about z, turning about z) and C (under B's joint
/// (n − 1)/2, 20 units off its axis, turning about y), one skin each over the column.
fn nested_skeletons(n: usize) -> Value {
    let mut j = json!({
        "asset": {"version": "2.0", "generator": "cagerig test"},
        "scene": 0,
        "scenes": [{"nodes": []}],
        "nodes": [],
        "buffers": [], "bufferViews": [], "accessors": [], "skins": []
    });
    push_column_mesh(&mut j, n);
    let a = push_chain(&mut j, n, None, [0.0, 0.0, 0.0], DQuat::IDENTITY);
    let b = push_chain(
        &mut j,
        n,
        Some(a[n / 2]),
        [20.0, 0.0, 0.0],
        DQuat::from_rotation_z(-std::f64::consts::FRAC_PI_2),
    );
    let c = push_chain(
        &mut j,
        n,
        Some(b[(n - 1) / 2]),
        [0.0, 0.0, 20.0],
        DQuat::IDENTITY,
    );
    // Each skinned node under a joint of another skin (C's under A's root, A's under C's tip).
    push_skin(&mut j, "A", &a, c[n - 1]);
    push_skin(&mut j, "B", &b, a[n / 5]);
    push_skin(&mut j, "C", &c, a[0]);
    push_twist_animation(&mut j, &[(&a, DVec3::X), (&b, DVec3::Z), (&c, DVec3::Y)]);
    j
}

/// The skins' names, in the file's order.
const SKINS: [&str; 3] = ["A", "B", "C"];

/// 41 times over the animation: between the keys (where an arc of the root is not a straight
/// line) and at them.
fn probe_times() -> Vec<f64> {
    (0..=40).map(|i| i as f64 * 0.05).collect()
}

/// Skin `name` of `path`, imported by name.
fn import_skin(path: &Path, name: &str) -> ImportedCharacter {
    let options = ImportOptions {
        skin: Some(name.into()),
        ..ImportOptions::default()
    };
    import_character(path, &options).unwrap()
}

#[test]
fn skins_of_nested_skeletons_pose_as_a_viewer_shows_them() {
    let document = nested_skeletons(CHAIN);
    let indices = &document["accessors"][3];
    assert_eq!(indices["count"], 228, "the sample's index count: {indices}");
    let path = write_temp("nested_skeletons.gltf", &document);
    let times = probe_times();
    for (skin, name) in SKINS.into_iter().enumerate() {
        let c = import_skin(&path, name);
        assert_eq!(c.summary.chosen_skin, skin);
        assert_eq!(c.skeleton.len(), CHAIN, "skin {name}");
        assert_eq!(c.mesh.num_vertices(), 4 * CHAIN, "skin {name}");
        assert_eq!(c.mesh.triangles.len(), 76, "skin {name}");
        let err = worst_distance(&path, &c, skin, &times);
        let keys = c.animations[0].track.num_keyframes();
        eprintln!("skin {name}: worst {err:e} of the diagonal, {keys} keys");
        assert!(err <= 1e-5, "skin {name}: {err:e} of the diagonal");
        // A hangs from nothing that moves: the file's three keys, exact. B and C are carried
        // by the joints above them: keys added, the animation marked and the note naming it.
        let notes: Vec<String> = c.warnings.iter().map(|w| w.to_string()).collect();
        let noted = notes.iter().any(|n| n.contains("keys were added"));
        if skin == 0 {
            assert_eq!(keys, 3);
            assert!(c.animations[0].exact && !noted, "{notes:?}");
        } else {
            assert!(keys > 3 && keys < 20_000, "{keys}");
            assert!(!c.animations[0].exact && noted, "{notes:?}");
        }
    }
}

/// The `gltf_import` fuzz target's seed (`fuzz/seeds/gltf_import/nested_skeletons.gltf`): the
/// document with chains of 3 joints, under the fuzzer's 8192-byte inputs, so that mutations
/// start from skeletons carried by other animated skeletons. Its skins pose as a viewer shows
/// them too. The test fails when the seed is not what this test builds;
/// `CAGERIG_WRITE_FUZZ_SEEDS=1` rewrites it.
#[test]
fn the_fuzz_seed_of_nested_skeletons_is_current() {
    let document = nested_skeletons(3);
    let bytes = serde_json::to_vec(&document).unwrap();
    assert!(bytes.len() <= 8192, "{} bytes", bytes.len());
    let path = write_temp("nested_skeletons_3.gltf", &document);
    let times = probe_times();
    for (skin, name) in SKINS.into_iter().enumerate() {
        let c = import_skin(&path, name);
        let err = worst_distance(&path, &c, skin, &times);
        assert!(err <= 1e-5, "skin {name}: {err:e} of the diagonal");
    }
    let seed = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/seeds/gltf_import/nested_skeletons.gltf");
    if std::env::var_os("CAGERIG_WRITE_FUZZ_SEEDS").is_some() {
        std::fs::create_dir_all(seed.parent().unwrap()).unwrap();
        std::fs::write(&seed, &bytes).unwrap();
    }
    let written = std::fs::read(&seed).unwrap_or_default();
    assert!(
        written == bytes,
        "{} is not what this test builds: rerun with CAGERIG_WRITE_FUZZ_SEEDS=1",
        seed.display()
    );
}
