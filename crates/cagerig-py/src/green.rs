//! `cagerig.green_coordinates`: Green coordinates (φ, ψ) of points w.r.t. a closed cage.

use cagerig::TriMesh;
use cagerig::coords::green::compute_green_coords;
use numpy::PyArray2;
use pyo3::prelude::*;

use crate::convert;
use crate::errors::rig_error;
use crate::functions::cage_coords_to_py;

/// Green coordinates (Lipman et al. 2008) of ``points`` w.r.t. a closed triangle cage.
///
/// Every point inside the cage is ``φ @ cage_vertices + ψ @ normals``, with ``normals`` the
/// unit outward normals of ``cage_triangles``; a deformed cage moves it to
/// ``φ @ C' + ψ @ (s · n')`` (see docs/green-coordinates.md).
///
/// Parameters
/// ----------
/// points : (n, 3) float64 array
/// cage_vertices : (c, 3) float64 array
/// cage_triangles : (f, 3) int array
///     A closed cage; wound either way (an inward cage is used with its triangles reversed, and
///     ψ's columns still follow ``cage_triangles``).
///
/// Returns
/// -------
/// phi : (n, c) float64 array
///     Vertex coordinates (Σ φ = 1 inside the cage, 0 outside).
/// psi : (n, f) float64 array
///     Face coordinates, one column per cage triangle.
///
/// Raises
/// ------
/// RigError
///     If the cage has no triangles or a point is not finite.
/// (φ, ψ) as numpy arrays.
type GreenArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

#[pyfunction]
#[pyo3(signature = (points, cage_vertices, cage_triangles))]
pub fn green_coordinates<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    cage_vertices: &Bound<'py, PyAny>,
    cage_triangles: &Bound<'py, PyAny>,
) -> PyResult<GreenArrays<'py>> {
    let points = convert::points(points, "points")?;
    let cage_positions = convert::points(cage_vertices, "cage_vertices")?;
    let tris = convert::triangles(cage_triangles, "cage_triangles", cage_positions.len())?;
    let cage = TriMesh::new(cage_positions, tris).map_err(rig_error)?;
    let coords = py
        .detach(|| compute_green_coords(&cage, &points, None))
        .map_err(rig_error)?;
    Ok((
        cage_coords_to_py(py, &coords.vertex)?,
        cage_coords_to_py(py, &coords.face)?,
    ))
}
