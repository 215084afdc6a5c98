//! Files without a skin read as static meshes (`import_static_mesh`): glTF mesh nodes under a
//! scaled, rotated and mirrored parent, a `_cage` node, points skipped, a node outside the
//! default scene left out; SimpleSkin and the Fox without (and with) their skins; hand-written
//! ASCII FBX files in centimetres, Z up, right- and left-handed; the sausage's bind shape.
//! Expected world positions are composed in the tests from the written TRS values; outward
//! winding is checked by the signed volume of each closed part.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use std::path::PathBuf;

use base64::Engine;
use cagerig_formats::{
    FormatError, ImportOptions, SpaceSummary, StaticMesh, import_character, import_static_mesh,
};
use common::data;
use glam::{DAffine3, DMat3, DQuat, DVec3};
use serde_json::{Value, json};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cagerig-static-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The unit tetrahedron, its faces wound outward (counter-clockwise seen from outside).
const TETRA: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const TETRA_FACES: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

/// Signed volume enclosed by triangles `tris` of `positions` (positive: wound outward).
fn signed_volume(positions: &[DVec3], tris: &[[u32; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// One part of a static mesh: its world positions and its triangles, re-indexed locally.
fn part(m: &StaticMesh, k: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let p = &m.primitives[k];
    let positions = m.mesh.positions[p.first_vertex..p.first_vertex + p.vertices].to_vec();
    let base = p.first_vertex as u32;
    let tris = m
        .mesh
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&i| i >= base && i < base + p.vertices as u32))
        .map(|t| t.map(|i| i - base))
        .collect();
    (positions, tris)
}

fn trs(t: [f64; 3], r: DQuat, s: [f64; 3]) -> DAffine3 {
    DAffine3::from_translation(DVec3::from(t))
        * DAffine3::from_quat(r)
        * DAffine3::from_scale(DVec3::from(s))
}

/// A glTF with the tetrahedron as mesh 0 (indexed triangles) and mesh 1 (the same positions as
/// POINTS); nodes: 0 a parent translated, rotated and scaled by (2, 0.5, -1.5) (mirroring,
/// non-uniform) over mesh nodes 1 and 2; 3 `body_cage`, mirrored on its own; 4 a mesh node
/// outside the scene; 5 the points.
fn two_parts_document(parent: DQuat, child: DQuat) -> Value {
    let mut bytes: Vec<u8> = TETRA
        .iter()
        .flatten()
        .flat_map(|&x| (x as f32).to_le_bytes())
        .collect();
    bytes.extend(
        TETRA_FACES
            .iter()
            .flatten()
            .flat_map(|&i| (i as u16).to_le_bytes()),
    );
    let q = |r: DQuat| json!([r.x, r.y, r.z, r.w]);
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3, 5]}],
        "nodes": [
            {"name": "rig", "children": [1, 2], "translation": [1.0, 2.0, 3.0],
             "rotation": q(parent), "scale": [2.0, 0.5, -1.5]},
            {"name": "partA", "mesh": 0, "translation": [0.5, 0.0, 0.0]},
            {"name": "partB", "mesh": 0, "translation": [0.0, 1.0, 0.0], "rotation": q(child)},
            {"name": "body_cage", "mesh": 0, "scale": [-3.0, 3.0, 3.0]},
            {"name": "elsewhere", "mesh": 0},
            {"name": "dots", "mesh": 1}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}
        ],
        "buffers": [{"byteLength": bytes.len(), "uri": format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bytes))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}
        ]
    })
}

#[test]
fn gltf_mesh_nodes_under_a_mirrored_parent_land_in_world_space_wound_outward() {
    let parent = DQuat::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), 0.7);
    let child = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let path = temp_dir("gltf").join("two_parts.gltf");
    std::fs::write(
        &path,
        serde_json::to_vec(&two_parts_document(parent, child)).unwrap(),
    )
    .unwrap();
    let m = import_static_mesh(&path).unwrap();

    let world_parent = trs([1.0, 2.0, 3.0], parent, [2.0, 0.5, -1.5]);
    let worlds = [
        world_parent * trs([0.5, 0.0, 0.0], DQuat::IDENTITY, [1.0; 3]),
        world_parent * trs([0.0, 1.0, 0.0], child, [1.0; 3]),
    ];
    // Nodes 1 and 2 only: not the cage, not the node outside the scene, not the points.
    assert_eq!(m.primitives.len(), 2, "{:?}", m.primitives);
    assert_eq!(m.mesh.num_vertices(), 8);
    assert_eq!(m.mesh.num_triangles(), 8);
    assert_eq!(m.name, "two_parts");
    assert!(!m.had_skin);
    for (k, world) in worlds.iter().enumerate() {
        assert!(world.matrix3.determinant() < 0.0, "the test must mirror");
        let (positions, tris) = part(&m, k);
        for (v, p) in positions.iter().enumerate() {
            let expected = world.transform_point3(DVec3::from(TETRA[v]));
            assert!(
                p.distance(expected) < 1e-6,
                "part {k} vertex {v}: {p} vs {expected}"
            );
        }
        let volume = signed_volume(&positions, &tris);
        let expected = world.matrix3.determinant().abs() / 6.0;
        assert!(
            (volume - expected).abs() < 1e-6 * expected,
            "part {k}: volume {volume}, expected +{expected}"
        );
    }
    assert!(
        m.warnings.iter().any(|w| w.to_string().contains("Points")),
        "{:?}",
        m.warnings
    );

    // The `_cage` node is the cage, in world space, wound outward though mirrored.
    let cage = m.cage.as_ref().expect("the body_cage node");
    assert_eq!(cage.num_vertices(), 4);
    for (v, p) in cage.positions.iter().enumerate() {
        assert_eq!(*p, DVec3::from(TETRA[v]) * DVec3::new(-3.0, 3.0, 3.0));
    }
    assert!(
        (cage.signed_volume() - 27.0 / 6.0).abs() < 1e-9,
        "{}",
        cage.signed_volume()
    );

    // As a character the file is refused with a sentence that names it and says what works.
    let e = import_character(&path, &ImportOptions::default()).unwrap_err();
    assert!(
        matches!(e, FormatError::NoSkin { format: "glTF", .. }),
        "{e:?}"
    );
    let message = e.to_string();
    assert!(
        message.contains("two_parts.gltf")
            && message.contains("no skin")
            && message.contains("cagerig weights"),
        "{message}"
    );
}

/// SimpleSkin with its skin removed (skins, the node's skin, JOINTS_0/WEIGHTS_0) reads as the
/// same mesh as the character's rest skin; so do the skinned SimpleSkin and Fox themselves.
#[test]
fn skinned_samples_and_their_unskinned_copies_give_the_characters_rest_skin() {
    for file in ["gltf/SimpleSkin/SimpleSkin.gltf", "fox/Fox.glb"] {
        let character = import_character(&data(file), &ImportOptions::default()).unwrap();
        let m = import_static_mesh(&data(file)).unwrap();
        assert!(m.had_skin, "{file}");
        assert_eq!(m.mesh.positions, character.mesh.positions, "{file}");
        assert_eq!(m.mesh.triangles, character.mesh.triangles, "{file}");
    }
    let mut j: Value =
        serde_json::from_slice(&std::fs::read(data("gltf/SimpleSkin/SimpleSkin.gltf")).unwrap())
            .unwrap();
    j.as_object_mut().unwrap().remove("skins");
    j["nodes"][0].as_object_mut().unwrap().remove("skin");
    let attributes = j["meshes"][0]["primitives"][0]["attributes"]
        .as_object_mut()
        .unwrap();
    attributes.remove("JOINTS_0");
    attributes.remove("WEIGHTS_0");
    let path = temp_dir("simple").join("SimpleSkin_noskin.gltf");
    std::fs::write(&path, serde_json::to_vec(&j).unwrap()).unwrap();
    let m = import_static_mesh(&path).unwrap();
    let character = import_character(
        &data("gltf/SimpleSkin/SimpleSkin.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    assert!(!m.had_skin);
    assert_eq!(m.mesh.positions, character.mesh.positions);
    assert_eq!(m.mesh.triangles, character.mesh.triangles);
    assert!(m.cage.is_none());
}

/// An ASCII FBX 7.4 file: the tetrahedron's geometry under `tet` (translated, scaled by 2) and
/// under `tet_cage`, no skin; axes and unit as given.
fn fbx_document(coord_axis_sign: i32) -> String {
    let vertices: Vec<String> = TETRA.iter().flatten().map(|x| format!("{x}")).collect();
    // FBX polygons: the last index of each polygon is stored as -(i + 1).
    let polygons: Vec<String> = TETRA_FACES
        .iter()
        .flat_map(|&[a, b, c]| [a as i64, b as i64, -(c as i64) - 1])
        .map(|i| i.to_string())
        .collect();
    format!(
        r#"; FBX 7.4.0 project file
FBXHeaderExtension:  {{
	FBXHeaderVersion: 1003
	FBXVersion: 7400
}}
GlobalSettings:  {{
	Version: 1000
	Properties70:  {{
		P: "UpAxis", "int", "Integer", "",2
		P: "UpAxisSign", "int", "Integer", "",1
		P: "FrontAxis", "int", "Integer", "",1
		P: "FrontAxisSign", "int", "Integer", "",-1
		P: "CoordAxis", "int", "Integer", "",0
		P: "CoordAxisSign", "int", "Integer", "",{coord_axis_sign}
		P: "UnitScaleFactor", "double", "Number", "",1
	}}
}}
Objects:  {{
	Geometry: 1000, "Geometry::tet", "Mesh" {{
		Vertices: *12 {{
			a: {vertices}
		}}
		PolygonVertexIndex: *12 {{
			a: {polygons}
		}}
		GeometryVersion: 124
	}}
	Model: 2000, "Model::tet", "Mesh" {{
		Version: 232
		Properties70:  {{
			P: "Lcl Translation", "Lcl Translation", "", "A",10,20,30
			P: "Lcl Scaling", "Lcl Scaling", "", "A",2,2,2
		}}
	}}
	Model: 3000, "Model::tet_cage", "Mesh" {{
		Version: 232
		Properties70:  {{
			P: "Lcl Scaling", "Lcl Scaling", "", "A",5,5,5
		}}
	}}
}}
Connections:  {{
	C: "OO",2000,0
	C: "OO",3000,0
	C: "OO",1000,2000
	C: "OO",1000,3000
}}
"#,
        vertices = vertices.join(","),
        polygons = polygons.join(",")
    )
}

/// The conversion to right-handed, +Y up, +Z front, metres from the file's stated axes and
/// unit alone (as `tests/fbx_import.rs` builds it).
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
    let file_axes = DMat3::from_cols(
        direction(&space.file_right),
        direction(&space.file_up),
        direction(&space.file_front),
    );
    file_axes.transpose() * space.file_unit_meters
}

#[test]
fn fbx_without_a_skin_in_centimetres_z_up_right_and_left_handed() {
    let dir = temp_dir("fbx");
    for (sign, right) in [(1, "+X"), (-1, "-X")] {
        let path = dir.join(format!("tet{sign}.fbx"));
        std::fs::write(&path, fbx_document(sign)).unwrap();
        let m = import_static_mesh(&path).unwrap();
        assert_eq!(m.space.file_up, "+Z");
        assert_eq!(m.space.file_right, right);
        assert!((m.space.file_unit_meters - 0.01).abs() < 1e-12);
        let conversion = expected_world_from_file(&m.space);
        assert_eq!(
            conversion.determinant() < 0.0,
            sign < 0,
            "the left-handed file must mirror"
        );
        assert!(!m.had_skin);
        assert_eq!(m.primitives.len(), 1, "{:?}", m.primitives);
        assert_eq!(m.mesh.num_triangles(), 4);
        for (v, p) in m.mesh.positions.iter().enumerate() {
            let local = DVec3::from(TETRA[v]) * 2.0 + DVec3::new(10.0, 20.0, 30.0);
            let expected = conversion * local;
            assert!(p.distance(expected) < 1e-9, "vertex {v}: {p} vs {expected}");
        }
        let volume = m.mesh.signed_volume();
        let expected = 8.0 * 1e-6 / 6.0;
        assert!(
            (volume - expected).abs() < 1e-9 * expected + 1e-15,
            "volume {volume}, expected +{expected}"
        );
        let cage = m.cage.as_ref().expect("tet_cage");
        for (v, p) in cage.positions.iter().enumerate() {
            let expected = conversion * (DVec3::from(TETRA[v]) * 5.0);
            assert!(
                p.distance(expected) < 1e-9,
                "cage vertex {v}: {p} vs {expected}"
            );
        }
        assert!(cage.signed_volume() > 0.0);
        let e = import_character(&path, &ImportOptions::default()).unwrap_err();
        assert!(
            matches!(e, FormatError::NoSkin { format: "FBX", .. }),
            "{e:?}"
        );
        assert!(e.to_string().contains(&format!("tet{sign}.fbx")), "{e}");
    }
}

/// A skinned FBX read this way gives the character's rest skin (the bind shape), as glTF does.
#[test]
fn the_sausage_read_as_a_static_mesh_is_its_bind_shape() {
    let path = data("fbx/blender_279_sausage_7400_binary.fbx");
    let character = import_character(&path, &ImportOptions::default()).unwrap();
    let m = import_static_mesh(&path).unwrap();
    assert!(m.had_skin);
    assert_eq!(m.mesh.positions, character.mesh.positions);
    assert_eq!(m.mesh.triangles, character.mesh.triangles);
}
