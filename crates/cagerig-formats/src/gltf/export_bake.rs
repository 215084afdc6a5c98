//! `--bake`: a DQS / CoR result carried by a glTF file as one morph target per sample.
//!
//! glTF skins with LBS only. A viewer computes, for vertex v at a sample time t_k,
//! `p_v = A_v(t_k) · (x_v(t_k) + b_{k,v})`, where `x_v(t)` is the file's bind shape at t (M₀ plus
//! the cage-key targets at their weights), `A_v = Σ_j ω_vj T_j` the blend of the skinning
//! transforms (`G_j · IBM_j = T_j`, see [`super::export_animation`]) and `b_{k,v}` the baked
//! target k, whose weight is 1 at t_k and 0 at every other sample. glTF adds morph targets
//! *before* skinning, so the world-space difference `δ_v = M'_v − A_v x_v` between cagerig's
//! displayed skin M' (DQS / CoR) and the viewer's LBS is pulled back through the linear part
//! `L_v` of `A_v`: `b_{k,v} = L_v⁻¹ δ_v`. Then `p_v = A_v x_v + L_v b_{k,v} = M'_v`.
//!
//! `L_v` is a weighted sum of rotations (times scales): it is singular only where the blended
//! rotations cancel along some axis (two influences half-and-half, turned 180° apart: the LBS
//! "candy wrapper" collapse). Where its normalised determinant is below [`SINGULAR_DETERMINANT`]
//! the target is the damped least-squares solution `(LᵀL + λI)⁻¹ Lᵀ δ` (bounded, exact on the
//! directions `L_v` keeps) and the vertex is counted; every target is measured after its f32
//! rounding (`‖L_v · f32(b) − δ_v‖`), and the worst is reported, so a caller can say how far the
//! file is from M' at the samples.

use cagerig::session::RigSession;
use glam::{DMat3, DVec3};
use serde_json::{Value, json};

use super::export::{Builder, position_accessor, session_to_gltf};

/// A blended linear part whose `|det L| / (‖L‖_F / √3)³` is below this is treated as singular
/// (1 for a rotation; the ratio is scale-free).
pub const SINGULAR_DETERMINANT: f64 = 1e-9;

/// What the baking measured over all samples.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BakeReport {
    /// Number of baked targets (one per sample).
    pub samples: usize,
    /// Largest `‖L_v · f32(b) − δ_v‖` over vertices and samples (model units): how far a viewer
    /// is from cagerig's M' at the samples, beyond the f32 rounding of the rest of the file.
    pub worst_residual: f64,
    /// Largest correction `‖δ_v‖` (model units): how far the viewer's LBS alone would be.
    pub largest_correction: f64,
    /// Vertex-samples whose blended matrix was singular (damped least squares used).
    pub singular: usize,
}

/// The rounding glTF applies to a position: to f32 and back.
pub(crate) fn f32_rounded(p: DVec3) -> DVec3 {
    DVec3::new(
        f64::from(p.x as f32),
        f64::from(p.y as f32),
        f64::from(p.z as f32),
    )
}

/// The baked target of the session's current state (`#V`, bind space) into `out`, given the
/// file's bind shape at this time `bind_shape` (`#V`); `report` accumulates the measures.
/// `M'` is `session.posed_mesh()` (the session's method), `T_j` `session.posed_from_rest()`.
pub(crate) fn bake_target(
    session: &RigSession,
    bind_shape: &[DVec3],
    out: &mut Vec<DVec3>,
    report: &mut BakeReport,
) {
    let transforms = session.posed_from_rest();
    let weights = session.skin_weights();
    let posed = session.posed_mesh();
    out.clear();
    for (v, (&x, &target)) in bind_shape.iter().zip(posed).enumerate() {
        let (joints, ws) = weights.row(v);
        let sum: f64 = ws.iter().sum();
        let mut linear = DMat3::ZERO;
        let mut translation = DVec3::ZERO;
        if sum > 0.0 {
            for (&j, &w) in joints.iter().zip(ws) {
                let t = &transforms[j as usize];
                linear += t.matrix3 * (w / sum);
                translation += t.translation * (w / sum);
            }
        }
        let delta = target - (linear * x + translation);
        let (correction, singular) = pull_back(&linear, delta);
        let stored = f32_rounded(correction);
        report.worst_residual = report
            .worst_residual
            .max((linear * stored - delta).length());
        report.largest_correction = report.largest_correction.max(delta.length());
        report.singular += usize::from(singular);
        out.push(correction);
    }
    report.samples += 1;
}

/// The glTF document (JSON and binary chunk) of the session's current state, as
/// [`session_to_gltf`] writes it, with its skinning result baked: under DQS, CoR or the blended
/// method one morph target (the correction [`bake_target`] computes for the current pose), whose
/// default weight is 1, so that a viewer shows cagerig's M' without playing anything. The mesh's
/// `extras` name the target and mark it baked (`cagerig_baked_skinning`), so cagerig's importer
/// leaves it out. Under LBS nothing needs baking: the plain document and an empty report.
pub fn baked_state_to_gltf(
    session: &RigSession,
    name: &str,
) -> Result<(Value, Vec<u8>, BakeReport), String> {
    let (mut document, bin) = session_to_gltf(session, name)?;
    if session.skinning().is_linear() {
        return Ok((document, bin, BakeReport::default()));
    }
    let mut b = Builder::from_document(&document, bin);
    let bind_shape: Vec<DVec3> = session
        .rest_mesh()
        .iter()
        .copied()
        .map(f32_rounded)
        .collect();
    let (mut correction, mut report) = (Vec::new(), BakeReport::default());
    bake_target(session, &bind_shape, &mut correction, &mut report);
    let target = position_accessor(&mut b, &correction, true);
    let mesh = &mut document["meshes"][0];
    mesh["primitives"][0]["targets"] = json!([{ "POSITION": target }]);
    mesh["weights"] = json!([1.0]);
    mesh["extras"] = json!({
        "targetNames": [format!("{} (current pose)", session.skinning().label())],
        "cagerig_baked_skinning": {"method": session.skinning().name(), "first_target": 0},
    });
    let (document, bin) = b.finish(document);
    Ok((document, bin, report))
}

/// `L⁻¹ δ`, or the damped least-squares `(LᵀL + λI)⁻¹ Lᵀ δ` (λ = 1e-12 · ‖L‖_F²) when `L` is
/// singular by [`SINGULAR_DETERMINANT`]; the flag says which.
fn pull_back(linear: &DMat3, delta: DVec3) -> (DVec3, bool) {
    let norm2 = [linear.x_axis, linear.y_axis, linear.z_axis]
        .iter()
        .map(|c| c.length_squared())
        .sum::<f64>();
    let scale = (norm2 / 3.0).sqrt();
    let det = linear.determinant();
    if scale > 0.0 && det.abs() > SINGULAR_DETERMINANT * scale.powi(3) {
        return (linear.inverse() * delta, false);
    }
    let lambda = 1e-12 * norm2.max(f64::MIN_POSITIVE);
    let normal = linear.transpose() * *linear + DMat3::from_diagonal(DVec3::splat(lambda));
    (normal.inverse() * (linear.transpose() * delta), true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use std::f64::consts::PI;

    #[test]
    fn an_invertible_blend_is_inverted_exactly() {
        let l = DMat3::from_quat(DQuat::from_rotation_y(0.7)) * 0.5
            + DMat3::from_quat(DQuat::from_rotation_x(-1.2)) * 0.5;
        let delta = DVec3::new(0.3, -0.2, 0.1);
        let (b, singular) = pull_back(&l, delta);
        assert!(!singular);
        assert!((l * b - delta).length() < 1e-14);
    }

    /// Two halves turned 180° apart about y cancel x and z: singular, and the damped solution
    /// keeps the direction L keeps (y) exactly and stays bounded.
    #[test]
    fn a_collapsed_blend_is_solved_in_least_squares() {
        let l = DMat3::IDENTITY * 0.5 + DMat3::from_quat(DQuat::from_rotation_y(PI)) * 0.5;
        let delta = DVec3::new(0.3, -0.2, 0.1);
        let (b, singular) = pull_back(&l, delta);
        assert!(singular);
        assert!(b.is_finite() && b.length() < 1.0, "{b}");
        assert!(((l * b).y - delta.y).abs() < 1e-9, "{}", (l * b).y);
    }
}
