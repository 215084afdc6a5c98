//! `OutputFolder`: files that appear together or not at all (the library's
//! [`StagedDir`], shared with the CLI's `--out` folders and the editor's export).

use std::path::PathBuf;
use std::sync::Mutex;

use cagerig::io::staged_dir::{FolderNaming, StagedDir};
use cagerig::io::text::FloatFormat;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::convert;
use crate::errors::folder_error;

/// How Python messages name the folder and the argument that replaces an earlier output.
pub const DIRECTORY: FolderNaming = FolderNaming {
    folder: "directory",
    replace_option: Some("overwrite=True"),
};

/// A folder of files that appears complete, only when :meth:`finish` is called (or the ``with``
/// block ends without an exception); until then the files are written into a staging folder
/// beside it (``.<name>.partial-<pid>``), which is removed if the output is abandoned.
///
/// ``directory`` must be new or empty; with ``overwrite=True`` it may also be an earlier
/// cagerig output (its ``.cagerig-output`` manifest lists every file in it), which is then
/// replaced as a whole. A folder holding anything else is never replaced (``FileExistsError``).
#[pyclass(module = "cagerig", name = "OutputFolder")]
pub struct OutputFolder {
    staged: Mutex<Option<StagedDir>>,
    target: PathBuf,
}

impl OutputFolder {
    fn with_staged<T>(&self, f: impl FnOnce(&mut StagedDir) -> PyResult<T>) -> PyResult<T> {
        let mut guard = self
            .staged
            .lock()
            .map_err(|_| PyValueError::new_err("the output folder was poisoned by a panic"))?;
        match guard.as_mut() {
            Some(staged) => f(staged),
            None => Err(PyValueError::new_err(format!(
                "the output folder {} is already finished or discarded",
                self.target.display()
            ))),
        }
    }
}

#[pymethods]
impl OutputFolder {
    #[new]
    #[pyo3(signature = (directory, overwrite = false))]
    fn new(py: Python<'_>, directory: PathBuf, overwrite: bool) -> PyResult<Self> {
        let staged = py
            .detach(|| StagedDir::create(&directory, overwrite, DIRECTORY))
            .map_err(folder_error)?;
        Ok(Self {
            staged: Mutex::new(Some(staged)),
            target: directory,
        })
    }

    /// Writes ``name`` (a plain file name) as OBJ: ``vertices`` ``(n, 3)`` and ``triangles``
    /// ``(m, 3)``, round-trip exact floats.
    fn write_obj(
        &self,
        name: &str,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let pos = convert::points(vertices, "vertices")?;
        let tris = convert::triangles(triangles, "triangles", pos.len())?;
        self.with_staged(|staged| {
            staged
                .write(name, &|w| {
                    cagerig::io::obj::write_obj_to(w, &pos, &tris, FloatFormat::RoundTrip)
                })
                .map_err(folder_error)
        })
    }

    /// Writes ``name`` (a plain file name) holding ``text`` (UTF-8).
    fn write_text(&self, name: &str, text: &str) -> PyResult<()> {
        self.with_staged(|staged| {
            staged
                .write(name, &|w| w.write_all(text.as_bytes()))
                .map_err(folder_error)
        })
    }

    /// Puts the complete folder in place and returns its files (``pathlib.Path``), in the order
    /// they were written.
    fn finish(&self, py: Python<'_>) -> PyResult<Vec<PathBuf>> {
        let staged = self
            .staged
            .lock()
            .map_err(|_| PyValueError::new_err("the output folder was poisoned by a panic"))?
            .take();
        let Some(staged) = staged else {
            return Err(PyValueError::new_err(format!(
                "the output folder {} is already finished or discarded",
                self.target.display()
            )));
        };
        let names = staged.names().to_vec();
        py.detach(|| staged.finish()).map_err(folder_error)?;
        Ok(names.iter().map(|n| self.target.join(n)).collect())
    }

    /// Abandons the output: the staging folder is removed and ``directory`` is left as it was.
    fn discard(&self) -> PyResult<()> {
        if let Ok(mut guard) = self.staged.lock() {
            guard.take();
        }
        Ok(())
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// Finishes the folder when the block ended normally (unless already finished), discards
    /// it when it raised.
    fn __exit__(
        &self,
        py: Python<'_>,
        exc_type: Option<&Bound<'_, PyAny>>,
        _exc_value: Option<&Bound<'_, PyAny>>,
        _traceback: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        let pending = self.staged.lock().map(|g| g.is_some()).unwrap_or(false);
        if exc_type.is_some() || !pending {
            self.discard()?;
        } else {
            self.finish(py)?;
        }
        Ok(false)
    }
}
