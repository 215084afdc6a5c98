//! `Rig` animation playback and edit scripts.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use cagerig::playback::AnimationPlayer;

use crate::errors::rig_error;
use crate::rig::Rig;
use crate::script::EditScriptPy;
use crate::tracks;

#[pymethods]
impl Rig {
    // ----- animation -------------------------------------------------------------------------

    /// Attaches animation tracks, sampled by :meth:`sample_animation` (Section 5: each track
    /// has its own keyframe times).
    ///
    /// Parameters
    /// ----------
    /// skeleton : path or (times, keyframes), optional
    ///     A skeleton animation file (the paper tool's text format), or ``times`` (K,) with
    ///     local transforms ``parent_from_joint`` (K, J, 4, 4).
    /// cage : path or (times, offsets), optional
    ///     A cage animation file, or ``times`` (K,) with rest-cage offsets from the cage as
    ///     loaded (K, #C, 3).
    #[pyo3(signature = (skeleton = None, cage = None))]
    fn set_animation(
        &mut self,
        py: Python<'_>,
        skeleton: Option<&Bound<'_, PyAny>>,
        cage: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        if skeleton.is_none() && cage.is_none() {
            return Err(PyValueError::new_err(
                "give a skeleton and/or a cage animation",
            ));
        }
        let skeleton_track = skeleton
            .map(|s| tracks::skeleton_track(py, s, self.session.skeleton()))
            .transpose()?;
        let nc = self.session.rest_cage().len();
        let cage_track = cage.map(|c| tracks::cage_track(py, c, nc)).transpose()?;
        let session = &self.session;
        let player = py
            .detach(|| AnimationPlayer::new(session, skeleton_track, cage_track))
            .map_err(rig_error)?;
        self.player = Some(player);
        Ok(())
    }

    /// Last keyframe time over the attached tracks (seconds); 0 without animation.
    #[getter]
    fn animation_duration(&self) -> f64 {
        self.player.as_ref().map_or(0.0, |p| p.duration())
    }

    /// Poses the rig at time ``t`` (seconds, clamped to each track's range): rest cage from the
    /// cage track, SkelUp, pose from the skeleton track, skinning, CageUp.
    fn sample_animation(&mut self, py: Python<'_>, t: f64) -> PyResult<()> {
        if !t.is_finite() {
            return Err(PyValueError::new_err(format!(
                "t is {t}: the time must be finite"
            )));
        }
        let Self {
            session, player, ..
        } = self;
        let player = player.as_mut().ok_or_else(|| {
            PyValueError::new_err("no animation attached: call set_animation first")
        })?;
        py.detach(|| player.apply(t, session)).map_err(rig_error)
    }

    // ----- scripts ---------------------------------------------------------------------------

    /// Runs an edit script (the ``cagerig edit`` JSON format: ``{"skinning": ..., "steps":
    /// [...]}``) on this rig: the script's skinning first, then every step. The script is
    /// checked against the rig before any step runs.
    ///
    /// Parameters
    /// ----------
    /// script : EditScript, str, dict or os.PathLike
    ///     A parsed script, JSON text, the parsed JSON, or a file.
    fn run_script(&mut self, py: Python<'_>, script: &Bound<'_, PyAny>) -> PyResult<()> {
        let script = EditScriptPy::from_any(script)?;
        script.run_all(py, self)
    }
}
