//! Automatic skinning weights from Python (`cagerig.skin_weights`), and the skeleton built from
//! joint arrays that it shares with `Rig.from_arrays`.

use cagerig::Skeleton;
use cagerig::auto_weights::{AutoWeights, AutoWeightsOptions, TipJoints};
use cagerig::mesh::TriMesh;
use cagerig::skeleton::Joint;
use cagerig::weights_source::WeightsSourceError;
use glam::DAffine3;
use numpy::PyArrayMethods;
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;

use crate::convert;
use crate::errors::{RigError, file_error, rig_error, warn_all};

/// A skeleton from `(J, 3)` rest joint positions, `(J,)` parents (-1 for a root) and optional
/// names (default `joint0`, `joint1`, …); rest frames get identity rotations.
pub fn skeleton_from_arrays(
    joint_positions: &Bound<'_, PyAny>,
    joint_parents: &Bound<'_, PyAny>,
    joint_names: Option<Vec<String>>,
) -> PyResult<Skeleton> {
    let joints = convert::points(joint_positions, "joint_positions")?;
    let nj = joints.len();
    let parents_arr = convert::int_array(joint_parents, "joint_parents")?;
    let parents: Vec<i64> = parents_arr.readonly().as_array().iter().copied().collect();
    if parents.len() != nj {
        return Err(PyValueError::new_err(format!(
            "joint_parents must have one entry per joint ({nj}), got {}",
            parents.len()
        )));
    }
    let names = joint_names.unwrap_or_else(|| (0..nj).map(|j| format!("joint{j}")).collect());
    if names.len() != nj {
        return Err(PyValueError::new_err(format!(
            "joint_names must have one name per joint ({nj}), got {}",
            names.len()
        )));
    }
    let mut skeleton_joints = Vec::with_capacity(nj);
    for (j, ((p, name), position)) in parents.iter().zip(names).zip(&joints).enumerate() {
        let parent = match *p {
            -1 => None,
            p if p >= 0 && (p as usize) < nj => Some(p as usize),
            p => {
                return Err(PyIndexError::new_err(format!(
                    "joint_parents[{j}] = {p} is out of range (-1 for a root, else 0..{nj})"
                )));
            }
        };
        skeleton_joints.push(Joint {
            name,
            parent,
            rest_world_from_joint: DAffine3::from_translation(*position),
        });
    }
    Skeleton::new(skeleton_joints).map_err(rig_error)
}

/// A weights-source failure as a Python error (files as file errors, the rest as RigError).
pub fn weights_source_error(e: WeightsSourceError) -> PyErr {
    match e {
        WeightsSourceError::Read(e) => file_error(e),
        e @ WeightsSourceError::Automatic { .. } => RigError::new_err(e.to_string()),
    }
}

/// Automatic skinning weights Ω (geodesic voxel binding, as ``cagerig weights``): the
/// geodesic distance through the voxelised volume of the mesh from each joint's bones, an
/// inverse-power falloff, the strongest ``max_influences`` kept. Works on triangle soups,
/// several pieces and meshes with small holes.
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
///     Rest skin M.
/// triangles : (f, 3) int array
/// joint_positions : (J, 3) float64 array
///     Rest joint positions, in the mesh's space.
/// parents : (J,) int array
///     Parent of each joint, -1 for a root. Joint j's bones are the segments to its children.
/// max_influences : int, default 4
///     Most joints per vertex.
/// cage : tuple of ((c, 3) float64 array, (g, 3) int array), optional
///     A closed cage around the mesh; its interior is part of the volume.
/// joint_names : list of str, optional
///     Names (used by ``tips`` and to recognise end markers such as ``head_end``).
/// tips : {"auto", "all", "none"} or list of int, default "auto"
///     Which joints with no child deform: all but names ending in end/nub/tip/null, all, none,
///     or the listed tip joints.
/// resolution : int, default 128
///     Voxels along the longest side of the mesh's box.
/// exponent : float, default 8
///     Falloff exponent: larger gives sharper joints.
///
/// Returns
/// -------
/// (n, J) float64 array
///     Rows sum to 1, at most ``max_influences`` non-zeros each; joints that do not deform
///     (zero-length bones, static tips) have zero columns.
///
/// Raises
/// ------
/// ValueError, IndexError
///     Malformed arrays or options.
/// RigError
///     No triangle, no deforming joint, a grid too large.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, joint_positions, parents, max_influences = 4,
                    cage = None, *, joint_names = None, tips = None, resolution = 128,
                    exponent = 8.0))]
#[expect(clippy::too_many_arguments)]
pub fn skin_weights<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
    joint_positions: &Bound<'py, PyAny>,
    parents: &Bound<'py, PyAny>,
    max_influences: usize,
    cage: Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    joint_names: Option<Vec<String>>,
    tips: Option<&Bound<'py, PyAny>>,
    resolution: usize,
    exponent: f64,
) -> PyResult<convert::F64Array2<'py>> {
    let positions = convert::points(vertices, "vertices")?;
    let tris = convert::triangles(triangles, "triangles", positions.len())?;
    let mesh = TriMesh::new(positions, tris).map_err(rig_error)?;
    let skeleton = skeleton_from_arrays(joint_positions, parents, joint_names)?;
    let cage = match cage {
        Some((cv, ct)) => {
            let cage_pos = convert::points(&cv, "cage[0]")?;
            let cage_tris = convert::triangles(&ct, "cage[1]", cage_pos.len())?;
            Some(TriMesh::new(cage_pos, cage_tris).map_err(rig_error)?)
        }
        None => None,
    };
    let tips = match tips {
        None => TipJoints::AllButEndMarkers,
        Some(t) => match t.extract::<String>() {
            Ok(s) => match s.as_str() {
                "auto" => TipJoints::AllButEndMarkers,
                "all" => TipJoints::All,
                "none" => TipJoints::None,
                other => {
                    return Err(PyValueError::new_err(format!(
                        "tips: expected \"auto\", \"all\", \"none\" or a list of joint indices, \
                         got {other:?}"
                    )));
                }
            },
            Err(_) => TipJoints::Only(t.extract::<Vec<usize>>().map_err(|_| {
                PyValueError::new_err(
                    "tips: expected \"auto\", \"all\", \"none\" or a list of joint indices",
                )
            })?),
        },
    };
    let options = AutoWeightsOptions {
        max_influences,
        resolution,
        exponent,
        tips,
        ..AutoWeightsOptions::default()
    };
    let aw = AutoWeights::new(options).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let result = py
        .detach(|| aw.compute(&mesh, &skeleton, cage.as_ref()))
        .map_err(|e| RigError::new_err(e.to_string()))?;
    warn_all(py, &result.report.warnings)?;
    convert::skin_weights_to_py(py, &result.weights)
}
