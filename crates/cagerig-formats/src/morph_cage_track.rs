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
//! A Green-coordinates rig (M = φC + ψ·g(C), not linear in C) fits each key's cage instead:
//! C_k is CageUp's Gauss–Newton fit of the rest rows M₀[R] + Δ_k[R], exact when the target is a
//! Green deformation (a cagerig export of a Green rig), and its reproduction is M(C_k) − M₀.
//! Where that fit does not converge (a key that folds the cage, far from the rest cage), the
//! key's cage is the vertex part's linear fit P·(M₀ + Δ_k)[R], and the residual says how far it
//! is.
//!
//! Morph targets that are not cage deformations (face shapes, corrective shapes) are reproduced
//! only through the cage; [`MorphCageTrack::worst_residual`] says how far, and callers report it.
//!
//! The skeleton keys of such an export already contain the motion SkelUp gave the rest joints
//! (node transforms `T_j(t)·B_j(0)`): play them with
//! [`cagerig::playback::AnimationPlayer::holding_rest_skeleton`], or the joints move twice.

use cagerig::animation::{CageTrack, SkeletonTrack};
use cagerig::session::RigSession;
use cagerig::{CoordsKind, RigError};
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
    /// The rest bounding-box diagonal of the session's M, the scale of `worst_residual`.
    pub diagonal: f64,
}

/// A target reproduced through the cage within this fraction of the diagonal is a cage
/// deformation (a cagerig export's targets come back to ≤ 5e-8: the f32 rounding of the file).
pub const REPRODUCED_FRACTION: f64 = 1e-5;

impl MorphCageTrack {
    /// The warning to show when some target is not a deformation of the cage (its cage
    /// reproduction is off by more than [`REPRODUCED_FRACTION`] of the diagonal), else `None`.
    pub fn warning(&self) -> Option<String> {
        (self.worst_residual > REPRODUCED_FRACTION * self.diagonal).then(|| {
            format!(
                "morph target {} is not a deformation of the cage: played through the cage, it \
                 is off by up to {:.3e} ({:.2e} of the diagonal)",
                self.worst_target,
                self.worst_residual,
                self.worst_residual / self.diagonal.max(f64::MIN_POSITIVE)
            )
        })
    }
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
    // Green rigs: M(C) is not linear in C, so each target's cage is fitted to the rows of
    // M₀ + Δ_k (from the rest cage C₀) and its reproduction is M(C_k) − M₀.
    let rest_cage = session.original_rest_cage();
    let mut rest_mesh = vec![DVec3::ZERO; nv];
    let mut cage = vec![DVec3::ZERO; nc];
    match session.coords_kind() {
        CoordsKind::Mvc => {}
        CoordsKind::Green => session.rest_mesh_for_cage(rest_cage, &mut rest_mesh)?,
    }
    for (k, target) in targets.iter().enumerate() {
        rows.clear();
        let mut delta = vec![DVec3::ZERO; nc];
        match session.coords_kind() {
            CoordsKind::Mvc => {
                rows.extend(updater.rows().iter().map(|&r| target[r]));
                updater.apply_rows(&rows, &mut delta);
                session.cage_coords().apply(&delta, &mut reproduced);
            }
            CoordsKind::Green => {
                rows.extend(updater.rows().iter().map(|&r| rest_mesh[r] + target[r]));
                cage.copy_from_slice(rest_cage);
                if session.rest_cage_from_rows(&rows, &mut cage).is_err() {
                    // No Green cage reproduces the target (or the fit did not reach it): the
                    // vertex part's linear fit, reported through `worst_residual` like any
                    // target the cage does not reproduce.
                    updater.apply_rows(&rows, &mut cage);
                }
                for ((d, c), c0) in delta.iter_mut().zip(&cage).zip(rest_cage) {
                    *d = *c - *c0;
                }
                session.rest_mesh_for_cage(&cage, &mut reproduced)?;
                for (r, m0) in reproduced.iter_mut().zip(&rest_mesh) {
                    *r -= *m0;
                }
            }
        }
        let residual = reproduced
            .iter()
            .zip(target)
            .fold(0.0f64, |m, (a, b)| m.max(a.distance(*b)));
        if residual > worst_residual {
            (worst_residual, worst_target) = (residual, k);
        }
        cage_deltas.push(delta);
    }
    let offsets: Vec<Vec<DVec3>> = (0..times.len())
        .map(|key| {
            let weights = &morph_weights[key * num_targets..][..num_targets];
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
    let track = CageTrack::new(times.to_vec(), offsets)
        .map_err(|e| RigError::Invalid(format!("cage track from the morph weights: {e}")))?;
    let (lo, hi) = cagerig::mesh::bounding_box(session.rest_mesh());
    Ok(MorphCageTrack {
        track,
        worst_residual,
        worst_target,
        diagonal: (hi - lo).length(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use cagerig::session::{RigParts, SessionOptions};
    use glam::DAffine3;

    fn bar() -> RigSession {
        let rig = cagerig::demo::builtin("bar", Some(8)).unwrap();
        let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        RigSession::new(parts, SessionOptions::default()).unwrap().0
    }

    /// A track of `times` (rest pose keys) for the session's skeleton.
    fn still_track(session: &RigSession, times: &[f64]) -> SkeletonTrack {
        let nj = session.skeleton().len();
        SkeletonTrack::new(
            times.to_vec(),
            vec![vec![DAffine3::IDENTITY; nj]; times.len()],
        )
        .unwrap()
    }

    /// Targets that are cage deformations (ΦΔC) come back as exactly those cage
    /// displacements, weighted per key and relative to the default weights already in M.
    #[test]
    fn cage_deformation_targets_become_their_cage_offsets() {
        let session = bar();
        let nc = session.rest_cage().len();
        let cage_deltas: Vec<Vec<DVec3>> = (0..2)
            .map(|k| {
                (0..nc)
                    .map(|i| {
                        DVec3::new(
                            0.01 * (i % 3) as f64,
                            0.02 * k as f64,
                            -0.01 * (i % 2) as f64,
                        )
                    })
                    .collect()
            })
            .collect();
        let displacements: Vec<Vec<DVec3>> = cage_deltas
            .iter()
            .map(|d| {
                let mut out = vec![DVec3::ZERO; session.num_vertices()];
                session.cage_coords().apply(d, &mut out);
                out
            })
            .collect();
        let morphs = MorphTargets {
            displacements,
            default_weights: vec![0.25, 0.0],
        };
        let skeleton = still_track(&session, &[0.0, 1.0]);
        // Key 0: weights (0.25, 0) = the defaults → no offset; key 1: (1, 0.5).
        let weights = [0.25, 0.0, 1.0, 0.5];
        let fit = morph_cage_track(&session, &morphs, &skeleton, &weights).unwrap();
        assert!(fit.worst_residual < 1e-12, "{}", fit.worst_residual);
        assert_eq!(fit.warning(), None);
        assert_eq!(fit.track.times(), &[0.0, 1.0]);
        let offsets = fit.track.offsets();
        assert!(offsets[0].iter().all(|o| o.length() < 1e-12));
        for (i, o) in offsets[1].iter().enumerate() {
            let expected = cage_deltas[0][i] * 0.75 + cage_deltas[1][i] * 0.5;
            assert!(
                o.distance(expected) < 1e-12,
                "cage vertex {i}: {o} vs {expected}"
            );
        }
    }

    /// A target the cage cannot make (one vertex pushed alone) is reported by its residual, and
    /// mismatched sizes are errors naming what was expected.
    #[test]
    fn other_targets_are_measured_and_sizes_checked() {
        let session = bar();
        let nv = session.num_vertices();
        let mut bump = vec![DVec3::ZERO; nv];
        bump[nv / 2] = DVec3::new(0.0, 0.5, 0.0);
        let morphs = MorphTargets {
            displacements: vec![vec![DVec3::ZERO; nv], bump],
            default_weights: Vec::new(),
        };
        let skeleton = still_track(&session, &[0.0]);
        let fit = morph_cage_track(&session, &morphs, &skeleton, &[0.0, 1.0]).unwrap();
        assert_eq!(fit.worst_target, 1);
        assert!(fit.worst_residual > 0.05, "{}", fit.worst_residual);
        let w = fit.warning().expect("a warning");
        assert!(w.contains("morph target 1 is not a deformation"), "{w}");
        let e = morph_cage_track(&session, &morphs, &skeleton, &[0.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("morph weights"), "{e}");
        let short = MorphTargets {
            displacements: vec![vec![DVec3::ZERO; nv - 1]],
            default_weights: Vec::new(),
        };
        let e = morph_cage_track(&session, &short, &skeleton, &[0.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("morph target"), "{e}");
    }
}
