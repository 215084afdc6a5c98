//! The session's Green-coordinates terms ([`crate::CoordsKind::Green`]): M = φC + ψ·g(C), the
//! Newton CageUp and CageRev, and the face part of the CoR centres.
//!
//! The session keeps the vertex part φ where MVC rigs keep Φ (`cage_coords`), so everything that
//! is linear in C — the MaxVol rows, the linear CageUp map P, SkelUp's Ψ and the linear CageRev
//! L — is built on φ unchanged; this module adds the face terms ψ·g(C) and turns CageUp and
//! CageRev into the Newton solves of [`crate::sync::green_cage_fit`] and
//! [`crate::sync::green_cage_fit::reverser`]. The derivation is in `docs/green-coordinates.md`.

use std::sync::OnceLock;

use faer::Mat;

use super::*;
use crate::coords::stretched_normals::StretchedNormals;
use crate::error::UnfittedCage;
use crate::sync::green_cage_fit::reverser::{GrabState, GreenCageReverser};
use crate::sync::green_cage_fit::{FitBudget, GreenCageFit};
use crate::sync::newton::NewtonReport;

/// The Green terms of a session.
#[derive(Debug, Clone)]
pub(super) struct GreenState {
    /// ψ, `#V × #F`.
    pub(super) face_coords: CageCoords,
    /// The vertex part's linear fit on the rows of [φ ψ]: the fitting rows R, and P·M'_R as a
    /// start for the Newton fit.
    pub(super) linear: CageUpdater,
    pub(super) fit: GreenCageFit,
    pub(super) reverser: GreenCageReverser,
    /// g(C) for the current rest cage C, `#F`.
    pub(super) rest_terms: Vec<DVec3>,
    /// 0..#F, to add ψ·g with `CageCoords::apply_delta`.
    all_faces: Vec<usize>,
    /// Faces around each cage vertex (CSR: `vertex_face_start[k]..vertex_face_start[k+1]`).
    vertex_face_start: Vec<usize>,
    vertex_faces: Vec<usize>,
    /// Scratch: faces touched by an edit, their g changes, a per-face mark.
    touched_faces: Vec<usize>,
    face_changes: Vec<DVec3>,
    face_marked: Vec<bool>,
    /// The skinned fitting rows M'_R CageUp fitted last, `#R`.
    pub(super) target_rows: Vec<DVec3>,
    /// Skinning weights of the cage vertices, P·Ω̃ (`#C × #J`, row-major): the predictor of
    /// CageUp's warm start.
    cage_weights: Vec<f64>,
    /// The skinning transforms (`#J`) and the rest cage (`#C`) of the last CageUp, for the
    /// predictor.
    last_transforms: Vec<DAffine3>,
    last_rest_cage: Vec<DVec3>,
    has_last_transforms: bool,
    /// Scratch: the rest cage skinned with the cage weights, `#C`.
    skinned_cage: Vec<DVec3>,
    /// Set by a grab: the next CageUp starts from the grabbed C' (CageRev made it the answer).
    pub(super) start_from_posed_cage: bool,
    /// Λ_ψ = S·ψ (`#V × #F`) for the CoR centres, built with them.
    pub(super) face_centre_coords: Option<CageCoords>,
    /// max_v Σ_f |ψ_vf|: bounds what a face term below a threshold can add to any vertex.
    /// Computed when the first cage keyframe is made ([`GreenState::keyframe_terms_of`]), not at
    /// binding.
    face_coords_norm: OnceLock<f64>,
    /// Whether the failure in `unfitted` is yet to be reported to `finish_event` (a fit
    /// outside an event, e.g. a rollback's, is not that event's).
    pub(super) failure_unreported: bool,
    /// Where the last CageUp stopped when it found no current cage (`None`: C' is its fit).
    pub(super) unfitted: Option<UnfittedCage>,
    /// The cage's bounding-box diagonal.
    size: f64,
    /// Newton reports of the last CageUp and CageRev.
    pub(super) last_reverse: NewtonReport,
}

/// A Green CageUp that stops above this fraction of the cage size refuses the event (the fit's
/// own acceptance, [`crate::sync::green_cage_fit::ACCEPTED_GRADIENT`]).
pub const GREEN_FIT_LIMIT: f64 = crate::sync::green_cage_fit::ACCEPTED_GRADIENT;

/// Between two cage keyframes, the faces whose g departs from the blend of the keys' g by more
/// than this fraction of the cage size over max_v Σ_f |ψ_vf| get their term ψ_f·e_f; the others
/// together move no vertex by more than this fraction of the cage size (round-off).
pub const KEYFRAME_TERM_TOLERANCE: f64 = 1e-14;

impl GreenState {
    /// From the Green coordinates of the rest mesh (φ is the session's `cage_coords`, ψ is
    /// `face_coords`), the CageUp rows, the rest cage and the number of joints.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        vertex_coords: &CageCoords,
        face_coords: CageCoords,
        triangles: Vec<[u32; 3]>,
        linear: CageUpdater,
        skin_weights: &SkinWeights,
        rest_cage: &[DVec3],
        num_joints: usize,
    ) -> Result<Self, RigError> {
        let (rows, cage_from_rows) = (linear.rows(), linear.cage_from_rows());
        let mut cage_weights = vec![0.0; rest_cage.len() * num_joints];
        for (r, &row) in rows.iter().enumerate() {
            let (joints, weights) = skin_weights.row(row);
            for k in 0..rest_cage.len() {
                let p = cage_from_rows[(k, r)];
                for (&j, &w) in joints.iter().zip(weights) {
                    cage_weights[k * num_joints + j as usize] += p * w;
                }
            }
        }
        let (lo, hi) = rest_cage.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let size = (hi - lo).length();
        let normals = StretchedNormals::new(rest_cage, triangles);
        let num_faces = normals.len();
        let num_cage = rest_cage.len();
        let mut vertex_face_start = vec![0usize; num_cage + 1];
        for t in normals.triangles() {
            for &v in t {
                vertex_face_start[v as usize + 1] += 1;
            }
        }
        for k in 0..num_cage {
            vertex_face_start[k + 1] += vertex_face_start[k];
        }
        let mut fill = vertex_face_start.clone();
        let mut vertex_faces = vec![0usize; vertex_face_start[num_cage]];
        for (f, t) in normals.triangles().iter().enumerate() {
            for &v in t {
                vertex_faces[fill[v as usize]] = f;
                fill[v as usize] += 1;
            }
        }
        let mut rest_terms = vec![DVec3::ZERO; num_faces];
        normals.apply(rest_cage, &mut rest_terms);
        let fit = GreenCageFit::new(
            vertex_coords.select_rows(rows),
            face_coords.select_rows(rows),
            rest_cage,
            normals,
        )?;
        Ok(Self {
            face_coords,
            reverser: GreenCageReverser::new(num_cage, num_faces, rows.len(), num_joints, size),
            fit,
            rest_terms,
            all_faces: (0..num_faces).collect(),
            vertex_face_start,
            vertex_faces,
            touched_faces: Vec::with_capacity(num_faces),
            face_changes: Vec::with_capacity(num_faces),
            face_marked: vec![false; num_faces],
            target_rows: vec![DVec3::ZERO; rows.len()],
            linear,
            cage_weights,
            last_transforms: vec![DAffine3::IDENTITY; num_joints],
            last_rest_cage: rest_cage.to_vec(),
            has_last_transforms: false,
            start_from_posed_cage: false,
            skinned_cage: rest_cage.to_vec(),
            face_centre_coords: None,
            face_coords_norm: OnceLock::new(),
            failure_unreported: false,
            unfitted: None,
            size,
            last_reverse: NewtonReport::default(),
        })
    }

    /// The cage's bounding-box diagonal.
    pub(super) fn size(&self) -> f64 {
        self.size
    }

    /// out += Λ_ψ·g (the CoR centres' face part), when built.
    pub(super) fn add_centre_face_terms(&self, g: &[DVec3], out: &mut [DVec3]) {
        if let Some(lambda) = &self.face_centre_coords {
            lambda.apply_delta(&self.all_faces, g, out);
        }
    }

    /// max_v Σ_f |ψ_vf| (one pass over ψ the first time).
    fn face_coords_norm(&self) -> f64 {
        *self.face_coords_norm.get_or_init(|| {
            let mut row_sums = vec![0.0f64; self.face_coords.num_vertices()];
            for f in 0..self.all_faces.len() {
                for (sum, w) in row_sums.iter_mut().zip(self.face_coords.column(f)) {
                    *sum += w.abs();
                }
            }
            row_sums.iter().fold(0.0f64, |m, s| m.max(*s))
        })
    }

    /// [`GreenState::terms_of`] for a cage keyframe, which also makes the bound
    /// [`KEYFRAME_TERM_TOLERANCE`] uses, so that playing the keys allocates nothing.
    pub(super) fn keyframe_terms_of(&self, cage: &[DVec3]) -> Vec<DVec3> {
        self.face_coords_norm();
        self.terms_of(cage)
    }

    /// g of `cage` into a new vector (`#F`).
    pub(super) fn terms_of(&self, cage: &[DVec3]) -> Vec<DVec3> {
        let mut g = vec![DVec3::ZERO; self.all_faces.len()];
        self.fit.normals().apply(cage, &mut g);
        g
    }
}

impl GreenState {
    /// Between two cage keyframes whose g are `lo_terms` and `hi_terms` (`#F`): `rest_cage` is
    /// their blend with weight `a` on `hi` and `rest_mesh` the blend of their meshes. Sets g(C)
    /// and adds ψ_f·e_f with e_f = g_f(C) − lerp(g_lo,f, g_hi,f, a) for the faces where e_f is
    /// above round-off ([`KEYFRAME_TERM_TOLERANCE`]): none when the blend moves every face by a
    /// similarity growing linearly along it (a translation, a uniform scaling), few when the
    /// keys differ in one part of the cage. No allocation.
    pub(super) fn add_keyframe_blend_terms(
        &mut self,
        lo_terms: &[DVec3],
        hi_terms: &[DVec3],
        a: f64,
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        let normals = self.fit.normals();
        normals.apply(rest_cage, &mut self.rest_terms);
        let tolerance =
            KEYFRAME_TERM_TOLERANCE * self.size / self.face_coords_norm().max(f64::MIN_POSITIVE);
        self.touched_faces.clear();
        self.face_changes.clear();
        for (f, ((g, lo), hi)) in self
            .rest_terms
            .iter()
            .zip(lo_terms)
            .zip(hi_terms)
            .enumerate()
        {
            let excess = *g - lo.lerp(*hi, a);
            if excess.abs().max_element() > tolerance || !excess.is_finite() {
                self.touched_faces.push(f);
                self.face_changes.push(excess);
            }
        }
        self.face_coords
            .apply_delta(&self.touched_faces, &self.face_changes, rest_mesh);
    }

    /// After the rest-cage vertices `vertices` moved (`rest_cage` already updated, `rest_mesh`
    /// += φ ΔC applied): the faces around them get their new g, and `rest_mesh` += ψ_f·Δg_f for
    /// those faces only. No allocation.
    pub(super) fn apply_rest_delta(
        &mut self,
        vertices: &[usize],
        rest_cage: &[DVec3],
        rest_mesh: &mut [DVec3],
    ) {
        self.touched_faces.clear();
        self.face_changes.clear();
        for &k in vertices {
            for &f in &self.vertex_faces[self.vertex_face_start[k]..self.vertex_face_start[k + 1]] {
                if !self.face_marked[f] {
                    self.face_marked[f] = true;
                    self.touched_faces.push(f);
                }
            }
        }
        let normals = self.fit.normals();
        for &f in &self.touched_faces {
            let new = normals.face(rest_cage, f);
            self.face_changes.push(new - self.rest_terms[f]);
            self.rest_terms[f] = new;
            self.face_marked[f] = false;
        }
        self.face_coords
            .apply_delta(&self.touched_faces, &self.face_changes, rest_mesh);
    }
}

impl RigSession {
    /// CageUp under Green coordinates: C' fitted to the rows M'_R (in `green.target_rows`) by
    /// Gauss–Newton, warm-started from the current C'. Records a failure to converge for
    /// `finish_event`.
    pub(super) fn fit_green_cage(&mut self) {
        let CageMap::Green(green) = self.rest_map.cage_map_mut() else {
            return;
        };
        let limit = GREEN_FIT_LIMIT * green.size;
        let predict = !green.start_from_posed_cage;
        green.start_from_posed_cage = false;
        if predict {
            // Two warm starts, the one the fit likes better: the previous C' moved by the change
            // of the skinning transforms and the skinned change of the rest cage, and the rest
            // cage skinned outright — both blended with the cage vertices' weights P·Ω̃ (the
            // normals turn with the bones; at the rest pose the second is C, the exact answer).
            let nj = green.last_transforms.len();
            let continuing =
                green.has_last_transforms && self.posed_cage.iter().all(|p| p.is_finite());
            for (k, (p, s)) in self
                .posed_cage
                .iter_mut()
                .zip(green.skinned_cage.iter_mut())
                .enumerate()
            {
                let weights = &green.cage_weights[k * nj..(k + 1) * nj];
                let rest_change = self.rest_cage[k] - green.last_rest_cage[k];
                let (mut moved, mut skinned) = (DVec3::ZERO, DVec3::ZERO);
                for (j, &w) in weights.iter().enumerate() {
                    if w != 0.0 {
                        let transform = &self.posed_from_rest[j];
                        skinned += w * transform.transform_point3(self.rest_cage[k]);
                        if continuing {
                            let back = green.last_transforms[j].inverse().transform_point3(*p);
                            moved += w
                                * (transform.transform_point3(back)
                                    + transform.transform_vector3(rest_change));
                        }
                    }
                }
                *s = skinned;
                if continuing {
                    *p = moved;
                }
            }
            let skinned_energy = green.fit.energy(&green.target_rows, &green.skinned_cage);
            if !continuing
                || skinned_energy < green.fit.energy(&green.target_rows, &self.posed_cage)
            {
                self.posed_cage.copy_from_slice(&green.skinned_cage);
            }
        }
        green.last_transforms.copy_from_slice(&self.posed_from_rest);
        green.last_rest_cage.copy_from_slice(&self.rest_cage);
        green.has_last_transforms = true;
        // A run of kept events past the fold tries a few steps each (`FitBudget`).
        let budget = match (self.options.unfitted_cage, green.unfitted) {
            (UnfittedCagePolicy::KeepEvent, Some(_)) => FitBudget::UNFITTED_STREAK,
            (UnfittedCagePolicy::KeepEvent | UnfittedCagePolicy::Refuse, _) => FitBudget::FULL,
        };
        let result = green
            .fit
            .apply_within(&green.target_rows, &mut self.posed_cage, budget);
        let residual = match result {
            Ok(report) if report.residual <= limit => {
                green.failure_unreported = false;
                green.unfitted = None;
                return;
            }
            Ok(report) => report.residual,
            Err(_) => f64::INFINITY,
        };
        let (face, area_ratio) = green
            .fit
            .normals()
            .triangles()
            .iter()
            .enumerate()
            .map(|(f, t)| {
                // Signed: negative when the triangle turned over against its binding normal.
                let [a, b, c] = t.map(|v| self.posed_cage[v as usize]);
                let [a0, b0, c0] = t.map(|v| self.original_rest_cage[v as usize]);
                let rest = (b0 - a0).cross(c0 - a0);
                let now = (b - a).cross(c - a);
                let signed = now.length() * now.dot(rest).signum();
                (f, signed / rest.length().max(f64::MIN_POSITIVE))
            })
            .fold(
                (0, f64::INFINITY),
                |best, x| if x.1 < best.1 { x } else { best },
            );
        green.unfitted = Some(UnfittedCage {
            residual,
            limit,
            face,
            area_ratio,
        });
        green.failure_unreported = true;
    }

    /// Builds R̃ and K_A = Ω̃ ∂T/∂A of the Green CageRev for the current pose and SkelUp lock,
    /// unless they are already built for them. K_A in closed form: the translations are affine
    /// in the rest joints for fixed rotations (0.27 ms by differences, 3#J forward kinematics,
    /// at 133k on the Arm). Zero while SkelUp is locked (a grab then moves no joint).
    pub(super) fn prepare_green_reverser(&mut self) -> Result<(), RigError> {
        let CageMap::Green(green) = self.rest_map.cage_map() else {
            return Ok(());
        };
        let pose = || self.posed_from_rest.iter().map(|t| t.matrix3);
        let locked = self.locks.skel_up;
        if green.reverser.is_ready_for(pose(), locked) {
            return Ok(());
        }
        // Owned: `green` is updated below while the closure reads them.
        let rows = green.linear.rows().to_vec();
        let rows = &rows[..];
        let nj = self.skeleton.len();
        let row_linear: Vec<DMat3> = rows
            .iter()
            .map(|&row| {
                let (joints, weights) = self.skin_weights.row(row);
                joints
                    .iter()
                    .zip(weights)
                    .fold(DMat3::ZERO, |acc, (&j, &w)| {
                        acc + self.posed_from_rest[j as usize].matrix3 * w
                    })
            })
            .collect();
        // ∂t_j/∂A_k in closed form (`Skeleton::skinning_translation_jacobian`), then
        // K_A = Ω̃ ∂t/∂A row by row.
        let mut translation_jacobian = vec![DMat3::ZERO; nj * nj];
        self.skeleton
            .skinning_translation_jacobian(&self.posed_from_rest, &mut translation_jacobian);
        let skin_weights = &self.skin_weights;
        let fill_skeleton_rows = |out: &mut Mat<f64>| {
            for (i, &row) in rows.iter().enumerate() {
                let (joints, weights) = skin_weights.row(row);
                for k in 0..nj {
                    let block = joints
                        .iter()
                        .zip(weights)
                        .fold(DMat3::ZERO, |acc, (&j, &w)| {
                            acc + translation_jacobian[j as usize * nj + k] * w
                        });
                    for c in 0..3 {
                        let column = block.col(c);
                        for a in 0..3 {
                            out[(3 * i + a, 3 * k + c)] = column[a];
                        }
                    }
                }
            }
        };
        let pose_linear = self.posed_from_rest.iter().map(|t| t.matrix3);
        if let CageMap::Green(green) = self.rest_map.cage_map_mut() {
            green.reverser.prepare(
                row_linear.into_iter(),
                pose_linear,
                locked,
                fill_skeleton_rows,
            );
        }
        Ok(())
    }

    /// CageRev under Green coordinates: the rest-cage change `rest_delta` (`#C`) for the
    /// current-cage change `posed_delta` (`#C`).
    pub(super) fn reverse_green(
        &mut self,
        posed_delta: &[DVec3],
        rest_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        self.prepare_green_reverser()?;
        let CageMap::Green(green) = self.rest_map.cage_map_mut() else {
            return Err(RigError::Invalid(
                "the Green CageRev was asked of a rig bound with another coordinates kind".into(),
            ));
        };
        for (r, &row) in self.scratch_rows_rest.iter_mut().zip(green.linear.rows()) {
            *r = self.rest_mesh[row];
        }
        let at = GrabState {
            rest_cage: &self.rest_cage,
            rest_rows: &self.scratch_rows_rest,
            posed_rows: &green.target_rows,
            posed_cage: &self.posed_cage,
        };
        let report = green
            .reverser
            .solve(&green.fit, at, posed_delta, rest_delta)?;
        green.last_reverse = report;
        if report.residual > GREEN_FIT_LIMIT * green.size {
            return Err(RigError::GreenGrabFailed {
                residual: report.residual,
                limit: GREEN_FIT_LIMIT * green.size,
                iterations: report.iterations,
            });
        }
        Ok(())
    }

    /// Green rigs: ψ (`#V × #F`, one column per cage triangle of
    /// [`RigSession::green_triangles`]); `None` for MVC rigs.
    pub fn green_face_coords(&self) -> Option<&CageCoords> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some(&green.face_coords),
        }
    }

    /// Green rigs: the outward-oriented cage triangles the face coordinates refer to.
    pub fn green_triangles(&self) -> Option<&[[u32; 3]]> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some(green.fit.normals().triangles()),
        }
    }

    /// Green rigs: the Newton reports of the last CageUp and the last CageRev.
    pub fn green_newton_reports(&self) -> Option<(NewtonReport, NewtonReport)> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some((green.fit.last_report(), green.last_reverse)),
        }
    }
}
