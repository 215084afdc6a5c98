//! Skeletons nested in other skeletons, built in the test after the Khronos sample
//! RecursiveSkeletons (whose binary buffer could not be obtained here: its README describes one
//! mesh reused by 84 skins over chains of 10 joints, chains attached to the joints of other
//! chains, and an animation in which each column twists about its own axis, carrying the chains
//! attached to it). Two scenes:
//!
//! - the sample's own scene ([`recursive_skeletons`]), rebuilt from the description of the
//!   program that generated it (SharpGLTF's `InfiniteSkinnedTentacle` example, the generator
//!   and licensor the sample names), with the layout, counts and ranges of the sample's JSON
//!   accessors (40 vertices interleaved with a 36-byte stride, 228 indices, 84 skins of 10 inverse bind matrices translating by 0 to −90
//!   along y, rotation keys at 0, 1 and 2 s reaching 0.0998 = sin 0.1 in one component): every
//!   one of its 84 skins;
//! - a harder variant ([`nested_skeletons`]), described below.
//!
//! The variant: one square column (10 rings of 4 vertices, each ring bound with weight 1 to one joint,
//! the sample's 40 vertices and 228 indices), three chains of 10 joints — B hangs from joint 5
//! of A, C from joint 4 of B, each 20 units off its parent's axis — and one skin per chain over
//! that same mesh, with the sample's inverse bind matrices (pure translations along y), so the
//! file's node pose is not its bind pose. Every joint turns LINEAR over three keys about its
//! chain's axis. The skinned nodes sit under joints of other skins (a skinned node's own
//! transform is ignored). Each skin is imported and compared with the independent evaluation of
//! `common::ReferenceGltf` between the keys, where the root of B and C is carried along an arc
//! by the turning joints above it.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
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
/// Its vertex attributes in one buffer view each, or, `interleaved`, as the sample's generator
/// writes them: one view with a 36-byte stride holding POSITION, a white COLOR_0 (normalised
/// bytes), JOINTS_0 (bytes) and WEIGHTS_0 at offsets 0, 12, 16 and 20.
fn push_column_mesh(j: &mut Value, n: usize, interleaved: bool) {
    let corners = [(-5.0f32, -5.0f32), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)];
    let positions: Vec<[f32; 3]> = (0..n)
        .flat_map(|k| {
            corners
                .iter()
                .map(move |&(x, z)| [x, SPACING * k as f32, z])
        })
        .collect();
    let joint_bytes: Vec<[u8; 4]> = (0..4 * n).map(|v| [(v / 4) as u8, 0, 0, 0]).collect();
    let weights = [1.0f32, 0.0, 0.0, 0.0];
    let top = SPACING * (n - 1) as f32;
    let position_accessor = json!({"componentType": 5126, "count": 4 * n, "type": "VEC3",
                                   "min": [-5.0, 0.0, -5.0], "max": [5.0, top, 5.0]});
    let joints_accessor = json!({"componentType": 5121, "count": 4 * n, "type": "VEC4"});
    let weights_accessor = json!({"componentType": 5126, "count": 4 * n, "type": "VEC4"});
    let mut attributes = json!({});
    if interleaved {
        let bytes: Vec<u8> = positions
            .iter()
            .zip(&joint_bytes)
            .flat_map(|(p, joints)| {
                let mut vertex = f32_bytes(*p);
                vertex.extend([255u8; 4]);
                vertex.extend(joints);
                vertex.extend(f32_bytes(weights));
                vertex
            })
            .collect();
        assert_eq!(bytes.len(), 36 * 4 * n);
        let view = push_view(j, &bytes);
        j["bufferViews"][view]["byteStride"] = 36.into();
        let color_accessor = json!({"componentType": 5121, "normalized": true,
                                    "count": 4 * n, "type": "VEC4"});
        for (name, mut accessor, offset) in [
            ("POSITION", position_accessor, 0),
            ("COLOR_0", color_accessor, 12),
            ("JOINTS_0", joints_accessor, 16),
            ("WEIGHTS_0", weights_accessor, 20),
        ] {
            accessor["bufferView"] = view.into();
            accessor["byteOffset"] = offset.into();
            attributes[name] = j["accessors"].as_array().unwrap().len().into();
            j["accessors"].as_array_mut().unwrap().push(accessor);
        }
    } else {
        let position = f32_bytes(positions.into_iter().flatten());
        attributes["POSITION"] = push_accessor(j, &position, position_accessor).into();
        let joints: Vec<u8> = joint_bytes.into_iter().flatten().collect();
        attributes["JOINTS_0"] = push_accessor(j, &joints, joints_accessor).into();
        let weights = f32_bytes((0..4 * n).flat_map(|_| weights));
        attributes["WEIGHTS_0"] = push_accessor(j, &weights, weights_accessor).into();
    }
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
    j["meshes"] = json!([{"primitives": [{"attributes": attributes, "indices": indices}]}]);
}

/// A chain of `n` joint nodes under `parent` (or at the top), its root at `offset` from the
/// parent turned by `root_rotation` and scaled by `root_scale`; returns the joint nodes.
fn push_chain(
    j: &mut Value,
    n: usize,
    parent: Option<usize>,
    offset: [f32; 3],
    root_rotation: DQuat,
    root_scale: f32,
) -> Vec<usize> {
    let mut nodes = Vec::with_capacity(n);
    for k in 0..n {
        let node = j["nodes"].as_array().unwrap().len();
        let mut n = if k == 0 {
            let q = root_rotation.as_quat();
            let mut root = json!({"translation": offset, "rotation": [q.x, q.y, q.z, q.w]});
            if root_scale != 1.0 {
                root["scale"] = json!([root_scale, root_scale, root_scale]);
            }
            root
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
/// y), and a node of the column mesh with that skin: under `parent` with a transform a viewer
/// must ignore, or at the top of the scene without one (as the sample's).
fn push_skin(j: &mut Value, name: Option<&str>, joints: &[usize], parent: Option<usize>) {
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
    let mut entry = json!({"joints": joints, "inverseBindMatrices": ibm});
    if let Some(name) = name {
        entry["name"] = name.into();
    }
    j["skins"].as_array_mut().unwrap().push(entry);
    let node = j["nodes"].as_array().unwrap().len();
    let Some(parent) = parent else {
        j["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({"mesh": 0, "skin": skin}));
        j["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(node.into());
        return;
    };
    // A transform the viewer must ignore: the node of a skinned mesh does not place it.
    j["nodes"].as_array_mut().unwrap().push(
        json!({"name": format!("{} mesh", name.unwrap_or("skin")), "mesh": 0, "skin": skin, "translation": [3.0, 7.0, -2.0]}),
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

/// A glTF document with one empty scene and empty lists to push into.
fn empty_document() -> Value {
    json!({
        "asset": {"version": "2.0", "generator": "cagerig test"},
        "scene": 0,
        "scenes": [{"nodes": []}],
        "nodes": [],
        "buffers": [], "bufferViews": [], "accessors": [], "skins": []
    })
}

/// The document with chains of `n` joints: A (at the top, turning about x), B (under A's joint
/// n/2, 20 units off its axis, turned 90° about z, turning about z) and C (under B's joint
/// (n − 1)/2, 20 units off its axis, turning about y), one skin each over the column.
fn nested_skeletons(n: usize) -> Value {
    let mut j = empty_document();
    push_column_mesh(&mut j, n, false);
    let a = push_chain(&mut j, n, None, [0.0, 0.0, 0.0], DQuat::IDENTITY, 1.0);
    let b = push_chain(
        &mut j,
        n,
        Some(a[n / 2]),
        [20.0, 0.0, 0.0],
        DQuat::from_rotation_z(-std::f64::consts::FRAC_PI_2),
        1.0,
    );
    let c = push_chain(
        &mut j,
        n,
        Some(b[(n - 1) / 2]),
        [0.0, 0.0, 20.0],
        DQuat::IDENTITY,
        1.0,
    );
    // Each skinned node under a joint of another skin (C's under A's root, A's under C's tip).
    push_skin(&mut j, Some("A"), &a, Some(c[n - 1]));
    push_skin(&mut j, Some("B"), &b, Some(a[n / 5]));
    push_skin(&mut j, Some("C"), &c, Some(a[0]));
    push_twist_animation(&mut j, &[(&a, DVec3::X), (&b, DVec3::Z), (&c, DVec3::Y)]);
    j
}

/// The four chains the scene's top and every chain's last joint carry: where each root sits
/// (signs of its x and z offsets) and the axis its joints turn about — the generator's pitch,
/// yaw, roll and yaw of 0.2 rad, about x, y, z and y.
const TENTACLES: [([f32; 2], DVec3); 4] = [
    ([1.0, 1.0], DVec3::X),
    ([-1.0, 1.0], DVec3::Y),
    ([-1.0, -1.0], DVec3::Z),
    ([1.0, -1.0], DVec3::Y),
];

/// Skins per chain at the top of [`recursive_skeletons`]: itself, 4 children, 16 grandchildren.
const SKINS_PER_TOP_CHAIN: usize = 21;

/// The scene of RecursiveSkeletons as its generator describes it (SharpGLTF's
/// `InfiniteSkinnedTentacle` example; the sample's README credits SharpGLTF): four chains of 10
/// joints with their roots at (±25, 0, ±25) at the top of the scene; on the last joint of every
/// chain four more, their roots 3 units off its axis in x and z and scaled by 0.2 (the
/// generator's translation by 15 followed by a scaling by 0.2), two levels deep — 4 + 16 + 64 =
/// 84 chains. Each chain has its own skin over the one column mesh, whose node sits at the top
/// of the scene, with the sample's inverse bind matrices; every joint turns LINEAR to 0.2 rad
/// about its chain's axis and back over 0, 1 and 2 s. Chains and skins in the generator's
/// depth-first order.
fn recursive_skeletons() -> Value {
    fn tentacle(
        j: &mut Value,
        parent: Option<usize>,
        (offset, scale, axis): ([f32; 3], f32, DVec3),
        depth: usize,
        chains: &mut Vec<(Vec<usize>, DVec3)>,
    ) {
        let joints = push_chain(j, CHAIN, parent, offset, DQuat::IDENTITY, scale);
        push_skin(j, None, &joints, None);
        let tip = joints[CHAIN - 1];
        chains.push((joints, axis));
        for ([x, z], axis) in TENTACLES.into_iter().filter(|_| depth > 0) {
            let placement = ([3.0 * x, 0.0, 3.0 * z], 0.2, axis);
            tentacle(j, Some(tip), placement, depth - 1, chains);
        }
    }
    let mut j = empty_document();
    push_column_mesh(&mut j, CHAIN, true);
    let mut chains = Vec::new();
    for ([x, z], axis) in TENTACLES {
        let placement = ([25.0 * x, 0.0, 25.0 * z], 1.0, axis);
        tentacle(&mut j, None, placement, 2, &mut chains);
    }
    let chains: Vec<(&[usize], DVec3)> = chains.iter().map(|(c, a)| (&c[..], *a)).collect();
    push_twist_animation(&mut j, &chains);
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

/// Every one of the 84 skins of the RecursiveSkeletons scene (the sample's hierarchy, scales,
/// skins and animation: [`recursive_skeletons`]) imports by its index and animates as a viewer
/// shows it. The four chains at the top hang from nothing that moves and keep the file's three
/// keys; the others are carried by 10 or 20 turning joints above them, scaled by 0.2 or 0.04.
#[test]
fn the_recursive_skeletons_scene_poses_as_a_viewer_shows_it() {
    let document = recursive_skeletons();
    assert_eq!(document["accessors"][0]["count"], 40);
    assert_eq!(document["accessors"][4]["count"], 228);
    assert_eq!(document["bufferViews"][0]["byteStride"], 36);
    let skins = document["skins"].as_array().unwrap().len();
    assert_eq!(skins, 4 * SKINS_PER_TOP_CHAIN);
    assert_eq!(
        document["nodes"].as_array().unwrap().len(),
        skins * (CHAIN + 1)
    );
    let path = write_temp("recursive_skeletons.gltf", &document);
    let times: Vec<f64> = (0..=20).map(|i| i as f64 * 0.1).collect();
    let (mut worst, mut most_keys) = (0.0f64, 0);
    for skin in 0..skins {
        let c = import_skin(&path, &skin.to_string());
        assert_eq!(c.summary.chosen_skin, skin);
        assert_eq!(c.skeleton.len(), CHAIN, "skin {skin}");
        let err = worst_distance(&path, &c, skin, &times);
        assert!(err <= 1e-5, "skin {skin}: {err:e} of the diagonal");
        let keys = c.animations[0].track.num_keyframes();
        let at_top = skin % SKINS_PER_TOP_CHAIN == 0;
        assert_eq!(c.animations[0].exact, at_top, "skin {skin}");
        assert_eq!(keys == 3, at_top, "skin {skin}: {keys} keys");
        worst = worst.max(err);
        most_keys = most_keys.max(keys);
    }
    eprintln!("{skins} skins: worst {worst:e} of the diagonal, at most {most_keys} keys");
    // Without --skin: skin 0, and a warning naming the first 8 skins, not all 84.
    let c = import_character(&path, &ImportOptions::default()).unwrap();
    assert_eq!(c.summary.chosen_skin, 0);
    let warning = c
        .warnings
        .iter()
        .map(|w| w.to_string())
        .find(|w| w.contains("84 skins"))
        .unwrap();
    assert!(
        warning.contains(r#"7 "" (10 joints), and 76 more"#) && !warning.contains(r#"8 """#),
        "{warning}"
    );
}
