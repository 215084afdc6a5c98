//! End-to-end tests of `cagerig weights` and of `--weights` / `--auto-weights` on the commands
//! that build a rig: the `.skw` written reads back as valid weights (rows sum to 1, at most
//! `--max-influences`), in the joint order `edit` writes in `step0_joints.json`; an OBJ needs
//! `--skeleton`; a hand-written five-joint `.skt` (the README's) binds the Arm.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::{Path, PathBuf};

use cagerig::SkinWeights;
use support::{cagerig, run_ok, temp_dir};

fn root(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

fn check_rows(w: &SkinWeights, max_influences: usize) {
    for v in 0..w.num_vertices() {
        let (joints, weights) = w.row(v);
        assert!(
            !joints.is_empty() && joints.len() <= max_influences,
            "vertex {v}"
        );
        assert!(
            (weights.iter().sum::<f64>() - 1.0).abs() < 1e-12,
            "vertex {v}"
        );
    }
}

#[test]
fn weights_on_the_arm_write_valid_rows_with_the_asked_influences() {
    let dir = temp_dir("weights-arm");
    for k in [4, 2] {
        let out = dir.join(format!("arm{k}.skw"));
        let json = run_ok(
            cagerig()
                .arg("weights")
                .arg(root("data/arm/arm.obj"))
                .arg("--skeleton")
                .arg(root("data/arm/arm.skt"))
                .args(["--max-influences", &k.to_string(), "--json", "--out"])
                .arg(&out),
        );
        let report: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(report["vertices"], 2089);
        assert_eq!(report["max_influences"], k);
        // `Skeleton` and `upperarm01.R` sit on their child: no bone, no weight.
        assert_eq!(
            report["static_joints"],
            serde_json::json!(["Skeleton", "upperarm01.R"])
        );
        let (w, warnings) = cagerig::io::skw::read_skw(&out, 2089, 25).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        check_rows(&w, k);
        assert_eq!(w.max_influences(), k);
    }
}

#[test]
fn an_obj_needs_a_skeleton_and_nothing_is_written_without_one() {
    let dir = temp_dir("weights-noskel");
    let out_path = dir.join("w.skw");
    let out = cagerig()
        .arg("weights")
        .arg(root("data/arm/arm.obj"))
        .arg("--out")
        .arg(&out_path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--skeleton"), "{stderr}");
    assert!(!out_path.exists());
    // A bad option names itself.
    let out = cagerig()
        .arg("weights")
        .arg(root("data/fox/Fox.glb"))
        .args(["--max-influences", "0", "--out"])
        .arg(&out_path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("max_influences"));
    assert!(!out_path.exists());
}

#[test]
fn fox_weights_follow_the_joint_order_of_edit_and_drive_edit() {
    let dir = temp_dir("weights-fox");
    let skw = dir.join("fox.skw");
    run_ok(
        cagerig()
            .arg("weights")
            .arg(root("data/fox/Fox.glb"))
            .arg("--out")
            .arg(&skw),
    );
    let script = dir.join("empty.json");
    std::fs::write(&script, r#"{"steps":[]}"#).unwrap();
    let out = dir.join("edit");
    run_ok(
        cagerig()
            .arg("edit")
            .arg(root("data/fox/Fox.glb"))
            .arg("--cage")
            .arg(root("data/fox/Fox_cage.obj"))
            .arg("--weights")
            .arg(&skw)
            .arg("--script")
            .arg(&script)
            .arg("--out")
            .arg(&out),
    );
    let joints: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("step0_joints.json")).unwrap()).unwrap();
    let names: Vec<&str> = joints
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    let mesh = cagerig::io::obj::read_obj(&out.join("step0_mesh_rest.obj")).unwrap();
    let (w, _) = cagerig::io::skw::read_skw(&skw, mesh.num_vertices(), names.len()).unwrap();
    check_rows(&w, 4);
    // The vertex farthest forward (the snout) follows the head; the one farthest back (the
    // tail's tip) the last tail joint.
    let by = |key: fn(&glam::DVec3) -> f64| {
        (0..mesh.num_vertices())
            .max_by(|&a, &b| key(&mesh.positions[a]).total_cmp(&key(&mesh.positions[b])))
            .unwrap()
    };
    let snout = by(|p| p.z);
    let tail = by(|p| -p.z);
    assert_eq!(names[w.heaviest(snout).unwrap()], "b_Head_05");
    assert_eq!(names[w.heaviest(tail).unwrap()], "b_Tail03_014");
}

#[test]
fn auto_weights_rig_an_obj_that_has_no_skw_and_conflict_with_weights() {
    let dir = temp_dir("weights-auto");
    for f in ["arm.obj", "arm.skt", "arm_cage.obj"] {
        std::fs::copy(root("data/arm").join(f), dir.join(f)).unwrap();
    }
    let script = root("examples/edits.json");
    let out = cagerig()
        .arg("edit")
        .arg(dir.join("arm.obj"))
        .arg("--script")
        .arg(&script)
        .arg("--out")
        .arg(dir.join("without"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--auto-weights"), "{stderr}");
    run_ok(
        cagerig()
            .arg("edit")
            .arg(dir.join("arm.obj"))
            .arg("--auto-weights")
            .arg("--script")
            .arg(&script)
            .arg("--out")
            .arg(dir.join("auto")),
    );
    let posed = cagerig::io::obj::read_obj(&dir.join("auto/step1_mesh_posed.obj")).unwrap();
    let rest = cagerig::io::obj::read_obj(&dir.join("auto/step1_mesh_rest.obj")).unwrap();
    // The elbow bend moved the forearm.
    assert!(
        posed
            .positions
            .iter()
            .zip(&rest.positions)
            .any(|(a, b)| a.distance(*b) > 1.0)
    );
    let out = cagerig()
        .arg("edit")
        .arg(dir.join("arm.obj"))
        .arg("--auto-weights")
        .arg("--weights")
        .arg(dir.join("x.skw"))
        .arg("--script")
        .arg(&script)
        .arg("--out")
        .arg(dir.join("both"))
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn the_readmes_five_joint_skeleton_binds_the_arm() {
    let dir = temp_dir("weights-five");
    let out = dir.join("arm5.skw");
    let json = run_ok(
        cagerig()
            .arg("weights")
            .arg(root("data/arm/arm.obj"))
            .arg("--skeleton")
            .arg(root("examples/arm-5-joints.skt"))
            .arg("--json")
            .arg("--out")
            .arg(&out),
    );
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(report["deforming_joints"].as_array().unwrap().len(), 5);
    let (w, _) = cagerig::io::skw::read_skw(&out, 2089, 5).unwrap();
    check_rows(&w, 4);
    // Every joint is the heaviest somewhere.
    for j in 0..5 {
        assert!((0..2089).any(|v| w.heaviest(v) == Some(j)), "joint {j}");
    }
}

/// `Fox.glb` with its skin removed (skins, animations, the node's skin, JOINTS_0/WEIGHTS_0),
/// written as a GLB over the same binary chunk: a static mesh like a sculpt's export.
fn unskinned_fox(path: &Path) {
    let glb = std::fs::read(root("data/fox/Fox.glb")).unwrap();
    let u32_at = |k: usize| u32::from_le_bytes(glb[k..k + 4].try_into().unwrap()) as usize;
    assert_eq!(&glb[0..4], b"glTF");
    let json_len = u32_at(12);
    assert_eq!(&glb[16..20], b"JSON");
    let mut j: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = &glb[20 + json_len..];
    let root_object = j.as_object_mut().unwrap();
    root_object.remove("skins");
    root_object.remove("animations");
    for node in j["nodes"].as_array_mut().unwrap() {
        node.as_object_mut().unwrap().remove("skin");
    }
    for mesh in j["meshes"].as_array_mut().unwrap() {
        for primitive in mesh["primitives"].as_array_mut().unwrap() {
            let attributes = primitive["attributes"].as_object_mut().unwrap();
            attributes.remove("JOINTS_0");
            attributes.remove("WEIGHTS_0");
        }
    }
    let mut json = serde_json::to_vec(&j).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + json.len() + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(bin);
    std::fs::write(path, out).unwrap();
}

/// A mesh with no skin binds to `--skeleton` (the same weights as the skinned Fox bound to the
/// same skeleton: the static mesh is its rest skin); without `--skeleton` the command says it
/// is required and writes nothing; the rig commands say how to bind the file.
#[test]
fn weights_bind_a_glb_with_no_skin_to_the_given_skeleton() {
    let dir = temp_dir("weights-noskin");
    let glb = dir.join("fox_noskin.glb");
    unskinned_fox(&glb);
    let fox = cagerig_formats::import_character(
        &root("data/fox/Fox.glb"),
        &cagerig_formats::ImportOptions::default(),
    )
    .unwrap();
    // The Fox's joints as positions (what a `.skt` holds; its frames are scaled).
    let joints = (0..fox.skeleton.len())
        .map(|j| {
            let joint = fox.skeleton.joint(j);
            cagerig::Joint {
                name: joint.name.clone(),
                parent: joint.parent,
                rest_world_from_joint: glam::DAffine3::from_translation(
                    joint.rest_world_from_joint.translation,
                ),
            }
        })
        .collect();
    let skeleton = cagerig::Skeleton::new(joints).unwrap();
    let skt = dir.join("fox.skt");
    cagerig::io::skt::write_skt(&skt, &skeleton).unwrap();
    let (skinned, unskinned) = (dir.join("skinned.skw"), dir.join("unskinned.skw"));
    for (mesh, out) in [(&root("data/fox/Fox.glb"), &skinned), (&glb, &unskinned)] {
        run_ok(
            cagerig()
                .arg("weights")
                .arg(mesh)
                .arg("--skeleton")
                .arg(&skt)
                .arg("--out")
                .arg(out),
        );
    }
    let nv = fox.mesh.num_vertices();
    let (w, warnings) = cagerig::io::skw::read_skw(&unskinned, nv, skeleton.len()).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    check_rows(&w, 4);
    assert_eq!(
        std::fs::read(&unskinned).unwrap(),
        std::fs::read(&skinned).unwrap()
    );

    let missing = dir.join("missing.skw");
    let out = cagerig()
        .arg("weights")
        .arg(&glb)
        .arg("--out")
        .arg(&missing)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--skeleton FILE.skt is required for a file with no skin")
            && stderr.contains("fox_noskin.glb"),
        "{stderr}"
    );
    assert!(!missing.exists());

    let out = cagerig().arg("info").arg(&glb).output().unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("fox_noskin.glb")
            && stderr.contains("has no skin: bind it with `cagerig weights"),
        "{stderr}"
    );
}
