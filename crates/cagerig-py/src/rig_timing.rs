//! `Rig` benchmark support: the edits looped in Rust, to measure the binding's overhead against.

use glam::DVec3;
use pyo3::prelude::*;

use crate::convert;
use crate::rig::Rig;

#[pymethods]
impl Rig {
    // ----- benchmark support -------------------------------------------------------------------

    /// Seconds for ``n`` calls of ``rotate_joint`` made in Rust (sign alternating), to measure
    /// the Python call overhead against (see ``bench/overhead.py``).
    fn _time_rotate_joint_in_rust(
        &mut self,
        py: Python<'_>,
        joint: &Bound<'_, PyAny>,
        axis: &Bound<'_, PyAny>,
        degrees: f64,
        n: usize,
    ) -> PyResult<f64> {
        let j = self.joint_index(joint)?;
        let axis = convert::vec3(axis, "axis")?;
        self.time_in_rust(py, n, move |s, sign| {
            s.rotate_joint(j, axis, (sign * degrees).to_radians())
        })
    }

    /// As :meth:`_time_rotate_joint_in_rust` for ``move_rest_cage`` (posed: ``move_posed_cage``).
    #[pyo3(signature = (indices, offsets, n, posed = false))]
    fn _time_move_cage_in_rust(
        &mut self,
        py: Python<'_>,
        indices: &Bound<'_, PyAny>,
        offsets: &Bound<'_, PyAny>,
        n: usize,
        posed: bool,
    ) -> PyResult<f64> {
        let (vertices, offsets) = self.cage_edit_args(indices, offsets)?;
        let negated: Vec<DVec3> = offsets.iter().map(|o| -*o).collect();
        self.time_in_rust(py, n, move |s, sign| {
            let o = if sign > 0.0 { &offsets } else { &negated };
            if posed {
                s.move_posed_cage(&vertices, o)
            } else {
                s.move_rest_cage(&vertices, o)
            }
        })
    }
}
