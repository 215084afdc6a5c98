//! Why an output folder could not be staged, filled or put in place: every variant names the
//! folder (as the front end calls it, e.g. `--out` or `export folder`) and what was expected.

use std::path::PathBuf;

use thiserror::Error;

/// How a front end names the output folder and its replace option in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FolderNaming {
    /// What the folder is called, e.g. `--out` (the CLI) or `export folder` (the editor).
    pub folder: &'static str,
    /// The option that allows replacing an earlier output, e.g. `--force` or `overwrite=True`;
    /// `None` for a front end that always replaces an earlier output of its own.
    pub replace_option: Option<&'static str>,
}

/// An output folder could not be staged, filled or put in place.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StagedDirError {
    /// The target has no folder name of its own (`.`, `..`, a root or empty).
    #[error("{folder} {:?}: expected a folder name (not `.`, `..` or a root)", path.display().to_string())]
    NotAFolderName {
        /// What the front end calls the folder.
        folder: &'static str,
        /// The target as given.
        path: PathBuf,
    },
    /// The target exists and is a file.
    #[error("{folder} {}: expected a folder, found a file", path.display())]
    NotAFolder {
        /// What the front end calls the folder.
        folder: &'static str,
        /// The target.
        path: PathBuf,
    },
    /// The target is a non-empty folder and replacing was not asked for.
    #[error(
        "{folder} {} already holds {count} entries (e.g. {example}): {}",
        path.display(),
        replace_hint(*replace_option)
    )]
    NotEmpty {
        /// What the front end calls the folder.
        folder: &'static str,
        /// The target.
        path: PathBuf,
        /// How many entries it holds.
        count: usize,
        /// The name of one of them.
        example: String,
        /// The option that would replace an earlier output.
        replace_option: Option<&'static str>,
    },
    /// The target holds an entry that no earlier cagerig output lists: it is never replaced.
    #[error(
        "{folder} {} holds {foreign}, which this command did not write: refusing to replace \
         the folder{}; choose a new folder",
        path.display(),
        replace_option.map(|o| format!(" even with {o}")).unwrap_or_default()
    )]
    Foreign {
        /// What the front end calls the folder.
        folder: &'static str,
        /// The target.
        path: PathBuf,
        /// The entry that makes the folder not an earlier output.
        foreign: String,
        /// The option that replaces earlier outputs (which does not apply here).
        replace_option: Option<&'static str>,
    },
    /// A file of the output was given a name that is not a plain file name.
    #[error("output file name {name:?}: expected a plain file name")]
    BadFileName {
        /// The name given.
        name: String,
    },
    /// Two files of one output were given the same name.
    #[error("two outputs of this run are both named {name}")]
    DuplicateName {
        /// The name given twice.
        name: String,
    },
    /// The operating system refused a step (`context` says which and names the path).
    #[error("{context}: {message}")]
    Io {
        /// What was being done, with the path, e.g. `creating the staging folder out/.a.partial-7`.
        context: String,
        /// The file or folder concerned.
        path: PathBuf,
        /// The kind of the I/O error.
        kind: std::io::ErrorKind,
        /// The operating system's message.
        message: String,
    },
}

fn replace_hint(option: Option<&'static str>) -> String {
    match option {
        Some(o) => format!("give {o} to replace an earlier run's output, or choose a new folder"),
        None => "choose a new folder".into(),
    }
}

impl StagedDirError {
    /// An I/O failure while `context` (which names `path`).
    pub(crate) fn io(context: String, path: &std::path::Path, e: &std::io::Error) -> Self {
        Self::Io {
            context,
            path: path.to_path_buf(),
            kind: e.kind(),
            message: e.to_string(),
        }
    }
}
