//! The session's Green-coordinates terms ([`crate::CoordsKind::Green`]): M = φC + ψ·g(C), the
//! Newton CageUp and CageRev, and the face part of the CoR centres.
//!
//! The session keeps the vertex part φ where MVC rigs keep Φ (`cage_coords`), so everything that
//! is linear in C — the MaxVol rows, the linear CageUp map P, SkelUp's Ψ and the linear CageRev
//! L — is built on φ unchanged; this module adds the face terms ψ·g(C) and turns CageUp and
//! CageRev into the Newton solves of [`crate::sync::green_cage_fit`] and
//! [`crate::sync::green_cage_fit::reverser`]. The derivation is in `docs/green-coordinates.md`.

use std::sync::OnceLock;

use super::green_cage_up::GreenCageUp;
use crate::cage_coords::CageCoords;
use crate::coords::stretched_normals::{FaceTermKind, StretchedNormals};
use crate::error::RigError;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_updater::CageUpdater;
use crate::sync::green_cage_fit::reverser::GreenCageReverser;
use crate::sync::green_cage_fit::{FitPrior, GreenCageFit};
use crate::sync::newton::NewtonReport;
use glam::DVec3;

/// The Green terms of a session.
#[derive(Debug, Clone)]
pub(super) struct GreenState {
    /// ψ, `#V × #F`.
    pub(super) face_coords: CageCoords,
    /// The vertex part's linear fit on the rows of [φ ψ]: the fitting rows R, and P·M'_R as a
    /// start for the Newton fit.
    pub(super) linear: CageUpdater,
    /// CageUp: the fit, its target rows and warm start.
    pub(super) cage_up: GreenCageUp,
    pub(super) reverser: GreenCageReverser,
    /// g(C) for the current rest cage C, `#F`.
    pub(super) rest_terms: Vec<DVec3>,
    /// 0..#F, to add ψ·g with `CageCoords::apply_delta`.
    pub(super) all_faces: Vec<usize>,
    /// Faces around each cage vertex (CSR: `vertex_face_start[k]..vertex_face_start[k+1]`).
    pub(super) vertex_face_start: Vec<usize>,
    pub(super) vertex_faces: Vec<usize>,
    /// Scratch: faces touched by an edit, their g changes, a per-face mark.
    pub(super) touched_faces: Vec<usize>,
    pub(super) face_changes: Vec<DVec3>,
    pub(super) face_marked: Vec<bool>,
    /// Λ_ψ = S·ψ (`#V × #F`) for the CoR centres, built with them.
    pub(super) face_centre_coords: Option<CageCoords>,
    /// max_v Σ_f |ψ_vf|: bounds what a face term below a threshold can add to any vertex.
    /// Computed when the first cage keyframe is made ([`GreenState::keyframe_terms_of`]), not at
    /// binding.
    pub(super) face_coords_norm: OnceLock<f64>,
    /// The cage's bounding-box diagonal.
    pub(super) size: f64,
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
    /// From the Green coordinates of the rest mesh (φ is the rest map's vertex part, ψ is
    /// `face_coords`), the CageUp rows, the rest cage, the skeleton of the binding, the face term and
    /// the rest mesh (`#V`); with `regularised` CageUp is regularised towards the carried cage
    /// ([`crate::sync::green_cage_fit::prior`]).
    #[expect(
        clippy::too_many_arguments,
        reason = "the binding's coordinates, rows and rest state, and the fit's two options"
    )]
    pub(super) fn new(
        vertex_coords: &CageCoords,
        face_coords: CageCoords,
        triangles: Vec<[u32; 3]>,
        linear: CageUpdater,
        skin_weights: &SkinWeights,
        rest_cage: &[DVec3],
        binding_joints: &crate::sync::cage_prior::BindingJoints,
        face_term: FaceTermKind,
        rest_mesh: &[DVec3],
        regularised: bool,
    ) -> Result<Self, RigError> {
        let num_joints = binding_joints.len();
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
        let normals = StretchedNormals::with_kind(rest_cage, triangles, face_term);
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
        let mut fit = GreenCageFit::new(
            vertex_coords.select_rows(rows),
            face_coords.select_rows(rows),
            rest_cage,
            normals,
        )?;
        // The regulariser's prior; kept aside when the rig asks for the paper's fit (a rig
        // that cannot have one then fits on the rows alone).
        let rows_scale = fit.binding_rows_scale();
        let prior = FitPrior::for_binding(
            vertex_coords,
            rows,
            rest_cage,
            fit.normals().triangles(),
            rest_mesh,
            skin_weights,
            binding_joints,
            rows_scale,
        );
        match (prior, regularised) {
            (Ok(prior), on) => fit = fit.with_prior(prior, on),
            (Err(e), true) => return Err(e),
            (Err(_), false) => {}
        }
        Ok(Self {
            face_coords,
            reverser: GreenCageReverser::new(num_cage, num_faces, rows.len(), num_joints, size),
            cage_up: GreenCageUp::new(fit, rows.len(), cage_weights, num_joints, rest_cage),
            rest_terms,
            all_faces: (0..num_faces).collect(),
            vertex_face_start,
            vertex_faces,
            touched_faces: Vec::with_capacity(num_faces),
            face_changes: Vec::with_capacity(num_faces),
            face_marked: vec![false; num_faces],
            linear,
            face_centre_coords: None,
            face_coords_norm: OnceLock::new(),
            size,
            last_reverse: NewtonReport::default(),
        })
    }

    /// The largest gradient a Green CageUp, CageRev or rest-cage fit may end with: its
    /// acceptance ([`GREEN_FIT_LIMIT`]) times the cage size.
    pub(super) fn fit_limit(&self) -> f64 {
        GREEN_FIT_LIMIT * self.size
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
        self.cage_up.fit.normals().apply(cage, &mut g);
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
        let normals = self.cage_up.fit.normals();
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

    /// After the rest-cage vertices `vertices` moved by `deltas` (`rest_cage` already
    /// updated): the faces around them get their new g, and `rest_mesh` += φ_k·ΔC_k +
    /// ψ_f·Δg_f over those vertices and faces only, in one pass over the rows
    /// ([`CageCoords::apply_delta_with_extra`], `vertex_coords` being φ). No allocation.
    pub(super) fn apply_rest_delta(
        &mut self,
        vertex_coords: &CageCoords,
        vertices: &[usize],
        deltas: &[DVec3],
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
        let normals = self.cage_up.fit.normals();
        for &f in &self.touched_faces {
            let new = normals.face(rest_cage, f);
            self.face_changes.push(new - self.rest_terms[f]);
            self.rest_terms[f] = new;
            self.face_marked[f] = false;
        }
        vertex_coords.apply_delta_with_extra(
            vertices,
            deltas,
            &self.face_coords,
            &self.touched_faces,
            &self.face_changes,
            rest_mesh,
        );
    }
}
