//! Set-up shared by the CLI's integration tests: the binary under test, the repository's sample
//! data, fresh temporary folders and commands that must succeed. Each test file uses its part.

#![expect(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `cagerig` binary built for these tests.
pub fn cagerig() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cagerig"))
}

/// The repository's root folder.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A file or folder under the repository's `data/`.
pub fn data(rel: &str) -> PathBuf {
    repo().join("data").join(rel)
}

/// The paper's Arm rig folder, `data/arm`.
pub fn arm_dir() -> PathBuf {
    data("arm")
}

/// The Arm's mesh, `data/arm/arm.obj` (its rig files lie beside it).
pub fn arm() -> PathBuf {
    data("arm/arm.obj")
}

/// A new empty folder for one test: named after the test file, `name` and the process, so
/// that test files and parallel runs never share one.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "cagerig-{}-{name}-{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A command's standard error as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Runs `cmd`, failing the test with its standard error unless it succeeds; returns
/// (standard output, standard error).
pub fn run_ok_with_stderr(cmd: &mut Command) -> (String, String) {
    let output = cmd.output().unwrap();
    let err = stderr(&output);
    assert!(output.status.success(), "{err}");
    (String::from_utf8(output.stdout).unwrap(), err)
}

/// Runs `cmd`, failing the test with its standard error unless it succeeds; returns its
/// standard output.
pub fn run_ok(cmd: &mut Command) -> String {
    run_ok_with_stderr(cmd).0
}

/// The `v x y z` points of an OBJ file, in order.
pub fn obj_vertices(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|rest| {
            let v: Vec<f64> = rest
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}
