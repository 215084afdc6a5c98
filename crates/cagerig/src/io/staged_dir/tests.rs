//! The staging policy: complete or absent, replace only earlier outputs, clean up after kills.

use super::*;

const OUT: FolderNaming = FolderNaming {
    folder: "--out",
    replace_option: Some("--force"),
};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cagerig-staged-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn complete_or_absent() {
    let root = scratch("complete");
    let out = root.join("out");
    let mut d = StagedDir::create(&out, false, OUT).unwrap();
    d.write("step0_joints.json", &|w| w.write_all(b"[]"))
        .unwrap();
    assert!(!out.exists(), "nothing visible before finish");
    assert_eq!(d.finish().unwrap(), 1);
    assert_eq!(entries(&out), [MANIFEST_FILE, "step0_joints.json"]);
    assert_eq!(entries(&root), ["out"]);

    // A failed run leaves the earlier output untouched and no staging folder.
    {
        let mut d = StagedDir::create(&out, true, OUT).unwrap();
        d.write("step0_joints.json", &|w| w.write_all(b"[1]"))
            .unwrap();
        assert!(
            d.write("step1_joints.json", &|_| Err(std::io::Error::other(
                "disk full"
            )))
            .is_err()
        );
    }
    assert_eq!(entries(&root), ["out"]);
    assert_eq!(std::fs::read(out.join("step0_joints.json")).unwrap(), b"[]");

    // Non-empty without --force: refused. With --force: replaced, no stale files.
    assert!(StagedDir::create(&out, false, OUT).is_err());
    let mut d = StagedDir::create(&out, true, OUT).unwrap();
    d.write("step5_mesh_rest.obj", &|w| w.write_all(b""))
        .unwrap();
    d.finish().unwrap();
    assert_eq!(entries(&out), [MANIFEST_FILE, "step5_mesh_rest.obj"]);
    assert_eq!(entries(&root), ["out"]);

    // Foreign files are never deleted, even with --force.
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let e = StagedDir::create(&out, true, OUT).err().unwrap();
    assert!(e.to_string().contains("notes.txt"), "{e}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// Regression: `--force` replaced a folder holding only the user's PNGs, and refused an
/// earlier output holding `generated_cage.obj`.
#[test]
fn force_replaces_only_what_an_earlier_run_wrote() {
    let root = scratch("force");
    let pictures = root.join("pictures");
    std::fs::create_dir_all(&pictures).unwrap();
    std::fs::write(pictures.join("holiday.png"), b"mine").unwrap();
    let e = StagedDir::create(&pictures, true, OUT).err().unwrap();
    assert!(e.to_string().contains("holiday.png"), "{e}");
    assert!(pictures.join("holiday.png").exists());

    let out = root.join("out");
    for run in 0..2 {
        let mut d = StagedDir::create(&out, run > 0, OUT).unwrap();
        d.write("generated_cage.obj", &|w| w.write_all(b"v 0 0 0\n"))
            .unwrap();
        d.write("step0.png", &|w| w.write_all(b"png")).unwrap();
        d.finish().unwrap();
    }
    assert_eq!(
        entries(&out),
        [MANIFEST_FILE, "generated_cage.obj", "step0.png"]
    );
    // A file the user added is not in the manifest: refused.
    std::fs::write(out.join("notes.png"), b"mine").unwrap();
    assert!(StagedDir::create(&out, true, OUT).is_err());
    std::fs::remove_dir_all(&root).unwrap();
}

/// Regression: the moved-aside `.partial-<pid>.old` name never parsed as a PID, so it was
/// never removed, and a kill between the two renames lost `--out`.
#[test]
fn an_earlier_output_moved_aside_by_a_killed_run_is_put_back() {
    let root = scratch("aside");
    let out = root.join("out");
    let aside = root.join(".out.partial-4294967.old");
    std::fs::create_dir_all(&aside).unwrap();
    std::fs::write(aside.join("step0_joints.json"), b"[]").unwrap();
    let stale = root.join(".other.partial-4294968.old");
    std::fs::create_dir_all(&stale).unwrap();
    let d = StagedDir::create(&out, true, OUT).unwrap();
    if Path::new("/proc/self").exists() {
        assert_eq!(entries(&out), ["step0_joints.json"]);
        assert!(!aside.exists());
        assert!(stale.exists(), "another target's folder is left alone");
    }
    drop(d);
    // With --out present, a dead run's moved-aside copy is just removed.
    std::fs::create_dir_all(&aside).unwrap();
    let d = StagedDir::create(&out, true, OUT).unwrap();
    assert!(!aside.exists() || !Path::new("/proc/self").exists());
    d.finish().unwrap();
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn abandoned_staging_of_dead_processes_is_removed() {
    let root = scratch("abandoned");
    let out = root.join("out");
    // PIDs are below 2^22 on Linux: this one cannot be alive.
    let dead = root.join(".out.partial-4294967");
    std::fs::create_dir_all(&dead).unwrap();
    let d = StagedDir::create(&out, false, OUT).unwrap();
    assert!(!dead.exists() || !Path::new("/proc/self").exists());
    d.finish().unwrap();
    std::fs::remove_dir_all(&root).unwrap();
}

/// Two outputs of one process into the same target (two threads of a Python program) stage
/// in two folders; the second to finish replaces the first.
#[test]
fn two_outputs_of_one_process_do_not_share_a_staging_folder() {
    let root = scratch("twice");
    let out = root.join("out");
    let mut a = StagedDir::create(&out, true, OUT).unwrap();
    let mut b = StagedDir::create(&out, true, OUT).unwrap();
    a.write("a_joints.json", &|w| w.write_all(b"[]")).unwrap();
    b.write("b_joints.json", &|w| w.write_all(b"[]")).unwrap();
    assert_eq!(entries(&root).len(), 2, "two staging folders");
    assert_eq!(a.finish().unwrap(), 1);
    assert_eq!(b.finish().unwrap(), 1);
    assert_eq!(entries(&out), [MANIFEST_FILE, "b_joints.json"]);
    assert_eq!(entries(&root), ["out"]);
    std::fs::remove_dir_all(&root).unwrap();
}

/// A front end with no replace option (the editor) names neither an option nor `--out`.
#[test]
fn messages_follow_the_front_end_naming() {
    let root = scratch("naming");
    let naming = FolderNaming {
        folder: "export folder",
        replace_option: None,
    };
    std::fs::write(root.join("notes.txt"), b"mine").unwrap();
    let e = StagedDir::create(&root, true, naming).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "export folder {} holds notes.txt, which this command did not write: refusing to \
             replace the folder; choose a new folder",
            root.display()
        )
    );
    let e = StagedDir::create(&root, false, OUT).unwrap_err();
    assert!(
        matches!(&e, StagedDirError::NotEmpty { count: 1, example, .. } if example == "notes.txt"),
        "{e:?}"
    );
    assert!(e.to_string().contains("give --force to replace"), "{e}");
    let file = root.join("notes.txt");
    assert!(matches!(
        StagedDir::create(&file, true, naming),
        Err(StagedDirError::NotAFolder { .. })
    ));
    let mut d = StagedDir::create(&root.join("out"), false, naming).unwrap();
    assert!(matches!(
        d.write(".hidden", &|_| Ok(())),
        Err(StagedDirError::BadFileName { .. })
    ));
    d.write("a.obj", &|_| Ok(())).unwrap();
    assert!(matches!(
        d.write("a.obj", &|_| Ok(())),
        Err(StagedDirError::DuplicateName { .. })
    ));
    std::fs::remove_dir_all(&root).unwrap();
}
