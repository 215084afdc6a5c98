//! The sign rule of DQS and CoR blending as a per-frame table: `s(p, j) = sign(r_p · r_j)` for
//! every pivot joint `p` and joint `j` (`#J × #J`), so a vertex looks its signs up instead of
//! taking a quaternion dot product per influence. Only the (pivot, joint) pairs that occur in Ω
//! are filled, each frame; the table is used when there are at most `#V` of them (it then costs
//! less to fill than it saves) and `#J ≤ 256` (at most 64 Ki entries); the blends are bit-identical either way (`w · s = w.copysign(r_p · r_j)`
//! for the non-negative weights of Ω).

use super::precision::SkinReal;

/// Most joints for which a table is kept.
pub(crate) const MAX_TABLE_JOINTS: usize = 256;

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

    /// Fills the entries `pairs` (`pivot · #J + joint`, see
    /// [`super::compact_weights::CountSortedWeights::sign_pairs`]) from the joint rotations
    /// `r_j` (`#J`) when a mesh of `num_vertices` vertices gains from it; returns whether the
    /// kernels are to read the table (other entries are never read).
    pub fn fill_if_worth_it(
        &mut self,
        pairs: &[u32],
        num_vertices: usize,
        rotations: impl Fn(usize) -> S::Quat,
    ) -> bool {
        let n = self.num_joints;
        if self.signs.is_empty() || pairs.is_empty() || pairs.len() > num_vertices {
            return false;
        }
        for &pair in pairs {
            let pair = pair as usize;
            let (p, j) = (pair / n, pair % n);
            self.signs[pair] = S::ONE.copysign(S::quat_dot(rotations(p), rotations(j)));
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
        let all: Vec<u32> = (0..9).collect();
        let mut table = AntipodalSigns::<f64>::new(3);
        assert!(table.fill_if_worth_it(&all, 9, |j| rotations[j]));
        assert_eq!(table.row(0), &[1.0, -1.0, 1.0]);
        assert_eq!(table.row(1), &[-1.0, 1.0, -1.0]);
        // Only the listed pairs are filled.
        let mut table = AntipodalSigns::<f64>::new(3);
        assert!(table.fill_if_worth_it(&[1, 5], 9, |j| rotations[j]));
        assert_eq!((table.row(0)[1], table.row(1)[2]), (-1.0, -1.0));
        assert_eq!(table.row(2), &[1.0, 1.0, 1.0]);
        // Not worth it: more pairs than vertices; too many joints for a table.
        let none = |_| glam::Quat::IDENTITY;
        assert!(!AntipodalSigns::<f32>::new(3).fill_if_worth_it(&all, 8, none));
        assert!(
            !AntipodalSigns::<f64>::new(257).fill_if_worth_it(&[0], 1 << 20, |_| DQuat::IDENTITY)
        );
    }
}
