//! Outputs survive `kill -9`: every command that writes several files is killed with SIGKILL at
//! random moments (110 kills in all, and 10 of `render --times` where there is an adapter;
//! `CAGERIG_SKIP_GPU_TESTS=1` leaves them out), alternating between two runs that write different outputs
//! into the same place. After each kill the place must hold the complete earlier output or the
//! complete new one — never a mix, never nothing — and the next run must succeed.

#![cfg(unix)]
#![expect(clippy::unwrap_used)]

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};
use support::{cagerig, data, temp_dir};

/// File name → bytes.
type Snapshot = BTreeMap<String, Vec<u8>>;

/// xorshift64*, seeded from the clock (the seed is printed so a failure can be replayed with
/// CAGERIG_KILL_SEED).
struct Random(u64);

impl Random {
    fn new() -> Self {
        let seed = std::env::var("CAGERIG_KILL_SEED")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| {
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .unwrap()
                    .as_nanos() as u64
                    | 1
            });
        eprintln!("kill test seed: CAGERIG_KILL_SEED={seed}");
        Self(seed)
    }
    fn fraction(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn snapshot_folder(dir: &Path) -> Option<Snapshot> {
    let entries = std::fs::read_dir(dir).ok()?;
    let mut snap = Snapshot::new();
    for e in entries {
        let e = e.unwrap();
        snap.insert(
            e.file_name().to_string_lossy().into_owned(),
            std::fs::read(e.path()).unwrap(),
        );
    }
    Some(snap)
}

/// A `.gltf` and the buffer it refers to.
fn snapshot_gltf(path: &Path) -> Option<Snapshot> {
    let text = std::fs::read(path).ok()?;
    let json: serde_json::Value = serde_json::from_slice(&text)
        .unwrap_or_else(|e| panic!("{} is not complete JSON: {e}", path.display()));
    let uri = json["buffers"][0]["uri"].as_str().unwrap().to_owned();
    let bin = std::fs::read(path.with_file_name(&uri))
        .unwrap_or_else(|e| panic!("{} refers to {uri}, which is missing: {e}", path.display()));
    assert_eq!(
        bin.len() as u64,
        json["buffers"][0]["byteLength"].as_u64().unwrap(),
        "{uri} is incomplete"
    );
    Some(Snapshot::from([("gltf".into(), text), ("bin".into(), bin)]))
}

/// One multi-file command: two argument lists writing different outputs to the same place.
struct Case {
    name: &'static str,
    runs: [Vec<String>; 2],
    snapshot: fn(&Path) -> Option<Snapshot>,
    /// The folder or file the command writes.
    target: PathBuf,
    kills: usize,
}

fn run_to_end(args: &[String]) -> Duration {
    let start = Instant::now();
    let o = cagerig().args(args).output().unwrap();
    assert!(
        o.status.success(),
        "cagerig {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    start.elapsed()
}

fn check_case(case: &Case, random: &mut Random) {
    // The two complete outputs, as the command writes them.
    let mut complete = Vec::new();
    let mut longest = Duration::ZERO;
    for args in &case.runs {
        longest = longest.max(run_to_end(args));
        complete.push((case.snapshot)(&case.target).unwrap());
    }
    assert_ne!(
        complete[0], complete[1],
        "{}: the two runs must differ",
        case.name
    );
    // How often a kill left the place as it was (it landed before the commit) and how often it
    // found the new output in place (after the commit).
    let (mut unchanged, mut replaced) = (0, 0);
    let mut before = complete[1].clone();
    for k in 0..case.kills {
        let args = &case.runs[k % 2];
        let mut child = cagerig()
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let wait = longest.mul_f64(1.5 * random.fraction());
        std::thread::sleep(wait);
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        let now = (case.snapshot)(&case.target)
            .unwrap_or_else(|| panic!("{}: kill {k} after {wait:?} left no output", case.name));
        assert!(
            complete.contains(&now),
            "{}: kill {k} after {wait:?} left a mix: {:?}",
            case.name,
            now.keys().collect::<Vec<_>>()
        );
        if now == before {
            unchanged += 1;
        } else {
            replaced += 1;
        }
        before = now;
    }
    eprintln!(
        "{}: {} kills within {:.0} ms runs: {unchanged} left the place as it was, {replaced} \
         found the new output in place",
        case.name,
        case.kills,
        longest.as_secs_f64() * 1e3
    );
    // A following run succeeds and leaves no staging folder behind.
    run_to_end(&case.runs[0]);
    assert_eq!((case.snapshot)(&case.target).unwrap(), complete[0]);
    let parent = case.target.parent().unwrap();
    let leftovers: Vec<String> = std::fs::read_dir(parent)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".partial-"))
        .collect();
    assert!(leftovers.is_empty(), "{}: left {leftovers:?}", case.name);
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

#[test]
fn every_multi_file_output_is_complete_or_earlier_after_sigkill() {
    let dir = temp_dir("all");
    let mut random = Random::new();
    let script = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    };
    let one = script(
        "one.json",
        r#"{"steps":[{"op":"rotate_joint","joint":1,"axis":[0,0,1],"degrees":30}]}"#,
    );
    let two = script(
        "two.json",
        r#"{"steps":[{"op":"rotate_joint","joint":1,"axis":[0,0,1],"degrees":-20},
                     {"op":"move_rest_cage","vertices":[3],"offset":[0,0.1,0]},
                     {"op":"move_posed_cage","vertices":[5],"offset":[0.05,0,0]}]}"#,
    );
    let arm = data("arm/arm.obj").to_string_lossy().into_owned();
    let skel = data("arm/arm_skelAnim.txt").to_string_lossy().into_owned();
    let out = |name: &str| dir.join(name);
    let s = |p: &PathBuf| p.to_string_lossy().into_owned();
    let edit_out = out("edit");
    let animate_out = out("animate");
    let demo_out = out("demo");
    let subdivide_out = out("subdivide");
    let gltf_out = out("export.gltf");
    let render_out = out("render");
    let render = |times: &str| {
        strings(&[
            "render",
            &arm,
            "--skeleton-anim",
            &skel,
            "--times",
            times,
            "--size",
            "64x48",
            "--force",
            "--out",
            &s(&render_out),
        ])
    };
    let mut cases = vec![
        Case {
            name: "edit",
            runs: [
                strings(&[
                    "edit",
                    &arm,
                    "--script",
                    &one,
                    "--force",
                    "--out",
                    &s(&edit_out),
                ]),
                strings(&[
                    "edit",
                    &arm,
                    "--script",
                    &two,
                    "--force",
                    "--out",
                    &s(&edit_out),
                ]),
            ],
            snapshot: snapshot_folder,
            target: edit_out.clone(),
            kills: 25,
        },
        Case {
            name: "animate",
            runs: [
                strings(&[
                    "animate",
                    &arm,
                    "--skeleton-anim",
                    &skel,
                    "--times",
                    "0.75",
                    "--force",
                    "--out",
                    &s(&animate_out),
                ]),
                strings(&[
                    "animate",
                    &arm,
                    "--skeleton-anim",
                    &skel,
                    "--times",
                    "1,2,3",
                    "--force",
                    "--out",
                    &s(&animate_out),
                ]),
            ],
            snapshot: snapshot_folder,
            target: animate_out.clone(),
            kills: 25,
        },
        Case {
            name: "demo",
            runs: [
                strings(&[
                    "demo",
                    "--builtin",
                    "bar",
                    "--resolution",
                    "200",
                    "--no-pictures",
                    "--out",
                    &s(&demo_out),
                ]),
                strings(&[
                    "demo",
                    "--builtin",
                    "snake",
                    "--resolution",
                    "3000",
                    "--no-pictures",
                    "--out",
                    &s(&demo_out),
                ]),
            ],
            snapshot: snapshot_folder,
            target: demo_out.clone(),
            kills: 20,
        },
        Case {
            name: "subdivide",
            runs: [
                strings(&[
                    "subdivide",
                    &arm,
                    "--levels",
                    "1",
                    "--name",
                    "a",
                    "--force",
                    "--out",
                    &s(&subdivide_out),
                ]),
                strings(&[
                    "subdivide",
                    &arm,
                    "--levels",
                    "1",
                    "--name",
                    "b",
                    "--force",
                    "--out",
                    &s(&subdivide_out),
                ]),
            ],
            snapshot: snapshot_folder,
            target: subdivide_out.clone(),
            kills: 20,
        },
        Case {
            name: "export .gltf",
            runs: [
                strings(&["export", &arm, "--script", &one, "--out", &s(&gltf_out)]),
                strings(&["export", &arm, "--script", &two, "--out", &s(&gltf_out)]),
            ],
            snapshot: snapshot_gltf,
            target: gltf_out.clone(),
            kills: 20,
        },
    ];
    let total: usize = cases.iter().map(|c| c.kills).sum();
    assert!(total >= 100);
    // Pictures need an adapter (a software one is fine); render.rs's switch skips them.
    if std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_none() {
        cases.push(Case {
            name: "render --times",
            runs: [render("0.5,1.5,2.5"), render("1,2")],
            snapshot: snapshot_folder,
            target: render_out.clone(),
            kills: 10,
        });
    }
    for case in &cases {
        check_case(case, &mut random);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
