//! Every `cagerig` command the README and `docs/*.md` show in a shell block runs as written.
//!
//! Each document's blocks are replayed in order in a fresh folder that links the repository's
//! `data/` and `examples/` (so that the commands' `out/…` paths and the files one command
//! writes for the next stay in that folder), with this build's `cagerig` first on `PATH`. The
//! lines run are those starting with `cagerig ` and the `mkdir`/`cp` lines that prepare their
//! inputs; `cagerig bench` (minutes at its larger sizes, timed by the benches), the editor,
//! `cargo`, `python`, `pip` and Blender lines are left to their own tests (and, with
//! `CAGERIG_SKIP_GPU_TESTS=1`, the pictures). Regressions: the command-line page showed
//! `edit data/fox/Fox.glb --auto-weights` without a cage, which the command refuses, and the
//! weights page's file outputs failed on a fresh clone without `out/`.

#![expect(clippy::unwrap_used)]

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use support::{repo, temp_dir};

/// One shell line of a document, with where it starts.
struct DocumentedCommand {
    line: usize,
    text: String,
}

/// The lines of `markdown`'s ```sh blocks that this test runs, continuation lines (`\`) joined
/// and trailing `# comments` removed.
fn documented_commands(markdown: &str) -> Vec<DocumentedCommand> {
    let mut commands = Vec::new();
    let mut in_shell_block = false;
    let mut pending: Option<DocumentedCommand> = None;
    for (index, line) in markdown.lines().enumerate() {
        if let Some(language) = line.strip_prefix("```") {
            in_shell_block = !in_shell_block && language.trim() == "sh";
            pending = None;
            continue;
        }
        if !in_shell_block {
            continue;
        }
        let mut command = match pending.take() {
            Some(mut command) => {
                command.text.push(' ');
                command.text.push_str(line.trim());
                command
            }
            None => DocumentedCommand {
                line: index + 1,
                text: line.trim().to_owned(),
            },
        };
        if let Some(start) = command.text.strip_suffix('\\') {
            command.text = start.trim_end().to_owned();
            pending = Some(command);
            continue;
        }
        if let Some(comment) = command.text.find(" #") {
            command.text.truncate(comment);
        }
        command.text = command.text.trim().to_owned();
        if is_run_here(&command.text) {
            commands.push(command);
        }
    }
    commands
}

/// Whether this test runs the shell line `text`. Pictures need a graphics adapter:
/// `CAGERIG_SKIP_GPU_TESTS=1` leaves `render` and `--render` out, as for the other picture tests.
fn is_run_here(text: &str) -> bool {
    let pictures = text
        .split_whitespace()
        .any(|w| w == "render" || w == "--render");
    if pictures && std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some() {
        return false;
    }
    let mut words = text.split_whitespace();
    match words.next() {
        Some("cagerig") => words.next() != Some("bench"),
        Some("mkdir" | "cp") => true,
        _ => false,
    }
}

/// Replays `document`'s commands in a new folder; returns the failures, each naming the
/// document's line, the command and its standard error.
fn replay(document: &Path) -> Vec<String> {
    let markdown = std::fs::read_to_string(document).unwrap();
    let commands = documented_commands(&markdown);
    if commands.is_empty() {
        return Vec::new();
    }
    let name = document.file_stem().unwrap().to_string_lossy().into_owned();
    let dir = temp_dir(&format!("doc-{name}"));
    for linked in ["data", "examples"] {
        std::os::unix::fs::symlink(repo().join(linked), dir.join(linked)).unwrap();
    }
    let binary = PathBuf::from(env!("CARGO_BIN_EXE_cagerig"));
    let path = std::env::join_paths(
        std::iter::once(binary.parent().unwrap().to_path_buf()).chain(std::env::split_paths(
            &std::env::var_os("PATH").unwrap_or_default(),
        )),
    )
    .unwrap();
    let mut failures = Vec::new();
    for command in &commands {
        let output = Command::new("sh")
            .arg("-c")
            .arg(&command.text)
            .current_dir(&dir)
            .env("PATH", &path)
            .output()
            .unwrap();
        if !output.status.success() {
            failures.push(format!(
                "{}:{}: `{}` failed:\n{}",
                document.display(),
                command.line,
                command.text,
                String::from_utf8_lossy(&output.stderr)
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    failures
}

#[test]
fn the_readme_and_docs_commands_run_as_written() {
    let root = repo();
    let mut documents = vec![root.join("README.md")];
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    documents.extend(pages);
    let runs: usize = documents
        .iter()
        .map(|d| documented_commands(&std::fs::read_to_string(d).unwrap()).len())
        .sum();
    assert!(runs >= 40, "only {runs} documented commands found");
    // Two documents at a time (one per core of the smallest CI machine).
    let failures: Vec<String> = std::thread::scope(|scope| {
        let halves: Vec<_> = documents
            .chunks(documents.len().div_ceil(2))
            .map(|half| {
                scope.spawn(move || half.iter().flat_map(|d| replay(d)).collect::<Vec<_>>())
            })
            .collect();
        halves
            .into_iter()
            .flat_map(|half| half.join().unwrap())
            .collect()
    });
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn shell_blocks_are_read_with_their_continuations_and_without_comments() {
    let markdown = "text\n```sh\nmkdir -p out   # a folder\ncagerig animate a.obj \\\n    \
                    --times 1 --out out/x   # samples\ncagerig bench a.obj\ncargo test\n```\n\
                    ```json\ncagerig info not-a-shell-block\n```\n";
    let commands = documented_commands(markdown);
    let texts: Vec<&str> = commands.iter().map(|c| c.text.as_str()).collect();
    assert_eq!(
        texts,
        [
            "mkdir -p out",
            "cagerig animate a.obj --times 1 --out out/x"
        ]
    );
    assert_eq!(commands[1].line, 4);
}
