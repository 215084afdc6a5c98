//! `Rig` properties: the six structures, Φ, Ψ, Ω and the rest. Copies (snapshots), except
//! `cage_coords` (Φ), a read-only view of the rig's storage.

use glam::DVec3;
use numpy::ndarray::{ArrayView2, ShapeBuilder};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::convert;
use crate::rig::{Rig, rest_joints};

#[pymethods]
impl Rig {
    // ----- structures (copies unless said otherwise) -----------------------------------------

    /// The cage coordinates the rig is bound with: ``"mvc"`` or ``"green"``.
    #[getter]
    fn coords(&self) -> &'static str {
        self.session.coords_kind().name()
    }

    /// How CageUp fits the current cage C': ``"regularised"`` or ``"paper"``.
    #[getter]
    fn cage_fit(&self) -> &'static str {
        self.session.cage_fit().name()
    }

    /// Green rigs' face term: ``"fold-safe"`` or ``"lipman"``.
    #[getter]
    fn green_face_term(&self) -> &'static str {
        self.session.green_face_term().name()
    }

    /// What an edit does when a Green CageUp finds no current cage: ``"refuse"`` or ``"keep"``
    /// (:meth:`set_unfitted_cage`).
    #[getter]
    fn unfitted_cage(&self) -> &'static str {
        self.session.unfitted_cage_policy().name()
    }

    /// Why the current cage C' is not CageUp's fit of the pose (kept under
    /// ``set_unfitted_cage("keep")``), or None while it is.
    #[getter]
    fn posed_cage_unfitted(&self) -> Option<String> {
        self.session.posed_cage_unfitted().map(|u| u.to_string())
    }

    /// Rest skin M, (#V, 3) float64 (copy).
    #[getter]
    fn rest_mesh<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, self.session.rest_mesh())
    }

    /// Current skin M', (#V, 3) float64 (copy of M' only: Φ is not touched).
    #[getter]
    fn posed_mesh<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, self.session.posed_mesh())
    }

    /// The rest points whose linear blend skinning under the current pose is the current skin
    /// M', (#V, 3) float64: x_v = R_v⁻¹·(M'_v − t_v), with R_v, t_v the Ω-blended skinning
    /// transform of vertex v. Skinned with LBS they give M' whatever the rig's method: what a
    /// host with LBS only shows CoR or DQS with (the Blender add-on's CoR shape key). Raises
    /// ValueError naming the first vertex whose blended transform is singular.
    fn lbs_rest_preimage<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let mut out = vec![DVec3::ZERO; self.session.posed_mesh().len()];
        self.session
            .lbs_rest_preimage(&mut out)
            .map_err(crate::errors::rig_error)?;
        convert::points_to_py(py, &out)
    }

    /// Rest cage C, (#C, 3) float64 (copy).
    #[getter]
    fn rest_cage<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, self.session.rest_cage())
    }

    /// Current cage C', (#C, 3) float64 (copy).
    #[getter]
    fn posed_cage<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, self.session.posed_cage())
    }

    /// The rest cage as loaded, C₀ (cage-animation offsets are relative to it), (#C, 3) (copy).
    #[getter]
    fn original_rest_cage<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, self.session.original_rest_cage())
    }

    /// Rest joint positions (S), (#J, 3) float64 (copy).
    #[getter]
    fn rest_joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, &rest_joints(&self.session))
    }

    /// Current joint positions (S'), (#J, 3) float64 (copy).
    #[getter]
    fn posed_joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p: Vec<DVec3> = self.session.posed_joints().collect();
        convert::points_to_py(py, &p)
    }

    /// Rest joint frames ``rest_world_from_joint``, (#J, 4, 4) (copy).
    #[getter]
    fn rest_joint_frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        convert::transforms_to_py(py, self.session.rest_world_from_joint())
    }

    /// Current joint frames ``posed_world_from_joint``, (#J, 4, 4) (copy).
    #[getter]
    fn posed_joint_frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        convert::transforms_to_py(py, self.session.posed_world_from_joint())
    }

    /// Skinning transforms ``T_j = posed_from_rest`` (Eq. 1–3), (#J, 4, 4) (copy).
    #[getter]
    fn skinning_transforms<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        convert::transforms_to_py(py, self.session.posed_from_rest())
    }

    /// Skin triangles, (#F, 3) int64 (copy).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        convert::triangles_to_py(py, self.session.mesh_triangles())
    }

    /// Cage triangles, (#T, 3) int64 (copy).
    #[getter]
    fn cage_triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        convert::triangles_to_py(py, self.session.cage_triangles())
    }

    /// Joint names, in index order.
    #[getter]
    fn joint_names<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(
            py,
            self.session
                .skeleton()
                .joints()
                .iter()
                .map(|j| j.name.as_str()),
        )
    }

    /// Parent of each joint, (#J,) int64, -1 for roots (copy).
    #[getter]
    fn joint_parents<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let p: Vec<i64> = self
            .session
            .skeleton()
            .joints()
            .iter()
            .map(|j| j.parent.map_or(-1, |p| p as i64))
            .collect();
        PyArray1::from_vec(py, p)
    }

    /// Φ, the cage coordinates (#V, #C) float64 with M = ΦC: a READ-ONLY VIEW of the rig's
    /// storage (no copy; Fortran order; it keeps the rig alive). Φ never changes after the rig
    /// is built. ``np.array(rig.cage_coords)`` makes a writable copy.
    #[getter]
    #[expect(
        unsafe_code,
        reason = "Φ shared with numpy without a copy, kept alive by the Rig"
    )]
    fn cage_coords<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let view = {
            let this = slf.borrow();
            let m = this.session.cage_coords().matrix();
            let stride = usize::try_from(m.col_stride()).unwrap_or(0);
            // SAFETY: faer's owned matrix stores column k at `ptr + k·col_stride`, rows
            // contiguous; the view covers exactly nrows × ncols of that allocation.
            unsafe {
                ArrayView2::from_shape_ptr((m.nrows(), m.ncols()).strides((1, stride)), m.as_ptr())
            }
        };
        // SAFETY: the array's base is the Rig object, which owns the session and thus Φ; Φ is
        // never reallocated or written after construction (no method replaces the session or
        // its cage coordinates), so the memory stays valid and unchanged while the array lives.
        let array = unsafe { PyArray2::borrow_from_array(&view, slf.into_any()) };
        array.readwrite().make_nonwriteable();
        Ok(array)
    }

    /// Alias of :attr:`cage_coords` (Φ, read-only view).
    #[getter]
    fn phi<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Self::cage_coords(slf)
    }

    /// Ψ, the joint coordinates (#J, #C) float64 with rest joints = ΨC (SkelUp, Eq. 11); for
    /// Green rigs the vertex part Ψ_φ, with rest joints = Ψ_φ C + Ψ_ψ g(C) (see
    /// :attr:`joint_face_coords`) (copy).
    #[getter]
    fn joint_coords<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let up = self.session.skeleton_updater();
        let (nj, nc) = (up.num_joints(), self.session.rest_cage().len());
        let data: Vec<f64> = (0..nj).flat_map(|j| up.joint_row(j).to_vec()).collect();
        convert::matrix_to_py(py, nj, nc, data)
    }

    /// Alias of :attr:`joint_coords` (Ψ, copy).
    #[getter]
    fn psi<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.joint_coords(py)
    }

    /// Ψ_ψ, the joints' face coordinates (#J, #F) float64 of a Green rig's SkelUp (rest joints
    /// = Ψ_φ C + Ψ_ψ g(C), docs/green-coordinates.md G5); (#J, 0) for mean value rigs (copy).
    #[getter]
    fn joint_face_coords<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let up = self.session.skeleton_updater();
        let (nj, nf) = (up.num_joints(), up.num_faces());
        let data: Vec<f64> = (0..nj)
            .flat_map(|j| up.joint_face_row(j).to_vec())
            .collect();
        convert::matrix_to_py(py, nj, nf, data)
    }

    /// g(C), the stretched face normals of the current rest cage (#F, 3) float64 for a Green
    /// rig (the inputs of ψ and Ψ_ψ); (0, 3) for mean value rigs (copy).
    #[getter]
    fn rest_cage_terms<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::points_to_py(py, self.session.rest_cage_terms())
    }

    /// Ω, the skinning weights (#V, #J) float64, dense (copy; rows sum to 1).
    #[getter]
    fn skin_weights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        convert::skin_weights_to_py(py, self.session.skin_weights())
    }

    /// Alias of :attr:`skin_weights` (Ω, dense copy).
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.skin_weights(py)
    }

    /// CoR centres (#V, 3) (copy) once CoR data exists (after ``set_skinning("cor")``), else
    /// None. They follow the rest cage while CoR skinning is active.
    #[getter]
    fn cor_centres<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.session
            .cor_centres()
            .map(|c| convert::points_to_py(py, c))
            .transpose()
    }

    /// Mesh rows CageUp/CageRev fit (MaxVol rows by default), (k,) int64 (copy).
    #[getter]
    fn fit_rows<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let rows: Vec<i64> = self
            .session
            .cage_updater()
            .rows()
            .iter()
            .map(|&r| r as i64)
            .collect();
        PyArray1::from_vec(py, rows)
    }

    /// The active skinning method: ``"lbs"``, ``"dqs"``, ``"cor"`` or ``"blended"``.
    #[getter]
    fn skinning(&self) -> &'static str {
        self.session.skinning().name()
    }

    /// DQ blend weights b, (n,) float64 in [0, 1], of the ``"blended"`` method (vertex v is
    /// skinned ``(1 - b[v]) * LBS + b[v] * DQS``), or None when the rig has none.
    #[getter]
    fn dq_blend_weights<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.session
            .dq_blend_weights()
            .map(|b| PyArray1::from_slice(py, b.values()))
    }

    /// Warnings gathered while loading and building the rig.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    #[getter]
    fn num_vertices(&self) -> usize {
        self.session.rest_mesh().len()
    }

    #[getter]
    fn num_joints(&self) -> usize {
        self.session.skeleton().len()
    }

    #[getter]
    fn num_cage_vertices(&self) -> usize {
        self.session.rest_cage().len()
    }
}
