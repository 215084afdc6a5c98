//! Argument conversion at the Python boundary: numpy arrays (or anything `numpy.asarray` takes)
//! into the library's types, with the shape, dtype, finiteness and index-range checks done once
//! here, so the library is only ever called with valid data. Errors: `TypeError` for a wrong
//! dtype, `ValueError` for a wrong shape or a non-finite number, `IndexError` for an index out of
//! range; each names the argument, what was expected and what was found.

use cagerig::{SkinWeights, Warning};
use glam::{DAffine3, DMat3, DVec3};
use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyIndexError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;

/// `(5, 3)` as Python prints a shape.
pub fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn numpy_asarray(py: Python<'_>) -> PyResult<&Bound<'_, PyAny>> {
    static ASARRAY: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    ASARRAY
        .get_or_try_init(py, || {
            Ok::<_, PyErr>(py.import("numpy")?.getattr("asarray")?.unbind())
        })
        .map(|f| f.bind(py))
}

/// The argument as a numpy array of any dtype (`numpy.asarray` for lists, tuples, scalars).
fn any_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let converted = numpy_asarray(obj.py())?
        .call1((obj,))
        .map_err(|e| PyTypeError::new_err(format!("{name}: cannot be read as an array ({e})")))?;
    Ok(converted.cast_into::<PyUntypedArray>()?)
}

fn dtype_name(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype()
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// The argument as a float64 array: no copy when it already is one; integer and other float
/// dtypes are converted; anything else (bool, complex, strings, objects) is a `TypeError`.
pub fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        return Ok(a.clone());
    }
    let a = any_array(obj, name)?;
    match a.dtype().kind() {
        b'f' | b'i' | b'u' => Ok(a
            .call_method1("astype", ("float64",))?
            .cast_into::<PyArrayDyn<f64>>()?),
        _ => Err(PyTypeError::new_err(format!(
            "{name} must be a real-valued array (float64), got dtype {}",
            dtype_name(&a)
        ))),
    }
}

/// The argument as an int64 array: integer dtypes only (an empty list is accepted too).
pub fn int_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Bound<'py, PyArrayDyn<i64>>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<i64>>() {
        return Ok(a.clone());
    }
    let a = any_array(obj, name)?;
    match a.dtype().kind() {
        b'i' | b'u' => {}
        _ if a.len() == 0 => {}
        _ => {
            return Err(PyTypeError::new_err(format!(
                "{name} must be an integer array, got dtype {}",
                dtype_name(&a)
            )));
        }
    }
    Ok(a.call_method1("astype", ("int64",))?
        .cast_into::<PyArrayDyn<i64>>()?)
}

fn check_finite(value: f64, name: &str, at: impl FnOnce() -> String) -> PyResult<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{name}{} is {value}: every value must be finite",
            at()
        )))
    }
}

/// `(n,)` DQ blend weights of the blended skinning method, each a finite number in [0, 1].
pub fn dq_blend_weights(
    obj: &Bound<'_, PyAny>,
    name: &str,
    num_vertices: usize,
) -> PyResult<cagerig::skinning::DqBlendWeights> {
    let a = float_array(obj, name)?;
    let shape = a.shape().to_vec();
    if shape != [num_vertices] {
        return Err(PyValueError::new_err(format!(
            "{name} has shape {}: expected ({num_vertices},), one weight per mesh vertex",
            shape_str(&shape)
        )));
    }
    let values: Vec<f64> = a.to_vec()?;
    cagerig::skinning::DqBlendWeights::new(values)
        .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// `(n, 3)` float points, all finite.
pub fn points(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<DVec3>> {
    let a = float_array(obj, name)?;
    let ro = a.readonly();
    let v = ro.as_array();
    if v.ndim() != 2 || v.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (n, 3), got {}",
            shape_str(v.shape())
        )));
    }
    let mut out = Vec::with_capacity(v.shape()[0]);
    for (i, row) in v.outer_iter().enumerate() {
        for (c, &x) in row.iter().enumerate() {
            check_finite(x, name, || format!("[{i}, {c}]"))?;
        }
        out.push(DVec3::new(row[0], row[1], row[2]));
    }
    Ok(out)
}

/// `(n, 3)` points with exactly `count` rows.
pub fn points_n(
    obj: &Bound<'_, PyAny>,
    name: &str,
    count: usize,
    what: &str,
) -> PyResult<Vec<DVec3>> {
    let p = points(obj, name)?;
    if p.len() != count {
        return Err(PyValueError::new_err(format!(
            "{name} must have one row per {what} (shape ({count}, 3)), got {} rows",
            p.len()
        )));
    }
    Ok(p)
}

/// A 3-vector (list, tuple or array of 3 finite numbers). Arrays are read directly and lists
/// or tuples element by element (no temporary array, no failed conversion on the way).
pub fn vec3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<DVec3> {
    let is_array = obj.is_instance_of::<PyUntypedArray>();
    let v = match (!is_array).then(|| obj.extract::<[f64; 3]>()) {
        Some(Ok(v)) => v,
        _ => {
            let a = float_array(obj, name)?;
            let ro = a.readonly();
            let view = ro.as_array();
            if view.shape() != [3] {
                return Err(PyValueError::new_err(format!(
                    "{name} must have shape (3,), got {}",
                    shape_str(view.shape())
                )));
            }
            [view[[0]], view[[1]], view[[2]]]
        }
    };
    vec3_checked(v, name)
}

/// Offsets of a cage edit: one `(3,)` offset for every vertex, or `(k, 3)` with one row per vertex.
pub fn offsets(obj: &Bound<'_, PyAny>, name: &str, count: usize) -> PyResult<Vec<DVec3>> {
    if !obj.is_instance_of::<PyUntypedArray>()
        && let Ok(v) = obj.extract::<[f64; 3]>()
    {
        return Ok(vec![vec3_checked(v, name)?]);
    }
    let a = float_array(obj, name)?;
    let ndim = a.ndim();
    if ndim == 1 {
        return Ok(vec![vec3(a.as_any(), name)?]);
    }
    let p = points(a.as_any(), name)?;
    if p.len() != count && p.len() != 1 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (3,) or ({count}, 3) (one row per vertex), got ({}, 3)",
            p.len()
        )));
    }
    Ok(p)
}

fn vec3_checked(v: [f64; 3], name: &str) -> PyResult<DVec3> {
    for (c, &x) in v.iter().enumerate() {
        check_finite(x, name, || format!("[{c}]"))?;
    }
    Ok(DVec3::from_array(v))
}

/// Indices into `len` elements: an int, or a 1-D integer sequence/array; each in `0..len`.
pub fn indices(obj: &Bound<'_, PyAny>, name: &str, len: usize, what: &str) -> PyResult<Vec<usize>> {
    let scalar =
        obj.is_instance_of::<pyo3::types::PyInt>() && !obj.is_instance_of::<pyo3::types::PyBool>();
    let raw: Vec<i64> = match scalar.then(|| obj.extract::<i64>()) {
        Some(Ok(i)) => vec![i],
        _ => {
            let a = int_array(obj, name)?;
            let ro = a.readonly();
            let v = ro.as_array();
            if v.ndim() > 1 {
                return Err(PyValueError::new_err(format!(
                    "{name} must be an int or a 1-D integer array, got shape {}",
                    shape_str(v.shape())
                )));
            }
            v.iter().copied().collect()
        }
    };
    raw.iter()
        .enumerate()
        .map(|(k, &i)| {
            usize::try_from(i).ok().filter(|&u| u < len).ok_or_else(|| {
                PyIndexError::new_err(format!(
                    "{name}[{k}] = {i} is out of range (there are {len} {what})"
                ))
            })
        })
        .collect()
}

/// `(m, 3)` integer triangles, every index in `0..num_vertices`.
pub fn triangles(
    obj: &Bound<'_, PyAny>,
    name: &str,
    num_vertices: usize,
) -> PyResult<Vec<[u32; 3]>> {
    let a = int_array(obj, name)?;
    let ro = a.readonly();
    let v = ro.as_array();
    if v.is_empty() && v.ndim() == 1 {
        return Ok(Vec::new());
    }
    if v.ndim() != 2 || v.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (m, 3), got {}",
            shape_str(v.shape())
        )));
    }
    let mut out = Vec::with_capacity(v.shape()[0]);
    for (t, row) in v.outer_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (c, &i) in row.iter().enumerate() {
            tri[c] = u32::try_from(i)
                .ok()
                .filter(|&u| (u as usize) < num_vertices)
                .ok_or_else(|| {
                    PyIndexError::new_err(format!(
                        "{name}[{t}, {c}] = {i} is out of range (there are {num_vertices} vertices)"
                    ))
                })?;
        }
        out.push(tri);
    }
    Ok(out)
}

/// A finite `(rows, cols)` float matrix, returned row-major with its shape.
pub fn matrix(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(usize, usize, Vec<f64>)> {
    let a = float_array(obj, name)?;
    let ro = a.readonly();
    let v = ro.as_array();
    if v.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name} must be a 2-D array, got shape {}",
            shape_str(v.shape())
        )));
    }
    let (r, c) = (v.shape()[0], v.shape()[1]);
    let mut out = Vec::with_capacity(r * c);
    for (i, row) in v.outer_iter().enumerate() {
        for (k, &x) in row.iter().enumerate() {
            check_finite(x, name, || format!("[{i}, {k}]"))?;
            out.push(x);
        }
    }
    Ok((r, c, out))
}

/// `(J, 4, 4)` or `(J, 3, 4)` affine transforms (row-major matrices acting on column vectors).
pub fn transforms(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<DAffine3>> {
    let a = float_array(obj, name)?;
    let ro = a.readonly();
    let v = ro.as_array();
    let s = v.shape();
    if v.ndim() != 3 || !(s[1] == 4 || s[1] == 3) || s[2] != 4 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (J, 4, 4) or (J, 3, 4), got {}",
            shape_str(s)
        )));
    }
    let mut out = Vec::with_capacity(s[0]);
    for j in 0..s[0] {
        let m = |r: usize, c: usize| v[[j, r, c]];
        for r in 0..s[1] {
            for c in 0..4 {
                check_finite(m(r, c), name, || format!("[{j}, {r}, {c}]"))?;
            }
        }
        if s[1] == 4 && (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0) {
            return Err(PyValueError::new_err(format!(
                "{name}[{j}] is not affine: its last row must be (0, 0, 0, 1), got ({}, {}, {}, {})",
                m(3, 0),
                m(3, 1),
                m(3, 2),
                m(3, 3)
            )));
        }
        out.push(DAffine3 {
            matrix3: DMat3::from_cols(
                DVec3::new(m(0, 0), m(1, 0), m(2, 0)),
                DVec3::new(m(0, 1), m(1, 1), m(2, 1)),
                DVec3::new(m(0, 2), m(1, 2), m(2, 2)),
            ),
            translation: DVec3::new(m(0, 3), m(1, 3), m(2, 3)),
        });
    }
    Ok(out)
}

/// Checks that every transform is a rotation plus a translation (DQS and CoR blend rotations).
pub fn check_rigid(transforms: &[DAffine3], name: &str) -> PyResult<()> {
    for (j, t) in transforms.iter().enumerate() {
        let m = t.matrix3;
        let error = (m.transpose() * m - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |e, x| e.max(x.abs()));
        if error > 1e-6 || m.determinant() <= 0.0 {
            return Err(PyValueError::new_err(format!(
                "{name}[{j}] is not a rotation plus a translation (|RᵀR − I| = {error:.2e}, \
                 det = {:.6}); this skinning method needs rigid transforms",
                m.determinant()
            )));
        }
    }
    Ok(())
}

/// Skinning weights Ω from a dense `(n, J)` array or a scipy.sparse matrix (anything with
/// `tocoo()`), with `num_vertices` rows when given. Rows are renormalised to sum to 1 (reported
/// as warnings).
pub fn skin_weights(
    obj: &Bound<'_, PyAny>,
    name: &str,
    num_vertices: Option<usize>,
) -> PyResult<(SkinWeights, Vec<Warning>)> {
    let (rows, cols, triplets) = if obj.hasattr("tocoo")? {
        let coo = obj.call_method0("tocoo")?;
        let (rows, cols): (usize, usize) = coo.getattr("shape")?.extract()?;
        let r = indices(&coo.getattr("row")?, &format!("{name}.row"), rows, "rows")?;
        let c = indices(
            &coo.getattr("col")?,
            &format!("{name}.col"),
            cols,
            "columns",
        )?;
        let d = float_array(&coo.getattr("data")?, &format!("{name}.data"))?;
        let d: Vec<f64> = d.readonly().as_array().iter().copied().collect();
        if d.len() != r.len() || d.len() != c.len() {
            return Err(PyValueError::new_err(format!(
                "{name}: sparse row/col/data lengths differ ({}, {}, {})",
                r.len(),
                c.len(),
                d.len()
            )));
        }
        let t: Vec<_> = r
            .into_iter()
            .zip(c)
            .zip(d)
            .map(|((r, c), d)| (r, c, d))
            .collect();
        (rows, cols, t)
    } else {
        let (rows, cols, data) = matrix(obj, name)?;
        let t: Vec<_> = data
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != 0.0)
            .map(|(i, w)| (i / cols, i % cols, *w))
            .collect();
        (rows, cols, t)
    };
    if let Some(n) = num_vertices
        && rows != n
    {
        return Err(PyValueError::new_err(format!(
            "{name} must have one row per vertex ({n} rows), got {rows}"
        )));
    }
    SkinWeights::from_triplets(rows, cols, triplets).map_err(crate::errors::rig_error)
}

// ----- outputs ---------------------------------------------------------------------------------

/// A float64 `(n, 3)` (or other 2-D) array returned to Python.
pub type F64Array2<'py> = Bound<'py, PyArray2<f64>>;
/// An int64 `(m, 3)` array returned to Python.
pub type I64Array2<'py> = Bound<'py, PyArray2<i64>>;

/// `(n, 3)` float64 array (a new array: a copy).
pub fn points_to_py<'py>(py: Python<'py>, pts: &[DVec3]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = pts.iter().flat_map(|p| p.to_array()).collect();
    PyArray1::from_vec(py, flat).reshape([pts.len(), 3])
}

/// `(m, 3)` int64 array of triangles.
pub fn triangles_to_py<'py>(
    py: Python<'py>,
    tris: &[[u32; 3]],
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let flat: Vec<i64> = tris.iter().flatten().map(|&i| i64::from(i)).collect();
    PyArray1::from_vec(py, flat).reshape([tris.len(), 3])
}

/// Row-major `(rows, cols)` float64 array.
pub fn matrix_to_py<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    data: Vec<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, data).reshape([rows, cols])
}

/// `(J, 4, 4)` float64 array of affine transforms.
pub fn transforms_to_py<'py>(
    py: Python<'py>,
    ts: &[DAffine3],
) -> PyResult<Bound<'py, numpy::PyArray3<f64>>> {
    let mut flat = Vec::with_capacity(ts.len() * 16);
    for t in ts {
        let m = t.matrix3;
        for r in 0..3 {
            flat.extend([m.col(0)[r], m.col(1)[r], m.col(2)[r], t.translation[r]]);
        }
        flat.extend([0.0, 0.0, 0.0, 1.0]);
    }
    PyArray1::from_vec(py, flat).reshape([ts.len(), 4, 4])
}

/// Ω as a dense `(#V, #J)` float64 array.
pub fn skin_weights_to_py<'py>(
    py: Python<'py>,
    w: &SkinWeights,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (nv, nj) = (w.num_vertices(), w.num_joints());
    let mut dense = vec![0.0; nv * nj];
    for v in 0..nv {
        let (joints, weights) = w.row(v);
        for (&j, &x) in joints.iter().zip(weights) {
            dense[v * nj + j as usize] = x;
        }
    }
    matrix_to_py(py, nv, nj, dense)
}
