//! The sign rule of DQS and CoR blending as a per-frame table: `s(p, j) = sign(r_p · r_j)` for
//! every pivot joint `p` and joint `j` (`#J × #J`), so a vertex looks its signs up instead of
//! taking a quaternion dot product per influence. Used when `#J² ≤ #V` (the table costs less to
//! fill than it saves) and `#J ≤ 256` (at most 64 Ki entries); the blends are bit-identical either way (`w · s = w.copysign(r_p · r_j)`
//! for the non-negative weights of Ω).

use super::precision::SkinReal;

/// Most joints for which a table is kept.
const MAX_TABLE_JOINTS: usize = 256;

/// `s(p, j) ∈ {+1, −1}` in precision `S`, row-major by pivot; empty above 256 joints.
#[derive(Debug, Clone)]
pub(crate) struct AntipodalSigns<S> {
    num_joints: usize,
    signs: Vec<S>,
}

impl<S: SkinReal> AntipodalSigns<S> {
    /// Room for a table of `num_joints` joints (none above 256).
    pub fn new(num_joints: usize) -> Self {
        Self {
            num_joints,
            signs: if num_joints <= MAX_TABLE_JOINTS {
                vec![S::ONE; num_joints * num_joints]
            } else {
                Vec::new()
            },
        }
    }

    /// Fills the table from the joint rotations `r_j` (`#J`) when a mesh of `num_vertices`
    /// vertices gains from it; returns whether the kernels are to read it.
    pub fn fill_if_worth_it(
        &mut self,
        num_vertices: usize,
        rotations: impl Fn(usize) -> S::Quat,
    ) -> bool {
        let n = self.num_joints;
        if self.signs.is_empty() || n * n > num_vertices {
            return false;
        }
        for (p, row) in self.signs.chunks_exact_mut(n).enumerate() {
            let r_p = rotations(p);
            for (j, s) in row.iter_mut().enumerate() {
                *s = S::ONE.copysign(S::quat_dot(r_p, rotations(j)));
            }
        }
        true
    }

    /// The signs of pivot `p` against every joint (`#J`).
    #[inline(always)]
    pub fn row(&self, pivot: usize) -> &[S] {
        &self.signs[pivot * self.num_joints..(pivot + 1) * self.num_joints]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn signs_follow_the_dot_products_and_small_meshes_skip_the_table() {
        let rotations = [
            DQuat::IDENTITY,
            -DQuat::from_rotation_z(0.3),
            DQuat::from_rotation_x(3.0),
        ];
        let mut table = AntipodalSigns::<f64>::new(3);
        assert!(table.fill_if_worth_it(9, |j| rotations[j]));
        assert_eq!(table.row(0), &[1.0, -1.0, 1.0]);
        assert_eq!(table.row(1), &[-1.0, 1.0, -1.0]);
        assert!(!AntipodalSigns::<f32>::new(3).fill_if_worth_it(8, |_| glam::Quat::IDENTITY));
        assert!(!AntipodalSigns::<f64>::new(257).fill_if_worth_it(1 << 20, |_| DQuat::IDENTITY));
    }
}
