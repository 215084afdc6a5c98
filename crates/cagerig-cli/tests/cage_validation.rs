//! The cage is validated once, by the session of the commands that open one: an accepted mesh
//! outside the cage (`--allow-outside-cage`) is reported once per run, not once by the loader
//! and again by the session, and a refused one names the cage's file.

#![expect(clippy::unwrap_used)]

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::Path;

use support::{arm, arm_dir, cagerig, stderr, temp_dir};

/// The Arm's cage shrunk by 10 % towards its centroid, so that part of the arm is outside it.
fn shrunken_arm_cage(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(arm_dir().join("arm_cage.obj")).unwrap();
    let points = support::obj_vertices(&arm_dir().join("arm_cage.obj"));
    let n = points.len() as f64;
    let centre: Vec<f64> = (0..3)
        .map(|i| points.iter().map(|p| p[i]).sum::<f64>() / n)
        .collect();
    let mut next = points.iter();
    let shrunk: Vec<String> = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(_) => {
                let p = next.next().unwrap();
                let q: Vec<f64> = (0..3)
                    .map(|i| centre[i] + 0.9 * (p[i] - centre[i]))
                    .collect();
                format!("v {} {} {}", q[0], q[1], q[2])
            }
            None => l.to_string(),
        })
        .collect();
    let path = dir.join("small_cage.obj");
    std::fs::write(&path, shrunk.join("\n") + "\n").unwrap();
    path
}

#[test]
fn an_accepted_outside_mesh_is_reported_once_and_a_refused_one_names_the_cage() {
    let dir = temp_dir("outside-once");
    let cage = shrunken_arm_cage(&dir);
    let animation = arm_dir().join("arm_skelAnim.txt");
    let runs: [(&str, Vec<std::ffi::OsString>); 2] = [
        (
            "animate",
            vec![
                "--skeleton-anim".into(),
                animation.clone().into(),
                "--times".into(),
                "0.5".into(),
                "--out".into(),
                dir.join("animated").into(),
            ],
        ),
        ("export", vec!["--out".into(), dir.join("arm.glb").into()]),
    ];
    for (command, extra) in &runs {
        let refused = cagerig()
            .arg(command)
            .arg(arm())
            .arg("--cage")
            .arg(&cage)
            .args(extra)
            .output()
            .unwrap();
        let err = stderr(&refused);
        assert!(!refused.status.success(), "{command}: {err}");
        assert!(
            err.contains("small_cage.obj") && err.contains("outside the cage"),
            "{command}: {err}"
        );
        let accepted = cagerig()
            .arg(command)
            .arg(arm())
            .arg("--cage")
            .arg(&cage)
            .arg("--allow-outside-cage")
            .args(extra)
            .output()
            .unwrap();
        let err = stderr(&accepted);
        assert!(accepted.status.success(), "{command}: {err}");
        assert_eq!(
            err.matches("outside the cage").count(),
            1,
            "{command} reports the accepted outside vertices once: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
