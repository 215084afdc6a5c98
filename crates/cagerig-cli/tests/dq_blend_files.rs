//! DQ blend weights (the `blended` skinning method) in the paper tool's file set: an OBJ rig
//! picks up `<stem>_dqBlendWeights.txt` beside the mesh, `subdivide` carries the weights to the
//! new vertices (the mean of their edge's endpoints) and writes them with the rig, and the
//! written rig poses with `--skinning blended` as the original does at its own vertices.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::Path;

use support::{arm_dir, cagerig, run_ok_with_stderr, stderr, temp_dir};

/// The Arm's files and a blend-weights file (b_i = (i mod 11) / 10 on every third vertex) in `dir`.
fn arm_with_blend_weights(dir: &Path) -> Vec<f64> {
    for f in ["arm.obj", "arm.skt", "arm.skw", "arm_cage.obj"] {
        std::fs::copy(arm_dir().join(f), dir.join(f)).unwrap();
    }
    let nv = cagerig::io::read_obj(&dir.join("arm.obj"))
        .unwrap()
        .num_vertices();
    let values: Vec<f64> = (0..nv)
        .map(|i| {
            if i % 3 == 0 {
                (i % 11) as f64 / 10.0
            } else {
                0.0
            }
        })
        .collect();
    let text: String = values
        .iter()
        .enumerate()
        .filter(|(_, b)| **b != 0.0)
        .map(|(i, b)| format!("{i} {b}\n"))
        .collect();
    std::fs::write(dir.join("arm_dqBlendWeights.txt"), text).unwrap();
    values
}

/// `cagerig animate RIG --skinning METHOD` at t = 1 of the Arm's skeleton animation: the posed
/// skin, or the error text.
fn posed(rig: &Path, method: &str, out: &Path) -> Result<Vec<glam::DVec3>, String> {
    let output = cagerig()
        .arg("animate")
        .arg(rig)
        .arg("--skeleton-anim")
        .arg(arm_dir().join("arm_skelAnim.txt"))
        .args(["--times", "1", "--skinning", method, "--force", "--out"])
        .arg(out)
        .output()
        .unwrap();
    if !output.status.success() {
        return Err(stderr(&output));
    }
    Ok(cagerig::io::read_obj(&out.join("t1_mesh_posed.obj"))
        .unwrap()
        .positions)
}

#[test]
fn blend_weights_are_read_beside_the_mesh_carried_by_subdivide_and_pose_the_written_rig() {
    let dir = temp_dir("dq-blend-files");
    let values = arm_with_blend_weights(&dir);
    let rig = dir.join("arm.obj");
    let blended = posed(&rig, "blended", &dir.join("anim-blended")).unwrap();
    let lbs = posed(&rig, "lbs", &dir.join("anim-lbs")).unwrap();
    let apart = cagerig::mesh::max_distance(&blended, &lbs);
    assert!(apart > 1e-3, "blended is LBS: {apart:e}");

    let sub = dir.join("sub");
    run_ok_with_stderr(
        cagerig()
            .arg("subdivide")
            .arg(&rig)
            .args(["--levels", "1", "--out"])
            .arg(&sub),
    );
    let written = sub.join("rig_dqBlendWeights.txt");
    assert!(written.is_file(), "no {}", written.display());
    let mesh = cagerig::io::read_obj(&rig).unwrap();
    let (weights, _) =
        cagerig::io::read_skw(&dir.join("arm.skw"), mesh.num_vertices(), 25).unwrap();
    let expected = cagerig::subdivide::subdivide_midpoint(&mesh, &weights, 1).unwrap();
    let nv = expected.mesh.num_vertices();
    let carried = cagerig::io::read_dq_blend_weights(&written, nv).unwrap();
    assert_eq!(&carried.values()[..values.len()], &values[..]);
    for (k, [a, b]) in expected.edge_parents.iter().enumerate() {
        let mean = 0.5 * (carried.values()[*a as usize] + carried.values()[*b as usize]);
        assert_eq!(carried.values()[values.len() + k], mean, "new vertex {k}");
    }

    // The written rig poses with the blend at the original vertices as the original rig does
    // (the same weights, transforms and blend there).
    let sub_blended = posed(&sub.join("rig.obj"), "blended", &dir.join("sub-blended")).unwrap();
    let d = {
        let (lo, hi) = cagerig::mesh::bounding_box(&blended);
        (hi - lo).length()
    };
    let off = cagerig::mesh::max_distance(&sub_blended[..blended.len()], &blended);
    assert!(off <= 1e-9 * d, "{off:e}");

    // Without the file the rig has no blend weights, and says what to give.
    std::fs::remove_file(sub.join("rig_dqBlendWeights.txt")).unwrap();
    let refused = posed(&sub.join("rig.obj"), "blended", &dir.join("sub-none")).unwrap_err();
    assert!(refused.contains("blend"), "{refused}");
}

#[test]
fn a_bad_blend_weights_file_is_named_with_its_line() {
    let dir = temp_dir("dq-blend-bad");
    arm_with_blend_weights(&dir);
    std::fs::write(dir.join("arm_dqBlendWeights.txt"), "0 0.5\n3 1.5\n").unwrap();
    let refused = posed(&dir.join("arm.obj"), "lbs", &dir.join("anim")).unwrap_err();
    assert!(refused.contains("arm_dqBlendWeights.txt:2:"), "{refused}");
    assert!(refused.contains("[0, 1]"), "{refused}");
}
