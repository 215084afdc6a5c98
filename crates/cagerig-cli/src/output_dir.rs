//! Output folders that are complete or absent: `edit` and `animate` write every file into a
//! staging folder beside `--out` (`.<name>.partial-<pid>`) as each state is produced (nothing is
//! held in memory), and rename it to `--out` only after the whole run succeeded. On an error the
//! staging folder is removed; after a kill, the next run into the same `--out` removes the
//! staging folders of processes that no longer exist. An existing non-empty `--out` is refused
//! unless `--force`, and even then only when it holds nothing but files cagerig writes for a
//! state (so `--out . --force` cannot delete unrelated files); the old folder is removed only
//! once the new one is in place.

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

/// A folder being filled; see the module documentation.
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    files: usize,
    finished: bool,
}

fn staging_prefix(target: &Path) -> OsString {
    let mut prefix = OsString::from(".");
    prefix.push(target.file_name().unwrap_or_default());
    prefix.push(".partial-");
    prefix
}

/// Removes staging folders of `target` left by processes that no longer run (Linux: /proc).
fn remove_abandoned_staging(parent: &Path, target: &Path) {
    let prefix = staging_prefix(target);
    let prefix = prefix.to_string_lossy();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if let Some(pid) = name.strip_prefix(prefix.as_ref())
            && pid.parse::<u32>().is_ok()
            && Path::new("/proc/self").exists()
            && !Path::new("/proc").join(pid).exists()
        {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
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
            if let Some(foreign) = entries.iter().find(|e| {
                let name = e.file_name();
                let name = name.to_string_lossy();
                !e.path().is_file() || !STATE_FILE_SUFFIXES.iter().any(|s| name.ends_with(s))
            }) {
                bail!(
                    "--out {} holds {}, which cagerig did not write: refusing to replace the \
                     folder even with --force; choose a new folder",
                    target.display(),
                    foreign.file_name().to_string_lossy()
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
        Ok(())
    }

    /// Moves the complete folder into place and returns how many files it holds.
    pub fn finish(mut self) -> anyhow::Result<usize> {
        let mut old = None;
        if self.target.exists() {
            let mut aside = self.staging.clone().into_os_string();
            aside.push(".old");
            let aside = PathBuf::from(aside);
            std::fs::rename(&self.target, &aside)
                .with_context(|| format!("moving the old {} aside", self.target.display()))?;
            old = Some(aside);
        }
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            if let Some(aside) = &old {
                let _ = std::fs::rename(aside, &self.target);
            }
            return Err(e).with_context(|| {
                format!(
                    "moving {} into place as {}",
                    self.staging.display(),
                    self.target.display()
                )
            });
        }
        self.finished = true;
        if let Some(aside) = old {
            std::fs::remove_dir_all(&aside)
                .with_context(|| format!("removing the replaced output {}", aside.display()))?;
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
        assert_eq!(entries(&out), ["step0_joints.json"]);
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
        assert_eq!(entries(&out), ["step5_mesh_rest.obj"]);
        assert_eq!(entries(&root), ["out"]);

        // Foreign files are never deleted, even with --force.
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let e = StagedDir::create(&out, true).err().unwrap();
        assert!(e.to_string().contains("notes.txt"), "{e}");
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
