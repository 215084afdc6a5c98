//! `--cage-fit` on the command line: the regularised default keeps the Fox's current cage on
//! its body during the Run, where the paper's fit throws vertices far off; `animate --json`
//! reports the measures; an unknown fit lists the accepted ones.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use support::{cagerig, data, run_ok, temp_dir};

/// The worst spread, deviation and flipped of `animate --json` on the Fox's Run (shipped cage).
fn fox_run(cage_fit: &str) -> serde_json::Value {
    let out = temp_dir(&format!("cage-fit-{cage_fit}"));
    let json = run_ok(
        cagerig()
            .arg("animate")
            .arg(data("fox/Fox.glb"))
            .arg("--cage")
            .arg(data("fox/Fox_cage.obj"))
            .args([
                "--animation",
                "Run",
                "--times",
                "0,0.1,0.2,0.3,0.4,0.5,0.6,0.7",
            ])
            .args(["--cage-fit", cage_fit, "--json", "--force", "--out"])
            .arg(&out),
    );
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(report["cage_fit"], cage_fit);
    assert_eq!(report["samples"].as_array().unwrap().len(), 8);
    report["worst"].clone()
}

#[test]
fn the_regularised_fit_keeps_the_foxs_handle_on_its_body() {
    let paper = fox_run("paper");
    let regularised = fox_run("regularised");
    let spread = |v: &serde_json::Value| v["spread"].as_f64().unwrap();
    // The paper's fit: C' vertices twice as far from the body as the rest cage's farthest,
    // and 7 % of the triangles turned over; the default keeps it on the body.
    assert!(spread(&paper) > 2.0, "{paper}");
    assert!(spread(&regularised) <= 1.5, "{regularised}");
    let deviation = |v: &serde_json::Value| v["deviation"].as_f64().unwrap();
    assert!(
        deviation(&regularised) < 0.2 * deviation(&paper),
        "{regularised} {paper}"
    );
    let flipped = |v: &serde_json::Value| v["flipped"].as_f64().unwrap();
    assert!(flipped(&paper) > 0.05, "{paper}");
    assert_eq!(flipped(&regularised), 0.0, "{regularised}");
}

#[test]
fn an_unknown_cage_fit_lists_the_accepted_ones() {
    let output = cagerig()
        .arg("edit")
        .arg(data("arm/arm.obj"))
        .args(["--cage-fit", "exact", "--out"])
        .arg(temp_dir("cage-fit-unknown"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("regularised") && stderr.contains("paper"),
        "{stderr}"
    );
}

#[test]
fn info_bends_every_joint_and_reports_the_handle() {
    let json = run_ok(cagerig().arg("info").arg(data("arm/arm.obj")).args([
        "--bend-joints",
        "45",
        "--json",
    ]));
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    let bends = &report["joint_bends"];
    assert_eq!(bends["cage_fit"], "regularised");
    assert_eq!(bends["degrees"], 45.0);
    let joints = bends["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 25);
    assert!(joints.iter().all(|j| j["refused"] == 0), "{bends}");
    let worst = &bends["worst"];
    assert!(worst["deviation"].as_f64().unwrap() <= 0.06, "{worst}");
    assert!(worst["spread"].as_f64().unwrap() <= 1.5, "{worst}");
    // A glTF character with no cage: the error says how to give or generate one.
    let output = cagerig()
        .arg("info")
        .arg(data("fox/Fox.glb"))
        .args(["--bend-joints", "45"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("--cage") && stderr.contains("--auto-cage"),
        "{stderr}"
    );
}

#[test]
fn info_binds_a_gltf_character_with_a_given_or_generated_cage() {
    // A generated cage: the file's facts, and the rig with that cage, each joint bent.
    let json = run_ok(cagerig().arg("info").arg(data("fox/Fox.glb")).args([
        "--auto-cage",
        "--bend-joints",
        "45",
        "--json",
    ]));
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(report["cage_in_file"], false);
    assert_eq!(report["animations"].as_array().unwrap().len(), 3);
    let rig = &report["rig"];
    assert_eq!(rig["cage_generated"], true);
    assert!(rig["cage_vertices"].as_u64().unwrap() > 0);
    assert!(rig["cage_checks"].is_object(), "{rig}");
    let bends = &rig["joint_bends"];
    let joints = bends["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 24);
    assert!(joints.iter().all(|j| j["refused"] == 0), "{bends}");
    let worst = &bends["worst"];
    assert!(worst["deviation"].as_f64().unwrap() <= 0.06, "{worst}");
    assert!(worst["spread"].as_f64().unwrap() <= 1.5, "{worst}");
    assert_eq!(worst["flipped"].as_f64().unwrap(), 0.0, "{worst}");
    // A given cage: named where the file has none, then checked, as for a rig of OBJ files.
    let text = run_ok(
        cagerig()
            .arg("info")
            .arg(data("fox/Fox.glb"))
            .arg("--cage")
            .arg(data("fox/Fox_cage.obj")),
    );
    assert!(
        text.contains("cage in file   no; the rig below takes"),
        "{text}"
    );
    assert!(text.contains("Fox_cage.obj"), "{text}");
    assert!(
        text.contains("check          mesh_inside            ok"),
        "{text}"
    );
    // The importer's warnings are the rig's: said once, in the rig's section (and its JSON).
    let text = run_ok(
        cagerig()
            .arg("info")
            .arg(data("gltf/RiggedFigure/RiggedFigure.gltf"))
            .arg("--auto-cage"),
    );
    assert_eq!(text.matches("did not sum to 1").count(), 1, "{text}");
    assert!(report.get("warnings").is_none(), "{report}");
    assert!(rig["warnings"].is_array(), "{rig}");
    // Without a cage or a binding asked for, the file's facts alone, as before.
    let text = run_ok(cagerig().arg("info").arg(data("fox/Fox.glb")));
    assert!(text.contains("cage in file   no (give --cage"), "{text}");
    assert!(!text.contains("check "), "{text}");
}
