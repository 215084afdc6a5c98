//! `cagerig export --skinning dqs|cor|blended --bake`: at every sample time an independent glTF
//! viewer shows `cagerig animate --skinning dqs|cor|blended`'s posed skin to 1e-5 of the
//! diagonal.
//!
//! The viewer is `reference_skinning` of cagerig-formats' tests (the `gltf` crate's loader and
//! readers, skinning written from the specification: node TRS, morph targets at the animated
//! weights, LBS), not cagerig's importer. Also: the Khronos validator (when `.ci/run` installed
//! it) finds 0 errors and 0 warnings, Blender's importer (when `blender` is on PATH) shows the
//! same skin, cagerig reads the baked file back (the baked targets left out), and without
//! `--bake` the same viewer is far from DQS (the comparison can fail).

#![expect(clippy::unwrap_used, clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

#[path = "../../cagerig-formats/tests/common/mod.rs"]
#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use support::{cagerig, data, run_ok_with_stderr, temp_dir};

fn positions(path: &Path) -> Vec<DVec3> {
    cagerig::io::obj::read_obj(path).unwrap().positions
}

/// Validator summary, or None when the validator is not installed.
fn validate(path: &Path) -> Option<serde_json::Value> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::var_os("GLTF_VALIDATOR_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".ci/gltf-validator"));
    if !dir.join("node_modules/gltf-validator").is_dir() {
        eprintln!(
            "gltf-validator not installed in {}: validation skipped",
            dir.display()
        );
        return None;
    }
    let out = Command::new("node")
        .arg(root.join("tools/gltf-validate.js"))
        .arg(path)
        .env("GLTF_VALIDATOR_DIR", &dir)
        .output()
        .expect("running node");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

/// A rig and its animation options for `export` and `animate`.
struct Case {
    name: &'static str,
    rig: Vec<String>,
    method: &'static str,
    /// Sample times of the export (on its 30/s grid) at which `animate` writes the skin.
    samples: &'static [f64],
    /// Midpoints between two samples (1/60 s after a sample).
    midpoints: &'static [f64],
}

fn fox(method: &'static str) -> Case {
    Case {
        name: "fox",
        rig: [
            data("fox/Fox.glb").display().to_string(),
            "--cage".into(),
            data("fox/Fox_cage.obj").display().to_string(),
            "--animation".into(),
            "Walk".into(),
        ]
        .into(),
        method,
        samples: &[0.0, 0.2, 0.5],
        midpoints: &[0.2 + 1.0 / 60.0, 0.5 + 1.0 / 60.0],
    }
}

fn arm(method: &'static str) -> Case {
    Case {
        name: "arm",
        rig: [
            data("arm/arm.obj").display().to_string(),
            "--skeleton-anim".into(),
            data("arm/arm_skelAnim.txt").display().to_string(),
            "--cage-anim".into(),
            data("arm/arm_cageAnim.txt").display().to_string(),
        ]
        .into(),
        method,
        samples: &[0.5, 2.0, 4.0],
        midpoints: &[0.5 + 1.0 / 60.0, 2.0 + 1.0 / 60.0],
    }
}

/// Maya's "weight blended" skin cluster (ufbx's test file: per-vertex DQ blend weights), with a
/// generated cage: `blended` is the file's own method.
fn maya_blended() -> Case {
    Case {
        name: "maya",
        rig: [
            data("fbx/maya_dq_weights_7500_binary.fbx")
                .display()
                .to_string(),
            "--auto-cage".into(),
            "--animation".into(),
            "Take 001".into(),
        ]
        .into(),
        method: "blended",
        samples: &[0.0, 0.4, 0.7],
        midpoints: &[0.4 + 1.0 / 60.0, 0.7 + 1.0 / 60.0],
    }
}

/// `cagerig animate --skinning METHOD` at `times`: (posed skins, rest bbox diagonal).
fn animate(case: &Case, dir: &Path, times: &[f64]) -> (Vec<Vec<DVec3>>, f64) {
    let out = dir.join(format!("{}-{}-animate", case.name, case.method));
    let list: Vec<String> = times.iter().map(f64::to_string).collect();
    run_ok_with_stderr(
        cagerig()
            .arg("animate")
            .args(&case.rig)
            .args([
                "--skinning",
                case.method,
                "--force",
                "--times",
                &list.join(","),
            ])
            .arg("--out")
            .arg(&out),
    );
    let posed = times
        .iter()
        .map(|t| positions(&out.join(format!("t{t}_mesh_posed.obj"))))
        .collect();
    let (lo, hi) = cagerig::mesh::bounding_box(&positions(
        &out.join(format!("t{}_mesh_rest.obj", times[0])),
    ));
    (posed, (hi - lo).length())
}

/// Largest distance / diagonal between the viewer's skin of `file` at `t` and `reference`.
fn viewer_error(file: &common::ReferenceGltf, t: f64, reference: &[DVec3], diagonal: f64) -> f64 {
    // The file's key times are f32: evaluate at the time it holds.
    let shown = file.skin(Some(0), f64::from(t as f32));
    assert_eq!(shown.len(), reference.len());
    cagerig::mesh::max_distance(&shown, reference) / diagonal
}

/// Exports `case` (baked or not), returns the file and what `export` printed.
fn export(case: &Case, dir: &Path, bake: bool, extension: &str) -> (PathBuf, String, String) {
    let suffix = if bake { "baked" } else { "plain" };
    let out = dir.join(format!(
        "{}-{}-{suffix}.{extension}",
        case.name, case.method
    ));
    let mut cmd = cagerig();
    cmd.arg("export")
        .args(&case.rig)
        .args(["--skinning", case.method])
        .arg("--out")
        .arg(&out);
    if bake {
        cmd.arg("--bake");
    }
    let (stdout, stderr) = run_ok_with_stderr(&mut cmd);
    (out, stdout, stderr)
}

/// The baked file matches `animate` at the samples to 1e-5 of the diagonal, validates, and
/// (the control) the plain export does not match.
fn check(case: &Case) {
    let dir = temp_dir(&format!("{}-{}", case.name, case.method));
    let times: Vec<f64> = case.samples.iter().chain(case.midpoints).copied().collect();
    let (posed, diagonal) = animate(case, &dir, &times);
    let (baked, said, _) = export(case, &dir, true, "glb");
    assert!(said.contains("morph targets"), "{said}");
    let viewer = common::ReferenceGltf::load(&baked);
    let ns = case.samples.len();
    for (k, &t) in case.samples.iter().enumerate() {
        let e = viewer_error(&viewer, t, &posed[k], diagonal);
        eprintln!(
            "{} {} baked, sample t = {t}: {e:.2e} of the diagonal",
            case.name, case.method
        );
        assert!(e <= 1e-5, "{} {} t = {t}: {e:e}", case.name, case.method);
    }
    for (k, &t) in case.midpoints.iter().enumerate() {
        let e = viewer_error(&viewer, t, &posed[ns + k], diagonal);
        eprintln!(
            "{} {} baked, midpoint t = {t:.4}: {e:.2e} of the diagonal",
            case.name, case.method
        );
        // `--max-between` (default 1e-5) refines the samples against the baked skin too.
        assert!(
            e <= 1e-5,
            "{} {} midpoint t = {t}: {e:e}",
            case.name,
            case.method
        );
    }
    if let Some(report) = validate(&baked) {
        assert_eq!(report["errors"], 0, "{report}");
        assert_eq!(report["warnings"], 0, "{report}");
    }
    // Control: the same viewer on the plain export shows LBS, far from DQS/CoR; and export
    // says so.
    let (plain, _, warned) = export(case, &dir, false, "glb");
    assert!(
        warned.contains("viewers show the LBS result") && warned.contains("--bake"),
        "{warned}"
    );
    let viewer = common::ReferenceGltf::load(&plain);
    let worst = (0..ns)
        .map(|k| viewer_error(&viewer, case.samples[k], &posed[k], diagonal))
        .fold(0.0f64, f64::max);
    assert!(
        worst > 1e-3,
        "{} {}: plain export only {worst:e} off",
        case.name,
        case.method
    );
}

#[test]
fn baked_dqs_fox_walk_matches_animate_at_the_samples() {
    check(&fox("dqs"));
}

#[test]
fn baked_cor_fox_walk_matches_animate_at_the_samples() {
    check(&fox("cor"));
}

#[test]
fn baked_dqs_and_cor_arm_match_animate_at_the_samples() {
    check(&arm("dqs"));
    check(&arm("cor"));
}

#[test]
fn baked_maya_blended_skin_matches_animate_at_the_samples() {
    check(&maya_blended());
}

/// As glTF text (.gltf + .bin): the same skin at a sample; cagerig reads the file back with
/// the baked targets left out (a note), keeping the cage keys as a cage track.
#[test]
fn baked_text_gltf_reads_back_into_cagerig() {
    let case = arm("dqs");
    let dir = temp_dir("arm-text");
    let (posed, diagonal) = animate(&case, &dir, &[2.0]);
    let (file, _, _) = export(&case, &dir, true, "gltf");
    let viewer = common::ReferenceGltf::load(&file);
    let e = viewer_error(&viewer, 2.0, &posed[0], diagonal);
    assert!(e <= 1e-5, "{e:e}");
    let (_, stderr) = run_ok_with_stderr(
        cagerig()
            .arg("animate")
            .arg(&file)
            .args(["--animation", "0", "--skinning", "dqs", "--times", "2"])
            .arg("--out")
            .arg(dir.join("again")),
    );
    assert!(
        stderr.contains("301 of the 304 morph targets hold a baked DQS result"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("not a deformation of the cage"),
        "{stderr}"
    );
    let again = positions(&dir.join("again/t2_mesh_posed.obj"));
    let e = cagerig::mesh::max_distance(&again, &posed[0]) / diagonal;
    assert!(e <= 1e-5, "reimported and played: {e:e}");
}

/// `--bake` needs an animation; under LBS it adds nothing (a note says so).
#[test]
fn bake_without_animation_is_refused_and_under_lbs_adds_nothing() {
    let dir = temp_dir("refused");
    let out = cagerig()
        .arg("export")
        .arg(data("arm/arm.obj"))
        .args(["--skinning", "dqs", "--bake"])
        .arg("--out")
        .arg(dir.join("a.glb"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--bake") && err.contains("--animation"),
        "{err}"
    );
    assert!(!dir.join("a.glb").exists());
    let case = fox("lbs");
    let (file, said, noted) = export(&case, &dir, true, "glb");
    assert!(
        noted.contains("nothing to bake") && !said.contains("morph targets"),
        "{noted}"
    );
    let (document, _, _) = gltf::import(&file).unwrap();
    let targets = document
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap()
        .morph_targets()
        .count();
    assert_eq!(targets, 0);
}

/// Blender's glTF importer (when `blender` is on PATH) shows the baked DQS skin at a sample.
#[test]
fn blender_reads_the_baked_fox() {
    let found = Command::new("blender").arg("--version").output();
    if !found.is_ok_and(|o| o.status.success()) {
        eprintln!("blender not found: Blender read-back skipped");
        return;
    }
    let case = fox("dqs");
    let dir = temp_dir("blender");
    let (posed, diagonal) = animate(&case, &dir, &[0.5]);
    let (file, _, _) = export(&case, &dir, true, "glb");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender_read_baked.py");
    let posed_obj = dir.join("fox-dqs-animate/t0.5_mesh_posed.obj");
    let (stdout, _) = run_ok_with_stderr(
        Command::new("blender")
            .args(["-b", "--factory-startup", "--python"])
            .arg(&script)
            .arg("--")
            .arg(&file)
            .arg(&posed_obj)
            .arg("0.5"),
    );
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("BLENDER "))
        .unwrap_or_else(|| panic!("no BLENDER line: {stdout}"));
    let v: serde_json::Value = serde_json::from_str(line).unwrap();
    assert_eq!(v["vertices"], posed[0].len(), "{v}");
    assert!(v["shape_keys"].as_u64().unwrap() > 1, "{v}");
    let e = v["worst"].as_f64().unwrap() / diagonal;
    eprintln!("Blender at t = 0.5: {e:.2e} of the diagonal");
    assert!(e <= 1e-5, "Blender: {e:e} of the diagonal");
}
