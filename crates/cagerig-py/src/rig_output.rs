//! `Rig` output: the rig as a file set, one structure as OBJ.

use std::path::PathBuf;

use cagerig::mesh::TriMesh;
use cagerig::rig_files::write_rig_files;
use cagerig::session::RigParts;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::file_error;
use crate::rig::{Rig, rest_joints};

#[pymethods]
impl Rig {
    // ----- output ----------------------------------------------------------------------------

    /// Writes the current REST state as a rig file set that :meth:`load` reads back:
    /// ``<name>.obj`` (M), ``.skt`` (S), ``.skw`` (Ω), ``<name>_cage.obj`` (C),
    /// ``<name>_cage_cageWeights.txt`` (Φ, with M = ΦC) and ``<name>_cage.maxvol`` (CageUp's
    /// rows), each replaced atomically. The directory is created if needed.
    #[pyo3(signature = (directory, name = "rig"))]
    fn save(&self, py: Python<'_>, directory: PathBuf, name: &str) -> PyResult<()> {
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
        );
        py.detach(|| {
            std::fs::create_dir_all(&directory).map_err(|e| cagerig::io::ParseError::Io {
                path: directory.clone(),
                kind: e.kind(),
                message: e.to_string(),
            })?;
            write_rig_files(
                &directory,
                name,
                &parts,
                s.cage_coords(),
                s.cage_updater().rows(),
            )
        })
        .map_err(file_error)
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
