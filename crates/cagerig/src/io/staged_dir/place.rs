//! The file-system steps of [`super::StagedDir`]: naming the staging folder, cleaning up after
//! killed runs, telling an earlier output from the user's own folder, and the final swap.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use super::{MANIFEST_FILE, STATE_FILE_SUFFIXES};

/// `.<name>.partial-` for `target` = `…/<name>`.
pub(super) fn staging_prefix(target: &Path) -> OsString {
    let mut prefix = OsString::from(".");
    prefix.push(target.file_name().unwrap_or_default());
    prefix.push(".partial-");
    prefix
}

/// The owner part of a staging name: `<pid>` for the first output of a process, `<pid>-<k>`
/// for its k-th (so two outputs of one process, e.g. two Python calls on two threads, never
/// share a staging folder).
pub(super) fn staging_owner() -> String {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let pid = std::process::id();
    match NEXT.fetch_add(1, Ordering::Relaxed) {
        0 => pid.to_string(),
        k => format!("{pid}-{k}"),
    }
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
pub(super) fn remove_abandoned_staging(parent: &Path, target: &Path) {
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
        let (owner, moved_aside) = match rest.strip_suffix(".old") {
            Some(owner) => (owner, true),
            None => (rest, false),
        };
        let pid = owner.split('-').next().unwrap_or(owner);
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

/// Whether `target` (an existing folder with `entries`) is an earlier cagerig output that may
/// be replaced; otherwise the entry that makes it not one.
pub(super) fn foreign_entry(target: &Path, entries: &[std::fs::DirEntry]) -> Option<String> {
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
pub(super) fn swap_into_place(staging: &Path, target: &Path) -> std::io::Result<Option<PathBuf>> {
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
