//! An imported morph-weight animation played as a cage track.
//!
//! A cagerig export with a cage track stores each cage key k as a morph target
//! `Δ_k = ΦC_k − M₀` with animated weights (see [`crate::gltf::export_animation`]). Read back,
//! each target becomes a rest-cage displacement `ΔC_k = P Δ_k[R]`: CageUp's map P (Φ̃⁻¹ on the
//! MaxVol rows R, Φ̃⁺ in least-squares mode) applied to the target's rows, so that `ΦΔC_k`
//! reproduces the target on those rows exactly and everywhere when the target is a cage
//! deformation (for a cagerig export: to the f32 rounding of the file). The cage track then has a
//! key at every key of the animation, with offsets `Σ_k (w_k(t) − w_k^default) ΔC_k` from the
//! rest cage (the default weights are already in M); lerping the keys is lerping the weights,
//! which is what a viewer does with LINEAR weights.
//!
//! Morph targets that are not cage deformations (face shapes, corrective shapes) are reproduced
//! only through the cage; [`MorphCageTrack::worst_residual`] says how far, and callers report it.
//!
//! The skeleton keys of such an export already contain the motion SkelUp gave the rest joints
//! (node transforms `T_j(t)·B_j(0)`): play them with
//! [`cagerig::playback::AnimationPlayer::holding_rest_skeleton`], or the joints move twice.

use cagerig::RigError;
use cagerig::animation::{CageTrack, SkeletonTrack};
use cagerig::session::RigSession;
use glam::DVec3;

use crate::character::MorphTargets;

/// The cage track of a morph-weight animation and how well the cage reproduces the targets.
#[derive(Debug, Clone)]
pub struct MorphCageTrack {
    /// Keys at the skeleton track's key times; offsets from the session's original rest cage.
    pub track: CageTrack,
    /// Largest distance between a morph target and its cage reproduction `ΦΔC_k` over all
    /// vertices and targets (model units).
    pub worst_residual: f64,
    /// The target of `worst_residual`.
    pub worst_target: usize,
}

/// Cage track for `morph_weights` (`#keys × #targets`, row-major, at the keys of `skeleton`)
/// of `morphs` on the session's rig (M already holds the default weights).
pub fn morph_cage_track(
    session: &RigSession,
    morphs: &MorphTargets,
    skeleton: &SkeletonTrack,
    morph_weights: &[f64],
) -> Result<MorphCageTrack, RigError> {
    let (targets, default_weights) = (&morphs.displacements, &morphs.default_weights);
    let nv = session.num_vertices();
    let nc = session.rest_cage().len();
    let num_targets = targets.len();
    let times = skeleton.times();
    if let Some(bad) = targets.iter().find(|t| t.len() != nv) {
        return Err(RigError::SizeMismatch {
            what: "morph target displacements (one per skin vertex)",
            expected: nv,
            actual: bad.len(),
        });
    }
    if morph_weights.len() != times.len() * num_targets {
        return Err(RigError::SizeMismatch {
            what: "morph weights (#keys × #targets)",
            expected: times.len() * num_targets,
            actual: morph_weights.len(),
        });
    }
    let updater = session.cage_updater();
    let mut rows = Vec::with_capacity(updater.rows().len());
    let mut reproduced = vec![DVec3::ZERO; nv];
    let mut cage_deltas = Vec::with_capacity(num_targets);
    let (mut worst_residual, mut worst_target) = (0.0f64, 0);
    for (k, target) in targets.iter().enumerate() {
        rows.clear();
        rows.extend(updater.rows().iter().map(|&r| target[r]));
        let mut delta = vec![DVec3::ZERO; nc];
        updater.apply_rows(&rows, &mut delta);
        session.cage_coords().apply(&delta, &mut reproduced);
        let residual = reproduced
            .iter()
            .zip(target)
            .fold(0.0f64, |m, (a, b)| m.max(a.distance(*b)));
        if residual > worst_residual {
            (worst_residual, worst_target) = (residual, k);
        }
        cage_deltas.push(delta);
    }
    let offsets: Vec<Vec<DVec3>> = morph_weights
        .chunks_exact(num_targets.max(1))
        .take(times.len())
        .map(|weights| {
            let mut offset = vec![DVec3::ZERO; nc];
            for (k, delta) in cage_deltas.iter().enumerate() {
                let w = weights[k] - default_weights.get(k).copied().unwrap_or(0.0);
                if w != 0.0 {
                    for (o, d) in offset.iter_mut().zip(delta) {
                        *o += w * *d;
                    }
                }
            }
            offset
        })
        .collect();
    let offsets = if num_targets == 0 {
        vec![vec![DVec3::ZERO; nc]; times.len()]
    } else {
        offsets
    };
    let track = CageTrack::new(times.to_vec(), offsets)
        .map_err(|e| RigError::Invalid(format!("cage track from the morph weights: {e}")))?;
    Ok(MorphCageTrack {
        track,
        worst_residual,
        worst_target,
    })
}
