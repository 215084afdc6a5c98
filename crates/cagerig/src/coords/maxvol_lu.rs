//! The pieces the MaxVol selection and its refinements share ([`super::maxvol`],
//! [`super::maxvol_swaps`], [`super::maxvol_dominance`]): the swap threshold and a sequential
//! row-pivoted LU. A leaf: it imports none of them.

use faer::Mat;

/// Swap while some |B[i, j]| exceeds this (each swap multiplies |det| by at least this).
pub const SWAP_THRESHOLD: f64 = 1.0 + 1e-3;

/// Row-pivoted LU factors (faer) of a tall or square matrix, computed and applied sequentially:
/// faer's global parallelism hands the panels of these `#C`-column factorisations to rayon,
/// which made the whole Arm selection ~7 % slower with 2 threads than with 1.
pub(crate) struct SeqLu {
    /// L (unit lower, below the diagonal) and U (upper) packed, `m × n`.
    packed: Mat<f64>,
    /// Row `forward[k]` of the input is row k of L·U.
    pub(crate) forward: Vec<usize>,
    inverse: Vec<usize>,
}

impl SeqLu {
    pub(crate) fn new(mut packed: Mat<f64>) -> Self {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::linalg::lu::partial_pivoting::factor;
        let (m, n) = packed.shape();
        let mut forward = vec![0usize; m];
        let mut inverse = vec![0usize; m];
        let scratch =
            factor::lu_in_place_scratch::<usize, f64>(m, n, faer::Par::Seq, Default::default());
        let mut buffer = MemBuffer::new(scratch);
        factor::lu_in_place(
            packed.as_mut(),
            &mut forward,
            &mut inverse,
            faer::Par::Seq,
            MemStack::new(&mut buffer),
            Default::default(),
        );
        crate::vector_registers::clear_upper_halves();
        Self {
            packed,
            forward,
            inverse,
        }
    }

    /// U[k, k] for k < min(m, n).
    pub(crate) fn diagonal(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.packed.nrows().min(self.packed.ncols())).map(|k| self.packed[(k, k)])
    }

    /// A⁻¹ of a square A (non-finite entries if A is singular).
    pub(crate) fn inverse(&self) -> Mat<f64> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::linalg::lu::partial_pivoting::solve;
        let n = self.packed.nrows();
        let mut out = Mat::<f64>::identity(n, n);
        let permutation = faer::perm::PermRef::new_checked(&self.forward, &self.inverse, n);
        let mut buffer = MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(
            n,
            n,
            faer::Par::Seq,
        ));
        solve::solve_in_place(
            self.packed.as_ref(),
            self.packed.as_ref(),
            permutation,
            out.as_mut(),
            faer::Par::Seq,
            MemStack::new(&mut buffer),
        );
        out
    }
}
