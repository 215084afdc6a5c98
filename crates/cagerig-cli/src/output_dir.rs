//! Output folders that are complete or absent: `edit` and `animate` write every file into a
//! staging folder beside `--out` (`.<name>.partial-<pid>`) as each state is produced (nothing is
//! held in memory), and rename it to `--out` only after the whole run succeeded. On an error the
//! staging folder is removed; after a kill, the next run into the same `--out` removes the
//! staging folders of processes that no longer exist. An existing non-empty `--out` is refused
//! unless `--force`, and even then only when it is an earlier cagerig output: it holds the
//! manifest [`MANIFEST_FILE`] and nothing it does not list (so `--out . --force` cannot delete
//! unrelated files, and a folder of the user's own pictures is never replaced).
//!
//! Replacing an earlier output is one atomic step on Linux (`renameat2(RENAME_EXCHANGE)` swaps
//! the two folders; the old one, now under the staging name, is removed after): a kill at any
//! moment leaves `--out` holding the complete earlier output or the complete new one. Where the
//! exchange is not available the old folder is first renamed to `.<name>.partial-<pid>.old`;
//! a kill between the two renames leaves `--out` absent, and the next run puts that complete
//! earlier output back before it starts.

use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

/// Suffixes of the files written for one rig state (see [`crate::state_files`]).
pub const STATE_FILE_SUFFIXES: [&str; 6] = [
    ".png",
    "_mesh_rest.obj",
    "_mesh_posed.obj",
    "_cage_rest.obj",
    "_cage_posed.obj",
    "_joints.json",
];

/// `--out`, `--force`, `--render`: the output folder of a command that writes the rig's state
/// after each step or sample (`edit`, `animate`).
#[derive(Debug, Clone, clap::Args)]
pub struct StateOutputArgs {
    /// Output folder; it appears complete, only after every state was written.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a non-empty --out that holds an earlier run's output.
    #[arg(long)]
    pub force: bool,
    /// Also write a picture of each state (rest pose left, current pose right) as PNG;
    /// needs a Vulkan or GL adapter (software ones work).
    #[arg(long)]
    pub render: bool,
}

/// The file in every output folder that lists the files of the output, one per line: what
/// `--force` may replace.
pub const MANIFEST_FILE: &str = ".cagerig-output";

/// A folder being filled; see the module documentation.
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    files: usize,
    /// Names of the files written so far (the manifest's lines).
    names: Vec<String>,
    finished: bool,
}

fn staging_prefix(target: &Path) -> OsString {
    let mut prefix = OsString::from(".");
    prefix.push(target.file_name().unwrap_or_default());
    prefix.push(".partial-");
    prefix
}

/// Whether process `pid` has ended (Linux: /proc; elsewhere nothing is known to have ended).
fn process_ended(pid: &str) -> bool {
    pid.parse::<u32>().is_ok()
        && Path::new("/proc/self").exists()
        && !Path::new("/proc").join(pid).exists()
}

/// Cleans up after runs into `target` that were killed: puts back an earlier output moved aside
/// (`.partial-<pid>.old`) when `target` is absent, then removes the staging folders and
/// moved-aside outputs of processes that no longer run.
fn remove_abandoned_staging(parent: &Path, target: &Path) {
    let prefix = staging_prefix(target);
    let prefix = prefix.to_string_lossy();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let mut abandoned = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let Some(rest) = name.strip_prefix(prefix.as_ref()) else {
            continue;
        };
        let (pid, moved_aside) = match rest.strip_suffix(".old") {
            Some(pid) => (pid, true),
            None => (rest, false),
        };
        if process_ended(pid) {
            abandoned.push((entry.path(), moved_aside));
        }
    }
    for (path, moved_aside) in abandoned {
        if moved_aside && !target.exists() && std::fs::rename(&path, target).is_ok() {
            continue;
        }
        let _ = std::fs::remove_dir_all(&path);
    }
}

/// Whether `target` (an existing folder with `entries`) is an earlier cagerig output that
/// `--force` may replace; otherwise the entry that makes it not one.
fn foreign_entry(target: &Path, entries: &[std::fs::DirEntry]) -> Option<String> {
    let listed: Option<Vec<String>> = std::fs::read_to_string(target.join(MANIFEST_FILE))
        .ok()
        .map(|text| text.lines().map(str::to_owned).collect());
    entries.iter().find_map(|e| {
        let name = e.file_name().to_string_lossy().into_owned();
        let ours = e.path().is_file()
            && match &listed {
                Some(listed) => name == MANIFEST_FILE || listed.contains(&name),
                // An output written before manifests: state files only (pictures alone are
                // not enough to call a folder ours).
                None => STATE_FILE_SUFFIXES
                    .iter()
                    .filter(|s| **s != ".png")
                    .any(|s| name.ends_with(s)),
            };
        (!ours).then_some(name)
    })
}

/// Puts the complete folder `staging` in place of `target`, atomically when the platform
/// swaps folders; returns the path of the replaced output to remove, if any.
fn swap_into_place(staging: &Path, target: &Path) -> std::io::Result<Option<PathBuf>> {
    if !target.exists() {
        std::fs::rename(staging, target)?;
        return Ok(None);
    }
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        if renameat_with(CWD, staging, CWD, target, RenameFlags::EXCHANGE).is_ok() {
            return Ok(Some(staging.to_path_buf()));
        }
    }
    let mut aside = staging.as_os_str().to_owned();
    aside.push(".old");
    let aside = PathBuf::from(aside);
    std::fs::rename(target, &aside)?;
    if let Err(e) = std::fs::rename(staging, target) {
        let _ = std::fs::rename(&aside, target);
        return Err(e);
    }
    Ok(Some(aside))
}

impl StagedDir {
    /// Prepares to fill `target`. Fails if `target` exists and is not an empty folder, unless
    /// `force` and it holds only state files.
    pub fn create(target: &Path, force: bool) -> anyhow::Result<Self> {
        if target.as_os_str().is_empty() || target.file_name().is_none() {
            bail!(
                "--out {:?}: expected a folder name (not `.`, `..` or a root)",
                target.display().to_string()
            );
        }
        if target.exists() {
            if !target.is_dir() {
                bail!(
                    "--out {}: expected a folder, found a file",
                    target.display()
                );
            }
            let entries: Vec<_> = std::fs::read_dir(target)
                .with_context(|| format!("reading --out {}", target.display()))?
                .collect::<Result<_, _>>()
                .with_context(|| format!("reading --out {}", target.display()))?;
            if !entries.is_empty() && !force {
                bail!(
                    "--out {} already holds {} entries (e.g. {}): give --force to replace \
                     an earlier run's output, or choose a new folder",
                    target.display(),
                    entries.len(),
                    entries[0].file_name().to_string_lossy()
                );
            }
            if !entries.is_empty()
                && let Some(foreign) = foreign_entry(target, &entries)
            {
                bail!(
                    "--out {} holds {foreign}, which this command did not write: refusing to \
                     replace the folder even with --force; choose a new folder",
                    target.display(),
                );
            }
        }
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("creating the folder {}", parent.display()))?;
        remove_abandoned_staging(&parent, target);
        let mut name = staging_prefix(target);
        name.push(std::process::id().to_string());
        let staging = parent.join(name);
        if staging.exists() {
            std::fs::remove_dir_all(&staging)
                .with_context(|| format!("removing {}", staging.display()))?;
        }
        std::fs::create_dir(&staging)
            .with_context(|| format!("creating the staging folder {}", staging.display()))?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            files: 0,
            names: Vec::new(),
            finished: false,
        })
    }

    /// Writes one file of the output (buffered, straight to disk).
    pub fn write(
        &mut self,
        name: &str,
        write: &dyn Fn(&mut dyn Write) -> std::io::Result<()>,
    ) -> anyhow::Result<()> {
        if name.contains(['/', '\\']) || name.starts_with('.') {
            bail!("output file name {name:?}: expected a plain file name");
        }
        let path = self.staging.join(name);
        if path.exists() {
            bail!("two outputs of this run are both named {name}");
        }
        let file =
            std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        let mut w = std::io::BufWriter::new(file);
        write(&mut w)
            .and_then(|()| w.flush())
            .with_context(|| format!("writing {} (of --out {})", name, self.target.display()))?;
        self.files += 1;
        self.names.push(name.to_owned());
        Ok(())
    }

    /// Lets `write` fill the staging folder itself (for writers that take a folder), then
    /// records every file it created as part of the output.
    pub fn write_into(
        &mut self,
        write: impl FnOnce(&Path) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        write(&self.staging)?;
        let mut created = Vec::new();
        for entry in std::fs::read_dir(&self.staging)
            .with_context(|| format!("reading {}", self.staging.display()))?
        {
            let name = entry
                .with_context(|| format!("reading {}", self.staging.display()))?
                .file_name()
                .to_string_lossy()
                .into_owned();
            if !self.names.contains(&name) {
                created.push(name);
            }
        }
        created.sort();
        self.files += created.len();
        self.names.extend(created);
        Ok(())
    }

    /// Moves the complete folder into place (with its manifest) and returns how many files
    /// it holds, not counting the manifest.
    pub fn finish(mut self) -> anyhow::Result<usize> {
        let manifest = self.staging.join(MANIFEST_FILE);
        let mut text = self.names.join("\n");
        text.push('\n');
        std::fs::write(&manifest, text)
            .with_context(|| format!("writing {}", manifest.display()))?;
        let replaced = swap_into_place(&self.staging, &self.target).with_context(|| {
            format!(
                "moving {} into place as {}",
                self.staging.display(),
                self.target.display()
            )
        })?;
        self.finished = true;
        if let Some(old) = replaced {
            std::fs::remove_dir_all(&old)
                .with_context(|| format!("removing the replaced output {}", old.display()))?;
        }
        Ok(self.files)
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.finished {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("cagerig-staged-{name}-{}", std::process::id()));
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
        let mut d = StagedDir::create(&out, false).unwrap();
        d.write("step0_joints.json", &|w| w.write_all(b"[]"))
            .unwrap();
        assert!(!out.exists(), "nothing visible before finish");
        assert_eq!(d.finish().unwrap(), 1);
        assert_eq!(entries(&out), [MANIFEST_FILE, "step0_joints.json"]);
        assert_eq!(entries(&root), ["out"]);

        // A failed run leaves the earlier output untouched and no staging folder.
        {
            let mut d = StagedDir::create(&out, true).unwrap();
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
        assert!(StagedDir::create(&out, false).is_err());
        let mut d = StagedDir::create(&out, true).unwrap();
        d.write("step5_mesh_rest.obj", &|w| w.write_all(b""))
            .unwrap();
        d.finish().unwrap();
        assert_eq!(entries(&out), [MANIFEST_FILE, "step5_mesh_rest.obj"]);
        assert_eq!(entries(&root), ["out"]);

        // Foreign files are never deleted, even with --force.
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let e = StagedDir::create(&out, true).err().unwrap();
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
        let e = StagedDir::create(&pictures, true).err().unwrap();
        assert!(e.to_string().contains("holiday.png"), "{e}");
        assert!(pictures.join("holiday.png").exists());

        let out = root.join("out");
        for run in 0..2 {
            let mut d = StagedDir::create(&out, run > 0).unwrap();
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
        assert!(StagedDir::create(&out, true).is_err());
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
        let d = StagedDir::create(&out, true).unwrap();
        if Path::new("/proc/self").exists() {
            assert_eq!(entries(&out), ["step0_joints.json"]);
            assert!(!aside.exists());
            assert!(stale.exists(), "another target's folder is left alone");
        }
        drop(d);
        // With --out present, a dead run's moved-aside copy is just removed.
        std::fs::create_dir_all(&aside).unwrap();
        let d = StagedDir::create(&out, true).unwrap();
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
        let d = StagedDir::create(&out, false).unwrap();
        assert!(!dead.exists() || !Path::new("/proc/self").exists());
        d.finish().unwrap();
        std::fs::remove_dir_all(&root).unwrap();
    }
}
