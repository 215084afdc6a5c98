//! Python exceptions for the library's errors. Messages are the library's own (`Display`), which
//! name the file, line or element, what was expected and what was found.

use pyo3::exceptions::{
    PyFileNotFoundError, PyOSError, PyPermissionError, PyUserWarning, PyValueError,
};
use pyo3::prelude::*;

pyo3::create_exception!(
    cagerig,
    RigError,
    PyValueError,
    "The library refused an input or an operation (cagerig's own message). Subclass of ValueError."
);
pyo3::create_exception!(
    cagerig,
    RigFileError,
    RigError,
    "A rig or animation file could not be parsed; the message names the file and line."
);
pyo3::create_exception!(
    cagerig,
    ScriptError,
    RigError,
    "An edit script is malformed or does not fit the rig; the message names the step (1-based)."
);
pyo3::create_exception!(
    cagerig,
    RigWarning,
    PyUserWarning,
    "Something was accepted but changed or is suspicious (weights renormalised, cage flipped, …)."
);

/// A library error as a [`RigError`] exception.
pub fn rig_error(e: cagerig::RigError) -> PyErr {
    RigError::new_err(e.to_string())
}

/// A file error: the OS's refusals as `OSError` subclasses (a file standing where an output's
/// folder must be as `NotADirectoryError`), everything else as [`RigFileError`].
pub fn file_error(e: cagerig::io::ParseError) -> PyErr {
    use std::io::ErrorKind;
    match &e {
        cagerig::io::ParseError::Io { kind, .. } => match kind {
            ErrorKind::NotFound => PyFileNotFoundError::new_err(e.to_string()),
            ErrorKind::PermissionDenied => PyPermissionError::new_err(e.to_string()),
            ErrorKind::NotADirectory => {
                pyo3::exceptions::PyNotADirectoryError::new_err(e.to_string())
            }
            _ => PyOSError::new_err(e.to_string()),
        },
        _ => RigFileError::new_err(e.to_string()),
    }
}

/// An output-folder error: a folder that may not be replaced as `FileExistsError`, a file in
/// place of it as `NotADirectoryError`, the OS's refusals as `OSError` subclasses, a bad name as
/// `ValueError`.
pub fn folder_error(e: cagerig::io::StagedDirError) -> PyErr {
    use cagerig::io::StagedDirError as E;
    use pyo3::exceptions::{PyFileExistsError, PyNotADirectoryError};
    use std::io::ErrorKind;
    let message = e.to_string();
    match &e {
        E::NotEmpty { .. } | E::Foreign { .. } => PyFileExistsError::new_err(message),
        E::NotAFolder { .. } => PyNotADirectoryError::new_err(message),
        E::NotAFolderName { .. } | E::BadFileName { .. } | E::DuplicateName { .. } => {
            PyValueError::new_err(message)
        }
        E::Io { kind, .. } => match kind {
            ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
            ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
            ErrorKind::NotADirectory => PyNotADirectoryError::new_err(message),
            _ => PyOSError::new_err(message),
        },
    }
}

/// An edit-script error as a [`ScriptError`].
pub fn script_error(e: cagerig::script::ScriptError) -> PyErr {
    ScriptError::new_err(e.to_string())
}

/// Issues each library warning as a Python [`RigWarning`] pointing at the caller's line.
pub fn warn_all(py: Python<'_>, warnings: &[cagerig::Warning]) -> PyResult<()> {
    if warnings.is_empty() {
        return Ok(());
    }
    let category = py.get_type::<RigWarning>();
    let warn = py.import("warnings")?.getattr("warn")?;
    for w in warnings {
        warn.call1((w.to_string(), &category, 1))?;
    }
    Ok(())
}

/// An interchange-format (glTF / FBX) error: a missing file as `FileNotFoundError`, everything
/// else as [`RigFileError`] (the message names the file and the element).
pub fn format_error(e: cagerig_formats::FormatError) -> PyErr {
    match &e {
        cagerig_formats::FormatError::Io { path, .. } if !path.exists() => {
            PyFileNotFoundError::new_err(e.to_string())
        }
        _ => RigFileError::new_err(e.to_string()),
    }
}
