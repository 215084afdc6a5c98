//! glTF / FBX characters and automatic cages from Python: loading a skinned character (with a
//! generated cage when it has none), exporting a rig as glTF 2.0, and `generate_cage` over
//! numpy arrays.

use std::path::{Path, PathBuf};

use cagerig::Warning;
use cagerig::cage_gen::{CageLayout, CageOptions, generate_cage as generate};
use cagerig::cage_source::{CageOrigin, CageRequest, CageSourceError, generated_cage_note};
use cagerig::mesh::TriMesh;
use cagerig::session::RigParts;
use cagerig::skinning::SkinningMethod;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use cagerig_formats::OpenCharacterError;

use crate::convert;
use crate::errors::{RigError, file_error, format_error, rig_error};
use crate::rig::Rig;

/// Cage options for `vertices` target vertices, an optional margin (× bbox diagonal) and the
/// layout named `layout` (`cage_layout=`).
pub fn cage_options(vertices: usize, margin: Option<f64>, layout: &str) -> PyResult<CageOptions> {
    let layout: CageLayout = crate::options::named("cage_layout", layout)?;
    if vertices < 4 {
        return Err(PyValueError::new_err(format!(
            "a cage needs at least 4 vertices, asked for {vertices}"
        )));
    }
    let mut options = cagerig::cage_source::cage_options_with_vertices(vertices);
    if let Some(m) = margin {
        options.margin = m;
    }
    options.layout = layout;
    Ok(options)
}

/// Rig parts of a glTF / FBX character: its cage is `cage` (OBJ), else a cage node in the file,
/// else a generated one when `auto_cage` is given; with the skinning method the file says.
pub fn load_character(
    py: Python<'_>,
    path: &Path,
    cage: Option<&Path>,
    auto_cage: Option<usize>,
    cage_layout: &str,
    skin: Option<String>,
) -> PyResult<(RigParts, Vec<Warning>, Option<SkinningMethod>)> {
    let options = cagerig_formats::ImportOptions {
        skin,
        ..cagerig_formats::ImportOptions::default()
    };
    let request = CageRequest {
        given: cage,
        generate: auto_cage
            .map(|n| cage_options(n, None, cage_layout))
            .transpose()?,
        generated: None,
    };
    let opened = py
        .detach(|| cagerig_formats::open_character(path, &options, &request))
        .map_err(|e| match e {
            OpenCharacterError::Import(e) => format_error(e),
            OpenCharacterError::Cage(CageSourceError::Read(e)) => file_error(e),
            OpenCharacterError::Cage(
                e @ (CageSourceError::Generate { .. } | CageSourceError::Unusable { .. }),
            ) => RigError::new_err(e.to_string()),
            OpenCharacterError::Cage(CageSourceError::Missing { .. }) => {
                crate::errors::RigFileError::new_err(format!(
                    "{}: no cage: pass cage=CAGE.obj, or auto_cage=N to generate one with N \
                     vertices",
                    path.display()
                ))
            }
        })?;
    let mut warnings = opened.warnings;
    if let CageOrigin::Generated(g) = &opened.cage_origin {
        warnings.push(generated_cage_note(g));
    }
    Ok((opened.parts, warnings, opened.skinning))
}

#[pymethods]
impl Rig {
    /// Writes the rig's current state as glTF 2.0: ``.glb`` (binary) or ``.gltf`` (JSON with
    /// ``<stem>.bin`` beside it), replacing the files atomically. The rest skeleton and skin
    /// are the bind pose; the current pose is stored in the nodes.
    ///
    /// Parameters
    /// ----------
    /// path : str or os.PathLike
    ///     Ending in ``.glb`` or ``.gltf``.
    /// name : str, default "cagerig"
    ///     Name of the mesh and the skin in the file.
    /// bake : bool, default False
    ///     glTF skins with LBS only, so under ``"dqs"``, ``"cor"`` or ``"blended"`` a viewer
    ///     shows the LBS result of the pose (up to a few % of the diagonal off). With
    ///     ``bake=True`` the file also carries one morph target, at default weight 1, that turns
    ///     the viewer's LBS into this rig's posed skin (to the f32 rounding of the file); cagerig
    ///     reads the file back without it. Under ``"lbs"`` there is nothing to bake.
    #[pyo3(signature = (path, name = "cagerig", bake = false))]
    fn export_gltf(&self, py: Python<'_>, path: PathBuf, name: &str, bake: bool) -> PyResult<()> {
        let writable = cagerig_formats::CharacterFormat::of(&path).is_some_and(|f| f.can_export());
        if !writable {
            return Err(PyValueError::new_err(format!(
                "{}: expected a path ending in .glb or .gltf",
                path.display()
            )));
        }
        let session = self.session();
        py.detach(|| {
            if bake {
                cagerig_formats::export_character_baked(session, &path, name).map(|_| ())
            } else {
                cagerig_formats::export_character(session, &path, name)
            }
        })
        .map_err(format_error)
    }
}

/// A closed, validated deformation cage around a triangle mesh (``cagerig cage``'s method:
/// distance grid, marching tetrahedra, constrained edge collapses, offset search). The mesh has
/// no skeleton here, so the cage is one offset surface (``cage_layout="offset"``); a character
/// loaded with ``Rig.load(..., auto_cage=N)`` gets the skeleton layout.
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
/// triangles : (f, 3) int array
/// target_vertices : int, default 100
///     Vertex count of the cage (within ±10 %).
/// margin : float, optional
///     Least distance from the mesh to the cage as a fraction of the mesh's bounding-box
///     diagonal (default 0.005).
///
/// Returns
/// -------
/// cage_vertices : (c, 3) float64 array
/// cage_triangles : (g, 3) int64 array
///     Outward oriented, closed, one piece, without self-intersections, enclosing the mesh.
///
/// Raises
/// ------
/// RigError
///     When no valid cage can be made (the message says why and what to change).
#[pyfunction]
#[pyo3(signature = (vertices, triangles, target_vertices = 100, margin = None))]
pub fn generate_cage<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
    target_vertices: usize,
    margin: Option<f64>,
) -> PyResult<(convert::F64Array2<'py>, convert::I64Array2<'py>)> {
    let positions = convert::points(vertices, "vertices")?;
    let tris = convert::triangles(triangles, "triangles", positions.len())?;
    let mesh = TriMesh::new(positions, tris).map_err(rig_error)?;
    let options = cage_options(target_vertices, margin, CageLayout::Offset.name())?;
    let generated = py
        .detach(|| generate(&mesh, &options))
        .map_err(|e| RigError::new_err(format!("generate_cage: {e}")))?;
    Ok((
        convert::points_to_py(py, &generated.cage.positions)?,
        convert::triangles_to_py(py, &generated.cage.triangles)?,
    ))
}
