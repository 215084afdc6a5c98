//! The `.cagerig` session file: what to open and everything edited, as JSON.
//!
//! ```json
//! {"format": "cagerig-studio-session", "version": 1,
//!  "source": {"kind": "builtin", "name": "snake", "resolution": 4096},
//!  "state": {"rig": {"rest_cage": [[x,y,z],…], "rest_joints": […], "posed_cage": […],
//!                    "rotations": [[x,y,z,w],…], "scales": […], "translation_offsets": […],
//!                    "skinning": "lbs", "locks": {"skel_up": false, "cage_up": false},
//!                    "coords": "mvc", "unfitted_cage": "refuse"},
//!            "keys": {"skeleton": [{"time": 0.0, "rotations": …, "scales": …,
//!                                   "translation_offsets": …}],
//!                     "cage": [{"time": 0.0, "rest_cage": …}]}},
//!  "time": 0.0,
//!  "cameras": [[tx, ty, tz, distance, yaw, pitch, fov_y], [… rest view …]]}
//! ```
//! `source` is a built-in rig or `{"kind": "file", "path": …, "cage": null, "skin": null}`
//! (absolute paths). Files are written atomically (temporary file + rename). A file of a newer
//! version or a damaged one is refused with a message naming it; nothing is lost or changed.
//! The autosave after edits writes the same format to a recovery file in the state directory
//! (`$CAGERIG_STUDIO_STATE_DIR`, else `$XDG_STATE_HOME/cagerig-studio`, else
//! `~/.local/state/cagerig-studio`), removed on a clean exit and offered at the next start.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::document::Snapshot;
use crate::rig_open::RigSource;

/// The `format` value of a session file.
pub const FORMAT: &str = "cagerig-studio-session";
/// The newest version this build reads and writes: 2 adds a skeleton being built
/// (`state.draft`) and a skeleton bound in the studio (`binding`). A file without them is
/// written as version 1, which older builds read.
pub const VERSION: u32 = 2;

/// A session file's content.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionFile {
    pub format: String,
    pub version: u32,
    pub source: RigSource,
    pub state: Snapshot,
    /// Timeline position (seconds).
    #[serde(default)]
    pub time: f64,
    /// Cameras of the current and rest views: target x, y, z, distance, yaw, pitch, vertical
    /// field of view (radians); absent: framed on opening.
    #[serde(default)]
    pub cameras: Option<[[f64; 7]; 2]>,
    /// A skeleton and weights bound in the studio (absent: the source's own rig).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub binding: Option<crate::saved_binding::SavedBinding>,
}

#[derive(Debug, Error)]
pub enum SessionFileError {
    #[error("{path}: cannot read the session file: {message}", path = path.display())]
    Read { path: PathBuf, message: String },
    #[error(
        "{path}: not a cagerig session file (expected a JSON object with \"format\": \"{FORMAT}\"; \
         {found})",
        path = path.display()
    )]
    NotASession { path: PathBuf, found: String },
    #[error(
        "{path}: written by a newer cagerig-studio (session version {found}; this one reads \
         versions up to {VERSION}); update cagerig-studio to open it — the file was left as it is",
        path = path.display()
    )]
    Newer { path: PathBuf, found: u64 },
    #[error("{path}: damaged session file: {message}", path = path.display())]
    Damaged { path: PathBuf, message: String },
    #[error("{path}: cannot write the session file: {message}", path = path.display())]
    Write { path: PathBuf, message: String },
}

impl SessionFile {
    pub fn new(source: RigSource, state: Snapshot, time: f64) -> Self {
        Self {
            format: FORMAT.into(),
            version: 1,
            source: absolute_source(source),
            state,
            time,
            cameras: None,
            binding: None,
        }
        .versioned()
    }

    /// Sets the version to the oldest that holds this content (see [`VERSION`]).
    pub fn versioned(mut self) -> Self {
        self.version = if self.binding.is_some() || self.state.draft.is_some() {
            VERSION
        } else {
            1
        };
        self
    }

    /// Parses a session file's text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SessionFileError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| SessionFileError::NotASession {
                path: path.to_path_buf(),
                found: format!("it is not JSON: {e}"),
            })?;
        let format = value.get("format").and_then(|f| f.as_str());
        if format != Some(FORMAT) {
            return Err(SessionFileError::NotASession {
                path: path.to_path_buf(),
                found: match format {
                    Some(f) => format!("found \"format\": {f:?}"),
                    None => "found no \"format\" string".into(),
                },
            });
        }
        let version = value.get("version").and_then(|v| v.as_u64());
        match version {
            Some(v) if v > u64::from(VERSION) => {
                return Err(SessionFileError::Newer {
                    path: path.to_path_buf(),
                    found: v,
                });
            }
            Some(v) if v >= 1 => {}
            _ => {
                return Err(SessionFileError::Damaged {
                    path: path.to_path_buf(),
                    message: format!(
                        "\"version\": expected an integer 1 to {VERSION}, found {}",
                        value
                            .get("version")
                            .map_or("nothing".into(), |v| v.to_string())
                    ),
                });
            }
        }
        let file: SessionFile =
            serde_json::from_value(value).map_err(|e| SessionFileError::Damaged {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
        if let Some(c) = file
            .cameras
            .iter()
            .flatten()
            .flatten()
            .find(|v| !v.is_finite())
        {
            return Err(SessionFileError::Damaged {
                path: path.to_path_buf(),
                message: format!("\"cameras\": expected finite numbers, found {c}"),
            });
        }
        if !file.time.is_finite() {
            return Err(SessionFileError::Damaged {
                path: path.to_path_buf(),
                message: format!("\"time\": expected a finite number, found {}", file.time),
            });
        }
        Ok(file)
    }

    /// Reads a session file.
    pub fn read(path: &Path) -> Result<Self, SessionFileError> {
        let text = std::fs::read_to_string(path).map_err(|e| SessionFileError::Read {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Self::parse(&text, path)
    }

    /// The file's text (JSON), as [`Self::write`] writes it; `path` names it in the error.
    pub fn to_text(&self, path: &Path) -> Result<String, SessionFileError> {
        serde_json::to_string(self).map_err(|e| SessionFileError::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    }

    /// Writes the file atomically (temporary file beside it, then rename).
    pub fn write(&self, path: &Path) -> Result<(), SessionFileError> {
        let text = self.to_text(path)?;
        // Creates a missing folder; the error names the path once.
        cagerig::io::write_atomically(path, |w| w.write_all(text.as_bytes())).map_err(|e| {
            SessionFileError::Write {
                path: path.to_path_buf(),
                message: e.reason(),
            }
        })
    }
}

/// File sources with absolute paths, so a session opens from any working directory.
fn absolute_source(source: RigSource) -> RigSource {
    match source {
        RigSource::File {
            path,
            cage,
            skin,
            auto_cage,
        } => RigSource::File {
            path: std::path::absolute(&path).unwrap_or(path),
            cage: cage.map(|c| std::path::absolute(&c).unwrap_or(c)),
            skin,
            auto_cage,
        },
        // A file opened from memory (the web edition) reopens as the file of that name.
        RigSource::Memory {
            path, auto_cage, ..
        } => RigSource::File {
            path,
            cage: None,
            skin: None,
            auto_cage,
        },
        builtin @ RigSource::Builtin { .. } => builtin,
    }
}

/// The studio's state directory (recovery file, recent files).
pub fn default_state_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("CAGERIG_STUDIO_STATE_DIR") {
        return PathBuf::from(dir);
    }
    if let Some(dir) = std::env::var_os("XDG_STATE_HOME") {
        return PathBuf::from(dir).join("cagerig-studio");
    }
    match std::env::var_os("HOME") {
        Some(home) => PathBuf::from(home).join(".local/state/cagerig-studio"),
        None => std::env::temp_dir().join("cagerig-studio"),
    }
}

/// The recovery file and the recent-files list in a state directory.
#[derive(Debug, Clone)]
pub struct StateDir {
    dir: PathBuf,
}

impl StateDir {
    pub fn new(dir: PathBuf) -> Self {
        Self { dir }
    }

    pub fn recovery_path(&self) -> PathBuf {
        self.dir.join("recovery.cagerig")
    }

    /// The recovery file left by a session that did not exit cleanly, if any.
    pub fn pending_recovery(&self) -> Option<PathBuf> {
        let path = self.recovery_path();
        path.is_file().then_some(path)
    }

    /// Autosave.
    pub fn write_recovery(&self, file: &SessionFile) -> Result<(), SessionFileError> {
        file.write(&self.recovery_path())
    }

    /// After a clean exit or when the user discards the recovery.
    pub fn clear_recovery(&self) {
        let _ = std::fs::remove_file(self.recovery_path());
    }

    fn recent_path(&self) -> PathBuf {
        self.dir.join("recent.json")
    }

    /// Recently opened files, newest first (an unreadable list is treated as empty).
    pub fn recent(&self) -> Vec<PathBuf> {
        std::fs::read_to_string(self.recent_path())
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default()
    }

    /// Puts `path` first in the recent files (at most 10).
    pub fn add_recent(&self, path: &Path) {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let mut list = self.recent();
        list.retain(|p| p != &path);
        list.insert(0, path);
        list.truncate(10);
        if std::fs::create_dir_all(&self.dir).is_ok()
            && let Ok(text) = serde_json::to_string(&list)
        {
            let _ = cagerig::io::write_atomically(&self.recent_path(), |w| {
                w.write_all(text.as_bytes())
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::document::Document;
    use crate::rig_open::open_rig;

    fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("cagerig-studio-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn file() -> SessionFile {
        let source = RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        };
        let opened = open_rig(&source).unwrap();
        let doc = Document::new(source.clone(), opened.session);
        SessionFile::new(source, doc.snapshot(), 0.25)
    }

    #[test]
    fn a_session_file_round_trips_exactly() {
        let dir = temp_dir("roundtrip");
        let path = dir.join("a.cagerig");
        let f = file();
        f.write(&path).unwrap();
        assert_eq!(SessionFile::read(&path).unwrap(), f);
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn a_newer_version_is_refused_clearly() {
        let mut value = serde_json::to_value(file()).unwrap();
        value["version"] = 7.into();
        let err = SessionFile::parse(&value.to_string(), Path::new("x.cagerig"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("x.cagerig") && err.contains("newer") && err.contains('7'),
            "{err}"
        );
    }

    #[test]
    fn damaged_and_foreign_files_are_refused_with_the_file_named() {
        let text = serde_json::to_string(&file()).unwrap();
        let cut = &text[..text.len() / 2];
        let err = SessionFile::parse(cut, Path::new("cut.cagerig"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("cut.cagerig"), "{err}");
        let err = SessionFile::parse("{\"a\":1}", Path::new("other.json"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("not a cagerig session file"), "{err}");
        let mut value = serde_json::to_value(file()).unwrap();
        value["state"]["rig"]["rest_cage"] = serde_json::json!("oops");
        let err = SessionFile::parse(&value.to_string(), Path::new("bad.cagerig"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("damaged") && err.contains("bad.cagerig"),
            "{err}"
        );
    }

    #[test]
    fn recovery_and_recent_files_live_in_the_state_dir() {
        let dir = temp_dir("state");
        let state = StateDir::new(dir.clone());
        assert!(state.pending_recovery().is_none());
        state.write_recovery(&file()).unwrap();
        assert!(state.pending_recovery().is_some());
        state.clear_recovery();
        assert!(state.pending_recovery().is_none());
        state.add_recent(Path::new("/tmp/a.obj"));
        state.add_recent(Path::new("/tmp/b.obj"));
        state.add_recent(Path::new("/tmp/a.obj"));
        assert_eq!(
            state.recent(),
            [PathBuf::from("/tmp/a.obj"), PathBuf::from("/tmp/b.obj")]
        );
        std::fs::remove_dir_all(dir).ok();
    }
}
