//! How the translations of the skinning transforms move with the rest joint positions, the
//! rotations and scales held fixed: the K_A of the Green CageRev (`sync/green_cage_fit/reverser.rs`).

use glam::{DAffine3, DMat3};

use super::Skeleton;

impl Skeleton {
    /// ∂t_j/∂A_k into `out` (`#J × #J` blocks, block (j, k) at `j·#J + k`): the derivative of the
    /// translation t_j of the skinning transform T_j (`posed_from_rest[j]`, `#J`, Eq. 1) with
    /// respect to the rest position A_k of joint k, for the pose's local rotations, scales and
    /// translation offsets and the rest frames' linear parts held fixed. Zero unless k is j or
    /// one of its ancestors.
    ///
    /// With P_j the posed world frame, L_j the rest frame's linear part and M_j = P_j.linear·L_j⁻¹
    /// (T_j's linear part), the joint's local translation is its rest offset L_p⁻¹(A_j − A_p)
    /// plus a fixed offset, so down the hierarchy
    ///
    /// `τ_j = τ_p + M_p (A_j − A_p) + const` (τ_j the translation of P_j; a root's τ_r = A_r + const),
    /// `t_j = τ_j − M_j A_j`,
    ///
    /// affine in the rest positions: with G_j(k) = ∂τ_j/∂A_k, G_r(k) = δ_rk I,
    /// G_j(k) = G_p(k) + M_p (δ_jk − δ_pk), and ∂t_j/∂A_k = G_j(k) − δ_jk M_j. O(#J²) 3 × 3
    /// blocks, against #J forward kinematics per coordinate by differences.
    ///
    /// # Panics
    /// If `posed_from_rest` is not `#J` long or `out` not `#J²`.
    pub fn skinning_translation_jacobian(&self, posed_from_rest: &[DAffine3], out: &mut [DMat3]) {
        let n = self.len();
        assert_eq!(posed_from_rest.len(), n, "skinning transforms");
        assert_eq!(out.len(), n * n, "translation Jacobian blocks");
        // G first (parents before children), then the −M_j on the diagonal.
        for &j in self.topological_order() {
            match self.parent(j) {
                None => {
                    out[j * n..(j + 1) * n].fill(DMat3::ZERO);
                    out[j * n + j] = DMat3::IDENTITY;
                }
                Some(p) => {
                    out.copy_within(p * n..(p + 1) * n, j * n);
                    let linear = posed_from_rest[p].matrix3;
                    out[j * n + j] += linear;
                    out[j * n + p] -= linear;
                }
            }
        }
        for (j, transform) in posed_from_rest.iter().enumerate() {
            out[j * n + j] -= transform.matrix3;
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{DQuat, DVec3};

    use super::*;
    use crate::pose::local_transform;
    use crate::skeleton::Joint;

    /// T for rest positions `rest` (rest frames' linear parts from `skeleton`), local rotations,
    /// scales and offsets as the session poses them.
    fn skinning_transforms_at(
        skeleton: &Skeleton,
        rest: &[DVec3],
        rotations: &[DQuat],
        scales: &[DVec3],
        offsets: &[DVec3],
    ) -> Vec<DAffine3> {
        let n = skeleton.len();
        let rest_world: Vec<DAffine3> = (0..n)
            .map(|j| {
                let mut frame = skeleton.joint(j).rest_world_from_joint;
                frame.translation = rest[j];
                frame
            })
            .collect();
        let locals: Vec<DAffine3> = (0..n)
            .map(|j| {
                let rest_offset = match skeleton.parent(j) {
                    Some(p) => rest_world[p].inverse().transform_point3(rest[j]),
                    None => rest[j],
                };
                local_transform(rest_offset + offsets[j], rotations[j], scales[j])
            })
            .collect();
        let mut posed_world = vec![DAffine3::IDENTITY; n];
        skeleton.forward_kinematics(&locals, &mut posed_world);
        let mut out = vec![DAffine3::IDENTITY; n];
        Skeleton::skinning_transforms(&rest_world, &posed_world, &mut out);
        out
    }

    #[test]
    fn matches_differences_of_the_forward_kinematics() {
        // Two roots; a chain with a branch; rest frames rotated and scaled; a pose with
        // rotations, non-uniform scales and translation offsets.
        let parents = [None, Some(0), Some(1), Some(1), Some(3), None, Some(5)];
        let joints: Vec<Joint> = parents
            .iter()
            .enumerate()
            .map(|(j, &parent)| Joint {
                name: format!("j{j}"),
                parent,
                rest_world_from_joint: DAffine3::from_scale_rotation_translation(
                    DVec3::new(1.0 + 0.1 * j as f64, 0.9, 1.2),
                    DQuat::from_euler(glam::EulerRot::XYZ, 0.3 * j as f64, -0.2, 0.1 * j as f64),
                    DVec3::new(j as f64, 0.5 * (j * j) as f64, -0.3 * j as f64),
                ),
            })
            .collect();
        let skeleton = Skeleton::new(joints).unwrap();
        let n = skeleton.len();
        let rest = skeleton.rest_positions();
        let rotations: Vec<DQuat> = (0..n)
            .map(|j| {
                DQuat::from_euler(
                    glam::EulerRot::ZYX,
                    0.4 - 0.1 * j as f64,
                    0.7,
                    0.05 * j as f64,
                )
            })
            .collect();
        let scales: Vec<DVec3> = (0..n)
            .map(|j| DVec3::new(1.0, 1.1 + 0.05 * j as f64, 0.8))
            .collect();
        let offsets: Vec<DVec3> = (0..n)
            .map(|j| DVec3::new(0.1 * j as f64, 0.0, -0.2))
            .collect();
        let base = skinning_transforms_at(&skeleton, &rest, &rotations, &scales, &offsets);
        let mut jacobian = vec![DMat3::ZERO; n * n];
        skeleton.skinning_translation_jacobian(&base, &mut jacobian);
        // The translations are affine in the rest positions: a unit difference is exact up to
        // round-off.
        for k in 0..n {
            for c in 0..3 {
                let mut moved = rest.clone();
                moved[k][c] += 1.0;
                let after =
                    skinning_transforms_at(&skeleton, &moved, &rotations, &scales, &offsets);
                for j in 0..n {
                    let difference = after[j].translation - base[j].translation;
                    let analytic = jacobian[j * n + k].col(c);
                    assert!(
                        difference.abs_diff_eq(analytic, 1e-11 * (1.0 + difference.length())),
                        "∂t_{j}/∂A_{k}[{c}]: {difference} by differences, {analytic} analytic"
                    );
                    // Zero outside the ancestors.
                    let mut ancestor = Some(j);
                    while ancestor.is_some_and(|a| a != k) {
                        ancestor = ancestor.and_then(|a| skeleton.parent(a));
                    }
                    if ancestor.is_none() {
                        assert_eq!(analytic, DVec3::ZERO, "∂t_{j}/∂A_{k}");
                    }
                }
            }
        }
    }
}
