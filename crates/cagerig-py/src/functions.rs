//! Plain functions over numpy arrays, in the style of libigl / gpytoolbox: float64 `(n, 3)`
//! points, int `(m, 3)` triangles, new arrays out. Heavy work runs with the GIL released.

use std::path::PathBuf;

use cagerig::coords::mvc as mvc_coords;
use cagerig::coords::{maxvol, mec, mec_signed};
use cagerig::cor_centres::{CorCentresOptions, compute_cor_centres};
use cagerig::mesh::TriMesh;
use cagerig::skinning::{
    CorScratch, CorSkinning, DqsScratch, DualQuaternionSkinning, LinearBlendSkinning,
};
use cagerig::{CageCoords, SkinWeights};
use glam::{DAffine3, DVec3};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::convert;
use crate::errors::{file_error, rig_error, warn_all};

/// Mean value coordinates of points with respect to a closed triangle cage (Ju et al. 2005).
///
/// Parameters
/// ----------
/// points : (n, 3) float64 array
///     Query points (e.g. the rest mesh M).
/// cage_vertices : (c, 3) float64 array
///     Cage vertex positions C.
/// cage_triangles : (f, 3) int array
///     Cage triangles (indices into ``cage_vertices``), consistently oriented.
///
/// Returns
/// -------
/// phi : (n, c) float64 array
///     Φ with ``phi @ cage_vertices == points`` (to round-off) and rows summing to 1.
///     Fortran (column-major) order, like the library's storage.
///
/// Raises
/// ------
/// RigError
///     If the cage has no triangles or a point's coordinates cannot be normalised.
#[pyfunction]
#[pyo3(signature = (points, cage_vertices, cage_triangles))]
pub fn mvc<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    cage_vertices: &Bound<'py, PyAny>,
    cage_triangles: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let points = convert::points(points, "points")?;
    let cage_positions = convert::points(cage_vertices, "cage_vertices")?;
    let tris = convert::triangles(cage_triangles, "cage_triangles", cage_positions.len())?;
    let cage = TriMesh::new(cage_positions, tris).map_err(rig_error)?;
    let phi = py
        .detach(|| mvc_coords::compute_cage_coords(&cage, &points, None))
        .map_err(rig_error)?;
    cage_coords_to_py(py, &phi)
}

/// Φ (`#V × #C`) as a new Fortran-ordered array (one memcpy per column).
pub fn cage_coords_to_py<'py>(
    py: Python<'py>,
    phi: &CageCoords,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (n, c) = (phi.num_vertices(), phi.num_cage_vertices());
    let out = PyArray2::<f64>::zeros(py, [n, c], true);
    {
        let mut rw = out.readwrite();
        let slice = rw
            .as_slice_mut()
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        for k in 0..c {
            slice[k * n..(k + 1) * n].copy_from_slice(phi.column(k));
        }
    }
    Ok(out)
}

/// Φ from a `(n, c)` array argument.
fn cage_coords_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<CageCoords> {
    let (rows, cols, data) = convert::matrix(obj, name)?;
    CageCoords::from_matrix(faer::Mat::from_fn(rows, cols, |i, k| data[i * cols + k]))
        .map_err(rig_error)
}

/// MaxVol rows of cage coordinates: #C rows of Φ whose square submatrix has (locally) maximal
/// |det| (Goreinov et al.), the interpolation rows of CageUp and CageRev.
///
/// Parameters
/// ----------
/// phi : (n, c) float64 array
///     Cage coordinates, ``n >= c``.
///
/// Returns
/// -------
/// rows : (c,) int64 array
///     Selected row indices.
/// log_abs_det : float
///     ``log |det phi[rows]|``.
///
/// Raises
/// ------
/// RigError
///     If ``n < c`` or Φ is numerically rank deficient.
#[pyfunction]
pub fn maxvol_rows<'py>(
    py: Python<'py>,
    phi: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyArray1<i64>>, f64)> {
    let phi = cage_coords_arg(phi, "phi")?;
    let sel = py
        .detach(|| maxvol::select_maxvol_rows(&phi))
        .map_err(rig_error)?;
    let rows: Vec<i64> = sel.rows.iter().map(|&r| r as i64).collect();
    Ok((PyArray1::from_vec(py, rows), sel.log_abs_det))
}

/// Maximum-entropy coordinates with a prior (Hormann & Sukumar 2008; paper Eq. 11), as SkelUp
/// uses them to write each rest joint as a combination of rest-cage vertices (a row of Ψ).
///
/// Maximises ``-Σ b_k log(b_k / prior_k)`` subject to ``Σ b_k points_k = target`` and
/// ``Σ b_k = 1``. When the target is not strictly inside the convex hull of the points the
/// result is the least-squares projection of the prior onto the two constraints (weights may
/// then be negative; both constraints still hold).
///
/// Parameters
/// ----------
/// points : (k, 3) float64 array
///     The points c_k (e.g. rest-cage vertices).
/// prior : (k,) float64 array
///     Prior masses m_k (non-positive masses are clamped to a small positive floor).
/// targets : (3,) or (m, 3) float64 array
///     Point(s) a to reproduce.
/// signed : bool, default False
///     Use the paper tool's signed-prior variant (Newton on the linear-precision equations,
///     falling back to the positive solver).
///
/// Returns
/// -------
/// weights : (k,) or (m, k) float64 array
///     One row of coordinates per target.
#[pyfunction]
#[pyo3(signature = (points, prior, targets, signed = false))]
pub fn max_entropy_coordinates<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    prior: &Bound<'py, PyAny>,
    targets: &Bound<'py, PyAny>,
    signed: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let pts = convert::points(points, "points")?;
    let prior_arr = convert::float_array(prior, "prior")?;
    let prior: Vec<f64> = prior_arr.readonly().as_array().iter().copied().collect();
    if prior_arr.ndim() != 1 || prior.len() != pts.len() {
        return Err(PyValueError::new_err(format!(
            "prior must have shape ({},) (one mass per point), got {}",
            pts.len(),
            convert::shape_str(prior_arr.shape())
        )));
    }
    let single = convert::float_array(targets, "targets")?.ndim() == 1;
    let targets: Vec<DVec3> = if single {
        vec![convert::vec3(targets, "targets")?]
    } else {
        convert::points(targets, "targets")?
    };
    let k = pts.len();
    let weights = py.detach(|| {
        let mut out = vec![0.0; targets.len() * k];
        for (t, row) in targets.iter().zip(out.chunks_mut(k.max(1))) {
            if signed {
                mec_signed::max_entropy_coordinates_signed(&pts, &prior, *t, row);
            } else {
                mec::max_entropy_coordinates(&pts, &prior, *t, row);
            }
        }
        out
    });
    if single {
        Ok(PyArray1::from_vec(py, weights).into_any())
    } else {
        Ok(convert::matrix_to_py(py, targets.len(), k, weights)?.into_any())
    }
}

/// Skinning inputs shared by [`lbs`], [`dqs`] and [`cor`]: rest points, Ω and one transform per
/// joint of Ω.
fn skinning_inputs(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    weights: &Bound<'_, PyAny>,
    transforms: &Bound<'_, PyAny>,
) -> PyResult<(Vec<DVec3>, SkinWeights, Vec<DAffine3>)> {
    let rest = convert::points(vertices, "vertices")?;
    let (w, warnings) = convert::skin_weights(weights, "weights", Some(rest.len()))?;
    warn_all(py, &warnings)?;
    let t = convert::transforms(transforms, "transforms")?;
    if t.len() != w.num_joints() {
        return Err(PyValueError::new_err(format!(
            "transforms must have one matrix per joint (column of weights): expected {}, got {}",
            w.num_joints(),
            t.len()
        )));
    }
    Ok((rest, w, t))
}

/// Linear blend skinning (paper Eq. 2–3): ``v'_i = Σ_j w_ij T_j v_i``.
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
///     Rest positions.
/// weights : (n, J) float64 array or scipy.sparse matrix
///     Skinning weights Ω (non-negative; rows not summing to 1 are renormalised with a
///     RigWarning).
/// transforms : (J, 4, 4) or (J, 3, 4) float64 array
///     Skinning transforms ``T_j = posed_from_rest`` (matrices acting on column vectors).
///
/// Returns
/// -------
/// (n, 3) float64 array
///     Deformed positions.
#[pyfunction]
pub fn lbs<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    weights: &Bound<'py, PyAny>,
    transforms: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (rest, w, t) = skinning_inputs(py, vertices, weights, transforms)?;
    let out = py.detach(|| {
        let mut out = vec![DVec3::ZERO; rest.len()];
        LinearBlendSkinning::new(&w).apply(&t, &rest, &mut out);
        out
    });
    convert::points_to_py(py, &out)
}

/// Dual quaternion skinning (Kavan et al. 2008; paper Eq. 4).
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
///     Rest positions.
/// weights : (n, J) float64 array or scipy.sparse matrix
///     Skinning weights Ω.
/// transforms : (J, 4, 4) or (J, 3, 4) float64 array
///     Rigid skinning transforms (rotation + translation; anything else raises ValueError).
///
/// Returns
/// -------
/// (n, 3) float64 array
///     Deformed positions.
#[pyfunction]
pub fn dqs<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    weights: &Bound<'py, PyAny>,
    transforms: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (rest, w, t) = skinning_inputs(py, vertices, weights, transforms)?;
    convert::check_rigid(&t, "transforms")?;
    let out = py.detach(|| {
        let mut out = vec![DVec3::ZERO; rest.len()];
        let mut scratch = DqsScratch::new(w.num_joints());
        DualQuaternionSkinning::new(&w).apply(&t, &rest, &mut scratch, &mut out);
        out
    });
    convert::points_to_py(py, &out)
}

/// Skinning with optimised centres of rotation (Le & Hodgins 2016; paper Eq. 5–6).
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
///     Rest positions.
/// weights : (n, J) float64 array or scipy.sparse matrix
///     Skinning weights Ω.
/// transforms : (J, 4, 4) or (J, 3, 4) float64 array
///     Rigid skinning transforms.
/// centres : (n, 3) float64 array
///     Rest centres of rotation, e.g. from :func:`cor_centres`.
///
/// Returns
/// -------
/// (n, 3) float64 array
///     Deformed positions.
#[pyfunction]
pub fn cor<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    weights: &Bound<'py, PyAny>,
    transforms: &Bound<'py, PyAny>,
    centres: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (rest, w, t) = skinning_inputs(py, vertices, weights, transforms)?;
    convert::check_rigid(&t, "transforms")?;
    let centres = convert::points_n(centres, "centres", rest.len(), "vertex")?;
    let out = py.detach(|| {
        let mut out = vec![DVec3::ZERO; rest.len()];
        let mut scratch = CorScratch::new(w.num_joints());
        CorSkinning::new(&w).apply(&t, &rest, &centres, &mut scratch, &mut out);
        out
    });
    convert::points_to_py(py, &out)
}

/// Centres of rotation of every vertex (Le & Hodgins 2016, Eq. 5), exact form.
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
///     Rest mesh positions M.
/// triangles : (f, 3) int array
///     Rest mesh triangles.
/// weights : (n, J) float64 array or scipy.sparse matrix
///     Skinning weights Ω.
/// sigma : float, default 0.1
///     Width of the weight-similarity kernel.
///
/// Returns
/// -------
/// (n, 3) float64 array
///     Centres p_i (vertices with a single influence get p_i = v_i).
#[pyfunction]
#[pyo3(signature = (vertices, triangles, weights, sigma = 0.1))]
pub fn cor_centres<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
    weights: &Bound<'py, PyAny>,
    sigma: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let rest = convert::points(vertices, "vertices")?;
    let tris = convert::triangles(triangles, "triangles", rest.len())?;
    let (w, warnings) = convert::skin_weights(weights, "weights", Some(rest.len()))?;
    warn_all(py, &warnings)?;
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(PyValueError::new_err(format!(
            "sigma must be finite and positive, got {sigma}"
        )));
    }
    let options = CorCentresOptions {
        sigma,
        ..CorCentresOptions::default()
    };
    let centres = py
        .detach(|| {
            let s = compute_cor_centres(&rest, &tris, &w, &options, &|_, _| {})?;
            let mut centres = vec![DVec3::ZERO; rest.len()];
            s.apply(&rest, &mut centres);
            Ok::<_, cagerig::RigError>(centres)
        })
        .map_err(rig_error)?;
    convert::points_to_py(py, &centres)
}

/// Checks that a triangle mesh can serve as a cage: closed (every edge in two triangles),
/// manifold, consistently oriented, no degenerate or repeated-vertex triangle. A cage facing
/// inwards as a whole is flipped (with a RigWarning).
///
/// Parameters
/// ----------
/// vertices : (c, 3) float64 array
/// triangles : (f, 3) int array
///
/// Returns
/// -------
/// (f, 3) int64 array
///     The triangles, flipped if the cage faced inwards.
///
/// Raises
/// ------
/// RigError
///     Naming the first offending edge or triangle.
#[pyfunction]
pub fn validate_cage<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let pos = convert::points(vertices, "vertices")?;
    let tris = convert::triangles(triangles, "triangles", pos.len())?;
    let mesh = TriMesh::new(pos, tris).map_err(rig_error)?;
    let (cage, warnings) = cagerig::cage::validate_cage(mesh).map_err(rig_error)?;
    warn_all(py, &warnings)?;
    convert::triangles_to_py(py, &cage.triangles)
}

/// Midpoint (1-to-4) subdivision, carrying skinning weights along (new vertex = mean of its
/// edge's endpoints; original vertices keep their index). The shape does not change.
///
/// Parameters
/// ----------
/// vertices : (n, 3) float64 array
/// triangles : (f, 3) int array
/// levels : int, default 1
/// weights : (n, J) float64 array or scipy.sparse matrix, optional
///     Skinning weights to carry along.
///
/// Returns
/// -------
/// vertices : (n', 3) float64 array
/// triangles : (4**levels * f, 3) int64 array
/// weights : (n', J) float64 array
///     Only when ``weights`` was given.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, levels = 1, weights = None))]
pub fn subdivide<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
    levels: usize,
    weights: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    let pos = convert::points(vertices, "vertices")?;
    let tris = convert::triangles(triangles, "triangles", pos.len())?;
    let n = pos.len();
    let mesh = TriMesh::new(pos, tris).map_err(rig_error)?;
    let w = match weights {
        Some(w) => {
            let (w, warnings) = convert::skin_weights(w, "weights", Some(n))?;
            warn_all(py, &warnings)?;
            Some(w)
        }
        None => None,
    };
    let carried = match &w {
        Some(w) => w.clone(),
        None => {
            SkinWeights::from_triplets(n, 0, std::iter::empty())
                .map_err(rig_error)?
                .0
        }
    };
    let sub = py
        .detach(|| cagerig::subdivide::subdivide_midpoint(&mesh, &carried, levels))
        .map_err(rig_error)?;
    let v = convert::points_to_py(py, &sub.mesh.positions)?.into_any();
    let f = convert::triangles_to_py(py, &sub.mesh.triangles)?.into_any();
    if w.is_some() {
        let w = convert::skin_weights_to_py(py, &sub.skin_weights)?.into_any();
        pyo3::types::PyTuple::new(py, [v, f, w])
    } else {
        pyo3::types::PyTuple::new(py, [v, f])
    }
}

/// Reads a triangle mesh from an OBJ file (polygons are fan-triangulated).
///
/// Returns
/// -------
/// vertices : (n, 3) float64 array
/// triangles : (f, 3) int64 array
#[pyfunction]
pub fn read_obj<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(convert::F64Array2<'py>, convert::I64Array2<'py>)> {
    let mesh = py
        .detach(|| cagerig::io::obj::read_obj(&path))
        .map_err(file_error)?;
    Ok((
        convert::points_to_py(py, &mesh.positions)?,
        convert::triangles_to_py(py, &mesh.triangles)?,
    ))
}

/// Writes a triangle mesh as OBJ (round-trip exact floats; the file is replaced atomically).
#[pyfunction]
pub fn write_obj(
    py: Python<'_>,
    path: PathBuf,
    vertices: &Bound<'_, PyAny>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let pos = convert::points(vertices, "vertices")?;
    let tris = convert::triangles(triangles, "triangles", pos.len())?;
    py.detach(|| cagerig::io::obj::write_obj(&path, &pos, &tris))
        .map_err(file_error)
}
