//! `Rig` output: the rig as a file set, one structure as OBJ.

use std::path::PathBuf;

use cagerig::io::staged_dir::{StagedDir, StagedDirError};
use cagerig::mesh::TriMesh;
use cagerig::rig_files::write_rig_files;
use cagerig::session::RigParts;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::{file_error, folder_error};
use crate::output_folder::DIRECTORY;
use crate::rig::{Rig, rest_joints};

/// Why [`Rig::save`] failed: a file of the set, or the folder.
enum SaveError {
    File(cagerig::io::ParseError),
    Folder(StagedDirError),
}

impl From<StagedDirError> for SaveError {
    fn from(e: StagedDirError) -> Self {
        Self::Folder(e)
    }
}

#[pymethods]
impl Rig {
    // ----- output ----------------------------------------------------------------------------

    /// Writes the current REST state as a rig file set that :meth:`load` reads back, as the
    /// folder ``directory``: ``<name>.obj`` (M), ``.skt`` (S), ``.skw`` (Ω), ``<name>_cage.obj``
    /// (C), ``<name>_cage_cageWeights.txt`` (Φ, with M = ΦC), ``<name>_cage.maxvol``
    /// (CageUp's rows) and, when the rig has them, ``<name>_dqBlendWeights.txt`` (the per-vertex
    /// DQ blend weights of the ``"blended"`` method). The folder appears complete or not at all (see :class:`OutputFolder`):
    /// it must be new or empty, or, with ``overwrite=True``, an earlier cagerig output, which is
    /// replaced as a whole; a folder holding other files raises ``FileExistsError``.
    #[pyo3(signature = (directory, name = "rig", overwrite = false))]
    fn save(
        &self,
        py: Python<'_>,
        directory: PathBuf,
        name: &str,
        overwrite: bool,
    ) -> PyResult<()> {
        let s = &self.session;
        let parts = RigParts::new(
            TriMesh {
                positions: s.rest_mesh().to_vec(),
                triangles: s.mesh_triangles().to_vec(),
            },
            s.skeleton().with_rest_positions(&rest_joints(s)),
            s.skin_weights().clone(),
            TriMesh {
                positions: s.rest_cage().to_vec(),
                triangles: s.cage_triangles().to_vec(),
            },
        )
        .with_dq_blend_weights(s.dq_blend_weights().cloned());
        py.detach(|| -> Result<(), SaveError> {
            let mut staged = StagedDir::create(&directory, overwrite, DIRECTORY)?;
            staged.write_into(|dir| {
                write_rig_files(dir, name, &parts, s.cage_coords(), s.cage_updater().rows())
                    .map_err(SaveError::File)
            })?;
            staged.finish()?;
            Ok(())
        })
        .map_err(|e| match e {
            SaveError::File(e) => file_error(e),
            SaveError::Folder(e) => folder_error(e),
        })
    }

    /// Writes one structure as OBJ: ``what`` is ``"posed_mesh"`` (M', default),
    /// ``"rest_mesh"`` (M), ``"posed_cage"`` (C') or ``"rest_cage"`` (C).
    #[pyo3(signature = (path, what = "posed_mesh"))]
    fn export_obj(&self, py: Python<'_>, path: PathBuf, what: &str) -> PyResult<()> {
        let s = &self.session;
        let (positions, triangles) = match what {
            "posed_mesh" => (s.posed_mesh(), s.mesh_triangles()),
            "rest_mesh" => (s.rest_mesh(), s.mesh_triangles()),
            "posed_cage" => (s.posed_cage(), s.cage_triangles()),
            "rest_cage" => (s.rest_cage(), s.cage_triangles()),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "what must be 'posed_mesh', 'rest_mesh', 'posed_cage' or 'rest_cage', got {what:?}"
                )));
            }
        };
        py.detach(|| cagerig::io::obj::write_obj(&path, positions, triangles))
            .map_err(file_error)
    }
}
