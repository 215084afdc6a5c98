//! The k nearest of a set of points, with ties at the cut kept whole: the neighbourhoods of the
//! regularised CageUp's prior ([`crate::sync::cage_prior`]) and of the cage quality measures
//! ([`crate::cage_quality`]).
//!
//! On a mirror-symmetric character many distances from a cage vertex to the skin are equal in
//! exact arithmetic. Their computed values then differ only by round-off, which differs from one
//! SIMD tier to another (M = ΦC is rebuilt by each tier's kernels), so a cut through such a tie
//! decided by the computed values picks different vertices on different CPUs, and a cut decided
//! by index picks one side of the mirror. Here every distance within [`TIE_TOLERANCE`] of the
//! k-th is kept: the neighbourhood is the same everywhere and as symmetric as the character.

/// Relative difference under which two squared distances are the same distance measured twice
/// with different round-off: round-off (about 1e-16 per operation) stays far below it, and the
/// differences a modeller makes far above it.
pub const TIE_TOLERANCE: f64 = 1e-9;

/// The indices (in `distances`' order after the call; unsorted) of the `take` smallest squared
/// distances of `distances` (`(squared distance, index)` pairs), with every further one within
/// [`TIE_TOLERANCE`] of the `take`-th; all of them when `take` is at least their number.
/// Reorders `distances`; allocates the result only.
pub(crate) fn nearest_with_ties(distances: &mut [(f64, usize)], take: usize) -> Vec<usize> {
    if take == 0 {
        return Vec::new();
    }
    if take >= distances.len() {
        return distances.iter().map(|d| d.1).collect();
    }
    let (_, &mut (cut, _), _) =
        distances.select_nth_unstable_by(take - 1, |a, b| a.0.total_cmp(&b.0));
    let limit = cut + TIE_TOLERANCE * cut.abs();
    distances
        .iter()
        .filter(|d| d.0 <= limit)
        .map(|d| d.1)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted(mut v: Vec<usize>) -> Vec<usize> {
        v.sort_unstable();
        v
    }

    #[test]
    fn without_ties_the_k_nearest() {
        let mut d: Vec<(f64, usize)> = [5.0, 1.0, 4.0, 2.0, 3.0]
            .iter()
            .enumerate()
            .map(|(i, &x)| (x, i))
            .collect();
        assert_eq!(sorted(nearest_with_ties(&mut d, 3)), vec![1, 3, 4]);
        assert_eq!(sorted(nearest_with_ties(&mut d, 9)), vec![0, 1, 2, 3, 4]);
        assert!(nearest_with_ties(&mut d, 0).is_empty());
    }

    #[test]
    fn a_tie_at_the_cut_is_kept_whole_whatever_its_round_off() {
        // 1, then 2 three times with round-off either side, then 3: the 2nd nearest ties with two.
        let mut d = vec![
            (2.0 * (1.0 + 3e-16), 0),
            (1.0, 1),
            (3.0, 2),
            (2.0, 3),
            (2.0 * (1.0 - 2e-16), 4),
        ];
        assert_eq!(sorted(nearest_with_ties(&mut d, 2)), vec![0, 1, 3, 4]);
        // A real difference is not a tie.
        let mut d = vec![(1.0, 0), (2.0, 1), (2.0 * (1.0 + 1e-6), 2)];
        assert_eq!(sorted(nearest_with_ties(&mut d, 2)), vec![0, 1]);
    }
}
