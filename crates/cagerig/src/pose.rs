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
//! non-uniformly scaled parent) cannot be posed by this model and is refused.

use glam::{DAffine3, DMat3, DQuat, DVec3};

use crate::error::RigError;

/// A rest local is treated as rigid (scale exactly 1, the paper tool's rigs) when every column
/// length is within this of 1.
const RIGID_TOLERANCE: f64 = 1e-12;

/// Largest |L − T·R·S| (relative to the largest entry of L) accepted when decomposing a rest local.
pub const MAX_SHEAR: f64 = 1e-7;

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
    let det = m.determinant();
    if !det.is_finite() || det.abs() < 1e-300 {
        return Err(RigError::Invalid(format!(
            "joint {joint}: its rest frame relative to its parent is singular (det {det:e})"
        )));
    }
    let (scale, rotation, _) = local.to_scale_rotation_translation();
    let rotation = rotation.normalize();
    let back = DMat3::from_quat(rotation) * DMat3::from_diagonal(scale);
    let size = m.to_cols_array().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let residual = (back - m)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, x| a.max(x.abs()));
    if residual > MAX_SHEAR * size {
        return Err(RigError::Invalid(format!(
            "joint {joint}: its rest frame relative to its parent is sheared (|L − R·S| = {residual:e}, \
             from a non-uniformly scaled parent); the pose model (rotation, scale, translation per \
             joint) cannot represent it"
        )));
    }
    Ok((scale, rotation))
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
