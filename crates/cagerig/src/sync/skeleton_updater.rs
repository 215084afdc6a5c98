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
use crate::coords::local_mvc::{LocalMvc, LocalMvcScratch};
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

/// Cage columns accumulated together in [`project_prior`].
const MASS_BLOCK: usize = 8;

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
        Self::build(
            rest_mesh,
            skeleton,
            skin_weights,
            cage_coords,
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
        cage_coords: &CageCoords,
        rest_cage: &[DVec3],
        localisation: JointLocalisation,
        use_local_mvc: bool,
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
        let articulation =
            use_local_mvc && matches!(localisation, JointLocalisation::Articulation { .. });
        let inputs = JointInputs {
            rest_mesh,
            skeleton,
            skin_weights,
            cage_coords,
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
        let per_joint: Vec<(Vec<f64>, JointCoordsReport)> = (0..skeleton.len())
            .into_par_iter()
            .map_init(
                || inputs.local_mvc.as_ref().map(LocalMvc::scratch),
                |scratch, j| joint_coordinates(j, &inputs, scratch),
            )
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

    /// Number of joints `#J` (rows of Ψ).
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
/// `reference_floor_power` is `ε^s` for [`JointLocalisation::ReferenceTool`] (unused otherwise):
/// weights at most ε use it instead of a `powf` (same value).
fn localisation_value(
    loc: JointLocalisation,
    own: f64,
    parent: Option<f64>,
    reference_floor_power: f64,
) -> f64 {
    match loc {
        JointLocalisation::Articulation { exponent: s } => {
            let other = parent.unwrap_or(1.0 - own).max(0.0);
            (own.powf(s) + other.powf(s) - 1.0).max(0.0)
        }
        JointLocalisation::ReferenceTool {
            exponent: s,
            epsilon: eps,
        } => {
            let power = |w: f64| {
                if w.abs() <= eps {
                    reference_floor_power
                } else {
                    w.abs().powf(s)
                }
            };
            let mut l = -1.0 + power(own);
            if let Some(p) = parent {
                l += power(p);
            }
            l.max(eps)
        }
    }
}

/// One vertex where the articulation localisation of a joint may be non-zero: its index and
/// the weights (ω_ij, ω_if) of the joint and of its parent (`None` for a root).
#[derive(Debug, Clone, Copy)]
struct Candidate {
    vertex: usize,
    own: f64,
    parent: Option<f64>,
}

/// For every joint j, the vertices with ω_ij ≠ 0 and (unless j is a root) ω_if ≠ 0 — the only
/// ones where the [`JointLocalisation::Articulation`] L_j can be non-zero — in ascending vertex
/// order, from one pass over the rows of Ω.
fn articulation_candidates(skeleton: &Skeleton, skin_weights: &SkinWeights) -> Vec<Vec<Candidate>> {
    let mut candidates = vec![Vec::new(); skeleton.len()];
    for vertex in 0..skin_weights.num_vertices() {
        let (joints, weights) = skin_weights.row(vertex);
        // ω_vk as `SkinWeights::get` reads it (first entry of k).
        let weight_of = |k: usize| {
            joints
                .iter()
                .position(|&q| q as usize == k)
                .map_or(0.0, |i| weights[i])
        };
        for (idx, &j) in joints.iter().enumerate() {
            let j = j as usize;
            if j >= skeleton.len() || joints[..idx].contains(&(j as u32)) {
                continue;
            }
            let own = weights[idx];
            let parent = skeleton.parent(j).map(weight_of);
            if own == 0.0 || parent == Some(0.0) {
                continue;
            }
            candidates[j].push(Candidate {
                vertex,
                own,
                parent,
            });
        }
    }
    candidates
}

/// Shared, read-only inputs of the per-joint work.
struct JointInputs<'a> {
    rest_mesh: &'a TriMesh,
    skeleton: &'a Skeleton,
    skin_weights: &'a SkinWeights,
    cage_coords: &'a CageCoords,
    rest_cage: &'a [DVec3],
    localisation: JointLocalisation,
    /// ε^s in `ReferenceTool` mode (see [`localisation_value`]).
    reference_floor_power: f64,
    /// Articulation mode: per joint the vertices where L_j may be non-zero.
    candidates: Vec<Vec<Candidate>>,
    /// Articulation mode: unnormalised MVC at a few vertices (see [`LocalMvc`]).
    local_mvc: Option<LocalMvc<'a>>,
}

/// The prior π_j of Eq. 10 (`mvc_ji · L_ji`, up to a positive factor) as a sparse list
/// `(vertex, π_i)`, and whether it is the unlocalised fallback. Articulation mode goes through
/// [`local_prior`] when a [`LocalMvc`] is available, else (and in ReferenceTool mode) through
/// [`full_prior`].
fn joint_prior(
    j: usize,
    inputs: &JointInputs,
    scratch: &mut Option<LocalMvcScratch>,
) -> (Vec<(usize, f64)>, bool) {
    if let (Some(local_mvc), Some(scratch)) = (&inputs.local_mvc, scratch.as_mut())
        && let Some(prior) = local_prior(j, inputs, local_mvc, scratch)
    {
        return (prior, false);
    }
    full_prior(j, inputs)
}

/// The reference computation of the prior: the full MVC `mvc_j` (`#V`) of joint j w.r.t. the
/// whole rest mesh, times L_j (Eq. 9) at every vertex. In Articulation mode, L_j vanishes
/// wherever ω_ij or ω_if is zero; if no prior value is positive, the unlocalised prior
/// `π = mvc_j` is returned instead.
fn full_prior(j: usize, inputs: &JointInputs) -> (Vec<(usize, f64)>, bool) {
    let rest_mesh = inputs.rest_mesh;
    let target = inputs.skeleton.joint(j).rest_world_from_joint.translation;
    let parent = inputs.skeleton.parent(j);
    let mut mesh_mvc = vec![0.0; rest_mesh.num_vertices()];
    mvc::mean_value_coordinates(
        &rest_mesh.positions,
        &rest_mesh.triangles,
        target,
        &mut mesh_mvc,
    );
    let articulation = matches!(inputs.localisation, JointLocalisation::Articulation { .. });
    let prior: Vec<(usize, f64)> = (0..rest_mesh.num_vertices())
        .filter_map(|i| {
            let own = inputs.skin_weights.get(i, j);
            let par = parent.map(|p| inputs.skin_weights.get(i, p));
            if articulation && (own == 0.0 || par == Some(0.0)) {
                return None;
            }
            let l = localisation_value(inputs.localisation, own, par, inputs.reference_floor_power);
            (l != 0.0).then(|| (i, mesh_mvc[i] * l))
        })
        .collect();
    if articulation && prior.iter().all(|&(_, p)| p <= 0.0) {
        return (mesh_mvc.into_iter().enumerate().collect(), true);
    }
    (prior, false)
}

/// The Articulation prior from the MVC weights at the candidate vertices only (L_j vanishes
/// elsewhere): `π_i = w_i · sign(W) · L_ji`, i.e. [`full_prior`]'s `mvc_ji · L_ji` times the
/// positive factor |W| (W = Σ_i w_i), to which the floored cage masses and the max-entropy
/// solve (Eq. 11) are blind — the MEC objective changes by a constant times Σψ = 1. `None`
/// when [`full_prior`] is needed: no localised vertex, uncertified sign or degenerate joint
/// position (see [`LocalMvc::weights_at`]), or no positive prior value (unlocalised fallback).
fn local_prior(
    j: usize,
    inputs: &JointInputs,
    local_mvc: &LocalMvc,
    scratch: &mut LocalMvcScratch,
) -> Option<Vec<(usize, f64)>> {
    let target = inputs.skeleton.joint(j).rest_world_from_joint.translation;
    let (vertices, localisation): (Vec<usize>, Vec<f64>) = inputs.candidates[j]
        .iter()
        .filter_map(|c| {
            let l = localisation_value(inputs.localisation, c.own, c.parent, 0.0);
            (l != 0.0).then_some((c.vertex, l))
        })
        .unzip();
    if vertices.is_empty() {
        return None;
    }
    let mut weights = vec![0.0; vertices.len()];
    let sign = local_mvc.weights_at(target, &vertices, scratch, &mut weights)?;
    let prior: Vec<(usize, f64)> = vertices
        .iter()
        .zip(weights.iter().zip(&localisation))
        .map(|(&i, (&w, &l))| (i, w * sign * l))
        .collect();
    prior.iter().any(|&(_, p)| p > 0.0).then_some(prior)
}

/// Cage masses μ_k = Σ_i π_i Φ_ik (Eq. 10), `#C`, for a sparse prior `(i, π_i)`. Each sum runs
/// over the prior in order; [`MASS_BLOCK`] columns at a time, so that their chains of additions
/// overlap.
fn project_prior(prior: &[(usize, f64)], cage_coords: &CageCoords) -> Vec<f64> {
    let num_cage = cage_coords.num_cage_vertices();
    let mut masses = vec![0.0; num_cage];
    for (block, block_masses) in masses.chunks_mut(MASS_BLOCK).enumerate() {
        let first = block * MASS_BLOCK;
        let mut columns = [&[][..]; MASS_BLOCK];
        for (c, column) in columns.iter_mut().enumerate().take(block_masses.len()) {
            *column = cage_coords.column(first + c);
        }
        let mut sums = [0.0; MASS_BLOCK];
        if block_masses.len() == MASS_BLOCK {
            for &(i, p) in prior {
                for (sum, column) in sums.iter_mut().zip(&columns) {
                    *sum += column[i] * p;
                }
            }
        } else {
            for &(i, p) in prior {
                for (sum, column) in sums.iter_mut().zip(&columns).take(block_masses.len()) {
                    *sum += column[i] * p;
                }
            }
        }
        block_masses.copy_from_slice(&sums[..block_masses.len()]);
    }
    masses
}

fn joint_coordinates(
    j: usize,
    inputs: &JointInputs,
    scratch: &mut Option<LocalMvcScratch>,
) -> (Vec<f64>, JointCoordsReport) {
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

#[cfg(test)]
#[path = "skeleton_updater_tests.rs"]
mod tests;
