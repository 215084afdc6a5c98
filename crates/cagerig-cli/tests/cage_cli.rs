//! End-to-end tests of `cagerig cage`: a validated cage is written only with `--out`, `info`
//! runs the same validator on it, bad targets fail with a clear reason and write nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

fn cagerig() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cagerig"))
}

fn arm() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/arm/arm.obj")
}

#[test]
fn cage_writes_a_validated_cage_that_info_accepts() {
    let dir = std::env::temp_dir().join(format!("cagerig-cage-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out_path = dir.join("arm_auto.obj");
    let out = cagerig()
        .arg("cage")
        .arg(arm())
        .args(["--vertices", "40", "--json", "--out"])
        .arg(&out_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["passed"], true);
    assert_eq!(v["cage"]["cage_vertices"], 40);
    assert!(v["cage"]["min_distance_fraction"].as_f64().unwrap() >= 0.005);
    assert!(v["cage"]["maxvol_condition"].as_f64().unwrap().is_finite());
    let checks = v["cage"]["checks"].as_array().unwrap();
    assert!(checks.iter().any(|c| c["name"] == "coordinates"));
    let cage = cagerig::io::read_obj(&out_path).unwrap();
    assert_eq!(cage.num_vertices(), 40);
    let info = cagerig()
        .arg("info")
        .arg(arm())
        .arg("--cage")
        .arg(&out_path)
        .arg("--json")
        .output()
        .unwrap();
    assert!(info.status.success());
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    let checks = v["cage_checks"]["checks"].as_array().unwrap();
    assert!(checks.iter().all(|c| c["passed"] == true), "{checks:?}");
    // Too small a target: a clear error, nothing written.
    let bad_path = dir.join("bad.obj");
    let bad = cagerig()
        .arg("cage")
        .arg(arm())
        .args(["--vertices", "3", "--out"])
        .arg(&bad_path)
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("at least 8 vertices"));
    assert!(!bad_path.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
