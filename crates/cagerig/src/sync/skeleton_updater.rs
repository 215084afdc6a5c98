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

use glam::DVec3;
use rayon::prelude::*;

use crate::cage_coords::CageCoords;
use crate::coords::{mec, mec_signed, mvc};
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;

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
    Articulation { exponent: f64 },
    /// The paper tool's choice: `L_ji = max(ε, −1 + max(ε, ω_ij)^s + max(ε, ω_if)^s)` with
    /// s = 0.05, ε = 0.01 (roots: own weight only, so `L ≡ ε`), signed masses. Kept to compare
    /// with the tool's outputs.
    ReferenceTool { exponent: f64, epsilon: f64 },
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

/// Positive masses are floored at this fraction of the largest one in `Articulation` mode.
pub const MASS_FLOOR_RATIO: f64 = 1e-8;

/// How the coordinates of one joint were obtained.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct JointCoordsReport {
    pub joint: usize,
    /// True when the localised prior was empty and the unlocalised MVC prior was used.
    pub unlocalised: bool,
    /// The max-entropy solve outcome.
    pub method: String,
    /// |Ψ_j·C − a_j| at rest.
    pub residual: f64,
}

/// The SkelUp operator: Ψ (`#J × #C`, row-major) with A = Ψ·C.
#[derive(Debug, Clone)]
pub struct SkeletonUpdater {
    num_cage_vertices: usize,
    /// Ψ, row-major `#J × #C`.
    joint_coords: Vec<f64>,
    reports: Vec<JointCoordsReport>,
}

impl SkeletonUpdater {
    /// Computes Ψ from the rest skin M (positions and triangles), the rest skeleton S, Ω, Φ and
    /// the rest cage C (Eqs. 9–12). Parallel over joints.
    pub fn new(
        rest_mesh: &TriMesh,
        skeleton: &Skeleton,
        skin_weights: &SkinWeights,
        cage_coords: &CageCoords,
        rest_cage: &[DVec3],
        localisation: JointLocalisation,
    ) -> Result<(Self, Vec<Warning>), RigError> {
        let num_cage = cage_coords.num_cage_vertices();
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
        let per_joint: Vec<(Vec<f64>, JointCoordsReport)> = (0..skeleton.len())
            .into_par_iter()
            .map(|j| {
                joint_coordinates(
                    j,
                    rest_mesh,
                    skeleton,
                    skin_weights,
                    cage_coords,
                    rest_cage,
                    localisation,
                )
            })
            .collect();
        let mut joint_coords = Vec::with_capacity(skeleton.len() * num_cage);
        let mut reports = Vec::with_capacity(skeleton.len());
        let mut warnings = Vec::new();
        for (psi, report) in per_joint {
            joint_coords.extend_from_slice(&psi);
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
            reports: Vec::new(),
        })
    }

    pub fn num_joints(&self) -> usize {
        self.joint_coords.len() / self.num_cage_vertices.max(1)
    }

    /// Row j of Ψ (`#C`).
    pub fn joint_row(&self, j: usize) -> &[f64] {
        &self.joint_coords[j * self.num_cage_vertices..(j + 1) * self.num_cage_vertices]
    }

    /// Per-joint precomputation reports (empty when Ψ was given).
    pub fn reports(&self) -> &[JointCoordsReport] {
        &self.reports
    }

    /// Rest joints A = Ψ·C (Eq. 13): `rest_cage` is `#C`, `rest_joints` is `#J`. No allocation.
    pub fn apply(&self, rest_cage: &[DVec3], rest_joints: &mut [DVec3]) {
        for (j, a) in rest_joints.iter_mut().enumerate() {
            *a = self
                .joint_row(j)
                .iter()
                .zip(rest_cage)
                .fold(DVec3::ZERO, |acc, (&w, c)| acc + w * *c);
        }
    }
}

/// Eq. 9 localisation value of vertex weights `own` (ω_ij) and `parent` (ω_if, if any).
fn localisation_value(loc: JointLocalisation, own: f64, parent: Option<f64>) -> f64 {
    match loc {
        JointLocalisation::Articulation { exponent: s } => {
            let other = parent.unwrap_or(1.0 - own).max(0.0);
            (own.powf(s) + other.powf(s) - 1.0).max(0.0)
        }
        JointLocalisation::ReferenceTool {
            exponent: s,
            epsilon: eps,
        } => {
            let mut l = -1.0 + own.abs().max(eps).powf(s);
            if let Some(p) = parent {
                l += p.abs().max(eps).powf(s);
            }
            l.max(eps)
        }
    }
}

fn joint_coordinates(
    j: usize,
    rest_mesh: &TriMesh,
    skeleton: &Skeleton,
    skin_weights: &SkinWeights,
    cage_coords: &CageCoords,
    rest_cage: &[DVec3],
    localisation: JointLocalisation,
) -> (Vec<f64>, JointCoordsReport) {
    let num_vertices = rest_mesh.num_vertices();
    let num_cage = cage_coords.num_cage_vertices();
    let target = skeleton.joint(j).rest_world_from_joint.translation;
    let parent = skeleton.parent(j);

    let mut mesh_mvc = vec![0.0; num_vertices];
    mvc::mean_value_coordinates(
        &rest_mesh.positions,
        &rest_mesh.triangles,
        target,
        &mut mesh_mvc,
    );
    let floor_masses = matches!(localisation, JointLocalisation::Articulation { .. });
    // The prior π_i = mvc_i · L_i as a sparse list: in the articulation localisation L vanishes
    // wherever the joint's or its parent's weight is zero, i.e. on most of the mesh.
    let mut prior: Vec<(usize, f64)> = (0..num_vertices)
        .filter_map(|i| {
            let own = skin_weights.get(i, j);
            let par = parent.map(|p| skin_weights.get(i, p));
            if floor_masses && (own == 0.0 || par == Some(0.0)) {
                return None;
            }
            let l = localisation_value(localisation, own, par);
            (l != 0.0).then(|| (i, mesh_mvc[i] * l))
        })
        .collect();
    let mut unlocalised = false;
    if floor_masses && prior.iter().all(|&(_, p)| p <= 0.0) {
        prior = mesh_mvc.iter().copied().enumerate().collect();
        unlocalised = true;
    }
    // μ_k = Σ_i prior_i Φ_ik (Eq. 10).
    let mut masses: Vec<f64> = (0..num_cage)
        .map(|k| {
            let column = cage_coords.column(k);
            prior.iter().map(|&(i, p)| column[i] * p).sum()
        })
        .collect();
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
    let mut psi = vec![0.0; num_cage];
    let outcome = if floor_masses {
        mec::max_entropy_coordinates(rest_cage, &masses, target, &mut psi)
    } else {
        mec_signed::max_entropy_coordinates_signed(rest_cage, &masses, target, &mut psi)
    };
    let reached = psi
        .iter()
        .zip(rest_cage)
        .fold(DVec3::ZERO, |acc, (&w, c)| acc + w * *c);
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
    };
    (psi, report)
}
