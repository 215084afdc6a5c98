//! Output folders that are complete or absent, shared by every front end (the CLI's `--out`
//! folders, the editor's File ▸ Export, Python's `Rig.save` and `replay_script`).
//!
//! The files are written into a staging folder beside the target (`.<name>.partial-<pid>`, or
//! `…-<pid>-<k>` for a process's k-th output) as they are produced (nothing is held in memory),
//! and the folder is renamed to the target only after the whole output was written
//! ([`StagedDir::finish`]). Dropping an unfinished [`StagedDir`] (an error) removes the staging
//! folder; after a kill, the next output into the same target removes the staging folders of
//! processes that no longer exist. An existing non-empty target is refused unless replacing is
//! asked for, and even then only when it is an earlier cagerig output: it holds the manifest
//! [`MANIFEST_FILE`] and nothing it does not list (so an output into `.` cannot delete
//! unrelated files, and a folder of the user's own pictures is never replaced).
//!
//! Replacing an earlier output is one atomic step on Linux (`renameat2(RENAME_EXCHANGE)` swaps
//! the two folders; the old one, now under the staging name, is removed after): a kill at any
//! moment leaves the target holding the complete earlier output or the complete new one. Where
//! the exchange is not available the old folder is first renamed to `.<name>.partial-<pid>.old`;
//! a kill between the two renames leaves the target absent, and the next output into it puts
//! that complete earlier output back before it starts.

mod error;
mod place;

use std::io::Write;
use std::path::{Path, PathBuf};

pub use error::{FolderNaming, StagedDirError};
use place::{
    foreign_entry, remove_abandoned_staging, staging_owner, staging_prefix, swap_into_place,
};

/// Suffixes of the files written for one rig state (`stepK.png`, `stepK_mesh_rest.obj`, …):
/// an output folder written before manifests existed counts as an earlier output when it holds
/// only such files (pictures alone are not enough).
pub const STATE_FILE_SUFFIXES: [&str; 6] = [
    ".png",
    "_mesh_rest.obj",
    "_mesh_posed.obj",
    "_cage_rest.obj",
    "_cage_posed.obj",
    "_joints.json",
];

/// The file in every output folder that lists the files of the output, one per line: what may
/// be replaced by a later output.
pub const MANIFEST_FILE: &str = ".cagerig-output";

/// A folder being filled; see the module documentation.
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    naming: FolderNaming,
    /// Names of the files written so far (the manifest's lines).
    names: Vec<String>,
    finished: bool,
}

impl StagedDir {
    /// Prepares to fill `target`. Fails if `target` exists and is not an empty folder, unless
    /// `replace` and it is an earlier cagerig output. `naming` says how messages call the
    /// folder and the option that sets `replace`.
    pub fn create(
        target: &Path,
        replace: bool,
        naming: FolderNaming,
    ) -> Result<Self, StagedDirError> {
        let folder = naming.folder;
        if target.as_os_str().is_empty() || target.file_name().is_none() {
            return Err(StagedDirError::NotAFolderName {
                folder,
                path: target.to_path_buf(),
            });
        }
        if target.exists() {
            if !target.is_dir() {
                return Err(StagedDirError::NotAFolder {
                    folder,
                    path: target.to_path_buf(),
                });
            }
            let reading = |e: std::io::Error| {
                StagedDirError::io(format!("reading {folder} {}", target.display()), target, &e)
            };
            let entries: Vec<_> = std::fs::read_dir(target)
                .map_err(reading)?
                .collect::<Result<_, _>>()
                .map_err(reading)?;
            if let Some(first) = entries.first() {
                if !replace {
                    return Err(StagedDirError::NotEmpty {
                        folder,
                        path: target.to_path_buf(),
                        count: entries.len(),
                        example: first.file_name().to_string_lossy().into_owned(),
                        replace_option: naming.replace_option,
                    });
                }
                if let Some(foreign) = foreign_entry(target, &entries) {
                    return Err(StagedDirError::Foreign {
                        folder,
                        path: target.to_path_buf(),
                        foreign,
                        replace_option: naming.replace_option,
                    });
                }
            }
        }
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        crate::io::atomic::create_folder(&parent).map_err(|e| {
            StagedDirError::io(
                format!("creating the folder of {}", target.display()),
                &parent,
                &e,
            )
        })?;
        remove_abandoned_staging(&parent, target);
        let mut name = staging_prefix(target);
        name.push(staging_owner());
        let staging = parent.join(name);
        if staging.exists() {
            // Left by an earlier process that had the same ID.
            std::fs::remove_dir_all(&staging).map_err(|e| {
                StagedDirError::io(format!("removing {}", staging.display()), &staging, &e)
            })?;
        }
        std::fs::create_dir(&staging).map_err(|e| {
            StagedDirError::io(
                format!("creating the staging folder {}", staging.display()),
                &staging,
                &e,
            )
        })?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            naming,
            names: Vec::new(),
            finished: false,
        })
    }

    /// The folder the output will be once finished.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The names of the files written so far, in the order they were written.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Writes one file of the output (buffered, straight to disk).
    pub fn write(
        &mut self,
        name: &str,
        write: &dyn Fn(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), StagedDirError> {
        if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
            return Err(StagedDirError::BadFileName { name: name.into() });
        }
        let path = self.staging.join(name);
        if path.exists() {
            return Err(StagedDirError::DuplicateName { name: name.into() });
        }
        let context = || {
            format!(
                "writing {} (of {} {})",
                name,
                self.naming.folder,
                self.target.display()
            )
        };
        let file = std::fs::File::create(&path)
            .map_err(|e| StagedDirError::io(format!("creating {}", path.display()), &path, &e))?;
        let mut w = std::io::BufWriter::new(file);
        write(&mut w)
            .and_then(|()| w.flush())
            .map_err(|e| StagedDirError::io(context(), &path, &e))?;
        self.names.push(name.to_owned());
        Ok(())
    }

    /// Lets `write` fill the staging folder itself (for writers that take a folder), then
    /// records every file it created as part of the output.
    pub fn write_into<E: From<StagedDirError>>(
        &mut self,
        write: impl FnOnce(&Path) -> Result<(), E>,
    ) -> Result<(), E> {
        write(&self.staging)?;
        let reading = |e: std::io::Error| {
            StagedDirError::io(
                format!("reading {}", self.staging.display()),
                &self.staging,
                &e,
            )
        };
        let mut created = Vec::new();
        for entry in std::fs::read_dir(&self.staging).map_err(reading)? {
            let name = entry
                .map_err(reading)?
                .file_name()
                .to_string_lossy()
                .into_owned();
            if !self.names.contains(&name) {
                created.push(name);
            }
        }
        created.sort();
        self.names.extend(created);
        Ok(())
    }

    /// Moves the complete folder into place (with its manifest) and returns how many files
    /// it holds, not counting the manifest.
    pub fn finish(mut self) -> Result<usize, StagedDirError> {
        let manifest = self.staging.join(MANIFEST_FILE);
        let mut text = self.names.join("\n");
        text.push('\n');
        std::fs::write(&manifest, text).map_err(|e| {
            StagedDirError::io(format!("writing {}", manifest.display()), &manifest, &e)
        })?;
        let replaced = swap_into_place(&self.staging, &self.target).map_err(|e| {
            StagedDirError::io(
                format!(
                    "moving {} into place as {}",
                    self.staging.display(),
                    self.target.display()
                ),
                &self.target,
                &e,
            )
        })?;
        self.finished = true;
        if let Some(old) = replaced {
            std::fs::remove_dir_all(&old).map_err(|e| {
                StagedDirError::io(
                    format!("removing the replaced output {}", old.display()),
                    &old,
                    &e,
                )
            })?;
        }
        Ok(self.names.len())
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
mod tests;
