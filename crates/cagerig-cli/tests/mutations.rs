//! Corpus-free structured mutations of the shared Arm data through the commands:
//! each mutation edits one file of a private copy of the rig (drop, repeat or swap lines, cut
//! the file, replace a number by an extreme one, a BOM, an empty file, …) and runs `info`,
//! `coords`, `edit` and `animate`. Every run must exit 0 or 1 (never a panic or a signal), an
//! error must be one `error:` line, and a success must have written complete, finite output;
//! a failure must have written nothing. Deterministic (fixed seed), a few hundred runs.

// tests, benches and examples may panic on a broken fixture

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::arm_dir;

/// xorshift64*: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const EXTREMES: [&str; 10] = [
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "1e13",
    "-0",
    "0",
    "-1",
    "99999999999",
    "1e-320",
];

/// One structured mutation of `text`; returns the new text and a description.
fn mutate(text: &str, rng: &mut Rng) -> (String, String) {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    let i = rng.below(n);
    match rng.below(9) {
        0 => {
            lines.remove(i);
            (lines.join("\n") + "\n", format!("drop line {}", i + 1))
        }
        1 => {
            let l = lines[i].clone();
            lines.insert(i, l);
            (lines.join("\n") + "\n", format!("repeat line {}", i + 1))
        }
        2 => {
            let j = rng.below(n);
            lines.swap(i, j);
            (
                lines.join("\n") + "\n",
                format!("swap lines {} and {}", i + 1, j + 1),
            )
        }
        3 => {
            let cut = rng.below(text.len());
            let mut cut = cut;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            (text[..cut].to_string(), format!("cut at byte {cut}"))
        }
        4..=6 => {
            let mut tokens: Vec<String> = lines[i].split_whitespace().map(str::to_string).collect();
            if tokens.len() > 1 {
                let k = 1 + rng.below(tokens.len() - 1);
                tokens[k] = EXTREMES[rng.below(EXTREMES.len())].to_string();
            }
            let d = format!("line {} -> {:?}", i + 1, tokens.join(" "));
            lines[i] = tokens.join(" ");
            (lines.join("\n") + "\n", d)
        }
        7 => (format!("\u{feff}{text}"), "UTF-8 BOM".into()),
        _ => (String::new(), "empty file".into()),
    }
}

fn all_outputs_finite(out: &Path) -> Result<usize, String> {
    let mut n = 0;
    for entry in std::fs::read_dir(out).map_err(|e| e.to_string())? {
        let path = entry.map_err(|e| e.to_string())?.path();
        if path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        {
            continue; // the output manifest
        }
        if path.extension().is_some_and(|e| e == "obj") {
            // The reader refuses NaN, inf and anything beyond 1e12.
            cagerig::io::read_obj(&path).map_err(|e| e.to_string())?;
        } else {
            let text = std::fs::read_to_string(&path).map_err(|e| e.to_string())?;
            let joints: serde_json::Value =
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
            let finite = joints.as_array().is_some_and(|a| {
                a.iter().all(|j| {
                    ["rest", "posed"].iter().all(|k| {
                        j[k].as_array().is_some_and(|v| {
                            v.len() == 3 && v.iter().all(|x| x.as_f64().is_some_and(f64::is_finite))
                        })
                    })
                })
            });
            if !finite {
                return Err(format!("{} holds a non-finite joint", path.display()));
            }
        }
        n += 1;
    }
    Ok(n)
}

#[test]
fn mutated_arm_files_through_every_command() {
    let files = [
        "arm.obj",
        "arm.skt",
        "arm.skw",
        "arm_cage.obj",
        "arm_cage_cageWeights.txt",
        "arm_cage.maxvol",
        "arm_corWeights.txt",
        "arm_skelAnim.txt",
        "arm_cageAnim.txt",
    ];
    let root = std::env::temp_dir().join(format!("cagerig-mutations-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let rig = root.join("arm");
    std::fs::create_dir_all(&rig).unwrap();
    let originals: Vec<String> = files
        .iter()
        .map(|f| std::fs::read_to_string(arm_dir().join(f)).unwrap())
        .collect();
    let script = root.join("edits.json");
    std::fs::write(
        &script,
        r#"{"skinning":"lbs","steps":[
          {"op":"rotate_joint","joint":3,"axis":[1,0,0],"degrees":40},
          {"op":"move_rest_cage","vertices":[0,2,4],"offset":[0.5,-0.2,0.3]},
          {"op":"move_posed_cage","vertices":[10,13],"offset":[-0.3,0.4,0.1]},
          {"op":"set_skinning","method":"cor"}]}"#,
    )
    .unwrap();
    let mut rng = Rng(0x5eed_cafe_f00d_1234);
    let mut failures = Vec::new();
    let (mut ok, mut refused) = (0usize, 0usize);
    const MUTATIONS: usize = 72;
    for m in 0..MUTATIONS {
        let which = m % files.len();
        for (f, text) in files.iter().zip(&originals) {
            std::fs::write(rig.join(f), text).unwrap();
        }
        let (text, what) = mutate(&originals[which], &mut rng);
        std::fs::write(rig.join(files[which]), text).unwrap();
        let mesh = rig.join("arm.obj");
        let out = root.join("out");
        let anim_args: Vec<PathBuf> =
            vec![rig.join("arm_skelAnim.txt"), rig.join("arm_cageAnim.txt")];
        // `edit` for most, `animate` for the animation files, `info`/`coords` for a few.
        let mut runs: Vec<Command> = Vec::new();
        let mut c = Command::new(env!("CARGO_BIN_EXE_cagerig"));
        if which >= 7 {
            c.arg("animate")
                .arg(&mesh)
                .arg("--skeleton-anim")
                .arg(&anim_args[0]);
            c.arg("--cage-anim")
                .arg(&anim_args[1])
                .args(["--times", "0.75,2.25,4"]);
        } else {
            c.arg("edit").arg(&mesh).arg("--script").arg(&script);
        }
        c.arg("--out").arg(&out);
        runs.push(c);
        if m % 4 == 0 {
            let mut c = Command::new(env!("CARGO_BIN_EXE_cagerig"));
            c.args(["info", "--json"]).arg(&mesh);
            runs.push(c);
        }
        for mut c in runs {
            let _ = std::fs::remove_dir_all(&out);
            let o = c.output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            let label = format!("{} ({what}): {:?}", files[which], c.get_args().next());
            match o.status.code() {
                Some(0) => {
                    ok += 1;
                    if out.exists()
                        && let Err(e) = all_outputs_finite(&out)
                    {
                        failures.push(format!("{label}: exit 0 but {e}"));
                    }
                }
                Some(1) => {
                    refused += 1;
                    if out.exists() {
                        failures.push(format!("{label}: failed but wrote {}", out.display()));
                    }
                    let errors = err.lines().filter(|l| l.starts_with("error:")).count();
                    let json_error = String::from_utf8_lossy(&o.stdout).contains("\"error\"");
                    if errors != 1 && !json_error {
                        failures.push(format!("{label}: expected one error line, got: {err}"));
                    }
                }
                code => failures.push(format!("{label}: exit {code:?}: {err}")),
            }
            if err.contains("panicked") {
                failures.push(format!("{label}: panic: {err}"));
            }
        }
    }
    let staging: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(staging.is_empty(), "staging folders left: {staging:?}");
    println!("{MUTATIONS} mutations: {ok} runs succeeded, {refused} refused cleanly");
    let _ = std::fs::remove_dir_all(&root);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(ok > 0 && refused > 0);
}
