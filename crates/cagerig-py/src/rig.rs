//! `cagerig.Rig`: a live coupled rig (the library's `RigSession`) with numpy in and out.
//!
//! Arrays returned by properties are **copies** (snapshots that later edits do not change),
//! except `cage_coords` (Φ), which is a **read-only view** of the rig's own storage: Φ never
//! changes after the rig is built, and the view keeps the rig alive.

use std::path::PathBuf;
use std::time::Instant;

use cagerig::Warning;
use cagerig::auto_weights::AutoWeightsOptions;
use cagerig::mesh::TriMesh;
use cagerig::playback::AnimationPlayer;
use cagerig::rig_files::{MissingCage, load_rig_files_with_weights};
use cagerig::script::{JointRef, resolve_joint};
use cagerig::session::{BindStage, RigParts, RigSession, SessionOptions};
use cagerig::weights_source::{WeightsSource, apply_weights_source};
use glam::{DAffine3, DQuat, DVec3};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;

use crate::convert;
use crate::errors::{rig_error, warn_all};
use crate::options;

/// A coupled cage + skeleton rig (Corda et al. 2020): rest skin M, skeleton S, cage C and their
/// current counterparts M', S', C', kept in sync under the three edits (rotate a joint, move the
/// rest cage, move the current cage).
///
/// Build one with :meth:`Rig.load`, :meth:`Rig.builtin` or :meth:`Rig.from_arrays`.
///
/// Array properties return copies (snapshots), except :attr:`cage_coords` (Φ), a read-only view
/// of the rig's storage (Φ never changes once the rig is built). Reading :attr:`posed_mesh`
/// copies M' only (``#V × 3`` floats), never Φ.
#[pyclass(module = "cagerig", name = "Rig")]
pub struct Rig {
    pub(crate) session: RigSession,
    pub(crate) warnings: Vec<String>,
    pub(crate) source: String,
    pub(crate) player: Option<AnimationPlayer>,
}

impl Rig {
    pub fn session_mut(&mut self) -> &mut RigSession {
        &mut self.session
    }

    pub fn session(&self) -> &RigSession {
        &self.session
    }

    /// The rig of `parts` bound with `options`; `progress`, when given, is called as
    /// `progress(stage, done, total)` while it binds (from worker threads, each call holding the
    /// GIL; an exception it raises is reported as unraisable and the binding goes on).
    fn build(
        py: Python<'_>,
        parts: RigParts,
        options: SessionOptions,
        mut warnings: Vec<Warning>,
        source: String,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        let report = |stage: BindStage, done: usize, total: usize| {
            if let Some(callback) = &progress {
                Python::attach(|py| {
                    if let Err(error) = callback.call1(py, (stage.label(), done, total)) {
                        error.write_unraisable(py, Some(callback.bind(py)));
                    }
                });
            }
        };
        let (session, more) = py
            .detach(|| RigSession::with_progress(parts, options, &report))
            .map_err(rig_error)?;
        warnings.extend(more);
        warn_all(py, &warnings)?;
        Ok(Self {
            session,
            warnings: warnings.iter().map(|w| w.to_string()).collect(),
            source,
            player: None,
        })
    }

    pub(crate) fn joint_index(&self, joint: &Bound<'_, PyAny>) -> PyResult<usize> {
        let reference = if joint.is_instance_of::<pyo3::types::PyString>() {
            JointRef::Name(joint.extract::<String>()?)
        } else {
            let index: i64 = joint.extract().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(format!(
                    "joint must be a joint name (str) or index (int), got {}",
                    joint
                        .get_type()
                        .name()
                        .map(|n| n.to_string())
                        .unwrap_or_default()
                ))
            })?;
            let n = self.session.skeleton().len();
            let index = usize::try_from(index).map_err(|_| {
                PyIndexError::new_err(format!(
                    "joint {index} is out of range (the rig has {n} joints)"
                ))
            })?;
            JointRef::Index(index)
        };
        resolve_joint(&self.session, &reference).map_err(|message| match reference {
            JointRef::Index(_) => PyIndexError::new_err(message),
            JointRef::Name(_) => PyValueError::new_err(message),
        })
    }

    pub(crate) fn cage_edit_args(
        &self,
        indices: &Bound<'_, PyAny>,
        offsets: &Bound<'_, PyAny>,
    ) -> PyResult<(Vec<usize>, Vec<DVec3>)> {
        let nc = self.session.rest_cage().len();
        let vertices = convert::indices(indices, "indices", nc, "cage vertices")?;
        if vertices.is_empty() {
            return Err(PyValueError::new_err("indices: no cage vertex given"));
        }
        let offsets = convert::offsets(offsets, "offsets", vertices.len())?;
        Ok((vertices, offsets))
    }

    /// Times `n` calls of `edit` in Rust (alternating the sign of the edit so the rig returns
    /// to where it started); seconds in total.
    pub(crate) fn time_in_rust(
        &mut self,
        py: Python<'_>,
        n: usize,
        mut edit: impl FnMut(&mut RigSession, f64) -> Result<(), cagerig::RigError> + Send,
    ) -> PyResult<f64> {
        let session = &mut self.session;
        py.detach(|| {
            let start = Instant::now();
            for i in 0..n {
                edit(session, if i % 2 == 0 { 1.0 } else { -1.0 })?;
            }
            Ok(start.elapsed().as_secs_f64())
        })
        .map_err(rig_error)
    }
}

pub(crate) fn rest_joints(session: &RigSession) -> Vec<DVec3> {
    session.rest_joints().collect()
}

#[pymethods]
impl Rig {
    /// Loads a rig from files: the mesh (OBJ) and its companions discovered beside it as the
    /// paper tool does (``<stem>.skt``, ``<stem>.skw``, ``<stem>_cage.obj``, and optionally
    /// ``<cage>_cageWeights.txt`` (Φ), ``<cage>.maxvol``, ``<stem>_corWeights.txt``), or a
    /// skinned glTF 2.0 (``.glb``/``.gltf``) or FBX (``.fbx``) character.
    ///
    /// Parameters
    /// ----------
    /// path : str or os.PathLike
    ///     The character: OBJ with companions, or ``.glb`` / ``.gltf`` / ``.fbx``.
    /// cage : str or os.PathLike, optional
    ///     The cage (OBJ); default ``<stem>_cage.obj`` beside an OBJ mesh, or a cage node in a
    ///     glTF / FBX file.
    /// auto_cage : int, optional
    ///     When no cage is found, generate one with this many vertices (as ``cagerig cage``;
    ///     issued as a RigWarning) instead of failing.
    /// cage_layout : {"skeleton", "offset"}, default "skeleton"
    ///     How that generated cage is laid out (as ``cagerig --cage-layout``): by the skeleton
    ///     (limbs kept apart by the skin's dominant joints, rings of vertices at the
    ///     articulations) or as one offset surface around the whole skin.
    /// skin : str, optional
    ///     glTF / FBX: the skin to import, by name or index (``"0"``, ``"1"``, …; as
    ///     ``cagerig --skin``). Default: the first, with the skins that share its skeleton.
    /// skinning : {"lbs", "dqs", "cor", "blended"}, optional
    ///     Default: the method the file says its authoring tool uses (FBX skin deformers; a
    ///     Maya "weight blended" skin is "blended", with its per-vertex DQ blend weights),
    ///     else "lbs". "blended" needs DQ blend weights: FBX characters carry them.
    /// fit_rows : {"maxvol", "all"}, default "maxvol"
    ///     Mesh rows used by CageUp/CageRev (MaxVol square system, or least squares on all rows).
    /// localisation : {"articulation", "reference-tool"} ("reference_tool" is read alike), default "articulation"
    ///     SkelUp prior (see the README).
    /// fit_source : {"ghost", "displayed"}, default "ghost"
    ///     What CageUp fits under DQS/CoR.
    /// coords_precision : {"f64", "f32"}, default "f64"
    ///     Storage of Φ in the per-frame products.
    /// auto_weights : bool, default False
    ///     Compute the skinning weights (as :func:`skin_weights`, the rig's cage bounding the
    ///     volume) instead of using the character's own; an OBJ then needs no ``.skw``.
    /// cage_fit : {"regularised", "paper"}, default "regularised"
    ///     How CageUp fits the current cage C' (as ``cagerig --cage-fit``): near the rest cage
    ///     carried by the skeleton while fitting the skin, or the paper's fit of the rows alone.
    /// green_face_term : {"fold-safe", "lipman"}, default "fold-safe"
    ///     Green rigs: the stretched normals' face term (as ``cagerig --green-face-term``), smooth
    ///     through folds, or Lipman's, which jumps there.
    /// progress : callable, optional
    ///     Called as ``progress(stage, done, total)`` while the rig binds (``stage`` is
    ///     ``"cage coordinates"``; ``done`` of ``total`` vertices), from worker threads: to drive
    ///     a progress bar. An exception it raises is reported as unraisable.
    /// keep_file_coords : bool, default False
    ///     Keep a cage-weights file's Φ even when it does not reproduce the mesh (the paper
    ///     tool's 6-decimal files; for conformance). By default such a Φ is recomputed, so that
    ///     nothing the user did not touch moves at the first cage edit.
    ///
    /// Raises
    /// ------
    /// FileNotFoundError, RigFileError, RigError
    ///     With the file, line or element at fault. Accepted oddities (weights renormalised, …)
    ///     are issued as RigWarning and kept in :attr:`warnings`.
    #[staticmethod]
    #[pyo3(signature = (path, cage = None, *, skinning = None, fit_rows = "maxvol",
                        localisation = "articulation", fit_source = "ghost", coords_precision = "f64",
                        keep_file_coords = false, auto_cage = None, cage_layout = "skeleton", auto_weights = false,
                        coords = "mvc", skin = None, cage_fit = "regularised", green_face_term = "fold-safe", progress = None))]
    #[expect(clippy::too_many_arguments)]
    fn load(
        py: Python<'_>,
        path: PathBuf,
        cage: Option<PathBuf>,
        skinning: Option<&str>,
        fit_rows: &str,
        localisation: &str,
        fit_source: &str,
        coords_precision: &str,
        keep_file_coords: bool,
        auto_cage: Option<usize>,
        cage_layout: &str,
        auto_weights: bool,
        coords: &str,
        skin: Option<String>,
        cage_fit: &str,
        green_face_term: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        let weights_source = if auto_weights {
            WeightsSource::Automatic(AutoWeightsOptions::default())
        } else {
            WeightsSource::Character
        };
        let mut options = options::session_options(&options::OptionNames {
            skinning: skinning.unwrap_or("lbs"),
            fit_rows,
            localisation,
            fit_source,
            coords_precision,
            coords,
            cage_fit,
            green_face_term,
        })?;
        if keep_file_coords {
            options.given_cage_coords = cagerig::session::GivenCageCoords::Keep;
        }
        let (parts, warnings) = if cagerig_formats::CharacterFormat::of(&path).is_some() {
            let (parts, warnings, file_skinning) = crate::interchange::load_character(
                py,
                &path,
                cage.as_deref(),
                auto_cage,
                cage_layout,
                skin,
            )?;
            // `skinning=` was parsed into the options when given.
            let chosen = skinning.map(|_| options.skinning);
            options.skinning =
                cagerig::skinning::SkinningMethod::chosen_else_file(chosen, file_skinning);
            let (mut parts, mut warnings) = (parts, warnings);
            let name = path.display().to_string();
            let applied = py
                .detach(|| apply_weights_source(&weights_source, &mut parts, &name, &name, &|_| {}))
                .map_err(crate::auto_weights::weights_source_error)?;
            warnings.extend(applied.warnings);
            (parts, warnings)
        } else {
            if let Some(skin) = skin {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "skin={skin:?} chooses a skin of a glTF or FBX character; {} is a rig of \
                     files (OBJ with companions), which has one",
                    path.display()
                )));
            }
            let missing = match auto_cage {
                Some(n) => {
                    MissingCage::Generate(crate::interchange::cage_options(n, None, cage_layout)?)
                }
                None => MissingCage::Fail,
            };
            let files = py
                .detach(|| {
                    load_rig_files_with_weights(
                        &path,
                        cage.as_deref(),
                        missing,
                        &weights_source,
                        &|_| {},
                    )
                })
                .map_err(crate::auto_weights::weights_source_error)?;
            let mut warnings = files.warnings;
            if let Some(g) = &files.generated_cage {
                warnings.push(cagerig::cage_source::generated_cage_note(g));
            }
            (files.parts, warnings)
        };
        Self::build(
            py,
            parts,
            options,
            warnings,
            path.display().to_string(),
            progress,
        )
    }

    /// A built-in demo rig generated by the library: ``"bar"``, ``"bar_irregular"`` (the
    /// paper's Figure 5 bar) or ``"snake"`` (16 joints; ``resolution`` ≈ skin vertex count).
    /// Options as for :meth:`load`.
    #[staticmethod]
    #[pyo3(signature = (name, resolution = None, *, skinning = "lbs", fit_rows = "maxvol",
                        localisation = "articulation", fit_source = "ghost", coords_precision = "f64",
                        coords = "mvc", cage_fit = "regularised", green_face_term = "fold-safe", progress = None))]
    #[expect(clippy::too_many_arguments)]
    fn builtin(
        py: Python<'_>,
        name: &str,
        resolution: Option<usize>,
        skinning: &str,
        fit_rows: &str,
        localisation: &str,
        fit_source: &str,
        coords_precision: &str,
        coords: &str,
        cage_fit: &str,
        green_face_term: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        let options = options::session_options(&options::OptionNames {
            skinning,
            fit_rows,
            localisation,
            fit_source,
            coords_precision,
            coords,
            cage_fit,
            green_face_term,
        })?;
        let rig = py
            .detach(|| cagerig::demo::builtin(name, resolution))
            .map_err(rig_error)?;
        let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        Self::build(
            py,
            parts,
            options,
            Vec::new(),
            format!("builtin:{name}"),
            progress,
        )
    }

    /// Builds a rig from arrays. Joint rest frames get identity rotations.
    ///
    /// Parameters
    /// ----------
    /// vertices : (n, 3) float64 array
    ///     Rest skin M.
    /// triangles : (f, 3) int array
    /// skin_weights : (n, J) float64 array or scipy.sparse matrix
    ///     Ω.
    /// joint_positions : (J, 3) float64 array
    ///     Rest joint positions.
    /// joint_parents : (J,) int array
    ///     Parent index of each joint, -1 for a root.
    /// cage_vertices : (c, 3) float64 array
    ///     Rest cage C (must enclose the skin).
    /// cage_triangles : (g, 3) int array
    /// joint_names : list of str, optional
    ///     Default ``"joint0"``, ``"joint1"``, …
    /// dq_blend_weights : (n,) float64 array, optional
    ///     Per-vertex blend b in [0, 1] of the ``"blended"`` method (0: LBS, 1: DQS).
    ///
    /// Other keyword options as for :meth:`load`.
    #[staticmethod]
    #[pyo3(signature = (vertices, triangles, skin_weights, joint_positions, joint_parents,
                        cage_vertices, cage_triangles, joint_names = None, *, skinning = "lbs",
                        fit_rows = "maxvol", localisation = "articulation", fit_source = "ghost",
                        coords_precision = "f64", coords = "mvc", dq_blend_weights = None,
                        cage_fit = "regularised", green_face_term = "fold-safe", progress = None))]
    #[expect(clippy::too_many_arguments)]
    fn from_arrays(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        skin_weights: &Bound<'_, PyAny>,
        joint_positions: &Bound<'_, PyAny>,
        joint_parents: &Bound<'_, PyAny>,
        cage_vertices: &Bound<'_, PyAny>,
        cage_triangles: &Bound<'_, PyAny>,
        joint_names: Option<Vec<String>>,
        skinning: &str,
        fit_rows: &str,
        localisation: &str,
        fit_source: &str,
        coords_precision: &str,
        coords: &str,
        dq_blend_weights: Option<&Bound<'_, PyAny>>,
        cage_fit: &str,
        green_face_term: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        let options = options::session_options(&options::OptionNames {
            skinning,
            fit_rows,
            localisation,
            fit_source,
            coords_precision,
            coords,
            cage_fit,
            green_face_term,
        })?;
        let positions = convert::points(vertices, "vertices")?;
        let tris = convert::triangles(triangles, "triangles", positions.len())?;
        let (weights, warnings) =
            convert::skin_weights(skin_weights, "skin_weights", Some(positions.len()))?;
        let skeleton =
            crate::auto_weights::skeleton_from_arrays(joint_positions, joint_parents, joint_names)?;
        let cage_pos = convert::points(cage_vertices, "cage_vertices")?;
        let cage_tris = convert::triangles(cage_triangles, "cage_triangles", cage_pos.len())?;
        let mesh = TriMesh::new(positions, tris).map_err(rig_error)?;
        let cage = TriMesh::new(cage_pos, cage_tris).map_err(rig_error)?;
        let blend = dq_blend_weights
            .map(|b| convert::dq_blend_weights(b, "dq_blend_weights", mesh.num_vertices()))
            .transpose()?;
        let parts = RigParts::new(mesh, skeleton, weights, cage).with_dq_blend_weights(blend);
        Self::build(py, parts, options, warnings, "arrays".into(), progress)
    }

    /// An independent copy of the rig in its current state (cheap next to loading: no
    /// precomputation is repeated).
    fn copy(&self) -> Self {
        Self {
            session: self.session.clone(),
            warnings: self.warnings.clone(),
            source: self.source.clone(),
            player: self.player.clone(),
        }
    }

    fn __copy__(&self) -> Self {
        self.copy()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.copy()
    }

    fn __repr__(&self) -> String {
        format!(
            "Rig({:?}: {} vertices, {} joints, {} cage vertices, skinning={:?})",
            self.source,
            self.session.rest_mesh().len(),
            self.session.skeleton().len(),
            self.session.rest_cage().len(),
            self.session.skinning().name()
        )
    }

    // ----- edits ---------------------------------------------------------------------------

    /// S' edit: rotates a joint by ``degrees`` about the world-space ``axis`` through the
    /// joint's current position; descendants follow, then M' and C' (CageUp).
    ///
    /// Parameters
    /// ----------
    /// joint : str or int
    ///     Joint name or index.
    /// axis : (3,) array-like
    ///     World-space axis (any non-zero length).
    /// degrees : float
    fn rotate_joint(
        &mut self,
        py: Python<'_>,
        joint: &Bound<'_, PyAny>,
        axis: &Bound<'_, PyAny>,
        degrees: f64,
    ) -> PyResult<()> {
        let j = self.joint_index(joint)?;
        let axis = convert::vec3(axis, "axis")?;
        if axis.length_squared() == 0.0 {
            return Err(PyValueError::new_err(
                "axis must be non-zero, got (0, 0, 0)",
            ));
        }
        if !degrees.is_finite() {
            return Err(PyValueError::new_err(format!(
                "degrees is {degrees}: the angle must be finite"
            )));
        }
        let session = &mut self.session;
        py.detach(|| session.rotate_joint(j, axis, degrees.to_radians()))
            .map_err(rig_error)
    }

    /// C edit: moves rest-cage vertices. M follows (M += Φ[:, k]·ΔC_k), then SkelUp moves the
    /// bones, skinning gives M' and CageUp C'.
    ///
    /// Parameters
    /// ----------
    /// indices : int or (k,) int array
    ///     Rest-cage vertices (a vertex listed twice moves twice).
    /// offsets : (3,) or (k, 3) float64 array
    ///     One offset for all, or one per index.
    fn move_rest_cage(
        &mut self,
        py: Python<'_>,
        indices: &Bound<'_, PyAny>,
        offsets: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (vertices, offsets) = self.cage_edit_args(indices, offsets)?;
        let session = &mut self.session;
        py.detach(|| session.move_rest_cage(&vertices, &offsets))
            .map_err(rig_error)
    }

    /// C' edit: moves current-cage vertices; CageRev (Eq. 19) turns the grab into a rest-cage
    /// edit and the chain lands C' on the requested positions (exactly under LBS, and under
    /// DQS/CoR with ``fit_source="ghost"``). Arguments as for :meth:`move_rest_cage`.
    fn move_posed_cage(
        &mut self,
        py: Python<'_>,
        indices: &Bound<'_, PyAny>,
        offsets: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (vertices, offsets) = self.cage_edit_args(indices, offsets)?;
        let session = &mut self.session;
        py.detach(|| session.move_posed_cage(&vertices, &offsets))
            .map_err(rig_error)
    }

    /// Switches the skinning method: ``"lbs"``, ``"dqs"``, ``"cor"`` or ``"blended"`` (CoR
    /// centres are computed on the first switch to CoR; "blended" needs the rig's DQ blend
    /// weights, else a RigError).
    fn set_skinning(&mut self, py: Python<'_>, method: &str) -> PyResult<()> {
        let method = options::skinning_method(method)?;
        let session = &mut self.session;
        py.detach(|| session.set_skinning(method))
            .map_err(rig_error)
    }

    /// Green rigs: what an edit does when CageUp finds no current cage for it (past a fold):
    /// ``"refuse"`` (the default: RigError, nothing moves) or ``"keep"`` (the skin and
    /// skeletons exact, the current cage left at the fit's closest cage and reported by
    /// :attr:`posed_cage_unfitted`; grabs of it refused until a pose fits again).
    fn set_unfitted_cage(&mut self, policy: &str) -> PyResult<()> {
        let policy = policy
            .parse::<cagerig::session::UnfittedCagePolicy>()
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("unfitted_cage: {e}")))?;
        self.session.set_unfitted_cage_policy(policy);
        Ok(())
    }

    /// Selects what CageUp fits under DQS/CoR: ``"ghost"`` (exact loop) or ``"displayed"``.
    fn set_fit_source(&mut self, py: Python<'_>, source: &str) -> PyResult<()> {
        let source = options::fit_source(source)?;
        let session = &mut self.session;
        py.detach(|| session.set_fit_source(source));
        Ok(())
    }

    /// Sets the whole pose (S' edit).
    ///
    /// Parameters
    /// ----------
    /// local_rotations : (J, 4) float64 array
    ///     Local rotation of every joint (relative to its parent's frame) as quaternions
    ///     ``(x, y, z, w)``; normalised here.
    /// root_motion : (J, 3) float64 array, optional
    ///     Translation of each root from its rest position (ignored for non-roots).
    #[pyo3(signature = (local_rotations, root_motion = None))]
    fn set_pose(
        &mut self,
        py: Python<'_>,
        local_rotations: &Bound<'_, PyAny>,
        root_motion: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let nj = self.session.skeleton().len();
        let (rows, cols, q) = convert::matrix(local_rotations, "local_rotations")?;
        if rows != nj || cols != 4 {
            return Err(PyValueError::new_err(format!(
                "local_rotations must have shape ({nj}, 4) (x, y, z, w per joint), got ({rows}, {cols})"
            )));
        }
        let rotations: Vec<DQuat> = q.chunks(4).map(DQuat::from_slice).collect();
        if let Some(j) = rotations.iter().position(|r| r.length_squared() == 0.0) {
            return Err(PyValueError::new_err(format!(
                "local_rotations[{j}] is the zero quaternion"
            )));
        }
        let motion = match root_motion {
            Some(m) => convert::points_n(m, "root_motion", nj, "joint")?,
            None => vec![DVec3::ZERO; nj],
        };
        let session = &mut self.session;
        py.detach(|| session.set_pose(&rotations, &motion))
            .map_err(rig_error)
    }

    /// The current pose as ``(local_rotations (J, 4) xyzw, root_motion (J, 3))``, the
    /// arguments of :meth:`set_pose` (copies).
    #[getter]
    fn pose<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(convert::F64Array2<'py>, convert::F64Array2<'py>)> {
        let s = &self.session;
        let skeleton = s.skeleton();
        let mut locals = vec![DAffine3::IDENTITY; skeleton.len()];
        skeleton.locals_from_worlds(s.posed_world_from_joint(), &mut locals);
        let q: Vec<f64> = locals
            .iter()
            .flat_map(|l| DQuat::from_mat3(&l.matrix3).normalize().to_array())
            .collect();
        let motion: Vec<DVec3> = (0..skeleton.len())
            .map(|j| match skeleton.parent(j) {
                None => {
                    s.posed_world_from_joint()[j].translation
                        - s.rest_world_from_joint()[j].translation
                }
                Some(_) => DVec3::ZERO,
            })
            .collect();
        Ok((
            convert::matrix_to_py(py, skeleton.len(), 4, q)?,
            convert::points_to_py(py, &motion)?,
        ))
    }

    /// Back to the rest pose (rest-cage edits are kept).
    fn reset_pose(&mut self, py: Python<'_>) {
        let session = &mut self.session;
        py.detach(|| session.reset_pose());
    }
}
