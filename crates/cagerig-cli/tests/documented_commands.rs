//! Every shell block of the README and `docs/*.md` runs as written.
//!
//! Each page's ```sh blocks run in order, each as one `sh -e` script (so every line of a block
//! must succeed), in a fresh folder per page that links the repository's top-level files and
//! folders (`data/`, `examples/`, `crates/`, `tools/`, …) but not `out/` or `target/`, with this
//! build's `cagerig` first on `PATH`. A block is left out only when the line before its fence
//! says what it needs that a test machine does not give:
//!
//! - `<!-- needs: display -->`: a window (the editor);
//! - `<!-- needs: blender -->`: Blender;
//! - `<!-- needs: network -->`: downloads (`pip install`, and what the Python package it
//!   installs runs; the Python suite runs the package's documented blocks itself);
//! - `<!-- needs: build -->`: a build of the workspace (`cargo install`, `cargo run`,
//!   `cargo test`, `cargo bench`: minutes each; CI builds, tests and benches the workspace
//!   itself).
//!
//! Pages are replayed in separate folders, so a reader who follows them all in one clone is
//! checked separately: a folder that one page writes with `--out` may not be written by another
//! page (the commands refuse a non-empty output folder, so the second page would fail).
//! With `CAGERIG_SKIP_GPU_TESTS=1` blocks that draw pictures are left out as well, as the other
//! picture tests are.

#![expect(clippy::unwrap_used)]

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use support::{repo, temp_dir};

/// What a block needs that the test machine does not give.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Need {
    Display,
    Blender,
    Network,
    Build,
}

impl Need {
    fn parse(text: &str) -> Option<Need> {
        match text {
            "display" => Some(Need::Display),
            "blender" => Some(Need::Blender),
            "network" => Some(Need::Network),
            "build" => Some(Need::Build),
            _ => None,
        }
    }
}

/// One ```sh block of a page.
#[derive(Debug)]
struct ShellBlock {
    /// Line of the opening fence (1-based).
    line: usize,
    /// The block's text.
    text: String,
    /// The `<!-- needs: … -->` marker on the line before the fence, if any.
    needs: Option<Need>,
}

/// The ```sh blocks of `markdown`; an unknown `needs:` marker is an error naming its line.
fn shell_blocks(markdown: &str) -> Result<Vec<ShellBlock>, String> {
    let mut blocks = Vec::new();
    let mut previous = "";
    let mut open: Option<(ShellBlock, bool)> = None; // (block, is a shell block)
    for (index, line) in markdown.lines().enumerate() {
        if let Some(language) = line.trim_start().strip_prefix("```") {
            match open.take() {
                Some((block, true)) => blocks.push(block),
                Some((_, false)) => {}
                None => {
                    let marker = previous
                        .trim()
                        .strip_prefix("<!-- needs:")
                        .and_then(|m| m.strip_suffix("-->"))
                        .map(str::trim);
                    let needs = match marker {
                        Some(m) => Some(Need::parse(m).ok_or_else(|| {
                            format!(
                                "line {index}: unknown marker `needs: {m}` (expected display, \
                                 blender, network or build)"
                            )
                        })?),
                        None => None,
                    };
                    let shell = matches!(language.trim(), "sh" | "bash" | "shell");
                    open = Some((
                        ShellBlock {
                            line: index + 1,
                            text: String::new(),
                            needs,
                        },
                        shell,
                    ));
                }
            }
            previous = line;
            continue;
        }
        if let Some((block, _)) = &mut open {
            block.text.push_str(line);
            block.text.push('\n');
        }
        previous = line;
    }
    Ok(blocks)
}

/// Whether `block` draws pictures (a graphics adapter; `CAGERIG_SKIP_GPU_TESTS=1` skips it).
fn draws_pictures(block: &str) -> bool {
    block
        .split_whitespace()
        .any(|w| w == "render" || w == "--render")
}

/// The output folders that `block`'s commands refuse to write into when they are not empty:
/// `--out` paths with no extension, but for `demo` (which replaces its folder) and lines with
/// `--force`.
fn output_folders(block: &str) -> Vec<String> {
    let joined = block.replace("\\\n", " ");
    let mut folders = Vec::new();
    for line in joined.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.contains(&"demo") || words.contains(&"--force") {
            continue;
        }
        folders.extend(
            words
                .windows(2)
                .filter(|w| w[0] == "--out")
                .map(|w| w[1].trim_end_matches('/').to_string())
                .filter(|p| Path::new(p).extension().is_none()),
        );
    }
    folders
}

/// The blocks of `document` this test runs.
fn runnable(document: &Path, skip_pictures: bool) -> Vec<ShellBlock> {
    let markdown = std::fs::read_to_string(document).unwrap();
    shell_blocks(&markdown)
        .unwrap_or_else(|e| panic!("{}: {e}", document.display()))
        .into_iter()
        .filter(|b| b.needs.is_none() && !(skip_pictures && draws_pictures(&b.text)))
        .collect()
}

/// A fresh folder laid out like the repository's root, without `out/` and `target/`.
fn fresh_folder(name: &str) -> PathBuf {
    let dir = temp_dir(&format!("doc-{name}"));
    for entry in std::fs::read_dir(repo()).unwrap() {
        let entry = entry.unwrap();
        let file_name = entry.file_name();
        if matches!(file_name.to_str(), Some("out" | "target" | ".git")) {
            continue;
        }
        std::os::unix::fs::symlink(entry.path(), dir.join(&file_name)).unwrap();
    }
    dir
}

/// Replays `document`'s blocks in a fresh folder; returns the failures, each naming the
/// document's line, and the seconds taken.
fn replay(document: &Path) -> (Vec<String>, f64) {
    let started = Instant::now();
    let skip_pictures = std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some();
    let blocks = runnable(document, skip_pictures);
    if blocks.is_empty() {
        return (Vec::new(), 0.0);
    }
    let name = document.file_stem().unwrap().to_string_lossy().into_owned();
    let dir = fresh_folder(&name);
    let binary = PathBuf::from(env!("CARGO_BIN_EXE_cagerig"));
    let path = std::env::join_paths(
        std::iter::once(binary.parent().unwrap().to_path_buf()).chain(std::env::split_paths(
            &std::env::var_os("PATH").unwrap_or_default(),
        )),
    )
    .unwrap();
    let mut failures = Vec::new();
    for block in &blocks {
        let output = Command::new("sh")
            .arg("-e")
            .arg("-c")
            .arg(&block.text)
            .current_dir(&dir)
            .env("PATH", &path)
            .output()
            .unwrap();
        if !output.status.success() {
            failures.push(format!(
                "{}:{}: the block failed ({}):\n{}\n{}",
                document.display(),
                block.line,
                output.status,
                block.text,
                String::from_utf8_lossy(&output.stderr)
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    (failures, started.elapsed().as_secs_f64())
}

/// The README, then `docs/*.md` by name.
fn documents() -> Vec<PathBuf> {
    let root = repo();
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    std::iter::once(root.join("README.md"))
        .chain(pages)
        .collect()
}

#[test]
fn the_readme_and_docs_shell_blocks_run_as_written() {
    let documents = documents();
    // Counted with the picture blocks, which `CAGERIG_SKIP_GPU_TESTS=1` leaves out of the run.
    let runs: usize = documents.iter().map(|d| runnable(d, false).len()).sum();
    assert!(runs >= 10, "only {runs} documented blocks found");
    // Two pages at a time (one per core of the smallest CI machine).
    let (tx, rx) = std::sync::mpsc::channel();
    let queue = std::sync::Mutex::new(documents.clone());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            let tx = tx.clone();
            let queue = &queue;
            scope.spawn(move || {
                while let Some(document) = queue.lock().unwrap().pop() {
                    let (failures, seconds) = replay(&document);
                    tx.send((document, failures, seconds)).unwrap();
                }
            });
        }
    });
    drop(tx);
    let mut failures = Vec::new();
    for (document, mut page_failures, seconds) in rx {
        eprintln!("{}: {seconds:.1} s", document.display());
        failures.append(&mut page_failures);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A reader who follows every page in one clone: no output folder is written by two pages.
#[test]
fn no_two_pages_write_the_same_output_folder() {
    let mut writers: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for document in documents() {
        let markdown = std::fs::read_to_string(&document).unwrap();
        let name = document.strip_prefix(repo()).unwrap().display().to_string();
        for block in shell_blocks(&markdown).unwrap() {
            for folder in output_folders(&block.text) {
                let pages = writers.entry(folder).or_default();
                if !pages.contains(&name) {
                    pages.push(name.clone());
                }
            }
        }
    }
    let collisions: Vec<String> = writers
        .iter()
        .filter(|(_, pages)| pages.len() > 1)
        .map(|(folder, pages)| format!("{folder}: written by {}", pages.join(" and ")))
        .collect();
    assert!(collisions.is_empty(), "{}", collisions.join("\n"));
}

#[test]
fn blocks_are_read_with_their_markers() {
    let markdown = "text\n```sh\nmkdir -p out   # a folder\ncagerig animate a.obj \\\n    \
                    --times 1 --out out/x\n```\n<!-- needs: display -->\n```sh\n\
                    cagerig-studio\n```\n```json\n{}\n```\n";
    let blocks = shell_blocks(markdown).unwrap();
    assert_eq!(blocks.len(), 2);
    assert_eq!(blocks[0].line, 2);
    assert_eq!(blocks[0].needs, None);
    assert_eq!(output_folders(&blocks[0].text), ["out/x"]);
    assert!(
        output_folders("cagerig demo --out out/d\ncagerig edit a --force --out out/e").is_empty()
    );
    assert_eq!(blocks[1].needs, Some(Need::Display));
    let err = shell_blocks("<!-- needs: coffee -->\n```sh\nls\n```\n").unwrap_err();
    assert!(err.contains("coffee"), "{err}");
}
