//! What a session is assembled from: the rig parts, the options, and the constants and
//! helpers of that assembly (CoR coordinates Λ, the ΦC = M check).

use super::display_rest_map::DisplayRestMap;
use super::external_skinning::SkinningBackend;
use super::unfitted_cage::UnfittedCagePolicy;
use crate::cage_coords::{CageCoords, CoordsPrecision};
use crate::coords_kind::CoordsKind;
use crate::cor_centres::cage_coords::compute_cor_cage_coords;
use crate::cor_centres::grid::{CorGridOptions, compute_cor_cage_coords_grid};
use crate::cor_centres::{CorCentresMethod, CorCentresOptions};
use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use crate::skinning::{DqBlendWeights, SkinningMethod};
use crate::sparse_rows::SparseRows;
use crate::sync::cage_fit_kind::CageFitKind;
use crate::sync::skeleton_updater::JointLocalisation;
use glam::DVec3;
use std::sync::Arc;

/// Above this many vertices, CoR centres computed on demand with [`CorCentresMethod::Exact`] use
/// the similarity tables of [`crate::cor_centres::grid`] (seconds, centre error ≈ 1e-4 × bbox
/// diagonal) instead of the exact O(#V·#F) form.
pub const GRID_COR_CENTRES_ABOVE: usize = 20_000;

/// Φ reproduces the given rest mesh when max |ΦC − M| ≤ this × the cage's bbox diagonal.
pub const PHI_C_TOLERANCE: f64 = 1e-9;

/// With [`CoordsPrecision::F32`], ΦC within this × the cage's bbox diagonal of the given rest
/// mesh differs from it by the rounding of Φ only, and replaces it when the session is built.
pub const PHI_C_TOLERANCE_F32: f64 = 1e-5;

/// How [`compute_centre_coords`] computes Λ for a mesh of `num_vertices` vertices with the
/// default (exact) options.
pub fn centre_coords_method(num_vertices: usize) -> &'static str {
    if num_vertices > GRID_COR_CENTRES_ABOVE {
        "similarity tables"
    } else {
        "exact"
    }
}

/// CoR cage coordinates Λ (`#V × #C`, Eq. 14: centres = Λ·C) from the rest mesh, Ω and Φ, as
/// a session computes them when none were loaded: with `options`, except that the exact form
/// is replaced by the similarity tables of [`crate::cor_centres::grid`] on big meshes (see
/// [`centre_coords_method`]).
pub fn compute_centre_coords(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    skin_weights: &SkinWeights,
    cage_coords: &CageCoords,
    options: &CorCentresOptions,
) -> Result<CageCoords, RigError> {
    if options.method == CorCentresMethod::Exact && rest_positions.len() > GRID_COR_CENTRES_ABOVE {
        return compute_cor_cage_coords_grid(
            rest_positions,
            triangles,
            skin_weights,
            cage_coords,
            &CorGridOptions {
                sigma: options.sigma,
                ..Default::default()
            },
            &|_, _| {},
        );
    }
    compute_cor_cage_coords(
        rest_positions,
        triangles,
        skin_weights,
        cage_coords,
        options,
        &|_, _| {},
    )
}

/// The long stage of binding a rig that [`BindProgress`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindStage {
    /// The cage coordinates of the rest mesh's vertices: Φ for mean value rigs, φ and ψ for
    /// Green rigs (`done` and `total` count vertices).
    CageCoordinates,
}

impl BindStage {
    /// What the stage computes, for a progress bar's label.
    pub const fn label(self) -> &'static str {
        match self {
            Self::CageCoordinates => "cage coordinates",
        }
    }
}

/// Called while a rig binds, from worker threads, with the stage, the work done and its total:
/// front ends show progress with it and compute nothing themselves
/// ([`super::RigSession::with_progress`]).
pub type BindProgress<'a> = &'a (dyn Fn(BindStage, usize, usize) + Sync);

/// Which mesh CageUp fits when the skinning method is not LBS (Section 4.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CageFitSource {
    /// An LBS "ghost" of the fitted rows drives CageUp whatever the skinning method, so the
    /// loop C' → C → S → S' → C' stays exact for DQS and CoR too (the default).
    #[default]
    GhostLbs,
    /// CageUp fits the displayed mesh; with DQS/CoR the reverse deformer is then approximate.
    DisplayedMesh,
}

impl CageFitSource {
    /// Every source, the default first.
    pub const ALL: [CageFitSource; 2] = [Self::GhostLbs, Self::DisplayedMesh];

    /// The name front ends use (`--fit-source`, Python's `fit_source=`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::GhostLbs => "ghost",
            Self::DisplayedMesh => "displayed",
        }
    }

    /// One line for `--help`.
    pub const fn help(self) -> &'static str {
        match self {
            Self::GhostLbs => {
                "an LBS ghost of the fitted rows drives CageUp (exact loop for DQS/CoR)"
            }
            Self::DisplayedMesh => {
                "CageUp fits the displayed DQS/CoR mesh (approximate reverse deformer)"
            }
        }
    }
}

/// A name that is not a [`CageFitSource`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown fit source {found:?}: expected {}",
    CageFitSource::names_text()
)]
pub struct UnknownCageFitSource {
    /// The name given.
    pub found: String,
}

crate::named_kind::named_kind!(CageFitSource, UnknownCageFitSource, CageFitSource::help);

/// The named choices of [`FitRows`] (explicit rows are given as data, not by name).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FitRowsKind {
    /// [`FitRows::MaxVol`].
    #[default]
    MaxVol,
    /// [`FitRows::AllRows`].
    AllRows,
}

impl FitRowsKind {
    /// Every choice, the default first.
    pub const ALL: [FitRowsKind; 2] = [Self::MaxVol, Self::AllRows];

    /// The name front ends use (`--fit-rows`, Python's `fit_rows=`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::MaxVol => "maxvol",
            Self::AllRows => "all",
        }
    }

    /// One line for `--help`.
    pub const fn help(self) -> &'static str {
        match self {
            Self::MaxVol => {
                "MaxVol rows (a shipped .maxvol if found, else computed): exact square system"
            }
            Self::AllRows => {
                "all mesh rows, least squares (the paper tool's GUI; slow on big meshes)"
            }
        }
    }
}

impl From<FitRowsKind> for FitRows {
    fn from(kind: FitRowsKind) -> Self {
        match kind {
            FitRowsKind::MaxVol => FitRows::MaxVol,
            FitRowsKind::AllRows => FitRows::AllRows,
        }
    }
}

/// A name that is not a [`FitRowsKind`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown fit rows {found:?}: expected {}", FitRowsKind::names_text())]
pub struct UnknownFitRowsKind {
    /// The name given.
    pub found: String,
}

crate::named_kind::named_kind!(FitRowsKind, UnknownFitRowsKind, FitRowsKind::help);

/// Which mesh rows CageUp and CageRev use.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum FitRows {
    /// Given rows (e.g. a shipped `.maxvol` file) if any, else computed MaxVol rows.
    #[default]
    MaxVol,
    /// All mesh rows, least squares (the reference tool's GUI behaviour; slow on big meshes).
    AllRows,
    /// Explicit rows; interpolation when there are `#C` of them, least squares otherwise.
    Rows(Vec<usize>),
}

/// What a session does with given cage coordinates Φ that do not reproduce the rest mesh
/// (max |ΦC − M| above [`PHI_C_TOLERANCE`] × the cage's bbox diagonal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GivenCageCoords {
    /// Recompute Φ (mean value coordinates) and report it: M = ΦC holds from the start, so the
    /// first cage edit moves only what it touches (the default).
    #[default]
    RecomputeIfInexact,
    /// Keep the given Φ (to compare with the tool that wrote it): M stays as loaded until the
    /// first cage edit, which sets M = ΦC everywhere (untouched vertices jump by the residual).
    Keep,
}

/// max |ΦC − M| over the mesh vertices.
pub(super) fn phi_c_residual(cage_coords: &CageCoords, cage: &[DVec3], mesh: &[DVec3]) -> f64 {
    let mut phi_c = vec![DVec3::ZERO; mesh.len()];
    cage_coords.apply(cage, &mut phi_c);
    crate::mesh::max_distance(&phi_c, mesh)
}

/// Options for assembling a session.
#[derive(Debug, Clone, Default)]
pub struct SessionOptions {
    /// How SkelUp builds the joint localisation L of Eq. 9 from Ω.
    pub localisation: JointLocalisation,
    /// Which mesh rows CageUp and CageRev use.
    pub fit_rows: FitRows,
    /// Which mesh CageUp fits when the skinning method is not LBS.
    pub fit_source: CageFitSource,
    /// Skinning method to start with.
    pub skinning: SkinningMethod,
    /// How the CoR centres p_i are computed (for CoR skinning).
    pub cor_centres: CorCentresOptions,
    /// Precision of Φ (and Λ) in the per-frame products M = ΦC. With
    /// [`CoordsPrecision::F32`] the coordinates are rounded once when the session is built,
    /// everything (MaxVol rows, CageUp, Ψ, CageRev, Λ) is derived from the rounded Φ, and the
    /// rest mesh becomes ΦC at once (it moves by ~1e-7 of the cage size); the invariants then
    /// hold to f64 round-off as in the default f64 mode.
    pub cage_coords_precision: CoordsPrecision,
    /// Given Φ that does not reproduce M: recomputed (default) or kept.
    pub given_cage_coords: GivenCageCoords,
    /// Accept mesh vertices outside the cage (reported as a warning) instead of failing with
    /// [`RigError::MeshOutsideCage`].
    pub allow_mesh_outside_cage: bool,
    /// The cage coordinates to bind with: mean value (M = ΦC, the paper) or Green
    /// (M = φC + ψ·g(C); see `docs/green-coordinates.md`).
    pub coords: CoordsKind,
    /// What an event does when a Green CageUp finds no current cage for it: refuse it (the
    /// default) or keep it with C' unfitted ([`UnfittedCagePolicy`]).
    pub unfitted_cage: UnfittedCagePolicy,
    /// How CageUp fits C' ([`CageFitKind`]): regularised towards the rest cage carried by the
    /// skeleton (the default), or the paper's interpolation of the MaxVol rows. Green rigs fit
    /// by Gauss–Newton on the rows, with the same regulariser or without it
    /// ([`RigSession::cage_fit`]).
    pub cage_fit: CageFitKind,
    /// Green rigs: the face term g(C') of the map M = φC + ψ·g(C)
    /// ([`crate::coords::stretched_normals::FaceTermKind`]): smooth through folds (the default)
    /// or Lipman et al.'s stretched normal.
    pub green_face_term: crate::coords::stretched_normals::FaceTermKind,
    /// Who computes the drawn rest skin M̃ on the f32 display path: the CPU (the default) or a
    /// backend from another crate, such as a GPU one ([`DisplayRestMap`]). It changes what is
    /// drawn only; the rig's state is exact either way.
    pub display_rest_map: DisplayRestMap,
    /// A skinning method from another crate, bound with the rig and selected as
    /// [`crate::skinning::SkinningMethod::External`] (start with it through
    /// [`SessionOptions::skinning`], or switch to it with [`super::RigSession::set_skinning`]).
    /// CageUp fits its ghost LBS as for every method but LBS ([`super::SkinningBackend`]).
    pub external_skinning: Option<Arc<dyn SkinningBackend>>,
}

/// Rig inputs: the rest structures and optional precomputed data (computed when absent).
#[derive(Debug, Clone)]
pub struct RigParts {
    /// Rest skin M.
    pub mesh: TriMesh,
    /// Rest skeleton S.
    pub skeleton: Skeleton,
    /// Ω, `#V × #J`.
    pub skin_weights: SkinWeights,
    /// Rest cage C (validated here).
    pub cage: TriMesh,
    /// Φ, `#V × #C` (mean value coordinates computed when absent).
    pub cage_coords: Option<CageCoords>,
    /// MaxVol rows (computed when absent and needed).
    pub maxvol_rows: Option<Vec<usize>>,
    /// CoR centres as combinations of rest vertices, `#V × #V` sparse (computed on first use
    /// of CoR skinning when absent).
    pub cor_rows: Option<SparseRows>,
    /// Ψ, `#J` rows of `#C` (computed when absent).
    pub joint_coords: Option<Vec<Vec<f64>>>,
    /// Λ = S·Φ (`#V × #C`, Eq. 14), when already computed; takes precedence over `cor_rows`.
    pub cor_centre_coords: Option<CageCoords>,
    /// DQ blend weights b (`#V`, in [0, 1]) for [`SkinningMethod::Blended`]: vertex v is skinned
    /// `(1 − b_v)·LBS + b_v·DQS` (Maya's "weight blended" skin clusters, read from FBX). Without
    /// them a session refuses the blended method ([`RigError::NoDqBlendWeights`]).
    pub dq_blend_weights: Option<DqBlendWeights>,
}

impl RigParts {
    /// The four structures a rig needs — rest skin M, rest skeleton S, Ω and rest cage C — with
    /// no precomputed data: the session computes Φ, the MaxVol rows, Ψ and Λ when it needs them.
    pub fn new(
        mesh: TriMesh,
        skeleton: Skeleton,
        skin_weights: SkinWeights,
        cage: TriMesh,
    ) -> Self {
        Self {
            mesh,
            skeleton,
            skin_weights,
            cage,
            cage_coords: None,
            maxvol_rows: None,
            cor_rows: None,
            joint_coords: None,
            cor_centre_coords: None,
            dq_blend_weights: None,
        }
    }

    /// These parts with the DQ blend weights b (`#V`) of [`SkinningMethod::Blended`].
    pub fn with_dq_blend_weights(self, dq_blend_weights: Option<DqBlendWeights>) -> Self {
        Self {
            dq_blend_weights,
            ..self
        }
    }
}
