//! The rest map: how the rest skin follows the rest cage, M = f(C), with its inverses — CageUp
//! fits C' to M', CageRev turns a C' edit into a C edit — and the extension point of the
//! coordinates kinds ([`CoordsKind`]).
//!
//! [`RestMap`] owns the coordinates, each kind's own CageUp and CageRev, and the state of M
//! relative to C ([`RestMeshState`]). Every kind keeps its *vertex part* in
//! [`RestMap::coords`] (`#V × #C`: Φ for mean value coordinates, φ for Green coordinates), so
//! everything linear in C — the MaxVol rows, the linear map P, SkelUp's Ψ — is built on it for
//! every kind. [`CageMap`] holds what each kind adds, its fit included, and every place the
//! session's behaviour depends on the kind matches on it exhaustively:
//!
//! | hook | [`CageMap::Mvc`] (M = ΦC) | [`CageMap::Green`] (M = φC + ψ·g(C)) |
//! |---|---|---|
//! | [`RestMap::bind`] | Φ (given or computed), MaxVol rows of Φ, the fit ([`CageFitKind`]), Eq. 19 | φ, ψ (face term: [`crate::coords::stretched_normals::FaceTermKind`]), MaxVol rows of [φ ψ], the Gauss–Newton fit (regularised or on the rows alone) and the Newton CageRev |
//! | [`RestMap::rest_mesh_in_full`], [`RestMap::rest_mesh_of`], [`RestMap::apply_rest_delta`] | M = ΦC | M = φC + ψ·g(C) in one pass; M += ψ·g(C) by face |
//! | [`RestMap::is_linear`] (keyframe lerp, centre deltas) | yes | no |
//! | the f32 display path's M̃ ([`RestMap::extra_coords`], [`RestMap::terms`]) | Φ̃·C | [φ̃ ψ̃]·[C; g(C)] |
//! | CageUp ([`RigSession::fit_cage`]) | C' = P·M'_R, or regularised ([`MvcMap::fit`]) | Gauss–Newton on the rows, regularised towards the carried cage by default |
//! | CageRev ([`RigSession::reverse_cage`]) | Eq. 19, factorised per pose ([`MvcMap::reverser`]) | Newton on the fit's stationarity |
//! | CoR centres | Λ·C | Λ·C + Λ_ψ·g(C) |
//!
//! A new kind is a variant here, its state in its own file (as [`GreenState`] in
//! `session/green.rs`), and the arms the compiler asks for. See `docs/architecture.md`.

use super::green::GreenState;
use super::green_binding::{compute_green_coords_for_mesh, green_fit_rows};
use super::parts::{
    BindProgress, BindStage, FitRows, GivenCageCoords, PHI_C_TOLERANCE, PHI_C_TOLERANCE_F32,
    SessionOptions, phi_c_residual,
};
use crate::cage_coords::{CageCoords, CoordsPrecision};
use crate::coords::{maxvol, mvc};
use crate::coords_kind::CoordsKind;
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_fit_kind::CageFitKind;
use crate::sync::cage_prior::BindingJoints;
use crate::sync::cage_reverser::{CageReverser, ReverserMethod};
use crate::sync::cage_updater::{CageFitMode, CageUpdater};

/// Given Φ off M by at most this fraction of the size was only rounded when written (the
/// paper's Arm: 1.3e-5): recomputing it is a note, not a warning.
const ROUNDED_PHI_C: f64 = 1e-4;
use crate::sync::skeleton_updater::{JointFaceTerms, SkeletonUpdater};
use glam::{DAffine3, DVec3};

/// How the session's rest skin M stands to the map of the rest cage C.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum RestMeshState {
    /// M is the mesh as loaded and differs from the map of C (e.g. Φ read from a file with 6
    /// decimals); the first cage edit sets M to the map of C in full.
    AsLoaded,
    /// M is the map of C on every row.
    Map,
    /// On the f32 display path after a current-cage event: M is the map of C on CageUp's
    /// fitting rows only; the whole exact M is computed on demand.
    MapOnRows,
}

/// Mean value coordinates' own CageUp and CageRev.
#[derive(Debug, Clone)]
pub(super) struct MvcMap {
    /// CageUp: the paper's C' = P·M'_R or the regularised fit ([`CageFitKind`]).
    pub(super) fit: CageUpdater,
    /// CageRev: Eq. 19 for `fit`, factorised per pose.
    pub(super) reverser: CageReverser,
}

/// What each coordinates kind adds to the vertex part, its CageUp and CageRev included.
#[derive(Debug, Clone)]
pub(super) enum CageMap {
    /// Mean value coordinates: M = ΦC, linear; the linear CageUp and Eq. 19.
    Mvc(Box<MvcMap>),
    /// Green coordinates: M = φC + ψ·g(C), with the face coordinates ψ, the stretched normals
    /// g and the Newton CageUp and CageRev (see `session/green.rs`).
    Green(Box<GreenState>),
}

/// The rest map component: M = f(C), its fit and reverser, and the state of M.
#[derive(Debug, Clone)]
pub(super) struct RestMap {
    /// The vertex part: Φ or φ, `#V × #C`.
    coords: CageCoords,
    /// What the kind adds (its fit and reverser included).
    kind: CageMap,
    /// How the session's M stands to the map of C.
    mesh_state: RestMeshState,
}

/// A bound rest map with what binding produced for the rest of the session.
pub(super) struct BoundRestMap {
    pub(super) rest_map: RestMap,
    /// SkelUp, built on the map's vertex part (and face terms).
    pub(super) skeleton_updater: SkeletonUpdater,
    /// The given Λ, when it applies to the kind.
    pub(super) cor_centre_coords: Option<CageCoords>,
}

/// Builds SkelUp for a bound map: from the rest mesh (as the map adopted it), the vertex part
/// and the kind's face terms; returns its notes.
pub(super) type SkeletonUpdaterOf<'a> = dyn FnOnce(
        &TriMesh,
        &CageCoords,
        Option<JointFaceTerms<'_>>,
    ) -> Result<(SkeletonUpdater, Vec<Warning>), RigError>
    + 'a;

/// The coordinates given with a rig's parts (each optional).
pub(super) struct GivenCoords {
    /// Φ, `#V × #C`.
    pub(super) cage_coords: Option<CageCoords>,
    /// CageUp's MaxVol rows of Φ.
    pub(super) maxvol_rows: Option<Vec<usize>>,
    /// Λ = S·Φ, `#V × #C`.
    pub(super) cor_centre_coords: Option<CageCoords>,
}

impl RestMap {
    /// Binds the rest mesh `mesh` (M, `#V`) to `cage` (C₀) with the kind `options.coords`:
    /// the vertex part, the fitting rows, the kind's CageUp, M's state (an f32 Φ that differs
    /// from M only by its rounding makes M = ΦC now, documented in
    /// [`SessionOptions::cage_coords_precision`]), SkelUp by `skeleton_updater_of`, and the
    /// kind's CageRev, which needs SkelUp's Ψ. Given coordinates are checked (and recomputed
    /// when they do not reproduce M and the options say so); notes go to `warnings`.
    #[expect(
        clippy::too_many_arguments,
        reason = "the rig's inputs, each used by one kind or the other"
    )]
    pub(super) fn bind(
        mesh: &mut TriMesh,
        cage: &TriMesh,
        given: GivenCoords,
        options: &SessionOptions,
        skin_weights: &SkinWeights,
        skeleton: &Skeleton,
        skeleton_updater_of: Box<SkeletonUpdaterOf<'_>>,
        progress: BindProgress<'_>,
        warnings: &mut Vec<Warning>,
    ) -> Result<BoundRestMap, RigError> {
        let (lo, hi) = cage.bounding_box();
        let size = (hi - lo).length();
        let inputs = BindInputs {
            cage,
            options,
            skin_weights,
            skeleton,
            size,
            progress,
        };
        match options.coords {
            CoordsKind::Mvc => inputs.bind_mvc(mesh, given, skeleton_updater_of, warnings),
            CoordsKind::Green => inputs.bind_green(mesh, given, skeleton_updater_of, warnings),
        }
    }
}

/// The inputs every kind's binding reads.
struct BindInputs<'a> {
    cage: &'a TriMesh,
    options: &'a SessionOptions,
    skin_weights: &'a SkinWeights,
    skeleton: &'a Skeleton,
    /// The cage's bounding-box diagonal.
    size: f64,
    progress: BindProgress<'a>,
}

impl BindInputs<'_> {
    /// Mean value coordinates: Φ (given, checked, or computed), its MaxVol rows, CageUp with
    /// the options' fit, SkelUp, and Eq. 19.
    fn bind_mvc(
        &self,
        mesh: &mut TriMesh,
        given: GivenCoords,
        skeleton_updater_of: Box<SkeletonUpdaterOf<'_>>,
        warnings: &mut Vec<Warning>,
    ) -> Result<BoundRestMap, RigError> {
        let (cage, options) = (self.cage, self.options);
        let nv = mesh.num_vertices();
        let nc = cage.num_vertices();
        let GivenCoords {
            cage_coords,
            maxvol_rows,
            cor_centre_coords,
        } = given;
        let mut coords = match cage_coords {
            Some(phi) => {
                if phi.num_vertices() != nv || phi.num_cage_vertices() != nc {
                    return Err(RigError::SizeMismatch {
                        what: "cage coordinates shape (#V × #C)",
                        expected: nv * nc,
                        actual: phi.num_vertices() * phi.num_cage_vertices(),
                    });
                }
                let residual = phi_c_residual(&phi, &cage.positions, &mesh.positions);
                if residual > PHI_C_TOLERANCE * self.size
                    && options.given_cage_coords == GivenCageCoords::RecomputeIfInexact
                {
                    let message = format!(
                        "the given cage coordinates reproduce the rest mesh only to \
                         {residual:.3e} (M ≠ ΦC, e.g. a file with 6 decimals): recomputed, so \
                         that nothing the user does not touch moves at the first cage edit"
                    );
                    // Rounded when written (the paper's Arm): a note; farther off, the file may
                    // belong to another mesh or cage: a warning.
                    warnings.push(if residual <= ROUNDED_PHI_C * self.size {
                        Warning::Info { message }
                    } else {
                        Warning::Note { message }
                    });
                    self.cage_coordinates(&mesh.positions)?
                } else {
                    phi
                }
            }
            None => self.cage_coordinates(&mesh.positions)?,
        };
        let precision = options.cage_coords_precision;
        if precision == CoordsPrecision::F32 {
            coords.round_to_f32();
        }
        let (rows, mode) = match options.fit_rows.clone() {
            FitRows::MaxVol => match maxvol_rows {
                Some(rows) if rows.len() < nc => {
                    return Err(RigError::SizeMismatch {
                        what: "given MaxVol rows (at least one per cage vertex)",
                        expected: nc,
                        actual: rows.len(),
                    });
                }
                Some(rows) if rows.len() > nc => (rows, CageFitMode::LeastSquares),
                Some(rows) => (rows, CageFitMode::Interpolate),
                None => (
                    maxvol::select_maxvol_rows(&coords)?.rows,
                    CageFitMode::Interpolate,
                ),
            },
            FitRows::AllRows => ((0..nv).collect(), CageFitMode::LeastSquares),
            FitRows::Rows(rows) => {
                let mode = if rows.len() == nc {
                    CageFitMode::Interpolate
                } else {
                    CageFitMode::LeastSquares
                };
                (rows, mode)
            }
        };
        let paper = CageUpdater::new(&coords, rows, mode)?;
        // M₀ = ΦC₀: the regularised fit's neighbourhoods and the check of M's state.
        let mut map = vec![DVec3::ZERO; nv];
        coords.apply(&cage.positions, &mut map);
        let mesh_state = self.adopt_map(mesh, &map, precision, warnings);
        let (skeleton_updater, notes) = skeleton_updater_of(mesh, &coords, None)?;
        warnings.extend(notes);
        let fit = with_cage_fit(
            paper,
            options.cage_fit,
            &coords,
            cage,
            Some(&map),
            self.skin_weights,
            &skeleton_updater,
            self.skeleton,
        )?;
        let reverser = CageReverser::new(
            &coords,
            &fit,
            self.skin_weights,
            |j| skeleton_updater.joint_row(j).to_vec(),
            self.skeleton,
        )?;
        Ok(BoundRestMap {
            rest_map: RestMap {
                coords,
                kind: CageMap::Mvc(Box::new(MvcMap { fit, reverser })),
                mesh_state,
            },
            skeleton_updater,
            cor_centre_coords,
        })
    }

    /// Green coordinates: φ and ψ (always computed, in f64), the fitting rows of [φ ψ], the
    /// Gauss–Newton CageUp, SkelUp with its face part, and the Newton CageRev.
    fn bind_green(
        &self,
        mesh: &mut TriMesh,
        given: GivenCoords,
        skeleton_updater_of: Box<SkeletonUpdaterOf<'_>>,
        warnings: &mut Vec<Warning>,
    ) -> Result<BoundRestMap, RigError> {
        let (cage, options) = (self.cage, self.options);
        let nv = mesh.num_vertices();
        if given.cage_coords.is_some()
            || given.maxvol_rows.is_some()
            || given.cor_centre_coords.is_some()
        {
            warnings.push(Warning::Info {
                message: "Green coordinates: the given mean value coordinates (Φ, their \
                          MaxVol rows, Λ) do not apply and were recomputed"
                    .into(),
            });
        }
        if options.cage_coords_precision == CoordsPrecision::F32 {
            warnings.push(Warning::Info {
                message: "Green coordinates are kept in f64 (f32 coordinates are for mean \
                          value coordinates only)"
                    .into(),
            });
        }
        let report = |done| (self.progress)(BindStage::CageCoordinates, done, nv);
        let (green_coords, outside) =
            compute_green_coords_for_mesh(cage, &mesh.positions, Some(&report))?;
        if outside > 0 {
            warnings.push(Warning::Note {
                message: format!(
                    "{outside} mesh vertices lie outside the cage, where Green coordinates \
                     do not reach: they follow the cage by mean value coordinates"
                ),
            });
        }
        let crate::coords::green::GreenCoords {
            vertex: coords,
            face: face_coords,
            triangles,
        } = green_coords;
        // The MaxVol rows of [φ ψ], or the given rows, always least squares.
        let rows = match options.fit_rows.clone() {
            FitRows::MaxVol => green_fit_rows(&coords, &face_coords, &mesh.positions, warnings)?,
            FitRows::AllRows => (0..nv).collect(),
            FitRows::Rows(rows) => rows,
        };
        let linear = CageUpdater::new(&coords, rows, CageFitMode::LeastSquares)?;
        let mut green = GreenState::new(
            &coords,
            face_coords,
            triangles,
            linear,
            self.skin_weights,
            &cage.positions,
            &BindingJoints::of_skeleton(self.skeleton),
            options.green_face_term,
            &mesh.positions,
            options.cage_fit == CageFitKind::Regularised,
        )?;
        let mut map = vec![DVec3::ZERO; nv];
        coords.apply_with_extra(
            &cage.positions,
            &green.face_coords,
            &green.rest_terms,
            &mut map,
        );
        let mesh_state = self.adopt_map(mesh, &map, CoordsPrecision::F64, warnings);
        let face_terms = JointFaceTerms {
            face_coords: &green.face_coords,
            rest_terms: &green.rest_terms,
        };
        let (skeleton_updater, notes) = skeleton_updater_of(mesh, &coords, Some(face_terms))?;
        warnings.extend(notes);
        green.reverser.set_joint_coords(|j| {
            (
                skeleton_updater.joint_row(j),
                skeleton_updater.joint_face_row(j),
            )
        });
        Ok(BoundRestMap {
            rest_map: RestMap {
                coords,
                kind: CageMap::Green(Box::new(green)),
                mesh_state,
            },
            skeleton_updater,
            cor_centre_coords: None,
        })
    }

    /// Φ of `positions` (`#V`) for the cage, reporting progress.
    fn cage_coordinates(&self, positions: &[DVec3]) -> Result<CageCoords, RigError> {
        let report = |done| (self.progress)(BindStage::CageCoordinates, done, positions.len());
        mvc::compute_cage_coords(self.cage, positions, Some(&report))
    }

    /// M's state against `map`, the map of C₀ (`#V`): the map when it reproduces M; with f32
    /// coordinates, M becomes the map when only the rounding of Φ separates them; otherwise M
    /// stays as loaded, with a note.
    fn adopt_map(
        &self,
        mesh: &mut TriMesh,
        map: &[DVec3],
        precision: CoordsPrecision,
        warnings: &mut Vec<Warning>,
    ) -> RestMeshState {
        let residual = crate::mesh::max_distance(map, &mesh.positions);
        if residual <= PHI_C_TOLERANCE * self.size {
            return RestMeshState::Map;
        }
        if precision == CoordsPrecision::F32 && residual <= PHI_C_TOLERANCE_F32 * self.size {
            // Only the rounding of Φ separates M from ΦC: adopt ΦC now.
            mesh.positions.copy_from_slice(map);
            return RestMeshState::Map;
        }
        warnings.push(Warning::Note {
            message: format!(
                "the cage coordinates reproduce the rest mesh only to {residual:.3e} (M ≠ ΦC); \
                 the rest mesh becomes ΦC at the first cage edit"
            ),
        });
        RestMeshState::AsLoaded
    }
}

/// The paper's CageUp `paper` (on Φ `cage_coords`, `#V × #C`) as the fit `kind` for the
/// binding cage `cage` (C₀) and Ω `skin_weights`: itself, or regularised with the prior of the
/// binding (neighbourhoods found on M₀ = ΦC₀ and the joints at ΨC₀, SkelUp's Ψ of
/// `skeleton_updater` over `skeleton`'s hierarchy, so a rig switched to it later gets the same
/// fit). `binding_mesh` is M₀ (`#V`) when the caller has it; it is computed here otherwise.
#[expect(
    clippy::too_many_arguments,
    reason = "the binding's coordinates, cage, skin, weights and skeleton"
)]
fn with_cage_fit(
    paper: CageUpdater,
    kind: CageFitKind,
    cage_coords: &CageCoords,
    cage: &TriMesh,
    binding_mesh: Option<&[DVec3]>,
    skin_weights: &SkinWeights,
    skeleton_updater: &SkeletonUpdater,
    skeleton: &Skeleton,
) -> Result<CageUpdater, RigError> {
    match kind {
        CageFitKind::Paper => Ok(paper),
        CageFitKind::Regularised => {
            let computed;
            let binding_mesh = match binding_mesh {
                Some(mesh) => mesh,
                None => {
                    let mut mesh = vec![DVec3::ZERO; cage_coords.num_vertices()];
                    cage_coords.apply(&cage.positions, &mut mesh);
                    computed = mesh;
                    &computed
                }
            };
            let joints = (0..skeleton.len())
                .map(|j| {
                    skeleton_updater
                        .joint_row(j)
                        .iter()
                        .zip(&cage.positions)
                        .fold(DVec3::ZERO, |acc, (&w, c)| acc + w * *c)
                })
                .collect();
            paper.regularised(
                cage_coords,
                &cage.positions,
                &cage.triangles,
                binding_mesh,
                skin_weights,
                &BindingJoints::new(skeleton, joints)?,
            )
        }
    }
}

impl MvcMap {
    /// Switches CageUp to the fit `kind` on the same Φ `coords` and rows (for the binding cage
    /// `cage`, C₀), and rebuilds Eq. 19 for it with SkelUp's Ψ, keeping the reverser's method.
    /// Nothing changes on error.
    fn set_fit(
        &mut self,
        kind: CageFitKind,
        coords: &CageCoords,
        cage: &TriMesh,
        skin_weights: &SkinWeights,
        skeleton_updater: &SkeletonUpdater,
        skeleton: &Skeleton,
    ) -> Result<(), RigError> {
        let fit = with_cage_fit(
            self.fit.paper(),
            kind,
            coords,
            cage,
            None,
            skin_weights,
            skeleton_updater,
            skeleton,
        )?;
        let mut reverser = CageReverser::new(
            coords,
            &fit,
            skin_weights,
            |j| skeleton_updater.joint_row(j).to_vec(),
            skeleton,
        )?;
        reverser.set_method(self.reverser.method());
        self.fit = fit;
        self.reverser = reverser;
        Ok(())
    }
}

impl RestMap {
    /// The coordinates kind of this map.
    pub(super) fn kind(&self) -> CoordsKind {
        match self.kind {
            CageMap::Mvc(_) => CoordsKind::Mvc,
            CageMap::Green(_) => CoordsKind::Green,
        }
    }

    /// The kind's own state (its fit and reverser included).
    pub(super) fn cage_map(&self) -> &CageMap {
        &self.kind
    }

    /// The kind's own state, to update.
    pub(super) fn cage_map_mut(&mut self) -> &mut CageMap {
        &mut self.kind
    }

    /// The vertex part: Φ or φ, `#V × #C`.
    pub(super) fn coords(&self) -> &CageCoords {
        &self.coords
    }

    /// How the session's M stands to the map of C.
    pub(super) fn mesh_state(&self) -> RestMeshState {
        self.mesh_state
    }

    /// Records how the session's M now stands to the map of C.
    pub(super) fn set_mesh_state(&mut self, state: RestMeshState) {
        self.mesh_state = state;
    }

    /// CageUp's linear map on the fitting rows: MVC's CageUp itself; for Green rigs the
    /// vertex part's fit, which gives the rows and a start for the Newton fit.
    pub(super) fn linear_fit(&self) -> &CageUpdater {
        match &self.kind {
            CageMap::Mvc(mvc) => &mvc.fit,
            CageMap::Green(green) => &green.linear,
        }
    }

    /// The linear CageUp C' = K·M'_R (+ Q·P for the regularised fit, with the skinning
    /// transforms `posed_from_rest`, `#J`, and the rest cage `rest_cage`, `#C`) of the rows
    /// `posed_rows` (`#R`) into `posed_cage` (`#C`): MVC's CageUp (Sec. 4.1, Eq. 8).
    pub(super) fn fit_linear(
        &mut self,
        posed_rows: &[DVec3],
        posed_from_rest: &[DAffine3],
        rest_cage: &[DVec3],
        posed_cage: &mut [DVec3],
    ) {
        let fit = match &mut self.kind {
            CageMap::Mvc(mvc) => &mut mvc.fit,
            CageMap::Green(green) => &mut green.linear,
        };
        fit.fit(posed_rows, posed_from_rest, rest_cage, posed_cage);
    }

    /// CageUp's fitting rows R (indices into `#V`).
    pub(super) fn rows(&self) -> &[usize] {
        self.linear_fit().rows()
    }

    /// The CageUp fit in use: the bound [`CageFitKind`] for mean value rigs; for Green rigs
    /// `Regularised` when the Gauss–Newton fit on the rows is regularised towards the carried
    /// cage, `Paper` when it fits the rows alone.
    pub(super) fn fit_kind(&self) -> CageFitKind {
        match &self.kind {
            CageMap::Mvc(mvc) => mvc.fit.fit_kind(),
            CageMap::Green(green) if green.cage_up.fit.prior().is_some() => {
                CageFitKind::Regularised
            }
            CageMap::Green(_) => CageFitKind::Paper,
        }
    }

    /// Switches a mean value rig's CageUp to the fit `kind` (Eq. 19 rebuilt for it, with
    /// SkelUp's Ψ, for the binding cage `cage`); Green rigs switch their fit's regulariser (a
    /// rig whose cage has no prior keeps the fit on the rows alone). Nothing changes on error.
    pub(super) fn set_fit_kind(
        &mut self,
        kind: CageFitKind,
        cage: &TriMesh,
        skin_weights: &SkinWeights,
        skeleton_updater: &SkeletonUpdater,
        skeleton: &Skeleton,
    ) -> Result<(), RigError> {
        match &mut self.kind {
            CageMap::Mvc(mvc) => mvc.set_fit(
                kind,
                &self.coords,
                cage,
                skin_weights,
                skeleton_updater,
                skeleton,
            ),
            CageMap::Green(green) => {
                green
                    .cage_up
                    .fit
                    .set_regularised(kind == CageFitKind::Regularised);
                green.reverser.invalidate();
                Ok(())
            }
        }
    }

    /// Drops Eq. 19's factors (the pose or SkelUp's lock changed). The Green CageRev keys its
    /// own on the pose and the lock.
    pub(super) fn invalidate_reverser(&mut self) {
        match &mut self.kind {
            CageMap::Mvc(mvc) => mvc.reverser.invalidate(),
            CageMap::Green(_) => {}
        }
    }

    /// Chooses how a mean value rig's CageRev factorises Eq. 19 (Green rigs solve by Newton).
    pub(super) fn set_reverser_method(&mut self, method: ReverserMethod) {
        match &mut self.kind {
            CageMap::Mvc(mvc) => mvc.reverser.set_method(method),
            CageMap::Green(_) => {}
        }
    }

    /// Whether a mean value rig's held factorisation of Eq. 19 is the low-rank one.
    pub(super) fn reverser_is_low_rank(&self) -> bool {
        match &self.kind {
            CageMap::Mvc(mvc) => mvc.reverser.is_low_rank(),
            CageMap::Green(_) => false,
        }
    }

    /// Whether a mean value rig's CageRev holds a factorisation of Eq. 19 (Green rigs hold
    /// none: their Newton CageRev prepares per grab).
    pub(super) fn reverser_is_factorised(&self) -> bool {
        match &self.kind {
            CageMap::Mvc(mvc) => mvc.reverser.is_factorised(),
            CageMap::Green(_) => false,
        }
    }

    /// Eq. 19 as factorised: the rest-cage change `rest_delta` (`#C`) for the current-cage
    /// change `posed_delta` (`#C`) of a mean value rig.
    pub(super) fn solve_linear_reverse(
        &mut self,
        posed_delta: &[DVec3],
        rest_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        match &mut self.kind {
            CageMap::Mvc(mvc) => mvc.reverser.solve(posed_delta, rest_delta),
            CageMap::Green(_) => Err(RigError::Invalid(
                "Eq. 19 was asked of a Green rig, whose CageRev is the Newton solve".into(),
            )),
        }
    }

    /// Whether M is linear in C (M = ΦC): then keyframes lerp, the CoR centres follow a cage
    /// edit by columns, and the f32 display path may compute M̃ = Φ̃·C; otherwise M is
    /// evaluated in full at each new cage.
    pub(super) fn is_linear(&self) -> bool {
        match self.kind {
            CageMap::Mvc(_) => true,
            CageMap::Green(_) => false,
        }
    }

    /// After C changed everywhere: M = ΦC + the kind's terms for `rest_cage` (`#C`) into
    /// `rest_mesh` (`#V`), refreshing what the kind keeps of C.
    pub(super) fn rest_mesh_in_full(&mut self, rest_cage: &[DVec3], rest_mesh: &mut [DVec3]) {
        self.update_terms(rest_cage);
        self.rest_mesh_at_terms(rest_cage, rest_mesh);
    }

    /// M = ΦC + the kind's terms as they are (current for `rest_cage`, `#C`) into `out` (`#V`).
    /// Green rigs take φC + ψ·g(C) in one pass over the rows
    /// ([`CageCoords::apply_with_extra`], the bits of φC followed by ψ·g).
    pub(super) fn rest_mesh_at_terms(&self, rest_cage: &[DVec3], out: &mut [DVec3]) {
        match &self.kind {
            CageMap::Mvc(_) => self.coords.apply(rest_cage, out),
            CageMap::Green(green) => {
                self.coords
                    .apply_with_extra(rest_cage, &green.face_coords, &green.rest_terms, out)
            }
        }
    }

    /// Brings the kind's terms of C up to date for `rest_cage` (`#C`) without touching M (the
    /// display path then evaluates M̃ and the exact rows from them).
    pub(super) fn update_terms(&mut self, rest_cage: &[DVec3]) {
        match &mut self.kind {
            CageMap::Mvc(_) => {}
            CageMap::Green(green) => green
                .cage_up
                .fit
                .normals()
                .apply(rest_cage, &mut green.rest_terms),
        }
    }

    /// The kind's terms of the current C, the inputs of its extra coordinate columns: g(C)
    /// (`#F`) for Green, none for MVC.
    pub(super) fn terms(&self) -> &[DVec3] {
        match &self.kind {
            CageMap::Mvc(_) => &[],
            CageMap::Green(green) => &green.rest_terms,
        }
    }

    /// The kind's extra coordinate columns (ψ, `#V × #F`, for Green), whose inputs are
    /// [`RestMap::terms`].
    pub(super) fn extra_coords(&self) -> Option<&CageCoords> {
        match &self.kind {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some(&green.face_coords),
        }
    }

    /// After the rest-cage vertices `vertices` moved by `deltas` (`rest_cage` already
    /// updated): `rest_mesh` += Φ[:, k]·ΔC_k, and the kind's terms of the change (Green: in
    /// the same pass over the rows). No allocation.
    pub(super) fn apply_rest_delta(
        &mut self,
        vertices: &[usize],
        deltas: &[DVec3],
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        match &mut self.kind {
            CageMap::Mvc(_) => self.coords.apply_delta(vertices, deltas, rest_mesh),
            CageMap::Green(green) => {
                green.apply_rest_delta(&self.coords, vertices, deltas, rest_cage, rest_mesh)
            }
        }
    }

    /// M(C) = ΦC + the kind's terms for the rest cage `cage` (`#C`), which need not be the
    /// session's, into `out` (`#V`): one pass, as [`RestMap::rest_mesh_at_terms`].
    pub(super) fn rest_mesh_of(&self, cage: &[DVec3], out: &mut [DVec3]) {
        match &self.kind {
            CageMap::Mvc(_) => self.coords.apply(cage, out),
            CageMap::Green(green) => {
                self.coords
                    .apply_with_extra(cage, &green.face_coords, &green.terms_of(cage), out)
            }
        }
    }

    /// The kind's terms of the rest cage `cage` (`#C`), kept with a cage keyframe: g(C) (`#F`)
    /// for Green, none for MVC.
    pub(super) fn terms_of(&self, cage: &[DVec3]) -> Vec<DVec3> {
        match &self.kind {
            CageMap::Mvc(_) => Vec::new(),
            CageMap::Green(green) => green.keyframe_terms_of(cage),
        }
    }

    /// Between two cage keyframes: `rest_cage` (`#C`) is the blend C = (1 − a)·C_lo + a·C_hi and
    /// `rest_mesh` (`#V`) the blend of the keys' meshes. Adds what the kind's terms add beyond
    /// the blend of the keys' terms `lo_terms`, `hi_terms` ([`RestMap::terms_of`]), refreshing
    /// what it keeps of C. MVC adds nothing (M is linear in C). No allocation.
    pub(super) fn add_keyframe_blend_terms(
        &mut self,
        lo_terms: &[DVec3],
        hi_terms: &[DVec3],
        a: f64,
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        match &mut self.kind {
            CageMap::Mvc(_) => {}
            CageMap::Green(green) => {
                green.add_keyframe_blend_terms(lo_terms, hi_terms, a, rest_cage, rest_mesh)
            }
        }
    }

    /// out (`#V`) += the kind's terms of the CoR centres at the current rest cage.
    pub(super) fn add_centre_terms(&self, out: &mut [DVec3]) {
        match &self.kind {
            CageMap::Mvc(_) => {}
            CageMap::Green(green) => green.add_centre_face_terms(&green.rest_terms, out),
        }
    }

    /// out (`#V`) += the kind's terms of the CoR centres for the rest cage `cage` (`#C`).
    pub(super) fn add_centre_terms_of(&self, cage: &[DVec3], out: &mut [DVec3]) {
        match &self.kind {
            CageMap::Mvc(_) => {}
            CageMap::Green(green) => green.add_centre_face_terms(&green.terms_of(cage), out),
        }
    }

    /// Builds the kind's part of the CoR centre coordinates with `centre_coords_of`, which
    /// turns per-vertex coordinates into the centres' (Λ = S·X for a coordinate matrix X).
    pub(super) fn build_centre_terms(
        &mut self,
        centre_coords_of: impl FnOnce(&CageCoords) -> Result<CageCoords, RigError>,
    ) -> Result<(), RigError> {
        match &mut self.kind {
            CageMap::Mvc(_) => Ok(()),
            CageMap::Green(green) => {
                // Green rigs: the centres' face part Λ_ψ = S·ψ, from the same centre rows.
                green.face_centre_coords = Some(centre_coords_of(&green.face_coords)?);
                Ok(())
            }
        }
    }

    /// The next CageUp starts from the current C' (a grab made it the answer, or a restored
    /// checkpoint holds it).
    pub(super) fn start_next_fit_from_posed_cage(&mut self) {
        match &mut self.kind {
            CageMap::Mvc(_) => {}
            CageMap::Green(green) => green.cage_up.start_from_posed_cage = true,
        }
    }

    /// Where the last CageUp stopped when it found no current cage (none for linear maps).
    pub(super) fn unfitted(&self) -> Option<crate::error::UnfittedCage> {
        match &self.kind {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => green.cage_up.unfitted,
        }
    }

    /// The failure of the last CageUp that refuses the event, taken (none for linear maps).
    pub(super) fn take_fit_failure(&mut self) -> Option<RigError> {
        match &mut self.kind {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => {
                let unreported = std::mem::take(&mut green.cage_up.failure_unreported);
                green
                    .cage_up
                    .unfitted
                    .filter(|_| unreported)
                    .map(RigError::GreenFitFailed)
            }
        }
    }
}
