//! SkelUp's prior (Eqs. 9–10): the localisation L_j of each joint from Ω, the prior π_j on the
//! rest skin (MVC of the joint times L_j) and its projection onto the cage, μ_j = π_j·Φ.

use super::{JointInputs, JointLocalisation};
use crate::cage_coords::CageCoords;
use crate::coords::local_mvc::{LocalMvc, LocalMvcScratch};
use crate::coords::mvc;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;

/// Cage columns accumulated together in [`project_prior`].
const MASS_BLOCK: usize = 8;

/// Eq. 9 localisation value of vertex weights `own` (ω_ij) and `parent` (ω_if, if any).
/// `reference_floor_power` is `ε^s` for [`JointLocalisation::ReferenceTool`] (unused otherwise):
/// weights at most ε use it instead of a `powf` (same value).
pub(super) fn localisation_value(
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
pub(super) struct Candidate {
    pub(super) vertex: usize,
    pub(super) own: f64,
    pub(super) parent: Option<f64>,
}

/// For every joint j, the vertices with ω_ij ≠ 0 and (unless j is a root) ω_if ≠ 0 — the only
/// ones where the [`JointLocalisation::Articulation`] L_j can be non-zero — in ascending vertex
/// order, from one pass over the rows of Ω.
pub(super) fn articulation_candidates(
    skeleton: &Skeleton,
    skin_weights: &SkinWeights,
) -> Vec<Vec<Candidate>> {
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

/// The prior π_j of Eq. 10 (`mvc_ji · L_ji`, up to a positive factor) as a sparse list
/// `(vertex, π_i)`, and whether it is the unlocalised fallback. Articulation mode goes through
/// [`local_prior`] when a [`LocalMvc`] is available, else (and in ReferenceTool mode) through
/// [`full_prior`].
pub(super) fn joint_prior(
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
pub(super) fn full_prior(j: usize, inputs: &JointInputs) -> (Vec<(usize, f64)>, bool) {
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
pub(super) fn local_prior(
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
pub(super) fn project_prior(prior: &[(usize, f64)], cage_coords: &CageCoords) -> Vec<f64> {
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
