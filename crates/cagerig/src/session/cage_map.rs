//! The cage map: how the rest skin follows the rest cage, M = f(C), and the extension point of
//! the coordinates kinds ([`CoordsKind`]).
//!
//! Every kind keeps its *vertex part* in the session's `cage_coords` (`#V × #C`: Φ for mean
//! value coordinates, φ for Green coordinates), so everything linear in C — the MaxVol rows,
//! CageUp's linear map P, SkelUp's Ψ, the linear CageRev of Eq. 19 — is built on it for every
//! kind. [`CageMap`] holds what a kind adds beyond that, and every place the session's
//! behaviour depends on the kind matches on it exhaustively:
//!
//! | hook | [`CageMap::Mvc`] (M = ΦC) | [`CageMap::Green`] (M = φC + ψ·g(C)) |
//! |---|---|---|
//! | [`bind_cage_map`] | Φ (given or computed), MaxVol rows of Φ | φ, ψ, MaxVol rows of [φ ψ] |
//! | [`CageMap::rest_mesh_in_full`], [`CageMap::rest_mesh_of`], [`CageMap::apply_rest_delta`] | M = ΦC | M = φC + ψ·g(C) in one pass; M += ψ·g(C) by face |
//! | [`CageMap::is_linear`] (keyframe lerp, centre deltas) | yes | no |
//! | the f32 display path's M̃ ([`CageMap::extra_coords`], [`CageMap::terms`]) | Φ̃·C | [φ̃ ψ̃]·[C; g(C)] |
//! | CageUp ([`RigSession::fit_cage`]) | C' = P·M'_R | Gauss–Newton on the rows |
//! | CageRev ([`RigSession::reverse_cage`]) | Eq. 19, factorised per pose | Newton on the fit's stationarity |
//! | CoR centres | Λ·C | Λ·C + Λ_ψ·g(C) |
//!
//! A new kind is a variant here, its state in its own file (as [`GreenState`] in
//! `session/green.rs`), and the arms the compiler asks for. See `docs/architecture.md`.

use super::green_binding::{compute_green_coords_for_mesh, green_fit_rows};
use super::*;

/// The non-linear part of the map from the rest cage C to the rest skin M, by kind.
#[derive(Debug, Clone)]
pub(super) enum CageMap {
    /// Mean value coordinates: M = ΦC, linear; nothing beyond Φ.
    Mvc,
    /// Green coordinates: M = φC + ψ·g(C), with the face coordinates ψ, the stretched normals
    /// g and the Newton CageUp and CageRev (see `session/green.rs`).
    Green(Box<GreenState>),
}

/// What binding a mesh to its cage produces for a session.
pub(super) struct BoundCageMap {
    /// Φ or φ, `#V × #C`.
    pub(super) cage_coords: CageCoords,
    /// CageUp on its fitting rows.
    pub(super) cage_updater: CageUpdater,
    pub(super) cage_map: CageMap,
    /// The precision the coordinates are kept in (Green coordinates stay f64).
    pub(super) precision: CoordsPrecision,
    /// The given Λ, when it applies to the kind.
    pub(super) cor_centre_coords: Option<CageCoords>,
}

/// The coordinates given with a rig's parts (each optional).
pub(super) struct GivenCoords {
    /// Φ, `#V × #C`.
    pub(super) cage_coords: Option<CageCoords>,
    /// CageUp's MaxVol rows of Φ.
    pub(super) maxvol_rows: Option<Vec<usize>>,
    /// Λ = S·Φ, `#V × #C`.
    pub(super) cor_centre_coords: Option<CageCoords>,
}

/// Binds `mesh_positions` (`#V`) to `cage` with the kind `options.coords`: the vertex part, the
/// fitting rows and CageUp, and the kind's own terms. Given coordinates are checked (and
/// recomputed when they do not reproduce M and the options say so); notes go to `warnings`.
#[allow(clippy::too_many_arguments)]
pub(super) fn bind_cage_map(
    cage: &TriMesh,
    mesh_positions: &[DVec3],
    given: GivenCoords,
    options: &SessionOptions,
    phi_c_tolerance: f64,
    skin_weights: &SkinWeights,
    num_joints: usize,
    warnings: &mut Vec<Warning>,
) -> Result<BoundCageMap, RigError> {
    let nv = mesh_positions.len();
    let nc = cage.num_vertices();
    let GivenCoords {
        cage_coords,
        mut maxvol_rows,
        mut cor_centre_coords,
    } = given;
    let mut green_parts = None;
    let mut precision = options.cage_coords_precision;
    let given_cage_coords = match options.coords {
        CoordsKind::Mvc => cage_coords,
        CoordsKind::Green => {
            if cage_coords.is_some() || maxvol_rows.is_some() || cor_centre_coords.is_some() {
                warnings.push(Warning::Note {
                    message: "Green coordinates: the given mean value coordinates (Φ, their \
                              MaxVol rows, Λ) do not apply and were recomputed"
                        .into(),
                });
            }
            if precision == CoordsPrecision::F32 {
                warnings.push(Warning::Note {
                    message: "Green coordinates are kept in f64 (f32 coordinates are for mean \
                              value coordinates only)"
                        .into(),
                });
                precision = CoordsPrecision::F64;
            }
            maxvol_rows = None;
            cor_centre_coords = None;
            let (coords, outside) = compute_green_coords_for_mesh(cage, mesh_positions)?;
            if outside > 0 {
                warnings.push(Warning::Note {
                    message: format!(
                        "{outside} mesh vertices lie outside the cage, where Green coordinates \
                         do not reach: they follow the cage by mean value coordinates"
                    ),
                });
            }
            green_parts = Some((coords.face, coords.triangles));
            Some(coords.vertex)
        }
    };
    let mut cage_coords = match given_cage_coords {
        Some(phi) if green_parts.is_some() => phi,
        Some(phi) => {
            if phi.num_vertices() != nv || phi.num_cage_vertices() != nc {
                return Err(RigError::SizeMismatch {
                    what: "cage coordinates shape (#V × #C)",
                    expected: nv * nc,
                    actual: phi.num_vertices() * phi.num_cage_vertices(),
                });
            }
            let residual = phi_c_residual(&phi, &cage.positions, mesh_positions);
            if residual > phi_c_tolerance
                && options.given_cage_coords == GivenCageCoords::RecomputeIfInexact
            {
                warnings.push(Warning::Note {
                    message: format!(
                        "the given cage coordinates reproduce the rest mesh only to \
                         {residual:.3e} (M ≠ ΦC, e.g. a file with 6 decimals): recomputed, so \
                         that nothing the user does not touch moves at the first cage edit"
                    ),
                });
                mvc::compute_cage_coords(cage, mesh_positions, None)?
            } else {
                phi
            }
        }
        None => mvc::compute_cage_coords(cage, mesh_positions, None)?,
    };
    if precision == CoordsPrecision::F32 {
        cage_coords.round_to_f32();
    }
    let green_rows = match (&green_parts, &options.fit_rows) {
        (Some((face_coords, _)), FitRows::MaxVol) => Some(green_fit_rows(
            &cage_coords,
            face_coords,
            mesh_positions,
            warnings,
        )?),
        (Some(_), FitRows::AllRows | FitRows::Rows(_))
        | (None, FitRows::MaxVol | FitRows::AllRows | FitRows::Rows(_)) => None,
    };
    let (rows, mode) = match (green_rows, options.fit_rows.clone()) {
        // Green: the MaxVol rows of [φ ψ], or the given rows, always least squares.
        (Some(rows), _) => (rows, CageFitMode::LeastSquares),
        (None, FitRows::Rows(rows)) if green_parts.is_some() => (rows, CageFitMode::LeastSquares),
        (None, FitRows::MaxVol) => match maxvol_rows {
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
                maxvol::select_maxvol_rows(&cage_coords)?.rows,
                CageFitMode::Interpolate,
            ),
        },
        (None, FitRows::AllRows) => ((0..nv).collect(), CageFitMode::LeastSquares),
        (None, FitRows::Rows(rows)) => {
            let mode = if rows.len() == nc {
                CageFitMode::Interpolate
            } else {
                CageFitMode::LeastSquares
            };
            (rows, mode)
        }
    };
    let mut cage_updater = CageUpdater::new(&cage_coords, rows, mode)?;
    let cage_map = match green_parts {
        Some((face_coords, triangles)) => CageMap::Green(Box::new(GreenState::new(
            &cage_coords,
            face_coords,
            triangles,
            cage_updater.rows(),
            cage_updater.cage_from_rows(),
            skin_weights,
            &cage.positions,
            num_joints,
        )?)),
        None => {
            cage_updater = with_cage_fit(
                cage_updater,
                options.cage_fit,
                &cage_coords,
                cage,
                skin_weights,
            )?;
            CageMap::Mvc
        }
    };
    Ok(BoundCageMap {
        cage_coords,
        cage_updater,
        cage_map,
        precision,
        cor_centre_coords,
    })
}

/// The paper's CageUp `paper` (on Φ `cage_coords`, `#V × #C`) as the fit `kind` for the
/// binding cage `cage` (C₀) and Ω `skin_weights`: itself, or regularised with the prior of the
/// binding (neighbourhoods found on M₀ = ΦC₀, so a rig switched to it later gets the same fit).
pub(super) fn with_cage_fit(
    paper: CageUpdater,
    kind: CageFitKind,
    cage_coords: &CageCoords,
    cage: &TriMesh,
    skin_weights: &SkinWeights,
) -> Result<CageUpdater, RigError> {
    match kind {
        CageFitKind::Paper => Ok(paper),
        CageFitKind::Regularised => {
            let mut binding_mesh = vec![DVec3::ZERO; cage_coords.num_vertices()];
            cage_coords.apply(&cage.positions, &mut binding_mesh);
            paper.regularised(
                cage_coords,
                &cage.positions,
                &cage.triangles,
                &binding_mesh,
                skin_weights,
            )
        }
    }
}

impl CageMap {
    /// The coordinates kind of this map.
    pub(super) fn kind(&self) -> CoordsKind {
        match self {
            CageMap::Mvc => CoordsKind::Mvc,
            CageMap::Green(_) => CoordsKind::Green,
        }
    }

    /// Whether M is linear in C (M = ΦC): then keyframes lerp, the CoR centres follow a cage
    /// edit by columns, and the f32 display path may compute M̃ = Φ̃·C; otherwise M is
    /// evaluated in full at each new cage.
    pub(super) fn is_linear(&self) -> bool {
        match self {
            CageMap::Mvc => true,
            CageMap::Green(_) => false,
        }
    }

    /// Hands SkelUp's coordinates to the kind's CageRev (Green: A(C) = Ψ_φ C + Ψ_ψ g(C) enters
    /// its Newton system). MVC's Eq. 19 takes Ψ at its own construction.
    pub(super) fn set_joint_coords(&mut self, skeleton_updater: &SkeletonUpdater) {
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => green.reverser.set_joint_coords(|j| {
                (
                    skeleton_updater.joint_row(j),
                    skeleton_updater.joint_face_row(j),
                )
            }),
        }
    }

    /// After C changed everywhere: M = ΦC + the kind's terms for `rest_cage` (`#C`) into
    /// `rest_mesh` (`#V`), refreshing what the kind keeps of C.
    pub(super) fn rest_mesh_in_full(
        &mut self,
        cage_coords: &CageCoords,
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        self.update_terms(rest_cage);
        self.rest_mesh_at_terms(cage_coords, rest_cage, rest_mesh);
    }

    /// M = ΦC + the kind's terms as they are (current for `rest_cage`, `#C`) into `out` (`#V`).
    /// Green rigs take φC + ψ·g(C) in one pass over the rows
    /// ([`CageCoords::apply_with_extra`], the bits of φC followed by ψ·g).
    pub(super) fn rest_mesh_at_terms(
        &self,
        cage_coords: &CageCoords,
        rest_cage: &[DVec3],
        out: &mut [DVec3],
    ) {
        match self {
            CageMap::Mvc => cage_coords.apply(rest_cage, out),
            CageMap::Green(green) => {
                cage_coords.apply_with_extra(rest_cage, &green.face_coords, &green.rest_terms, out)
            }
        }
    }

    /// Brings the kind's terms of C up to date for `rest_cage` (`#C`) without touching M (the
    /// display path then evaluates M̃ and the exact rows from them).
    pub(super) fn update_terms(&mut self, rest_cage: &[DVec3]) {
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => green.fit.normals().apply(rest_cage, &mut green.rest_terms),
        }
    }

    /// The kind's terms of the current C, the inputs of its extra coordinate columns: g(C)
    /// (`#F`) for Green, none for MVC.
    pub(super) fn terms(&self) -> &[DVec3] {
        match self {
            CageMap::Mvc => &[],
            CageMap::Green(green) => &green.rest_terms,
        }
    }

    /// The kind's extra coordinate columns (ψ, `#V × #F`, for Green), whose inputs are
    /// [`CageMap::terms`].
    pub(super) fn extra_coords(&self) -> Option<&CageCoords> {
        match self {
            CageMap::Mvc => None,
            CageMap::Green(green) => Some(&green.face_coords),
        }
    }

    /// After the rest-cage vertices `vertices` moved (`rest_cage` already updated and the
    /// vertex part's delta applied to `rest_mesh`): the kind's terms of the change. No
    /// allocation.
    pub(super) fn apply_rest_delta(
        &mut self,
        vertices: &[usize],
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => green.apply_rest_delta(vertices, rest_cage, rest_mesh),
        }
    }

    /// M(C) = ΦC + the kind's terms for the rest cage `cage` (`#C`), which need not be the
    /// session's, into `out` (`#V`): one pass, as [`CageMap::rest_mesh_at_terms`].
    pub(super) fn rest_mesh_of(&self, cage_coords: &CageCoords, cage: &[DVec3], out: &mut [DVec3]) {
        match self {
            CageMap::Mvc => cage_coords.apply(cage, out),
            CageMap::Green(green) => {
                cage_coords.apply_with_extra(cage, &green.face_coords, &green.terms_of(cage), out)
            }
        }
    }

    /// The kind's terms of the rest cage `cage` (`#C`), kept with a cage keyframe: g(C) (`#F`)
    /// for Green, none for MVC.
    pub(super) fn terms_of(&self, cage: &[DVec3]) -> Vec<DVec3> {
        match self {
            CageMap::Mvc => Vec::new(),
            CageMap::Green(green) => green.keyframe_terms_of(cage),
        }
    }

    /// Between two cage keyframes: `rest_cage` (`#C`) is the blend C = (1 − a)·C_lo + a·C_hi and
    /// `rest_mesh` (`#V`) the blend of the keys' meshes. Adds what the kind's terms add beyond
    /// the blend of the keys' terms `lo_terms`, `hi_terms` ([`CageMap::terms_of`]), refreshing
    /// what it keeps of C. MVC adds nothing (M is linear in C). No allocation.
    pub(super) fn add_keyframe_blend_terms(
        &mut self,
        lo_terms: &[DVec3],
        hi_terms: &[DVec3],
        a: f64,
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => {
                green.add_keyframe_blend_terms(lo_terms, hi_terms, a, rest_cage, rest_mesh)
            }
        }
    }

    /// out (`#V`) += the kind's terms of the CoR centres at the current rest cage.
    pub(super) fn add_centre_terms(&self, out: &mut [DVec3]) {
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => green.add_centre_face_terms(&green.rest_terms, out),
        }
    }

    /// out (`#V`) += the kind's terms of the CoR centres for the rest cage `cage` (`#C`).
    pub(super) fn add_centre_terms_of(&self, cage: &[DVec3], out: &mut [DVec3]) {
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => green.add_centre_face_terms(&green.terms_of(cage), out),
        }
    }

    /// Builds the kind's part of the CoR centre coordinates with `centre_coords_of`, which
    /// turns per-vertex coordinates into the centres' (Λ = S·X for a coordinate matrix X).
    pub(super) fn build_centre_terms(
        &mut self,
        centre_coords_of: impl FnOnce(&CageCoords) -> Result<CageCoords, RigError>,
    ) -> Result<(), RigError> {
        match self {
            CageMap::Mvc => Ok(()),
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
        match self {
            CageMap::Mvc => {}
            CageMap::Green(green) => green.start_from_posed_cage = true,
        }
    }

    /// Where the last CageUp stopped when it found no current cage (none for linear maps).
    pub(super) fn unfitted(&self) -> Option<crate::error::UnfittedCage> {
        match self {
            CageMap::Mvc => None,
            CageMap::Green(green) => green.unfitted,
        }
    }

    /// The failure of the last CageUp that refuses the event, taken (none for linear maps).
    pub(super) fn take_fit_failure(&mut self) -> Option<RigError> {
        match self {
            CageMap::Mvc => None,
            CageMap::Green(green) => {
                let unreported = std::mem::take(&mut green.failure_unreported);
                green
                    .unfitted
                    .filter(|_| unreported)
                    .map(RigError::GreenFitFailed)
            }
        }
    }
}

impl RigSession {
    /// The coordinates kind the rig is bound with.
    pub fn coords_kind(&self) -> CoordsKind {
        self.cage_map.kind()
    }

    /// CageUp: C' from the fitting rows of M' (or their ghost LBS, Sec. 4.3 for DQS/CoR): the
    /// linear map P for MVC rigs, the Gauss–Newton fit for Green rigs.
    pub(super) fn fit_cage(&mut self) {
        let ghost = !self.skinning.method().is_linear()
            && self.options_fit_source == CageFitSource::GhostLbs;
        match self.cage_map {
            CageMap::Mvc => self.fit_linear_cage(ghost),
            CageMap::Green(_) => self.fit_green_cage_rows(ghost),
        }
    }

    /// CageRev: the rest-cage change `rest_delta` (`#C`) for the current-cage change
    /// `posed_delta` (`#C`): Eq. 19 (factorised for the pose first if needed) for MVC rigs, the
    /// Newton solve for Green rigs.
    pub(super) fn reverse_cage(
        &mut self,
        posed_delta: &[DVec3],
        rest_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        match self.cage_map {
            CageMap::Mvc => {
                if !self.reverser.is_factorised() {
                    self.refactor_reverser()?;
                }
                self.reverser.solve(posed_delta, rest_delta)
            }
            CageMap::Green(_) => self.reverse_green(posed_delta, rest_delta),
        }
    }

    /// After a grab's CageRev moved C: a non-linear map's CageUp starts from the grabbed C'
    /// (C' + `posed_delta`, `#C`), which CageRev made the answer. A linear map re-fits C' in
    /// one product and needs nothing.
    pub(super) fn start_fit_from_grab(&mut self, posed_delta: &[DVec3]) {
        match self.cage_map {
            CageMap::Mvc => {}
            CageMap::Green(_) => {
                for (p, d) in self.posed_cage.iter_mut().zip(posed_delta) {
                    *p += *d;
                }
                self.cage_map.start_next_fit_from_posed_cage();
            }
        }
    }

    /// Factorises the reverse cage deformer (Eq. 19) for the current pose now. An editor calls
    /// this when a cage grab starts; [`RigSession::move_posed_cage`] does it lazily otherwise.
    pub fn refactor_reverser(&mut self) -> Result<(), RigError> {
        for (r, t) in self.scratch_rotations.iter_mut().zip(&self.posed_from_rest) {
            *r = t.matrix3;
        }
        match self.cage_map {
            CageMap::Mvc => self
                .reverser
                .refactor(&self.scratch_rotations, !self.locks.skel_up),
            CageMap::Green(_) => self.prepare_green_reverser(),
        }
    }

    /// M = ΦC (+ the kind's terms) for the rest cage `cage` (`#C`) into `out` (`#V`).
    pub(super) fn rest_mesh_of_cage(&self, cage: &[DVec3], out: &mut [DVec3]) {
        self.cage_map.rest_mesh_of(&self.cage_coords, cage, out);
    }

    /// The rest skin M(C) of the rest cage `cage` (`#C`) into `out` (`#V`): ΦC, plus ψ·g(C) for
    /// Green coordinates. The session is not changed.
    pub fn rest_mesh_for_cage(&self, cage: &[DVec3], out: &mut [DVec3]) -> Result<(), RigError> {
        if cage.len() != self.rest_cage.len() || out.len() != self.rest_mesh.len() {
            return Err(RigError::SizeMismatch {
                what: "rest cage (#C) and rest skin (#V) for M(C)",
                expected: self.rest_cage.len(),
                actual: cage.len(),
            });
        }
        self.rest_mesh_of_cage(cage, out);
        Ok(())
    }

    /// The rest cage C (`out`, `#C`; on entry the start of a non-linear fit) whose rest skin
    /// fits `rows`, the skin at CageUp's fitting rows ([`CageUpdater::rows`], `#R`): for mean
    /// value coordinates C = P·rows (exact on MaxVol rows); for Green coordinates the
    /// Gauss–Newton fit of φ_R C + ψ_R g(C) to `rows` (CageUp's solver, to a stationary point
    /// to round-off), which recovers C exactly when the rows are a Green deformation of the
    /// binding. Errors when the Green fit does not converge. The session is not changed.
    pub fn rest_cage_from_rows(&self, rows: &[DVec3], out: &mut [DVec3]) -> Result<(), RigError> {
        if rows.len() != self.cage_updater.rows().len() || out.len() != self.rest_cage.len() {
            return Err(RigError::SizeMismatch {
                what: "fitting rows (#R) for a rest cage",
                expected: self.cage_updater.rows().len(),
                actual: rows.len(),
            });
        }
        match &self.cage_map {
            CageMap::Mvc => {
                self.cage_updater.apply_rows(rows, out);
                Ok(())
            }
            CageMap::Green(green) => {
                let mut fit = green.fit.clone();
                // Start from the better of the given cage and the linear map's cage P·rows (the
                // vertex part's fit, which ignores ψ·g but follows large deformations).
                let mut linear = vec![DVec3::ZERO; out.len()];
                self.cage_updater.apply_rows(rows, &mut linear);
                if fit.energy(rows, &linear) < fit.energy(rows, out) {
                    out.copy_from_slice(&linear);
                }
                // A stalled solve continues from the start to `rows` in pieces.
                fit.restart_from(out);
                let report = fit.apply(rows, out)?;
                if report.residual <= GREEN_FIT_LIMIT * green.size() {
                    Ok(())
                } else {
                    Err(RigError::Invalid(format!(
                        "no rest cage reproduces the given skin rows through Green coordinates: \
                         the fit stopped with a gradient of {:.3e}, expected at most {:.3e}",
                        report.residual,
                        GREEN_FIT_LIMIT * green.size()
                    )))
                }
            }
        }
    }

    /// The CoR centres Λ·C (+ the kind's terms) into `out` (`#V`) for the rest cage `cage`.
    pub(super) fn centres_of_cage(&self, cor: &CorState, cage: &[DVec3], out: &mut [DVec3]) {
        cor.centre_coords.apply(cage, out);
        self.cage_map.add_centre_terms_of(cage, out);
    }
}
