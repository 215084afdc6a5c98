//! The pose model of the current skeleton S'.
//!
//! Joint j's local transform (`parent_from_joint`; roots: `world_from_joint`) is
//!
//! `L_j = Translate(o_j + d_j) · Rotate(q_j) · Scale(s_j)`
//!
//! with `o_j` the rest bone offset (the translation of the rest local `B_parent⁻¹ B_j`, re-derived
//! from the rest skeleton whenever SkelUp moves the rest joints), `q_j` the local rotation, `s_j`
//! the local scale and `d_j` the animated translation offset (for roots: the root motion). SkelUp's
//! rule (Sec. 4.2) is kept: `q_j`, `s_j` and `d_j` survive a rest-cage edit; only `o_j` changes.
//!
//! The paper tool's model is the special case `s_j` = rest scale, `d_j = 0` for non-roots
//! ([`LocalPose::roots_only`]). Rest frames may carry rotation and scale (glTF inverse bind
//! matrices, FBX bind poses); a rest local that is not a rotation times a scale (a shear from a
//! non-uniformly scaled parent) cannot be posed by this model. A shear within float32 noise
//! (relative [`MAX_NOISE_SHEAR`], e.g. inverse bind matrices stored in float32 under non-uniformly
//! scaled parents) is replaced by the nearest rotation-scale frame ([`regularise_rest_frames`]);
//! a larger one is refused.

use glam::{DAffine3, DMat3, DQuat, DVec3};

use crate::error::{RigError, Warning};
use crate::skeleton::Skeleton;

/// A rest local is treated as rigid (scale exactly 1, the paper tool's rigs) when every column
/// length is within this of 1.
const RIGID_TOLERANCE: f64 = 1e-12;

/// Largest |L − T·R·S| (relative to the largest entry of L) accepted when decomposing a rest local.
pub const MAX_SHEAR: f64 = 1e-7;

/// Largest |L − T·R·S| (relative to the largest entry of L) taken as float32 noise in a rest
/// local: [`regularise_rest_frames`] replaces such a frame by its nearest rotation-scale frame.
pub const MAX_NOISE_SHEAR: f64 = 1e-4;

/// A pose of the current skeleton in the model of the module doc; all slices `#J`.
#[derive(Debug, Clone, Copy)]
pub struct LocalPose<'a> {
    /// `q_j`, local rotations (normalised on use).
    pub rotations: &'a [DQuat],
    /// `s_j`, local scales; `None`: the rest scales.
    pub scales: Option<&'a [DVec3]>,
    /// `d_j`, local translation minus the rest bone offset.
    pub translation_offsets: &'a [DVec3],
    /// When true, `translation_offsets` are used for roots only (root motion; the paper tool's
    /// model) and taken as zero for every other joint.
    pub roots_only: bool,
}

/// The rotation part of a linear map (`DQuat::from_mat3` directly when it is rigid, so rigs
/// without scale keep bit-identical rotations).
pub fn rotation_of(m: &DMat3) -> DQuat {
    let lengths = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
    if (lengths - DVec3::ONE).abs().max_element() <= RIGID_TOLERANCE {
        DQuat::from_mat3(m)
    } else {
        DAffine3::from_mat3(*m)
            .to_scale_rotation_translation()
            .1
            .normalize()
    }
}

/// Splits the linear part of rest local `local` of joint `joint` into scale and rotation
/// (`m = R·diag(s)`). Rigid inputs give `s = 1` and `DQuat::from_mat3`. Errors when the part is
/// singular or sheared beyond [`MAX_SHEAR`].
pub fn decompose_rest_local(local: &DAffine3, joint: usize) -> Result<(DVec3, DQuat), RigError> {
    let m = local.matrix3;
    let lengths = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
    if (lengths - DVec3::ONE).abs().max_element() <= RIGID_TOLERANCE {
        return Ok((DVec3::ONE, DQuat::from_mat3(&m)));
    }
    if let Some((residual, _)) = shear_of(local, joint)? {
        return Err(sheared(joint, residual));
    }
    Ok(nearest_rotation_scale(local))
}

/// The rest skeleton S with every rest local whose shear is float noise (above [`MAX_SHEAR`], at
/// most [`MAX_NOISE_SHEAR`], relative) replaced by its nearest rotation-scale frame `R·diag(s)`.
/// Joint positions (the rest frames' translations) are kept exactly; the linear parts of the
/// rest frames below a replaced local are recomposed root-first so that every other local keeps
/// its linear part. A skeleton with no such joint is returned unchanged, bit for bit. Returns the
/// warning naming the worst joint and its residual, if any joint was replaced.
///
/// Errors when a rest local is singular or sheared beyond [`MAX_NOISE_SHEAR`].
pub fn regularise_rest_frames(
    skeleton: &Skeleton,
) -> Result<(Skeleton, Option<Warning>), RigError> {
    let worlds = skeleton.rest_world_from_joint();
    let mut locals = vec![DAffine3::IDENTITY; worlds.len()];
    skeleton.locals_from_worlds(&worlds, &mut locals);
    let mut new_worlds = worlds.clone();
    let mut changed = vec![false; worlds.len()];
    // (joint, residual, relative residual) of the worst replaced local, and how many.
    let mut worst: Option<(usize, f64, f64)> = None;
    let mut replaced = 0usize;
    for &j in skeleton.topological_order() {
        let mut linear = locals[j].matrix3;
        if let Some((residual, relative)) = shear_of(&locals[j], j)? {
            if relative > MAX_NOISE_SHEAR {
                return Err(sheared(j, residual));
            }
            let (scale, rotation) = nearest_rotation_scale(&locals[j]);
            linear = DMat3::from_quat(rotation) * DMat3::from_diagonal(scale);
            changed[j] = true;
            replaced += 1;
            if worst.is_none_or(|(_, _, r)| relative > r) {
                worst = Some((j, residual, relative));
            }
        }
        let parent = skeleton.parent(j);
        if changed[j] || parent.is_some_and(|p| changed[p]) {
            changed[j] = true;
            new_worlds[j].matrix3 = match parent {
                Some(p) => new_worlds[p].matrix3 * linear,
                None => linear,
            };
        }
    }
    let Some((joint, residual, relative)) = worst else {
        return Ok((skeleton.clone(), None));
    };
    let joints = skeleton
        .joints()
        .iter()
        .zip(&new_worlds)
        .map(|(joint, world)| crate::skeleton::Joint {
            rest_world_from_joint: *world,
            ..joint.clone()
        })
        .collect();
    let regularised = Skeleton::new(joints)?;
    let warning = Warning::Note {
        message: format!(
            "{replaced} joint rest frame(s) were sheared within float32 noise and were replaced by the nearest \
             rotation-scale frames (joint positions kept); the worst is joint {joint} \
              \"{}\" (|L − R·S| = {residual:.1e}, {relative:.1e} of the frame's size)",
            skeleton.joint(joint).name
        ),
    };
    Ok((regularised, Some(warning)))
}

/// `m = R·diag(s)` of a non-singular local, rotation normalised.
fn nearest_rotation_scale(local: &DAffine3) -> (DVec3, DQuat) {
    let (scale, rotation, _) = local.to_scale_rotation_translation();
    (scale, rotation.normalize())
}

/// The shear of rest local `local` of joint `joint` when it exceeds [`MAX_SHEAR`]: the residual
/// |L − R·S| and that residual relative to L's largest entry. Errors when L is singular.
fn shear_of(local: &DAffine3, joint: usize) -> Result<Option<(f64, f64)>, RigError> {
    let m = local.matrix3;
    let lengths = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
    if (lengths - DVec3::ONE).abs().max_element() <= RIGID_TOLERANCE {
        return Ok(None);
    }
    let det = m.determinant();
    if !det.is_finite() || det.abs() < 1e-300 {
        return Err(RigError::Invalid(format!(
            "joint {joint}: its rest frame relative to its parent is singular (det {det:e})"
        )));
    }
    let (scale, rotation) = nearest_rotation_scale(local);
    let back = DMat3::from_quat(rotation) * DMat3::from_diagonal(scale);
    let size = m.to_cols_array().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let residual = (back - m)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, x| a.max(x.abs()));
    Ok((residual > MAX_SHEAR * size).then_some((residual, residual / size)))
}

fn sheared(joint: usize, residual: f64) -> RigError {
    RigError::Invalid(format!(
        "joint {joint}: its rest frame relative to its parent is sheared (|L − R·S| = {residual:e}, \
         more than {MAX_NOISE_SHEAR:e} of the frame's size: not float noise, but a non-uniformly \
         scaled parent); the pose model (rotation, scale, translation per joint) cannot represent it"
    ))
}

/// `Translate(t) · Rotate(q) · Scale(s)`.
pub fn local_transform(translation: DVec3, rotation: DQuat, scale: DVec3) -> DAffine3 {
    DAffine3::from_scale_rotation_translation(scale, rotation, translation)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_locals_keep_the_direct_rotation() {
        let local = DAffine3::from_rotation_translation(
            DQuat::from_rotation_y(0.7),
            DVec3::new(1.0, 2.0, 3.0),
        );
        let (s, q) = decompose_rest_local(&local, 0).unwrap();
        assert_eq!(s, DVec3::ONE);
        assert_eq!(q, DQuat::from_mat3(&local.matrix3));
    }

    #[test]
    fn scaled_rotated_locals_recompose_exactly() {
        let q0 = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let s0 = DVec3::new(0.01, 0.02, 0.03);
        let local = local_transform(DVec3::new(4.0, 5.0, 6.0), q0, s0);
        let (s, q) = decompose_rest_local(&local, 3).unwrap();
        assert!(s.abs_diff_eq(s0, 1e-15));
        assert!(q.dot(q0).abs() > 1.0 - 1e-14);
        let back = local_transform(local.translation, q, s);
        assert!(back.abs_diff_eq(local, 1e-14));
        assert!((rotation_of(&local.matrix3).dot(q0)).abs() > 1.0 - 1e-14);
    }

    /// A chain under a non-uniformly scaled, rotated parent whose child frame carries float32
    /// noise (as some exporters' inverse bind matrices do): regularised, positions kept, one
    /// warning; a real shear is refused.
    #[test]
    fn float_noise_shear_is_regularised_and_real_shear_refused() {
        use crate::skeleton::Joint;
        let root = local_transform(
            DVec3::new(0.0, 1.0, 0.0),
            DQuat::from_rotation_z(0.4),
            DVec3::new(1.0, 3.0, 0.5),
        );
        let child_local = local_transform(
            DVec3::new(0.2, 0.7, 0.1),
            DQuat::from_rotation_x(0.9),
            DVec3::ONE,
        );
        let grandchild_local = local_transform(
            DVec3::new(0.0, 0.5, 0.0),
            DQuat::from_rotation_y(0.3),
            DVec3::ONE,
        );
        let noise = |m: DAffine3, e: f64| {
            let mut m = m;
            m.matrix3.y_axis.x += e * m.matrix3.y_axis.length();
            m
        };
        let build = |e: f64| {
            let child = noise(root * child_local, e);
            let grandchild = child * grandchild_local;
            let joint = |name: &str, parent, frame| Joint {
                name: name.into(),
                parent,
                rest_world_from_joint: frame,
            };
            Skeleton::new(vec![
                joint("root", None, root),
                joint("child", Some(0), child),
                joint("grandchild", Some(1), grandchild),
            ])
            .unwrap()
        };
        // Exact frames: unchanged, bit for bit, no warning.
        let exact = build(0.0);
        let (same, warning) = regularise_rest_frames(&exact).unwrap();
        assert_eq!(same, exact);
        assert!(warning.is_none());
        // Float32 noise: every local decomposes afterwards, positions are kept exactly.
        let noisy = build(6e-6);
        let worlds = noisy.rest_world_from_joint();
        let mut locals = vec![DAffine3::IDENTITY; 3];
        noisy.locals_from_worlds(&worlds, &mut locals);
        assert!(decompose_rest_local(&locals[1], 1).is_err());
        let (fixed, warning) = regularise_rest_frames(&noisy).unwrap();
        let message = warning.unwrap().to_string();
        assert!(
            message.contains("joint 1 \"child\"") && message.contains("1 joint"),
            "{message}"
        );
        assert_eq!(fixed.rest_positions(), noisy.rest_positions());
        let worlds = fixed.rest_world_from_joint();
        fixed.locals_from_worlds(&worlds, &mut locals);
        for (j, l) in locals.iter().enumerate() {
            decompose_rest_local(l, j).unwrap();
        }
        // The frames moved by no more than the noise.
        for (a, b) in worlds.iter().zip(noisy.rest_world_from_joint()) {
            assert!(a.abs_diff_eq(b, 1e-4), "{a} vs {b}");
        }
        // A real shear stays an error naming the joint.
        let e = regularise_rest_frames(&build(1e-2))
            .unwrap_err()
            .to_string();
        assert!(e.contains("joint 1") && e.contains("sheared"), "{e}");
    }

    #[test]
    fn sheared_or_singular_locals_are_refused() {
        let shear = DAffine3::from_mat3(DMat3::from_cols(
            DVec3::X,
            DVec3::new(0.5, 1.0, 0.0),
            DVec3::Z,
        ));
        let e = decompose_rest_local(&shear, 7).unwrap_err().to_string();
        assert!(e.contains("joint 7") && e.contains("sheared"), "{e}");
        let flat = DAffine3::from_scale(DVec3::new(1.0, 0.0, 2.0));
        assert!(
            decompose_rest_local(&flat, 2)
                .unwrap_err()
                .to_string()
                .contains("singular")
        );
    }
}
