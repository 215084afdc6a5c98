//! `--coords green` on the command line: the Arm scenario's grab lands exactly, `--unfitted-cage
//! keep` past the fold limit, `info` reports the Green binding, an unknown kind lists the
//! accepted ones.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::Path;
use support::{cagerig, repo, run_ok, temp_dir};

fn positions(path: &Path) -> Vec<glam::DVec3> {
    cagerig::io::read_obj(path).unwrap().positions
}

#[test]
fn edit_with_green_coordinates_lands_the_grab_exactly() {
    let dir = std::env::temp_dir().join(format!("cagerig-green-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let status = cagerig()
        .arg("edit")
        .arg(repo().join("data/arm/arm.obj"))
        .args(["--coords", "green", "--script"])
        .arg(repo().join("examples/edits.json"))
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    // Step 3 grabs current-cage vertices 10, 13, 15 by (-0.15, 0.2, 0.05).
    let before = positions(&dir.join("step2_cage_posed.obj"));
    let after = positions(&dir.join("step3_cage_posed.obj"));
    let (lo, hi) = cagerig::mesh::bounding_box(&before);
    let tol = 1e-9 * (hi - lo).length();
    let offset = glam::DVec3::new(-0.15, 0.2, 0.05);
    for (k, (a, b)) in after.iter().zip(&before).enumerate() {
        let expected = if [10, 13, 15].contains(&k) {
            *b + offset
        } else {
            *b
        };
        // The OBJ files hold 17 significant digits: round-off of the text is far below tol.
        assert!(
            a.distance(expected) < tol,
            "cage vertex {k}: {a} vs {expected}"
        );
    }
    // The rest mesh at step 0 is the loaded mesh (Green coordinates reproduce it).
    let loaded = positions(&repo().join("data/arm/arm.obj"));
    let rest = positions(&dir.join("step0_mesh_rest.obj"));
    assert!(cagerig::mesh::max_distance(&loaded, &rest) < tol);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `demo` takes the session options (it took none): the paper's scenario on the bar with Green
/// coordinates, the grab landing exactly and the other current-cage vertices still.
#[test]
fn demo_with_green_coordinates_lands_the_grab() {
    let root = temp_dir("demo");
    let (dir, mvc) = (root.join("green"), root.join("mvc"));
    let stdout = run_ok(
        cagerig()
            .args(["demo", "--coords", "green", "--no-pictures", "--out"])
            .arg(&dir),
    );
    assert!(stdout.contains("Green coordinates"), "{stdout}");
    let before = positions(&dir.join("2_inflate_cage_posed.obj"));
    let after = positions(&dir.join("3_grab_cage_posed.obj"));
    let (lo, hi) = cagerig::mesh::bounding_box(&before);
    let tol = 1e-9 * (hi - lo).length();
    let moved: Vec<usize> = (0..before.len())
        .filter(|&k| after[k].distance(before[k]) > tol)
        .collect();
    assert_eq!(moved.len(), 1, "one grabbed vertex: {moved:?}");
    let k = moved[0];
    let offset = after[k] - before[k];
    assert!(
        (offset.y - 0.1 * (hi - lo).length()).abs() < 0.02 * (hi - lo).length()
            && offset.x.abs() < tol,
        "{offset}"
    );
    // Rebinding with mean value coordinates gives another rest skin for the same inflate.
    run_ok(
        cagerig()
            .args(["demo", "--coords", "mvc", "--no-pictures", "--out"])
            .arg(&mvc),
    );
    let green_rest = positions(&dir.join("2_inflate_mesh_rest.obj"));
    let mvc_rest = positions(&mvc.join("2_inflate_mesh_rest.obj"));
    assert!(cagerig::mesh::max_distance(&green_rest, &mvc_rest) > 1e-4 * (hi - lo).length());
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn info_reports_the_green_binding_and_unknown_kinds_are_refused() {
    let output = cagerig()
        .arg("info")
        .arg(repo().join("data/arm/arm.obj"))
        .args(["--coords", "green", "--json"])
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let green = &report["green"];
    assert_eq!(green["face_coordinates"], 112);
    assert_eq!(green["outside_cage"], 0);
    assert!(green["reproduction_error"].as_f64().unwrap() < 1e-9);
    let output = cagerig()
        .arg("edit")
        .arg(repo().join("data/arm/arm.obj"))
        .args(["--coords", "harmonic", "--out", "unused"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("mvc") && stderr.contains("green"),
        "{stderr}"
    );
}

/// `bench --coords green` on the default built-in snake, whose Green cage folds before the MVC
/// pass's 60° bend: the bench does not stop at the refusal; it times the drag and grab at the
/// last pose reached and says which, with every row and its Newton steps in the JSON.
#[test]
fn bench_with_green_coordinates_reports_every_row_on_the_default_rig() {
    let out = cagerig()
        .args([
            "bench",
            "--coords",
            "green",
            "--json",
            "--skip-one-thread",
            "--repeat-scale",
            "0.2",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let model = &v[0];
    assert_eq!(model["coords"], "green");
    assert_eq!(model["cage_fit"], "regularised");
    assert!(model["binding_over_mvc"].as_f64().unwrap() > 0.0);
    for rows in [model, &model["display_f32"]] {
        for key in [
            "animation_frame",
            "rest_cage_drag",
            "grab_after_skeleton_edit",
            "rest_skin_product",
        ] {
            let ms = rows[key]["median_ms"].as_f64().unwrap();
            assert!(ms.is_finite() && ms > 0.0, "{key}: {ms}");
        }
        assert!(
            rows["rest_cage_drag_iterations"]["cageup_median"]
                .as_u64()
                .unwrap()
                > 0
        );
        assert!(
            rows["grab_after_skeleton_edit_iterations"]["cagerev_median"]
                .as_u64()
                .unwrap()
                > 0
        );
        let bend = rows["bend_degrees"].as_f64().unwrap();
        assert!((10.0..=60.0).contains(&bend), "bend {bend}°");
    }
    // The grab's read bound: the coordinate matrix in f64 and the skin weights, the same
    // weights for both kinds (a row start per vertex and at least one entry per vertex).
    let count = |key: &str| model[key].as_f64().unwrap();
    let (nv, nc, nf) = (
        count("vertices"),
        count("cage_vertices"),
        count("cage_faces"),
    );
    let bound = &model["grab_bound"];
    let bytes = |kind: &str, key: &str| bound[kind][key].as_f64().unwrap();
    assert_eq!(bytes("mvc", "product_bytes"), 8.0 * nv * nc);
    assert_eq!(bytes("green", "product_bytes"), 8.0 * nv * (nc + nf));
    let skin_mvc = bytes("mvc", "bytes") - 8.0 * nv * nc;
    let skin_green = bytes("green", "bytes") - 8.0 * nv * (nc + nf);
    assert_eq!(skin_mvc, skin_green);
    // A Green drag reads the moved vertices' columns and those of the faces touching them.
    let columns = |rows: &serde_json::Value| rows["rest_cage_drag_columns"].as_u64().unwrap();
    let mvc_columns = columns(&model["mvc_exact"]);
    assert!((1..=5).contains(&mvc_columns), "{mvc_columns}");
    assert!(columns(model) > mvc_columns);
    assert!(model["drag_bytes_over_mvc"].as_f64().unwrap() > 1.0);
    // Each ratio is a time over a positive bound; the fastest is at most the median.
    for kind in ["green", "mvc"] {
        for (best, median) in [
            ("best_over_bound", "over_bound"),
            ("product_best_over_bound", "product_over_bound"),
        ] {
            let (best, median) = (bytes(kind, best), bytes(kind, median));
            assert!(0.0 < best && best <= median, "{kind}: {best} > {median}");
        }
    }
    assert!(
        skin_mvc >= 14.0 * nv,
        "{skin_mvc} bytes of skin weights for {nv} vertices"
    );
}

/// `bench --coords green --cage-fit paper` times both of its sessions with the paper's fit, and
/// says which fit it timed.
#[test]
fn bench_with_green_coordinates_takes_the_cage_fit() {
    let out = cagerig()
        .args([
            "bench",
            "--coords",
            "green",
            "--cage-fit",
            "paper",
            "--json",
        ])
        .args(["--skip-one-thread", "--repeat-scale", "0.1"])
        .args(["--builtin", "bar"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v[0]["cage_fit"], "paper");
}

/// A Green rig does not compute mean value coordinates it would discard: `animate --auto-cage
/// --coords green` computes no Φ for the generated cage and does not warn that "the given mean
/// value coordinates … do not apply", of coordinates nobody gave.
#[test]
fn a_green_rig_with_a_generated_cage_computes_no_mean_value_coordinates() {
    let dir = std::env::temp_dir().join(format!("cagerig-green-auto-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let output = cagerig()
        .arg("animate")
        .arg(repo().join("data/fbx/blender_279_sausage_7400_binary.fbx"))
        .args(["--auto-cage", "--animation", "0", "--times", "0"])
        .args(["--coords", "green", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("generated one"), "{stderr}");
    assert!(!stderr.contains("mean value coordinates"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The Fox under Green coordinates: its unindexed mesh has 290 distinct points for a cage of
/// 100 vertices and 196 faces, so [φ ψ] has no MaxVol rows. Binding does not fail with "cage
/// coordinates Φ (rank deficient: MaxVol needs rank #C)": it fits all rows, says so, and
/// reproduces the rest mesh and follows a rest-cage edit.
#[test]
fn a_green_rig_whose_mesh_has_too_few_distinct_points_fits_all_rows() {
    let dir = std::env::temp_dir().join(format!("cagerig-green-fox-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("script.json");
    std::fs::write(
        &script,
        r#"{"steps":[{"op":"move_rest_cage","vertices":[0,1,2],"offset":[0.5,1.0,-0.5]}]}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let output = cagerig()
        .arg("edit")
        .arg(repo().join("data/fox/Fox.glb"))
        .arg("--cage")
        .arg(repo().join("data/fox/Fox_cage.obj"))
        .args(["--coords", "green", "--script"])
        .arg(&script)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("Green CageUp fits all 1728 mesh vertices")
            && stderr.contains("290 distinct positions"),
        "{stderr}"
    );
    let rest = positions(&out.join("step0_mesh_rest.obj"));
    let edited = positions(&out.join("step1_mesh_rest.obj"));
    let (lo, hi) = cagerig::mesh::bounding_box(&rest);
    let moved = cagerig::mesh::max_distance(&rest, &edited) / (hi - lo).length();
    assert!(
        moved > 1e-3,
        "the rest-cage edit moved the skin by {moved:e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn past_the_fold_keep_poses_the_skin_exactly_and_refuses_the_grab() {
    let dir = std::env::temp_dir().join(format!("cagerig-unfitted-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 120° at the elbow in one event: past the fold limit (about 66°) of the Arm's Green rig with
    // Lipman's stretched normal and the fit on the rows alone (the default rig follows it).
    let bend = r#"{"op":"rotate_joint","joint":"lowerarm01.R","axis":[1,0,0],"degrees":120}"#;
    let inflate = r#"{"op":"move_rest_cage","vertices":[0,2,4,5,6],"offset":[2,-1,1.5]}"#;
    let grab = r#"{"op":"move_posed_cage","vertices":[20],"offset":[0,1,0]}"#;
    let script = |name: &str, steps: &[&str]| {
        let path = dir.join(name);
        std::fs::write(&path, format!(r#"{{"steps":[{}]}}"#, steps.join(","))).unwrap();
        path
    };
    let pose_and_inflate = script("bend.json", &[bend, inflate]);
    let run = |coords: &str, policy: &str, script: &Path, out: &str| {
        cagerig()
            .arg("edit")
            .arg(repo().join("data/arm/arm.obj"))
            .args(["--coords", coords, "--unfitted-cage", policy])
            .args([
                "--green-face-term",
                "lipman",
                "--cage-fit",
                "paper",
                "--script",
            ])
            .arg(script)
            .arg("--out")
            .arg(dir.join(out))
            .output()
            .unwrap()
    };
    // The default refuses, and says which option keeps such events.
    let refused = run("green", "refuse", &pose_and_inflate, "refused");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(
        stderr.contains("Green CageUp found no current cage")
            && stderr.contains("--unfitted-cage keep"),
        "{stderr}"
    );
    // `keep`: the posed skin is the mean value rig's (skinning never reads C'), the rest-cage
    // edit moves the rest skin, and each unfitted C' written is named in a warning.
    let kept = run("green", "keep", &pose_and_inflate, "kept");
    let stderr = String::from_utf8_lossy(&kept.stderr);
    assert!(kept.status.success(), "{stderr}");
    for file in ["step1_cage_posed.obj", "step2_cage_posed.obj"] {
        assert!(
            stderr.contains(&format!("warning: {file}: CageUp found no current cage")),
            "{stderr}"
        );
    }
    let mvc = run("mvc", "keep", &pose_and_inflate, "mvc");
    assert!(
        mvc.status.success(),
        "{}",
        String::from_utf8_lossy(&mvc.stderr)
    );
    let green_posed = positions(&dir.join("kept/step1_mesh_posed.obj"));
    let mvc_posed = positions(&dir.join("mvc/step1_mesh_posed.obj"));
    let (lo, hi) = cagerig::mesh::bounding_box(&mvc_posed);
    let tol = 1e-9 * (hi - lo).length();
    assert!(cagerig::mesh::max_distance(&green_posed, &mvc_posed) < tol);
    let before = positions(&dir.join("kept/step1_mesh_rest.obj"));
    let after = positions(&dir.join("kept/step2_mesh_rest.obj"));
    assert!(cagerig::mesh::max_distance(&before, &after) > 1e-3 * (hi - lo).length());
    // A grab of the unfitted C' is refused with what to do.
    let with_grab = script("grab.json", &[bend, grab]);
    let grabbed = run("green", "keep", &with_grab, "grabbed");
    let stderr = String::from_utf8_lossy(&grabbed.stderr);
    assert!(!grabbed.status.success());
    assert!(
        stderr.contains("step 2") && stderr.contains("cannot be grabbed in this pose"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn export_past_the_fold_names_the_option_and_keeps_the_animation_with_it() {
    let dir = std::env::temp_dir().join(format!("cagerig-unfitted-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The Arm's own skeleton animation folds the current cage of its Green rig with Lipman's
    // stretched normal and the fit on the rows alone at t ≈ 1.17 s.
    let export = |policy: &str, out: &str| {
        cagerig()
            .arg("export")
            .arg(repo().join("data/arm/arm.obj"))
            .args([
                "--coords",
                "green",
                "--unfitted-cage",
                policy,
                "--green-face-term",
                "lipman",
                "--cage-fit",
                "paper",
                "--fps",
                "10",
            ])
            .arg("--skeleton-anim")
            .arg(repo().join("data/arm/arm_skelAnim.txt"))
            .arg("--out")
            .arg(dir.join(out))
            .output()
            .unwrap()
    };
    let refused = export("refuse", "refused.glb");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(
        stderr.contains("sample t = ") && stderr.contains("--unfitted-cage keep"),
        "{stderr}"
    );
    assert!(!dir.join("refused.glb").exists());
    let kept = export("keep", "kept.glb");
    let stderr = String::from_utf8_lossy(&kept.stderr);
    assert!(kept.status.success(), "{stderr}");
    assert!(dir.join("kept.glb").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `animate --json` says which samples left C' unfitted and counts them: the Arm's own
/// animation past t ≈ 1.2 s under Lipman's term with the fit on the rows alone (kept), and none
/// under the default rig.
#[test]
fn animate_json_counts_the_samples_whose_current_cage_is_unfitted() {
    let dir = temp_dir("unfitted-json");
    let report = |extra: &[&str], out: &str| -> serde_json::Value {
        let json = run_ok(
            cagerig()
                .arg("animate")
                .arg(repo().join("data/arm/arm.obj"))
                .arg("--skeleton-anim")
                .arg(repo().join("data/arm/arm_skelAnim.txt"))
                .args(["--times", "0,2", "--coords", "green", "--json", "--out"])
                .arg(dir.join(out))
                .args(extra),
        );
        serde_json::from_str(&json).unwrap()
    };
    let kept = report(
        &[
            "--green-face-term",
            "lipman",
            "--cage-fit",
            "paper",
            "--unfitted-cage",
            "keep",
        ],
        "kept",
    );
    let flags: Vec<bool> = kept["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["unfitted"].as_bool().unwrap())
        .collect();
    assert_eq!(flags, [false, true], "{kept}");
    assert_eq!(kept["unfitted_samples"], 1);
    let default = report(&[], "default");
    assert_eq!(default["unfitted_samples"], 0, "{default}");
    let _ = std::fs::remove_dir_all(&dir);
}
