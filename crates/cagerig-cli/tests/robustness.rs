//! Malformed input through the commands, one test per defect: every case gives a correct result
//! or a clear error (file, line or element, expected, found), never exit 0 with a non-finite
//! number, stale or partial output.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::{Path, PathBuf};
use std::process::Output;
use support::{arm_dir, cagerig, stderr, temp_dir};

/// A private copy of the Arm rig in `dir/arm`, with `edit` applied to the text of `file`.
fn arm_copy(dir: &Path, file: &str, edit: impl FnOnce(String) -> String) -> PathBuf {
    let rig = dir.join("arm");
    std::fs::create_dir_all(&rig).unwrap();
    for entry in std::fs::read_dir(arm_dir()).unwrap() {
        let entry = entry.unwrap();
        if entry.path().is_file() {
            std::fs::copy(entry.path(), rig.join(entry.file_name())).unwrap();
        }
    }
    let path = rig.join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, edit(text)).unwrap();
    rig.join("arm.obj")
}

fn run(args: &[&str], paths: &[(&str, &Path)]) -> Output {
    let mut c = cagerig();
    c.args(args);
    for (flag, p) in paths {
        if !flag.is_empty() {
            c.arg(flag);
        }
        c.arg(p);
    }
    c.output().unwrap()
}

/// Asserts a clean failure: exit 1 (not a panic), one `error:` line holding every needle.
fn assert_error(o: &Output, needles: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    for n in needles {
        assert!(e.contains(n), "expected {n:?} in: {e}");
    }
}

fn edit_script(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("edits.json");
    std::fs::write(&p, text).unwrap();
    p
}

const SMALL_SCRIPT: &str =
    r#"{"steps":[{"op":"rotate_joint","joint":3,"axis":[1,0,0],"degrees":30}]}"#;

fn edit(mesh: &Path, script: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut c = cagerig();
    c.arg("edit")
        .arg(mesh)
        .arg("--script")
        .arg(script)
        .arg("--out")
        .arg(out)
        .args(extra);
    c.output().unwrap()
}

#[test]
fn overflowing_values_are_rejected_with_file_line_and_value() {
    let dir = temp_dir("overflow");
    /// (file, mutation, expected location in the error)
    type Case = (&'static str, fn(String) -> String, &'static str);
    let cases: [Case; 4] = [
        (
            "arm.skt",
            |t| t.replacen("-23.712885 132.778816", "1e308 132.778816", 1),
            "arm.skt:4",
        ),
        (
            "arm.skw",
            |t| t.replacen("1 0 0.301943", "1 0 1e308", 1),
            "arm.skw:2",
        ),
        (
            "arm_cage_cageWeights.txt",
            |t| t.replacen("1 0 0.002031", "1 0 1e308", 1),
            "arm_cage_cageWeights.txt:2",
        ),
        (
            "arm_cageAnim.txt",
            |t| t.replacen("c 0 0.000000", "c 0 -1e308", 1),
            "arm_cageAnim.txt:",
        ),
    ];
    for (file, mutate, location) in cases {
        let case = dir.join(file);
        let mesh = arm_copy(&case, file, mutate);
        let out = case.join("out");
        let o = if file == "arm_cageAnim.txt" {
            let anim = mesh.with_file_name("arm_cageAnim.txt");
            let mut c = cagerig();
            c.arg("animate").arg(&mesh).arg("--cage-anim").arg(&anim);
            c.args(["--times", "0.5,2"]).arg("--out").arg(&out);
            c.output().unwrap()
        } else {
            edit(&mesh, &edit_script(&case, SMALL_SCRIPT), &out, &[])
        };
        assert_error(&o, &[location, "1e308", "1e12"]);
        assert!(!out.exists(), "{file}: output written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn skt_index_column_is_honoured() {
    let dir = temp_dir("skt-index");
    let swap = |t: String| {
        let mut lines: Vec<&str> = t.lines().collect();
        let a = lines.iter().position(|l| l.starts_with("j 5 ")).unwrap();
        let b = lines.iter().position(|l| l.starts_with("j 6 ")).unwrap();
        lines.swap(a, b);
        lines.join("\n") + "\n"
    };
    let swapped = arm_copy(&dir.join("swapped"), "arm.skt", swap);
    let original = arm_copy(&dir.join("original"), "arm.skt", |t| t);
    let script = edit_script(
        &dir,
        r#"{"steps":[{"op":"move_rest_cage","vertices":[3],"offset":[0,2,0]}]}"#,
    );
    let (a, b) = (dir.join("a"), dir.join("b"));
    assert!(edit(&original, &script, &a, &[]).status.success());
    let o = edit(&swapped, &script, &b, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(a.join("step1_joints.json")).unwrap(),
        std::fs::read(b.join("step1_joints.json")).unwrap()
    );
    // A repeated index is an error naming the line.
    let dup = arm_copy(&dir.join("dup"), "arm.skt", |t| {
        t.replacen("j 6 ", "j 5 ", 1)
    });
    assert_error(&run(&["info"], &[("", &dup)]), &["arm.skt:", "used twice"]);
    let own = arm_copy(&dir.join("own"), "arm.skt", |t| {
        t.replacen("j 4 lowerarm02.R 3 ", "j 4 lowerarm02.R 4 ", 1)
    });
    assert_error(
        &run(&["info"], &[("", &own)]),
        &["arm.skt:", "itself as its father"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn faceless_and_truncated_meshes_are_reported() {
    let dir = temp_dir("mesh");
    let faceless = arm_copy(&dir.join("faceless"), "arm.obj", |t| {
        t.lines()
            .filter(|l| !l.starts_with("f "))
            .collect::<Vec<_>>()
            .join("\n")
    });
    assert_error(&run(&["info"], &[("", &faceless)]), &["arm.obj", "no face"]);
    let truncated = arm_copy(&dir.join("truncated"), "arm.obj", |t| {
        let first_face = t.find("\nf ").unwrap();
        let cut = first_face + (t.len() - first_face) / 2;
        let end = t[cut..].find('\n').unwrap() + cut;
        t[..end].to_string()
    });
    let o = run(&["info", "--json"], &[("", &truncated)]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("used by no face"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn one_cage_validation_for_every_command() {
    let dir = temp_dir("cage");
    // Scale the cage by 0.5 about the origin: the mesh pokes out.
    let small = arm_copy(&dir.join("small"), "arm_cage.obj", |t| {
        t.lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(rest) => {
                    let v: Vec<f64> = rest
                        .split_whitespace()
                        .map(|x| x.parse().unwrap())
                        .collect();
                    format!("v {} {} {}", v[0] * 0.5, v[1] * 0.5, v[2] * 0.5)
                }
                None => l.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n")
    });
    let phi = dir.join("phi.txt");
    let rows = dir.join("rows.maxvol");
    let sub = dir.join("sub");
    for o in [
        run(&["coords"], &[("", &small), ("--out", &phi)]),
        run(&["maxvol"], &[("", &small), ("--out", &rows)]),
        run(&["subdivide"], &[("", &small), ("--out", &sub)]),
        edit(
            &small,
            &edit_script(&dir, SMALL_SCRIPT),
            &dir.join("e"),
            &[],
        ),
    ] {
        assert_error(
            &o,
            &["arm_cage.obj", "outside the cage", "farthest: vertex"],
        );
    }
    // The error names the flag that accepts it.
    assert_error(
        &run(&["coords"], &[("", &small), ("--out", &phi)]),
        &["--allow-outside-cage"],
    );
    let o = run(
        &["coords", "--allow-outside-cage"],
        &[("", &small), ("--out", &phi)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("outside the cage"));
    // With the flag, edit warns once, in one line of plain text (no `\` nor a run of spaces).
    let o = edit(
        &small,
        &edit_script(&dir, SMALL_SCRIPT),
        &dir.join("accepted"),
        &["--allow-outside-cage"],
    );
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert_eq!(e.matches("outside the cage").count(), 1, "{e}");
    let line = e.lines().find(|l| l.contains("outside the cage")).unwrap();
    assert!(!line.contains('\\') && !line.contains("   "), "{line}");
    assert!(line.contains("from it); accepted as asked"), "{line}");
    // An open cage: the same error from coords as from edit.
    let open = arm_copy(&dir.join("open"), "arm_cage.obj", |t| {
        let k = t.find("\nf ").unwrap();
        let end = t[k + 1..].find('\n').unwrap() + k + 1;
        format!("{}{}", &t[..k], &t[end..])
    });
    for o in [
        run(&["coords"], &[("", &open), ("--out", &phi)]),
        edit(&open, &edit_script(&dir, SMALL_SCRIPT), &dir.join("e"), &[]),
    ] {
        assert_error(&o, &["arm_cage.obj", "open boundary"]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn repeated_script_vertices_are_refused() {
    let dir = temp_dir("repeat");
    let script = edit_script(
        &dir,
        r#"{"steps":[{"op":"move_rest_cage","vertices":[2,2,2],"offset":[1,0,0]}]}"#,
    );
    let out = dir.join("out");
    let mesh = arm_dir().join("arm.obj");
    assert_error(
        &edit(&mesh, &script, &out, &[]),
        &["step 1", "listed 3 times"],
    );
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn animate_times_each_once_and_negative_allowed() {
    let dir = temp_dir("times");
    let mesh = arm_dir().join("arm.obj");
    let anim = arm_dir().join("arm_skelAnim.txt");
    let out = dir.join("out");
    let o = run(
        &["animate", "--times", "1,1.0,1.00"],
        &[("", &mesh), ("--skeleton-anim", &anim), ("--out", &out)],
    );
    assert_error(&o, &["--times", "twice"]);
    assert!(!out.exists());
    let o = run(
        &["animate", "--times", "-5,1"],
        &[("", &mesh), ("--skeleton-anim", &anim), ("--out", &out)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    // Five files per state for two times, and the output manifest.
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 11);
    assert!(out.join("t-5_mesh_posed.obj").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn shipped_arm_cage_edit_moves_only_what_it_touches() {
    let dir = temp_dir("arm-phi");
    let script = edit_script(
        &dir,
        r#"{"steps":[{"op":"move_rest_cage","vertices":[7],"offset":[0,0.5,0]}]}"#,
    );
    let mesh = arm_dir().join("arm.obj");
    let max_jump = |out: &Path| {
        let read = |f: &str| cagerig::io::read_obj(&out.join(f)).unwrap().positions;
        let (a, b) = (read("step0_cage_posed.obj"), read("step1_cage_posed.obj"));
        (0..a.len())
            .filter(|&k| k != 7)
            .map(|k| a[k].distance(b[k]))
            .fold(0.0, f64::max)
    };
    let out = dir.join("default");
    let o = edit(&mesh, &script, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("recomputed"), "{}", stderr(&o));
    let jump = max_jump(&out);
    assert!(
        jump < 1e-8,
        "untouched current-cage vertices moved by {jump}"
    );
    // The tool's Φ, kept on request: the documented jump of the 6 decimals.
    let kept = dir.join("kept");
    assert!(
        edit(&mesh, &script, &kept, &["--keep-file-coords"])
            .status
            .success()
    );
    assert!(max_jump(&kept) > 1e-4);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn output_is_complete_or_absent_and_never_stale() {
    let dir = temp_dir("stale");
    let mesh = arm_dir().join("arm.obj");
    let out = dir.join("out");
    let two = edit_script(
        &dir,
        r#"{"steps":[{"op":"reset_pose"},{"op":"reset_pose"}]}"#,
    );
    assert!(edit(&mesh, &two, &out, &[]).status.success());
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 16);
    // Non-empty --out: refused without --force, untouched.
    assert_error(&edit(&mesh, &two, &out, &[]), &["--force"]);
    let one = edit_script(&dir, r#"{"steps":[{"op":"reset_pose"}]}"#);
    assert!(edit(&mesh, &one, &out, &["--force"]).status.success());
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        11,
        "stale step2 files"
    );
    // A run failing at its second step leaves the earlier output and nothing else.
    let failing = edit_script(
        &dir,
        r#"{"steps":[{"op":"reset_pose"},{"op":"move_posed_cage","vertices":[0],"offset":[1e13,0,0]}]}"#,
    );
    let o = edit(&mesh, &failing, &out, &["--force"]);
    assert_error(&o, &["step 2"]);
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 11);
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.contains("partial")), "{names:?}");
    // Foreign files are never deleted.
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    assert_error(&edit(&mesh, &one, &out, &["--force"]), &["notes.txt"]);
    assert!(out.join("notes.txt").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn subdivide_name_cannot_escape_and_huge_requests_are_refused_up_front() {
    let dir = temp_dir("escape");
    let mesh = arm_dir().join("arm.obj");
    let out = dir.join("out");
    let o = run(
        &["subdivide", "--name", "../escaped"],
        &[("", &mesh), ("--out", &out)],
    );
    assert_error(&o, &["--name", "path separator"]);
    assert!(!dir.join("escaped.obj").exists());
    let start = std::time::Instant::now();
    for args in [
        vec![
            "subdivide",
            "--levels",
            "8",
            "--out",
            out.to_str().unwrap(),
            mesh.to_str().unwrap(),
        ],
        vec!["bench", "--subdivide", "8", mesh.to_str().unwrap()],
        vec![
            "demo",
            "--builtin",
            "snake",
            "--resolution",
            "10000000",
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let o = cagerig().args(&args).output().unwrap();
        assert_error(&o, &["GiB", "would need"]);
    }
    // Refused before any work (each run is a load of the Arm, not a subdivision).
    assert!(start.elapsed().as_secs() < 30);
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn json_errors_are_json_and_script_errors_print_once() {
    let dir = temp_dir("json");
    let missing = dir.join("missing.obj");
    let o = run(&["info", "--json"], &[("", &missing)]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["error"].as_str().unwrap().contains("missing.obj"));
    let script = edit_script(
        &dir,
        r#"{"steps":[{"op":"rotate_joint","joint":{"x":1},"axis":[1,0,0],"degrees":1}]}"#,
    );
    let o = run(
        &["edit", "--builtin", "bar", "--script"],
        &[("", &script), ("--out", &dir.join("o"))],
    );
    let e = stderr(&o);
    assert_error(
        &o,
        &[
            "edits.json",
            "step 1",
            "joint name or a non-negative integer",
        ],
    );
    assert!(!e.contains("untagged"), "{e}");
    assert_eq!(e.matches("step 1").count(), 1, "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn readme_example_runs_on_the_arm_and_the_bar_and_help_lists_operations() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/edits.json");
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md")).unwrap();
    assert!(
        readme.contains("examples/edits.json"),
        "the README names its example script"
    );
    let dir = temp_dir("readme");
    let arm = arm_dir().join("arm.obj");
    let o = edit(&arm, &script, &dir.join("arm"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(
        &["edit", "--builtin", "bar", "--script"],
        &[("", &script), ("--out", &dir.join("bar"))],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let fox = arm_dir().join("../fox");
    let o = run(
        &["edit", "--script"],
        &[
            ("", &script),
            ("", &fox.join("Fox.glb")),
            ("--cage", &fox.join("Fox_cage.obj")),
            ("--out", &dir.join("fox")),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let help = cagerig().args(["edit", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    for op in [
        "rotate_joint",
        "move_rest_cage",
        "move_posed_cage",
        "set_skinning",
        "reset_pose",
    ] {
        assert!(help.contains(op), "{op} missing from edit --help");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Regression: `cagerig … | head` panicked with "failed printing to stdout: Broken pipe".
#[test]
fn a_closed_stdout_pipe_ends_quietly() {
    for _ in 0..3 {
        let mut child = cagerig()
            .args(["info", "--builtin", "bar"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader goes away before anything is printed
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !err.contains("panicked") && !err.contains("Broken pipe"),
            "{err}"
        );
        assert_ne!(o.status.code(), Some(101), "{err}");
    }
}

/// The usage line says a rig source is required: MESH or --builtin, not an optional MESH.
#[test]
fn usage_names_mesh_or_builtin_as_required() {
    let o = cagerig().args(["info"]).output().unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("<MESH|--builtin <BUILTIN>>"), "{err}");
    let both = cagerig()
        .args(["info", "x.obj", "--builtin", "bar"])
        .output()
        .unwrap();
    assert!(!both.status.success());
}

/// File outputs create their missing folders, as folder outputs do (the weights page's
/// `weights … --out out/arm5.skw` failed on a fresh clone without `out/`); a file standing where
/// a folder must be is named once, for single files and folder outputs alike.
#[test]
fn missing_output_folders_are_created_and_a_file_in_the_way_is_named_once() {
    let dir = temp_dir("output-folders");
    for (args, written) in [
        (
            vec!["cage", "--builtin", "bar", "--faces", "40"],
            "new/cage.obj",
        ),
        (vec!["export", "--builtin", "bar"], "new/deeper/bar.glb"),
        (vec!["render", "--builtin", "bar"], "new/bar.png"),
    ] {
        let out = dir.join(written);
        let o = run(&args, &[("--out", &out)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(out.is_file(), "{} not written", out.display());
    }
    let blocker = dir.join("blocker");
    std::fs::write(&blocker, "a file").unwrap();
    let expected = format!("{} is a file, not a folder", blocker.display());
    for (args, out) in [
        (
            vec!["cage", "--builtin", "bar", "--faces", "40"],
            "cage.obj",
        ),
        (vec!["export", "--builtin", "bar"], "bar.glb"),
        (vec!["render", "--builtin", "bar"], "bar.png"),
        (
            vec!["render", "--builtin", "bar", "--turntable", "2"],
            "spin",
        ),
    ] {
        let out = blocker.join(out);
        let o = run(&args, &[("--out", &out)]);
        assert_error(&o, &[&expected]);
        let e = stderr(&o);
        assert_eq!(e.matches(&*out.to_string_lossy()).count(), 1, "{e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A skeleton file with no joint is refused when it is read, naming that file (not the weights
/// read after it, whose joint indices then all look out of range).
#[test]
fn an_empty_skeleton_is_blamed_on_its_file() {
    let dir = temp_dir("empty-skt");
    let mesh = arm_copy(&dir, "arm.skt", |_| "# no joints\n".to_string());
    let skt = mesh.with_extension("skt");
    let o = run(&["info"], &[("", &mesh)]);
    assert_error(
        &o,
        &[
            &format!("{}: expected joint lines", skt.display()),
            "found no joint",
        ],
    );
    assert!(!stderr(&o).contains("arm.skw"), "{}", stderr(&o));
}

/// Weights made for another skeleton are refused (the 5-joint weights of the README on the
/// 25-joint Arm), naming both files and both joint counts; `--skeleton` pairs them with the
/// skeleton they were made for, for `edit` and `render` alike; a skeleton of as many joints
/// with other names is refused at the first differing joint.
#[test]
fn weights_of_another_skeleton_are_refused_unless_paired_with_it() {
    let dir = temp_dir("weights-skeleton");
    let five = support::repo().join("examples/arm-5-joints.skt");
    let skw = dir.join("arm5.skw");
    let o = run(
        &["weights"],
        &[
            ("", &support::arm()),
            ("--skeleton", &five),
            ("--out", &skw),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let header = std::fs::read_to_string(&skw).unwrap();
    assert!(
        header.starts_with("# joints (5): shoulder elbow wrist hand fingers\n"),
        "{}",
        &header[..80]
    );
    let script = edit_script(
        &dir,
        SMALL_SCRIPT.replace("\"joint\":3", "\"joint\":1").as_str(),
    );
    let arm_skt = support::arm().with_extension("skt");
    let expected = [
        format!(
            "{}:1: the weights were made for a skeleton of 5 joints",
            skw.display()
        ),
        format!("the rig's skeleton ({}) has 25 joints", arm_skt.display()),
    ];
    let expected: Vec<&str> = expected.iter().map(String::as_str).collect();
    let o = edit(
        &support::arm(),
        &script,
        &dir.join("refused"),
        &["--weights", skw.to_str().unwrap()],
    );
    assert_error(&o, &expected);
    assert!(!dir.join("refused").exists());
    let picture = dir.join("refused.png");
    let o = run(
        &["render", "--size", "64x48"],
        &[
            ("", &support::arm()),
            ("--weights", &skw),
            ("--out", &picture),
        ],
    );
    assert_error(&o, &expected);

    let o = edit(
        &support::arm(),
        &script,
        &dir.join("paired"),
        &[
            "--weights",
            skw.to_str().unwrap(),
            "--skeleton",
            five.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let joints = std::fs::read_to_string(dir.join("paired/step1_joints.json")).unwrap();
    assert_eq!(joints.matches("\"name\"").count(), 5, "{joints}");
    assert!(joints.contains("\"fingers\""), "{joints}");
    let picture = dir.join("paired.png");
    let o = run(
        &["render", "--size", "64x48"],
        &[
            ("", &support::arm()),
            ("--weights", &skw),
            ("--skeleton", &five),
            ("--out", &picture),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(picture.is_file());

    let renamed = dir.join("renamed.skt");
    let text = std::fs::read_to_string(&five).unwrap();
    std::fs::write(&renamed, text.replace(" wrist ", " carpus ")).unwrap();
    let o = edit(
        &support::arm(),
        &script,
        &dir.join("renamed"),
        &[
            "--weights",
            skw.to_str().unwrap(),
            "--skeleton",
            renamed.to_str().unwrap(),
        ],
    );
    assert_error(
        &o,
        &[&format!(
            "their joint 2 is \"wrist\", joint 2 of the rig's skeleton ({}) is \"carpus\"",
            renamed.display()
        )],
    );
}

/// A mesh file is read by its extension, checked against its content: an unknown extension is
/// refused with the formats that are read (OBJ text named `.stl` was read as OBJ, a `.ply` failed
/// with "found no vertex (`v`) line"), and a binary glTF named `.obj` is refused as what it is
/// (it failed with "line 1 is not valid UTF-8"), by every command that reads a mesh.
#[test]
fn a_mesh_file_is_refused_unless_its_extension_and_content_are_a_format_read() {
    let dir = temp_dir("mesh-formats");
    let formats = "expected a mesh in a format cagerig reads, OBJ (.obj), glTF (.glb, .gltf), \
                   FBX (.fbx); found the extension";
    let stl = dir.join("arm.stl");
    std::fs::copy(support::arm(), &stl).unwrap();
    let ply = dir.join("arm.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n",
    )
    .unwrap();
    let bare = dir.join("arm");
    std::fs::copy(support::arm(), &bare).unwrap();
    for (path, found) in [(&stl, " .stl"), (&ply, " .ply")] {
        let o = run(&["info"], &[("", path)]);
        assert_error(&o, &[&format!("{}: {formats}{found}", path.display())]);
    }
    let o = run(&["info"], &[("", &bare)]);
    assert_error(&o, &["found no extension"]);

    let glb_as_obj = dir.join("fox.obj");
    std::fs::copy(support::data("fox/Fox.glb"), &glb_as_obj).unwrap();
    let gltf_as_txt = dir.join("fox.txt");
    std::fs::write(&gltf_as_txt, "{\"asset\":{\"version\":\"2.0\"}}").unwrap();
    let binary_gltf = format!(
        "{}: the file is a binary glTF (it starts with `glTF`), not OBJ text: rename it .glb",
        glb_as_obj.display()
    );
    let out = dir.join("out.obj");
    for args in [
        vec!["info"],
        vec!["cage", "--out", out.to_str().unwrap()],
        vec!["weights", "--out", out.to_str().unwrap()],
    ] {
        let o = run(&args, &[("", &glb_as_obj)]);
        assert_error(&o, &[&binary_gltf]);
        assert!(!stderr(&o).contains("UTF-8"), "{}", stderr(&o));
    }
    let o = run(&["info"], &[("", &gltf_as_txt)]);
    assert_error(
        &o,
        &[
            formats,
            "(the file is JSON, as a glTF is (it starts with `{`): rename it .gltf)",
        ],
    );
    // The formats read still open (OBJ named in capitals too).
    let upper = dir.join("ARM.OBJ");
    std::fs::copy(support::arm(), &upper).unwrap();
    let o = run(
        &["cage", "--faces", "40", "--out", out.to_str().unwrap()],
        &[("", &upper)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
}

fn fox_walk(command: &str, times: &str, out: &Path) -> Output {
    let fox = support::data("fox/Fox.glb");
    let cage = support::data("fox/Fox_cage.obj");
    let mut args = vec![command, "--animation", "Walk", "--times", times];
    if command == "render" {
        args.extend(["--size", "64x48"]);
    }
    run(&args, &[("", &fox), ("--cage", &cage), ("--out", out)])
}

/// Times past the end of an animation show its last frame: said once per command, naming the
/// animation and its length (the Fox's Walk is 0.708 s); times within it say nothing.
#[test]
fn times_past_the_end_of_an_animation_are_warned_about_once() {
    let dir = temp_dir("times-past-end");
    let o = fox_walk("animate", "0.25,5,6", &dir.join("animated"));
    assert!(o.status.success(), "{}", stderr(&o));
    let warning = "warning: --times 5,6 are past the end of animation 'Walk' (0.708 s): the last \
                   frame is shown";
    assert_eq!(stderr(&o).matches(warning).count(), 1, "{}", stderr(&o));
    assert_eq!(
        stderr(&o).matches("past the end").count(),
        1,
        "{}",
        stderr(&o)
    );
    let o = fox_walk("render", "5", &dir.join("late.png"));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(
            "warning: --times 5 is past the end of animation 'Walk' (0.708 s): the last frame \
             is shown"
        ),
        "{}",
        stderr(&o)
    );
    let o = fox_walk("animate", "0,0.7", &dir.join("within"));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("past the end"), "{}", stderr(&o));
}

/// One picture (one time of an animation) to an `--out` without `.png` is written with `.png`
/// added (it was written without an extension), said on stderr, and the path printed is the one
/// written.
#[test]
fn a_single_picture_gets_its_png_extension() {
    let dir = temp_dir("render-png");
    let out = dir.join("pose");
    let o = fox_walk("render", "0.25", &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let written = dir.join("pose.png");
    assert!(written.is_file() && !out.exists());
    assert!(std::fs::read(&written).unwrap().starts_with(b"\x89PNG"));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        written.display().to_string()
    );
    assert!(
        stderr(&o).contains("does not end in .png"),
        "{}",
        stderr(&o)
    );
}

/// The exported animation keeps its source's name (it was named after the character, "Fox"),
/// as the glTF reader reads it back.
#[test]
fn an_exported_animation_keeps_its_name() {
    let dir = temp_dir("export-animation-name");
    let out = dir.join("walk.glb");
    let o = run(
        &["export", "--animation", "Walk", "--max-between", "0"],
        &[
            ("", &support::data("fox/Fox.glb")),
            ("--cage", &support::data("fox/Fox_cage.obj")),
            ("--out", &out),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let exported =
        cagerig_formats::import_character(&out, &cagerig_formats::ImportOptions::default())
            .unwrap();
    let names: Vec<&str> = exported
        .animations
        .iter()
        .map(|a| a.name.as_str())
        .collect();
    assert_eq!(names, ["Walk"]);
}

/// A small OBJ mesh written to `dir/name`: a cube whose 24 vertices sit 3 at each corner (split
/// for flat shading) or a flat 11 × 11 grid, with a three-joint skeleton through it.
fn small_mesh(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    let mut obj = String::new();
    let skt = if name == "cube" {
        let faces: [[[f64; 3]; 4]; 6] = [
            [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            [[0., 0., 1.], [0., 1., 1.], [1., 1., 1.], [1., 0., 1.]],
            [[0., 0., 0.], [0., 1., 0.], [0., 1., 1.], [0., 0., 1.]],
            [[1., 0., 0.], [1., 0., 1.], [1., 1., 1.], [1., 1., 0.]],
            [[0., 0., 0.], [0., 0., 1.], [1., 0., 1.], [1., 0., 0.]],
            [[0., 1., 0.], [1., 1., 0.], [1., 1., 1.], [0., 1., 1.]],
        ];
        for (k, quad) in faces.iter().enumerate() {
            for p in quad {
                obj += &format!(
                    "v {} {} {}\n",
                    2.0 * p[0] - 1.0,
                    2.0 * p[1] - 1.0,
                    2.0 * p[2] - 1.0
                );
            }
            let b = 4 * k + 1;
            obj += &format!("f {} {} {}\nf {} {} {}\n", b, b + 1, b + 2, b, b + 2, b + 3);
        }
        "j 0 root -1 0 -0.8 0\nj 1 mid 0 0 0 0\nj 2 tip 1 0 0.8 0\n"
    } else {
        let n = 10;
        for j in 0..=n {
            for i in 0..=n {
                obj += &format!("v {} 0 {}\n", i as f64 / n as f64, j as f64 / n as f64);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = j * (n + 1) + i + 1;
                let (b, c) = (a + 1, a + n + 1);
                obj += &format!("f {a} {c} {b}\nf {b} {c} {}\n", c + 1);
            }
        }
        "j 0 root -1 0 0 0.5\nj 1 mid 0 0.5 0 0.5\nj 2 tip 1 1 0 0.5\n"
    };
    let mesh = dir.join(format!("{name}.obj"));
    std::fs::write(&mesh, obj).unwrap();
    let skeleton = dir.join(format!("{name}.skt"));
    std::fs::write(&skeleton, skt).unwrap();
    (mesh, skeleton)
}

/// `--auto-cage` and `cagerig cage` on a 24-vertex cube (8 distinct corners) and a flat grid:
/// the cube gets a cage the rig can use, with a note saying why it has fewer vertices than
/// asked; the flat grid is refused in a modeller's words, and no note names a folder that was
/// never written. Plain `cagerig cage` checks what the rig needs (it passed a 100-vertex cage on
/// the cube that `edit` then refused).
#[test]
fn auto_cages_on_tiny_and_flat_meshes_are_usable_or_refused_in_words() {
    let dir = temp_dir("small-meshes");
    let script = edit_script(
        &dir,
        r#"{"steps":[{"op":"rotate_joint","joint":"mid","axis":[1,0,0],"degrees":30}]}"#,
    );
    let (cube, cube_skt) = small_mesh(&dir, "cube");
    let weights = dir.join("cube.skw");
    let o = run(
        &["weights"],
        &[("", &cube), ("--skeleton", &cube_skt), ("--out", &weights)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.join("m-cube");
    let o = run(
        &["edit", "--auto-cage"],
        &[
            ("", &cube),
            ("--skeleton", &cube_skt),
            ("--weights", &weights),
            ("--script", &script),
            ("--out", &out),
        ],
    );
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("8 vertices instead of the 100 asked for"), "{e}");
    assert!(e.contains("8 distinct"), "{e}");
    assert!(out.join("generated_cage.obj").is_file());
    // Plain `cage`: the default size is lowered and said so; a size the rig cannot use fails
    // the rig's check, saying what to do.
    let o = run(&["cage"], &[("", &cube)]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("instead of the 100 asked for"), "{e}");
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("rig "),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let o = run(&["cage", "--vertices", "100"], &[("", &cube)]);
    assert_error(
        &o,
        &[
            "rig:",
            "only 8 distinct vertex positions",
            "at most 8",
            "cagerig subdivide",
        ],
    );

    let (grid, grid_skt) = small_mesh(&dir, "grid");
    let weights = dir.join("grid.skw");
    let o = run(
        &["weights"],
        &[("", &grid), ("--skeleton", &grid_skt), ("--out", &weights)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.join("m-grid");
    let o = run(
        &["edit", "--auto-cage"],
        &[
            ("", &grid),
            ("--skeleton", &grid_skt),
            ("--weights", &weights),
            ("--script", &script),
            ("--out", &out),
        ],
    );
    assert_error(&o, &["grid.obj", "the mesh is flat", "thickness"]);
    let e = stderr(&o);
    assert!(!e.contains("written to"), "{e}");
    assert!(!e.contains("MaxVol") && !e.contains("rank"), "{e}");
    assert!(!out.exists());
    assert_error(&run(&["cage"], &[("", &grid)]), &["the mesh is flat"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Automatic weights for a skeleton that is not in the mesh's space are refused, naming the
/// joints and how far they are (they were accepted with ~0.25 on 4 joints everywhere).
#[test]
fn automatic_weights_refuse_a_skeleton_outside_the_mesh() {
    let dir = temp_dir("skeleton-outside");
    let skt = std::fs::read_to_string(arm_dir().join("arm.skt")).unwrap();
    let moved = |shift: f64, scale: f64| {
        skt.lines()
            .map(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                if w.first() != Some(&"j") || w.len() < 7 {
                    return l.to_string();
                }
                let c: Vec<f64> = w[4..7].iter().map(|x| x.parse().unwrap()).collect();
                format!(
                    "j {} {} {} {} {} {}",
                    w[1],
                    w[2],
                    w[3],
                    c[0] * scale + shift,
                    c[1] * scale,
                    c[2] * scale
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    for (name, shift, scale) in [("shifted", 100.0, 1.0), ("scaled", 0.0, 100.0)] {
        let path = dir.join(format!("{name}.skt"));
        std::fs::write(&path, moved(shift, scale)).unwrap();
        let out = dir.join(format!("{name}.skw"));
        let o = run(
            &["weights"],
            &[
                ("", &support::arm()),
                ("--skeleton", &path),
                ("--out", &out),
            ],
        );
        assert_error(
            &o,
            &[
                "deforming joints lie outside the mesh",
                "away (",
                "share units, scale and origin",
            ],
        );
        assert!(!out.exists(), "{name}");
    }
}

/// The paper's Arm loads with its weight rows renormalised (rounded when written: worst sum
/// 0.99907) and, under Green coordinates, its shipped Φ recomputed: both are notes, not
/// warnings.
#[test]
fn known_harmless_facts_about_the_arm_are_notes() {
    let dir = temp_dir("arm-notes");
    let script = edit_script(&dir, SMALL_SCRIPT);
    for (coords, out) in [("mvc", "mvc"), ("green", "green")] {
        let o = edit(
            &support::arm(),
            &script,
            &dir.join(out),
            &["--coords", coords],
        );
        let e = stderr(&o);
        assert!(o.status.success(), "{e}");
        assert!(!e.contains("warning"), "{coords}: {e}");
        assert!(
            e.contains("note: 603 skinning-weight rows"),
            "{coords}: {e}"
        );
    }
    let e = stderr(&edit(
        &support::arm(),
        &script,
        &dir.join("g2"),
        &["--coords", "green"],
    ));
    assert!(
        e.contains("note: Green coordinates: the given mean value coordinates"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The samples' edit scripts show their edit: every cage step of the Arm's and the Fox's moves
/// its vertices by at least 5 % of the character's size (`examples/edits.json` moved them by
/// 0.06 % of the Fox's), and the Fox's cage indices are the parts the docs name for
/// `data/fox/Fox_cage.obj` (the ears: the highest vertices of the head; the tail's tip: the
/// rearmost). A regenerated cage that moves them fails here: pick the new indices.
#[test]
fn the_samples_edit_scripts_are_sized_to_their_character_and_name_their_parts() {
    let read_obj = support::obj_vertices;
    let diagonal = |points: &[[f64; 3]]| {
        (0..3)
            .map(|a| {
                let lo = points.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min);
                let hi = points
                    .iter()
                    .map(|p| p[a])
                    .fold(f64::NEG_INFINITY, f64::max);
                (hi - lo).powi(2)
            })
            .sum::<f64>()
            .sqrt()
    };
    let cage_steps = |script: &str| -> Vec<(String, Vec<usize>, f64)> {
        let text = std::fs::read_to_string(support::repo().join(script)).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["steps"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["op"] == "move_rest_cage" || s["op"] == "move_posed_cage")
            .map(|s| {
                let vertices = s["vertices"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|k| k.as_u64().unwrap() as usize)
                    .collect();
                let offset: f64 = s["offset"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap().powi(2))
                    .sum::<f64>()
                    .sqrt();
                (s["op"].as_str().unwrap().to_string(), vertices, offset)
            })
            .collect()
    };
    let arm_cage = read_obj(&arm_dir().join("arm_cage.obj"));
    let fox_cage = read_obj(&support::data("fox/Fox_cage.obj"));
    for (script, cage) in [
        ("examples/arm-edits.json", &arm_cage),
        ("examples/fox-edits.json", &fox_cage),
    ] {
        let size = diagonal(cage);
        let steps = cage_steps(script);
        assert!(steps.len() >= 2, "{script}");
        for (op, _, offset) in &steps {
            assert!(
                offset / size >= 0.05,
                "{script}: {op} by {offset} of {size}"
            );
        }
    }
    let fox = cage_steps("examples/fox-edits.json");
    let mut head: Vec<usize> = (0..fox_cage.len())
        .filter(|&k| fox_cage[k][2] > 25.0)
        .collect();
    head.sort_by(|&a, &b| fox_cage[b][1].total_cmp(&fox_cage[a][1]));
    let mut rear: Vec<usize> = (0..fox_cage.len()).collect();
    rear.sort_by(|&a, &b| fox_cage[a][2].total_cmp(&fox_cage[b][2]));
    for (op, vertices, _) in &fox {
        let part = if op == "move_rest_cage" {
            &head[..6]
        } else {
            &rear[..vertices.len()]
        };
        assert!(
            vertices.iter().all(|k| part.contains(k)),
            "{op} {vertices:?}: expected among {part:?}"
        );
    }
}
