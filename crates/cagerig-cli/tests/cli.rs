//! End-to-end tests of the `cagerig` binary: outputs reload bit-exactly, bad scripts fail with a
//! clear error naming the step and write nothing.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::{arm, cagerig, temp_dir};

const SCRIPT: &str = r#"{"skinning":"lbs","steps":[
  {"op":"rotate_joint","joint":"lowerarm01.R","axis":[1,0,0],"degrees":60},
  {"op":"move_rest_cage","vertices":[0,2,4,5,6],"offset":[2,-1,1.5]},
  {"op":"move_posed_cage","vertices":[20,23,25],"offset":[-1.5,2,0.5]},
  {"op":"set_skinning","method":"dqs"}]}"#;

#[test]
fn edit_writes_every_step_and_outputs_reload_bit_exactly() {
    let dir = temp_dir("edit");
    let out = run_edit(&dir, "out", &[]);
    for k in 0..=4 {
        for f in [
            "mesh_rest.obj",
            "mesh_posed.obj",
            "cage_rest.obj",
            "cage_posed.obj",
            "joints.json",
        ] {
            assert!(out.join(format!("step{k}_{f}")).is_file(), "step{k}_{f}");
        }
    }
    // Bit-exact reload: writing what was read gives the same bytes.
    let path = out.join("step3_mesh_posed.obj");
    let mesh = cagerig::io::read_obj(&path).unwrap();
    let again = dir.join("again.obj");
    cagerig::io::write_obj(&again, &mesh.positions, &mesh.triangles).unwrap();
    assert_eq!(
        std::fs::read(&path).unwrap(),
        std::fs::read(&again).unwrap()
    );
    // The grab landed: step-3 posed cage = step-2 posed cage + offset on vertices 20, 23, 25.
    let c2 = cagerig::io::read_obj(&out.join("step2_cage_posed.obj"))
        .unwrap()
        .positions;
    let c3 = cagerig::io::read_obj(&out.join("step3_cage_posed.obj"))
        .unwrap()
        .positions;
    let offset = glam::DVec3::new(-1.5, 2.0, 0.5);
    for (k, (a, b)) in c2.iter().zip(&c3).enumerate() {
        let expect = if [20, 23, 25].contains(&k) {
            *a + offset
        } else {
            *a
        };
        assert!(b.distance(expect) < 1e-9, "cage vertex {k}");
    }
    let joints: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("step1_joints.json")).unwrap()).unwrap();
    assert_eq!(joints.as_array().unwrap().len(), 25);
    assert_eq!(joints[3]["name"], "lowerarm01.R");
    assert_eq!(joints[3]["parent"], 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `edit` on the Arm with `SCRIPT` and extra options; returns the output directory.
fn run_edit(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let script = dir.join("edits.json");
    std::fs::write(&script, SCRIPT).unwrap();
    let out = dir.join(name);
    succeed(
        cagerig()
            .arg("edit")
            .arg(arm())
            .arg("--script")
            .arg(&script)
            .arg("--out")
            .arg(&out)
            .args(extra),
    );
    out
}

/// Runs `command`, which must succeed (its stderr is shown otherwise).
fn succeed(command: &mut Command) -> std::process::Output {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

#[test]
fn f32_coordinates_land_the_grab_and_stay_close_to_f64() {
    let dir = temp_dir("edit-f32");
    let exact = run_edit(&dir, "f64", &[]);
    let rounded = run_edit(&dir, "f32", &["--coords-precision", "f32"]);
    let read = |out: &Path, f: &str| cagerig::io::read_obj(&out.join(f)).unwrap().positions;
    // The grab lands exactly in f32 mode too.
    let (c2, c3) = (
        read(&rounded, "step2_cage_posed.obj"),
        read(&rounded, "step3_cage_posed.obj"),
    );
    let offset = glam::DVec3::new(-1.5, 2.0, 0.5);
    for (k, (a, b)) in c2.iter().zip(&c3).enumerate() {
        let expect = if [20, 23, 25].contains(&k) {
            *a + offset
        } else {
            *a
        };
        assert!(b.distance(expect) < 1e-9, "cage vertex {k}");
    }
    // Every output stays within f32 rounding effects of the f64 run (relative to the size).
    let rest = read(&exact, "step0_mesh_rest.obj");
    let (lo, hi) = cagerig::mesh::bounding_box(&rest);
    let diagonal = (hi - lo).length();
    for f in [
        "step4_mesh_posed.obj",
        "step4_cage_posed.obj",
        "step4_cage_rest.obj",
    ] {
        let d = cagerig::mesh::max_distance(&read(&exact, f), &read(&rounded, f));
        assert!(
            d > 0.0 && d < 1e-5 * diagonal,
            "{f}: {d} vs diagonal {diagonal}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_scripts_name_the_step_and_write_nothing() {
    let dir = temp_dir("bad");
    for (script, needle) in [
        (
            r#"{"steps":[{"op":"reset_pose"},{"op":"twist","joint":1}]}"#,
            "step 2",
        ),
        (
            r#"{"steps":[{"op":"rotate_joint","joint":"elbow.L","axis":[1,0,0],"degrees":5}]}"#,
            "unknown joint",
        ),
        (
            r#"{"steps":[{"op":"reset_pose"},{"op":"move_rest_cage","vertices":[999],"offset":[1,0,0]}]}"#,
            "step 2",
        ),
        ("{not json", "JSON"),
    ] {
        let path = dir.join("s.json");
        std::fs::write(&path, script).unwrap();
        let out = dir.join("out");
        let result = cagerig()
            .args(["edit", "--builtin", "bar", "--script"])
            .arg(&path)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{script}");
        assert!(stderr.contains(needle), "{script}: {stderr}");
        assert!(!out.exists(), "{script}: something was written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn info_reports_counts_files_and_warnings_as_json() {
    let out = cagerig()
        .arg("info")
        .arg(arm())
        .arg("--json")
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["vertices"], 2089);
    assert_eq!(v["triangles"], 4156);
    assert_eq!(v["joints"], 25);
    assert_eq!(v["cage_vertices"], 58);
    assert_eq!(v["cage_triangles"], 112);
    let files = v["files"].as_array().unwrap();
    assert!(files.iter().any(|f| f["role"] == "maxvol"));
    // The Arm's weight rows, rounded when written (worst sum 0.99907), are renormalised: a note,
    // not a warning.
    let mentions = |key: &str| {
        v[key]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("renormalised"))
    };
    assert!(mentions("notes"));
    assert!(!mentions("warnings"));
    let bad = cagerig()
        .args(["info", "/nonexistent/x.obj"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("/nonexistent/x.obj"));
}

#[test]
fn demo_runs_and_lands_the_grab() {
    let dir = temp_dir("demo");
    let out = cagerig()
        .args(["demo", "--out"])
        .arg(dir.join("d"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("current-cage grab"), "{stdout}");
    assert!(dir.join("d/3_grab_cage_posed.obj").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The demo stages its files and replaces `--out` whole (rather than writing them one by one
/// into it), so a run is complete or absent. Running it again replaces
/// an earlier demo's output; a folder holding anything else is refused and left as it was.
#[test]
fn demo_output_is_staged_rerunnable_and_never_replaces_foreign_files() {
    let dir = temp_dir("demo-staged");
    let run = |out: &std::path::Path| {
        cagerig()
            .args(["demo", "--no-pictures", "--out"])
            .arg(out)
            .output()
            .unwrap()
    };
    let out = dir.join("d");
    assert!(run(&out).status.success());
    let again = run(&out);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(out.join("0_loaded_mesh_rest.obj").is_file());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "staging folders left: {leftovers:?}");
    let mine = dir.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep me").unwrap();
    let refused = run(&mine);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("notes.txt"), "{err}");
    assert_eq!(
        std::fs::read_to_string(mine.join("notes.txt")).unwrap(),
        "keep me"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_reports_both_thread_counts_the_display_path_and_the_maxvol_quality() {
    let out = succeed(cagerig().args([
        "bench",
        "--builtin",
        "bar",
        "--json",
        "--repeat-scale",
        "0.2",
    ]));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let model = &v[0];
    let det = model["maxvol_log_abs_det"].as_f64().unwrap();
    assert!(det.is_finite(), "ln|det| {det}");
    for row in [model, &model["one_thread"]] {
        for key in [
            "lbs",
            "dqs",
            "cor",
            "mvc",
            "maxvol",
            "grab_after_skeleton_edit",
            "grab_after_skeleton_edit_display",
            "rest_cage_drag_display",
        ] {
            let ms = row[key]["median_ms"].as_f64().unwrap();
            assert!(ms.is_finite() && ms > 0.0, "{key}: {ms}");
        }
    }
}

/// `subdivide --auto-cage`: an OBJ rig without a cage is subdivided with a generated one, which
/// the written rig carries; without the option the missing cage is an error.
#[test]
fn subdivide_generates_a_cage_with_auto_cage() {
    let dir = temp_dir("subdivide-auto-cage");
    for f in ["arm.obj", "arm.skt", "arm.skw"] {
        std::fs::copy(support::arm_dir().join(f), dir.join(f)).unwrap();
    }
    let refused = cagerig()
        .arg("subdivide")
        .arg(dir.join("arm.obj"))
        .arg("--out")
        .arg(dir.join("none"))
        .output()
        .unwrap();
    assert!(!refused.status.success());
    assert!(!dir.join("none").exists());
    succeed(
        cagerig()
            .arg("subdivide")
            .arg(dir.join("arm.obj"))
            .args(["--auto-cage", "--levels", "1", "--out"])
            .arg(dir.join("sub")),
    );
    let cage = cagerig::io::read_obj(&dir.join("sub/rig_cage.obj")).unwrap();
    assert!(cage.num_vertices() >= 50, "{}", cage.num_vertices());
    let mesh = cagerig::io::read_obj(&dir.join("sub/rig.obj")).unwrap();
    assert_eq!(mesh.num_triangles(), 4 * 4156);
}
