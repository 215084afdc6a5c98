//! The tool's Euler convention (`.skt`, skeleton animation V2/V3): angles `(rx, ry, rz)` in
//! degrees, frame `T = Translate(t) · Rz(rz) · Ry(ry) · Rx(rx)`.

use glam::{DAffine3, DMat3, DVec3};

/// Tolerance on `RᵀR = I` and `det R = 1` for a matrix to count as a rotation when writing.
pub const ROTATION_TOLERANCE: f64 = 1e-9;

/// `Translate(translation) · Rz · Ry · Rx` with `degrees = (rx, ry, rz)`.
pub fn frame_from_euler_degrees(degrees: DVec3, translation: DVec3) -> DAffine3 {
    let r = DMat3::from_rotation_z(degrees.z.to_radians())
        * DMat3::from_rotation_y(degrees.y.to_radians())
        * DMat3::from_rotation_x(degrees.x.to_radians());
    DAffine3::from_mat3_translation(r, translation)
}

/// Degrees `(rx, ry, rz)` with `R = Rz · Ry · Rx`, or `None` if `rotation` is not a proper
/// rotation (within [`ROTATION_TOLERANCE`]). At gimbal lock (|ry| = 90°) rx is set to 0.
pub fn euler_degrees_from_rotation(rotation: DMat3) -> Option<DVec3> {
    let should_be_identity = rotation.transpose() * rotation;
    if !should_be_identity.abs_diff_eq(DMat3::IDENTITY, ROTATION_TOLERANCE)
        || (rotation.determinant() - 1.0).abs() > ROTATION_TOLERANCE
    {
        return None;
    }
    // Column-major: r_ij = row i, column j.
    let (r00, r10, r20) = (rotation.x_axis.x, rotation.x_axis.y, rotation.x_axis.z);
    let (r01, r11, r21) = (rotation.y_axis.x, rotation.y_axis.y, rotation.y_axis.z);
    let r22 = rotation.z_axis.z;
    let ry = (-r20).clamp(-1.0, 1.0).asin();
    let cos_ry = (r00 * r00 + r10 * r10).sqrt();
    let (rx, rz) = if cos_ry > 1e-12 {
        (r21.atan2(r22), r10.atan2(r00))
    } else {
        (0.0, (-r01).atan2(r11))
    };
    Some(DVec3::new(
        rx.to_degrees(),
        ry.to_degrees(),
        rz.to_degrees(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn composition_order_is_z_y_x() {
        let f = frame_from_euler_degrees(DVec3::new(90.0, 0.0, 90.0), DVec3::new(1.0, 2.0, 3.0));
        // Rx(90) maps y to z; then Rz(90) maps z to z: y -> z. x -> (Rx) x -> (Rz) y.
        assert!(f.transform_vector3(DVec3::Y).abs_diff_eq(DVec3::Z, 1e-15));
        assert!(f.transform_vector3(DVec3::X).abs_diff_eq(DVec3::Y, 1e-15));
        assert_eq!(f.translation, DVec3::new(1.0, 2.0, 3.0));
        let id = frame_from_euler_degrees(DVec3::ZERO, DVec3::ZERO);
        assert_eq!(id, DAffine3::IDENTITY);
    }

    #[test]
    fn euler_round_trip_including_gimbal_lock() {
        for d in [
            DVec3::new(10.0, -20.0, 30.0),
            DVec3::new(-170.0, 80.0, 5.0),
            DVec3::new(0.0, 90.0, 40.0),
            DVec3::new(25.0, -90.0, -60.0),
        ] {
            let r = frame_from_euler_degrees(d, DVec3::ZERO).matrix3;
            let back = euler_degrees_from_rotation(r).unwrap();
            let r2 = frame_from_euler_degrees(back, DVec3::ZERO).matrix3;
            assert!(r.abs_diff_eq(r2, 1e-12), "{d} -> {back}");
        }
        assert!(
            euler_degrees_from_rotation(DMat3::from_diagonal(DVec3::new(2.0, 1.0, 1.0))).is_none()
        );
        assert!(
            euler_degrees_from_rotation(DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0))).is_none()
        );
    }
}
