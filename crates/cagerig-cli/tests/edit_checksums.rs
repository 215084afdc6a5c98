//! `cagerig edit` on the Arm writes byte-identical files from one version to the next: the
//! checksums of every output file (the README's script `examples/edits.json`, under LBS→DQS as
//! written and with `--skinning cor`, with the paper's CageUp and with the regularised default)
//! are kept in `tests/data/arm_edit_checksums.<tier>.txt`, one list per SIMD tier of the CPU
//! (`avx512f`, `avx2`): the factorisations round differently on each. A change that moves any
//! output by one bit fails here; when the change is deliberate, the failure prints the new list
//! to paste into the tier's file, and the commit says why the outputs changed. A tier's file
//! may hold only some of the runs (those recorded on such a CPU); the runs it holds are
//! checked, and the paper's runs must be among them.

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
    for (label, extra, cage_fit) in [
        ("as-written", None, "paper"),
        ("cor", Some("cor"), "paper"),
        ("regularised", None, "regularised"),
        ("regularised-cor", Some("cor"), "regularised"),
    ] {
        let out = dir.join(label);
        let mut command = Command::new(env!("CARGO_BIN_EXE_cagerig"));
        command
            .arg("edit")
            .arg(root.join("data/arm/arm.obj"))
            .arg("--script")
            .arg(root.join("examples/edits.json"))
            .args(["--cage-fit", cage_fit])
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
    let tier = simd_tier();
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("tests/data/arm_edit_checksums.{tier}.txt"));
    let recorded = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "no checksums recorded for this CPU's tier ({}: {e}); record:\n{actual}",
            path.display()
        )
    });
    let runs: std::collections::BTreeSet<&str> = recorded
        .lines()
        .filter_map(|l| l.split('/').next())
        .collect();
    assert!(
        runs.contains("as-written") && runs.contains("cor"),
        "{}: the paper's runs must be recorded",
        path.display()
    );
    let checked: String = lines
        .iter()
        .filter(|l| l.split('/').next().is_some_and(|run| runs.contains(run)))
        .map(|l| format!("{l}\n"))
        .collect();
    if checked.len() < actual.len() {
        eprintln!(
            "note: {} records only the runs {runs:?}; the others are not checked on this CPU",
            path.display()
        );
    }
    assert!(
        checked == recorded,
        "the outputs of `cagerig edit` on the Arm changed ({tier} tier); if deliberate, \
         record in {}:\n{actual}",
        path.display()
    );
}

/// The SIMD tier this CPU runs (`simd_dispatch`'s widest: avx512f, avx2 (with FMA), baseline).
fn simd_tier() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return "avx512f";
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return "avx2";
        }
    }
    "baseline"
}
