//! The rotation factor of a 3×3 linear part (polar decomposition), as a unit quaternion.
//!
//! DQS and CoR blend rotations only. When a skinning transform's linear part `T_j^r` is not a
//! rotation (scale, shear), its orthonormal polar factor `Q` (`T^r = Q·P`, `P` symmetric positive
//! semi-definite) is used instead: the closest rotation in the Frobenius norm.

use glam::{DMat3, DQuat};

/// Linear parts within this Frobenius distance of orthonormal skip the polar iteration.
const ORTHONORMAL_TOLERANCE: f64 = 1e-12;
const MAX_POLAR_ITERATIONS: usize = 64;

/// Unit quaternion of the rotation closest to `linear`.
///
/// Rigid input: `DQuat::from_mat3` directly. Otherwise Higham's iteration
/// `Q ← (Q + Q⁻ᵀ)/2` gives the orthonormal polar factor. A reflection (det < 0) has no
/// quaternion: its polar factor `Q` is replaced by `−Q` (a rotation). A singular or non-finite
/// linear part gives the identity. The scalar part is made non-negative.
pub fn rotation_quaternion(linear: DMat3) -> DQuat {
    let orthonormal_error = (linear.transpose() * linear - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt();
    let mut q = linear;
    if orthonormal_error.is_nan() || orthonormal_error > ORTHONORMAL_TOLERANCE {
        let det = linear.determinant();
        if !det.is_finite() || det.abs() < f64::MIN_POSITIVE.sqrt() {
            return DQuat::IDENTITY;
        }
        for _ in 0..MAX_POLAR_ITERATIONS {
            let next = (q + q.inverse().transpose()) * 0.5;
            let change = (next - q)
                .to_cols_array()
                .iter()
                .map(|x| x.abs())
                .sum::<f64>();
            q = next;
            if change < 1e-15 {
                break;
            }
        }
    }
    if q.determinant() < 0.0 {
        q = -q;
    }
    let quat = DQuat::from_mat3(&q).normalize();
    if quat.w < 0.0 { -quat } else { quat }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn rotation_is_kept_and_scale_removed() {
        let r = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 2.1);
        let got = rotation_quaternion(DMat3::from_quat(r));
        assert!(got.abs_diff_eq(r, 1e-14) || got.abs_diff_eq(-r, 1e-14));
        // Q·P with P symmetric positive definite.
        let p = DMat3::from_cols(
            DVec3::new(2.0, 0.3, 0.0),
            DVec3::new(0.3, 1.5, 0.1),
            DVec3::new(0.0, 0.1, 0.7),
        );
        let got = rotation_quaternion(DMat3::from_quat(r) * p);
        assert!(
            got.abs_diff_eq(r, 1e-12) || got.abs_diff_eq(-r, 1e-12),
            "{got:?}"
        );
        assert_eq!(rotation_quaternion(DMat3::ZERO), DQuat::IDENTITY);
    }
}
