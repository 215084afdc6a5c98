//! SkelUp, C→S (Section 4.2, Eqs. 9–13): rest joints as fixed combinations of rest-cage vertices.
//!
//! Precomputation (once, at rest): for every joint j,
//! 1. mean value coordinates `mvc_j` of its rest position a_j w.r.t. the rest skin M;
//! 2. a localisation `L_j` (Eq. 9) from the skinning weights Ω, concentrating the prior on the
//!    mesh region where joint j articulates;
//! 3. prior masses on the cage `μ_j = Σ_i mvc_ji · L_ji · Φ_i` (Eq. 10);
//! 4. Ψ_j = MEC(μ_j): max-entropy coordinates of a_j w.r.t. the rest cage (Eq. 11), which satisfy
//!    Σ_k ψ_jk c_k = a_j and Σ_k ψ_jk = 1 — so Ψ·C reproduces every rest joint (Eq. 12).
//!
//! Per frame: A = Ψ·C (Eq. 13), `#J × #C` by `#C × 3`.
//!
//! **Green rigs** (M = φC + ψ·g(C)): the joints follow the skin's face terms too,
//! A = Ψ_φ·C + Ψ_ψ·g(C) (G5 in `docs/green-coordinates.md`). Ψ_ψ,j (`#F`) is the localised
//! average of the ψ rows of the mesh, Σ_i π̂_ji ψ_i with π̂_j the prior of step 3 normalised to
//! sum 1 (where the articulation ring's skin goes, its face part takes the joint along), and
//! Ψ_φ,j is step 4's max-entropy projection onto the shifted target a_j − Ψ_ψ,j·g(C₀), so A
//! still reproduces every rest joint. Σ_k Ψ_φ,jk = 1 and g(sRC + t) = sR·g(C), so A follows
//! every similarity of the cage exactly, as the skin does.

use glam::DVec3;
use rayon::prelude::*;

use crate::cage_coords::CageCoords;
use crate::coords::local_mvc::{LocalMvc, LocalMvcScratch};
use crate::coords::{mec, mec_signed};
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;

mod prior;
#[cfg(test)]
mod tests;

use prior::{Candidate, articulation_candidates, joint_prior, project_prior};

/// How the joint localisation function L of Eq. 9 is built from Ω.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum JointLocalisation {
    /// cagerig's default: `L_ji = max(0, ω_ij^s + ω_if^s − 1)` with f the parent of j — non-zero
    /// only where the bone of j and its parent's bone blend, i.e. around the articulation itself
    /// (Eq. 9 restricted to the two bones that meet at the joint). Roots use Eq. 9 as printed,
    /// `max(0, ω_ij^s + (1 − ω_ij)^s − 1)`. A joint with no blend region falls back to the
    /// unlocalised prior `L ≡ 1`. Cage masses are clamped to a small positive floor so that the
    /// max-entropy problem is well posed.
    Articulation {
        /// Exponent s of Eq. 9 (default 0.1).
        exponent: f64,
    },
    /// The paper tool's choice: `L_ji = max(ε, −1 + max(ε, ω_ij)^s + max(ε, ω_if)^s)` with
    /// s = 0.05, ε = 0.01 (roots: own weight only, so `L ≡ ε`), signed masses. Kept to compare
    /// with the tool's outputs.
    ReferenceTool {
        /// Exponent s of Eq. 9 (the tool: 0.05).
        exponent: f64,
        /// Floor ε of the weights and of L (the tool: 0.01).
        epsilon: f64,
    },
}

impl Default for JointLocalisation {
    fn default() -> Self {
        JointLocalisation::Articulation { exponent: 0.1 }
    }
}

impl JointLocalisation {
    /// The tool's parameters (s = 0.05, ε = 0.01).
    pub fn reference_tool() -> Self {
        JointLocalisation::ReferenceTool {
            exponent: 0.05,
            epsilon: 0.01,
        }
    }
}

/// The named choices of [`JointLocalisation`], with their parameters fixed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LocalisationKind {
    /// [`JointLocalisation::default`]: cagerig's articulation-localised prior.
    #[default]
    Articulation,
    /// [`JointLocalisation::reference_tool`]: the paper tool's localisation.
    ReferenceTool,
}

impl LocalisationKind {
    /// Every choice, the default first.
    pub const ALL: [LocalisationKind; 2] = [Self::Articulation, Self::ReferenceTool];

    /// The name front ends use (`--localisation`, Python's `localisation=`; `reference_tool` is
    /// read as `reference-tool`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Articulation => "articulation",
            Self::ReferenceTool => "reference-tool",
        }
    }

    /// One line for `--help`.
    pub const fn help(self) -> &'static str {
        match self {
            Self::Articulation => "cagerig's articulation-localised prior",
            Self::ReferenceTool => {
                "the paper tool's localisation (s = 0.05, ε = 0.01, signed masses)"
            }
        }
    }

    /// The localisation with this choice's parameters.
    pub fn localisation(self) -> JointLocalisation {
        match self {
            Self::Articulation => JointLocalisation::default(),
            Self::ReferenceTool => JointLocalisation::reference_tool(),
        }
    }
}

/// A name that is not a [`LocalisationKind`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown localisation {found:?}: expected {}",
    LocalisationKind::names_text()
)]
pub struct UnknownLocalisationKind {
    /// The name given.
    pub found: String,
}

crate::named_kind::named_kind!(
    LocalisationKind,
    UnknownLocalisationKind,
    LocalisationKind::help
);

/// Positive masses are floored at this fraction of the largest one in `Articulation` mode.
pub const MASS_FLOOR_RATIO: f64 = 1e-8;

/// How the coordinates of one joint were obtained.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct JointCoordsReport {
    /// The joint index.
    pub joint: usize,
    /// True when the localised prior was empty and the unlocalised MVC prior was used.
    pub unlocalised: bool,
    /// The max-entropy solve outcome.
    pub method: String,
    /// |Ψ_j·C − a_j| at rest (with the face part for Green rigs).
    pub residual: f64,
    /// Green rigs: whether the joint follows the face terms (false when the shifted target
    /// left the max-entropy domain and the vertex-only coordinates were kept).
    pub face_terms: bool,
}

/// A Green rig's face part for SkelUp: the face coordinates ψ of the rest skin (`#V × #F`) and
/// the stretched normals g(C₀) of the rest cage (`#F`).
#[derive(Debug, Clone, Copy)]
pub struct JointFaceTerms<'a> {
    /// ψ, `#V × #F`.
    pub face_coords: &'a CageCoords,
    /// g(C₀), `#F`.
    pub rest_terms: &'a [DVec3],
}

/// The SkelUp operator: Ψ (`#J × #C`, row-major) with A = Ψ·C; for Green rigs also Ψ_ψ
/// (`#J × #F`) with A = Ψ·C + Ψ_ψ·g(C).
#[derive(Debug, Clone)]
pub struct SkeletonUpdater {
    num_cage_vertices: usize,
    /// Ψ (Ψ_φ for Green rigs), row-major `#J × #C`.
    joint_coords: Vec<f64>,
    /// Number of cage faces `#F` of the face part (0: none).
    num_faces: usize,
    /// Ψ_ψ, row-major `#J × #F` (empty: none).
    joint_face_coords: Vec<f64>,
    reports: Vec<JointCoordsReport>,
}

impl SkeletonUpdater {
    /// Computes Ψ from the rest skin M (positions and triangles), the rest skeleton S, Ω, Φ and
    /// the rest cage C (Eqs. 9–12), and for Green rigs (`face_terms`) the face part Ψ_ψ (see
    /// the module docs). Parallel over joints.
    pub fn new(
        rest_mesh: &TriMesh,
        skeleton: &Skeleton,
        skin_weights: &SkinWeights,
        cage_coords: &CageCoords,
        face_terms: Option<JointFaceTerms<'_>>,
        rest_cage: &[DVec3],
        localisation: JointLocalisation,
    ) -> Result<(Self, Vec<Warning>), RigError> {
        Self::build(
            rest_mesh,
            skeleton,
            skin_weights,
            (cage_coords, face_terms),
            rest_cage,
            localisation,
            true,
        )
    }

    /// [`Self::new`]; `use_local_mvc` = false forces the reference full-MVC prior
    /// ([`full_prior`]) in Articulation mode too (for tests).
    fn build(
        rest_mesh: &TriMesh,
        skeleton: &Skeleton,
        skin_weights: &SkinWeights,
        (cage_coords, face_terms): (&CageCoords, Option<JointFaceTerms<'_>>),
        rest_cage: &[DVec3],
        localisation: JointLocalisation,
        use_local_mvc: bool,
    ) -> Result<(Self, Vec<Warning>), RigError> {
        let num_cage = cage_coords.num_cage_vertices();
        if let Some(face) = face_terms
            && (face.face_coords.num_vertices() != rest_mesh.num_vertices()
                || face.face_coords.num_cage_vertices() != face.rest_terms.len())
        {
            return Err(RigError::SizeMismatch {
                what: "SkelUp face terms: ψ (#V × #F) and g(C₀) (#F)",
                expected: rest_mesh.num_vertices() * face.rest_terms.len(),
                actual: face.face_coords.num_vertices() * face.face_coords.num_cage_vertices(),
            });
        }
        let num_vertices = rest_mesh.num_vertices();
        if cage_coords.num_vertices() != num_vertices || skin_weights.num_vertices() != num_vertices
        {
            return Err(RigError::SizeMismatch {
                what: "mesh vertices in Φ / Ω",
                expected: num_vertices,
                actual: cage_coords.num_vertices().min(skin_weights.num_vertices()),
            });
        }
        if rest_cage.len() != num_cage {
            return Err(RigError::SizeMismatch {
                what: "rest cage vertices",
                expected: num_cage,
                actual: rest_cage.len(),
            });
        }
        let articulation =
            use_local_mvc && matches!(localisation, JointLocalisation::Articulation { .. });
        let inputs = JointInputs {
            rest_mesh,
            skeleton,
            skin_weights,
            cage_coords,
            face_terms,
            rest_cage,
            localisation,
            reference_floor_power: match localisation {
                JointLocalisation::ReferenceTool { exponent, epsilon } => epsilon.powf(exponent),
                JointLocalisation::Articulation { .. } => 0.0,
            },
            candidates: if articulation {
                articulation_candidates(skeleton, skin_weights)
            } else {
                Vec::new()
            },
            local_mvc: articulation
                .then(|| LocalMvc::new(&rest_mesh.positions, &rest_mesh.triangles)),
        };
        let per_joint: Vec<JointCoordinates> = (0..skeleton.len())
            .into_par_iter()
            .map_init(
                || inputs.local_mvc.as_ref().map(LocalMvc::scratch),
                |scratch, j| joint_coordinates(j, &inputs, scratch),
            )
            .collect();
        let num_faces = face_terms.map_or(0, |f| f.rest_terms.len());
        let mut joint_coords = Vec::with_capacity(skeleton.len() * num_cage);
        let mut joint_face_coords = Vec::with_capacity(skeleton.len() * num_faces);
        let mut reports = Vec::with_capacity(skeleton.len());
        let mut warnings = Vec::new();
        for JointCoordinates {
            vertex_part,
            face_part,
            report,
        } in per_joint
        {
            joint_coords.extend_from_slice(&vertex_part);
            if num_faces > 0 {
                match face_part {
                    Some(face_part) => joint_face_coords.extend_from_slice(&face_part),
                    None => joint_face_coords.extend(std::iter::repeat_n(0.0, num_faces)),
                }
            }
            if report.method != "max_entropy" {
                warnings.push(Warning::MecFallback {
                    joint: report.joint,
                    name: skeleton.joint(report.joint).name.clone(),
                    reason: report.method.clone(),
                });
            }
            reports.push(report);
        }
        Ok((
            Self {
                num_cage_vertices: num_cage,
                joint_coords,
                num_faces,
                joint_face_coords,
                reports,
            },
            warnings,
        ))
    }

    /// Wraps given joint coordinates Ψ (`#J` rows of `#C`), e.g. loaded from a file.
    pub fn from_joint_coords(
        rows: &[Vec<f64>],
        num_cage_vertices: usize,
    ) -> Result<Self, RigError> {
        let mut joint_coords = Vec::with_capacity(rows.len() * num_cage_vertices);
        for (j, r) in rows.iter().enumerate() {
            if r.len() != num_cage_vertices {
                return Err(RigError::SizeMismatch {
                    what: "joint coordinate row length",
                    expected: num_cage_vertices,
                    actual: r.len(),
                });
            }
            if r.iter().any(|w| !w.is_finite()) {
                return Err(RigError::NonFinite {
                    what: "joint coordinate row",
                    index: j,
                });
            }
            joint_coords.extend_from_slice(r);
        }
        Ok(Self {
            num_cage_vertices,
            joint_coords,
            num_faces: 0,
            joint_face_coords: Vec::new(),
            reports: Vec::new(),
        })
    }

    /// Number of joints `#J` (rows of Ψ).
    pub fn num_joints(&self) -> usize {
        self.joint_coords.len() / self.num_cage_vertices.max(1)
    }

    /// Row j of Ψ (`#C`; Ψ_φ for Green rigs).
    pub fn joint_row(&self, j: usize) -> &[f64] {
        &self.joint_coords[j * self.num_cage_vertices..(j + 1) * self.num_cage_vertices]
    }

    /// Number of cage faces `#F` of the face part Ψ_ψ (0 when A = Ψ·C).
    pub fn num_faces(&self) -> usize {
        self.num_faces
    }

    /// Row j of the face part Ψ_ψ (`#F`; empty when A = Ψ·C).
    pub fn joint_face_row(&self, j: usize) -> &[f64] {
        &self.joint_face_coords[j * self.num_faces..(j + 1) * self.num_faces]
    }

    /// Per-joint precomputation reports (empty when Ψ was given).
    pub fn reports(&self) -> &[JointCoordsReport] {
        &self.reports
    }

    /// Rest joints A = Ψ·C (Eq. 13), or A = Ψ_φ·C + Ψ_ψ·g(C) with a face part (G5):
    /// `rest_cage` is `#C`, `face_terms` the stretched normals g(C) of that cage (`#F`, the
    /// session's `rest_cage_terms`; ignored, and may be empty, without a face part),
    /// `rest_joints` is `#J`. No allocation.
    pub fn apply(&self, rest_cage: &[DVec3], face_terms: &[DVec3], rest_joints: &mut [DVec3]) {
        debug_assert!(self.num_faces == 0 || face_terms.len() == self.num_faces);
        for (j, a) in rest_joints.iter_mut().enumerate() {
            let vertex_part = self
                .joint_row(j)
                .iter()
                .zip(rest_cage)
                .fold(DVec3::ZERO, |acc, (&w, c)| acc + w * *c);
            *a = self
                .joint_face_row(j)
                .iter()
                .zip(face_terms)
                .fold(vertex_part, |acc, (&w, g)| acc + w * *g);
        }
    }
}

/// Shared, read-only inputs of the per-joint work.
struct JointInputs<'a> {
    rest_mesh: &'a TriMesh,
    skeleton: &'a Skeleton,
    skin_weights: &'a SkinWeights,
    cage_coords: &'a CageCoords,
    /// Green rigs: ψ and g(C₀) for the face part.
    face_terms: Option<JointFaceTerms<'a>>,
    rest_cage: &'a [DVec3],
    localisation: JointLocalisation,
    /// ε^s in `ReferenceTool` mode (see [`localisation_value`]).
    reference_floor_power: f64,
    /// Articulation mode: per joint the vertices where L_j may be non-zero.
    candidates: Vec<Vec<Candidate>>,
    /// Articulation mode: unnormalised MVC at a few vertices (see [`LocalMvc`]).
    local_mvc: Option<LocalMvc<'a>>,
}

/// One joint's coordinates: Ψ_j (`#C`), its face part Ψ_ψ,j (`#F`, Green rigs) and how they
/// were obtained.
struct JointCoordinates {
    vertex_part: Vec<f64>,
    face_part: Option<Vec<f64>>,
    report: JointCoordsReport,
}

/// Ψ_j (Eqs. 9–12) and, for Green rigs, Ψ_ψ,j with the target shifted by Ψ_ψ,j·g(C₀) (module
/// docs). Where the shifted target leaves the max-entropy domain (the least-squares fallback),
/// the joint keeps the vertex-only coordinates of the unshifted target.
fn joint_coordinates(
    j: usize,
    inputs: &JointInputs,
    scratch: &mut Option<LocalMvcScratch>,
) -> JointCoordinates {
    let num_cage = inputs.cage_coords.num_cage_vertices();
    let rest_cage = inputs.rest_cage;
    let target = inputs.skeleton.joint(j).rest_world_from_joint.translation;
    let floor_masses = matches!(inputs.localisation, JointLocalisation::Articulation { .. });
    let (prior, unlocalised) = joint_prior(j, inputs, scratch);
    let mut masses = project_prior(&prior, inputs.cage_coords);
    if floor_masses {
        let max = masses.iter().copied().fold(0.0f64, f64::max);
        if max <= 0.0 {
            masses.iter_mut().for_each(|m| *m = 1.0);
        } else {
            masses
                .iter_mut()
                .for_each(|m| *m = m.max(MASS_FLOOR_RATIO * max));
        }
    }
    let solve = |shifted_target: DVec3, psi: &mut [f64]| {
        if floor_masses {
            mec::max_entropy_coordinates(rest_cage, &masses, shifted_target, psi)
        } else {
            mec_signed::max_entropy_coordinates_signed(rest_cage, &masses, shifted_target, psi)
        }
    };
    let mut psi = vec![0.0; num_cage];
    let mut face_part = inputs
        .face_terms
        .and_then(|face| localised_face_average(&prior, face));
    let outcome = match &face_part {
        Some((_, shift)) => {
            let outcome = solve(target - *shift, &mut psi);
            if outcome.method == mec::MecMethod::MaxEntropy {
                outcome
            } else {
                face_part = None;
                solve(target, &mut psi)
            }
        }
        None => solve(target, &mut psi),
    };
    let shift = face_part.as_ref().map_or(DVec3::ZERO, |(_, shift)| *shift);
    let reached = psi
        .iter()
        .zip(rest_cage)
        .fold(shift, |acc, (&w, c)| acc + w * *c);
    let report = JointCoordsReport {
        joint: j,
        unlocalised,
        method: match outcome.method {
            mec::MecMethod::MaxEntropy => "max_entropy".to_string(),
            mec::MecMethod::LeastSquaresFallback => format!(
                "least_squares_fallback ({})",
                outcome
                    .fallback_reason
                    .as_deref()
                    .unwrap_or("no reason given")
            ),
        },
        residual: reached.distance(target),
        face_terms: face_part.is_some(),
    };
    JointCoordinates {
        vertex_part: psi,
        face_part: face_part.map(|(weights, _)| weights),
        report,
    }
}

/// Ψ_ψ,j = Σ_i π̂_i ψ_i (`#F`): the face rows of the skin averaged with the prior `(i, π_i)`
/// normalised to sum 1, and the shift of the target it brings at rest, Ψ_ψ,j·g(C₀). `None` when
/// the prior does not sum to a positive number.
fn localised_face_average(
    prior: &[(usize, f64)],
    face: JointFaceTerms<'_>,
) -> Option<(Vec<f64>, DVec3)> {
    let total: f64 = prior.iter().map(|&(_, p)| p).sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut average = project_prior(prior, face.face_coords);
    average.iter_mut().for_each(|w| *w /= total);
    let shift = average
        .iter()
        .zip(face.rest_terms)
        .fold(DVec3::ZERO, |acc, (&w, g)| acc + w * *g);
    (average.iter().all(|w| w.is_finite()) && shift.is_finite()).then_some((average, shift))
}
