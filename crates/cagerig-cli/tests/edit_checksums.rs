//! `cagerig edit` on the Arm writes byte-identical files from one version to the next: the
//! checksums of every output file (the README's script `examples/edits.json`, under LBS→DQS as
//! written and with `--skinning cor`) are kept in `tests/data/arm_edit_checksums.txt`. A change
//! that moves any output by one bit fails here; when the change is deliberate, the failure prints
//! the new list to paste into that file, and the commit says why the outputs changed.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::Command;

/// 64-bit FNV-1a.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

#[test]
fn edit_on_the_arm_writes_the_recorded_bytes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::temp_dir().join(format!("cagerig-checksums-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut lines = Vec::new();
    for (label, extra) in [("as-written", None), ("cor", Some("cor"))] {
        let out = dir.join(label);
        let mut command = Command::new(env!("CARGO_BIN_EXE_cagerig"));
        command
            .arg("edit")
            .arg(root.join("data/arm/arm.obj"))
            .arg("--script")
            .arg(root.join("examples/edits.json"))
            .arg("--out")
            .arg(&out);
        if let Some(method) = extra {
            command.args(["--skinning", method]);
        }
        let o = command.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.'))
            .collect();
        names.sort();
        for name in names {
            let bytes = std::fs::read(out.join(&name)).unwrap();
            lines.push(format!("{label}/{name} {:016x}", fnv1a(&bytes)));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    let actual = lines.join("\n") + "\n";
    let recorded = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/arm_edit_checksums.txt"),
    )
    .unwrap();
    assert!(
        actual == recorded,
        "the outputs of `cagerig edit` on the Arm changed; if deliberate, record:\n{actual}"
    );
}
