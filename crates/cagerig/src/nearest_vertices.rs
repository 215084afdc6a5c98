//! The k nearest of a set of points, with ties at the cut kept whole, and the one rule that
//! picks a cage vertex's neighbourhood on the skin ([`skin_neighbourhoods`]): the neighbourhoods
//! of the regularised CageUp's prior ([`crate::sync::cage_prior`]) and of the cage quality
//! measures ([`crate::cage_quality`]), the same vertices for both on every skin.
//!
//! On a mirror-symmetric character many distances from a cage vertex to the skin are equal in
//! exact arithmetic. Their computed values then differ only by round-off, which differs from one
//! SIMD tier to another (M = ΦC is rebuilt by each tier's kernels), so a cut through such a tie
//! decided by the computed values picks different vertices on different CPUs, and a cut decided
//! by index picks one side of the mirror. Here every distance within [`TIE_TOLERANCE`] of the
//! k-th is kept: the neighbourhood is the same everywhere and as symmetric as the character.

use glam::DVec3;
use rayon::prelude::*;

/// Rest-skin vertices around a cage vertex ([`skin_neighbourhoods`]): the prior of the
/// regularised CageUp carries the cage vertex by their mean motion, and the cage quality
/// measures compare it with their best-fit rigid motion.
pub const SKIN_NEIGHBOURS: usize = 32;

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

/// N_k for every point of `points` (`#P` lists, each sorted by index; e.g. the rest cage C): its
/// [`SKIN_NEIGHBOURS`] nearest vertices of `skin` (the rest skin M, `#V`), searched among all of
/// them, and every further one as near as the last ([`nearest_with_ties`]: a mirror-symmetric
/// skin gets mirror-symmetric neighbourhoods whatever the round-off of its positions). All of
/// `skin` when it has no more vertices than that. The prior and the measures both take their
/// neighbourhoods from here, so a measure's reference is the motion the prior follows, on a skin
/// of any size. O(#P·#V), parallel over the points.
pub fn skin_neighbourhoods(points: &[DVec3], skin: &[DVec3]) -> Vec<Vec<usize>> {
    let take = SKIN_NEIGHBOURS.min(skin.len());
    points
        .par_iter()
        .map_init(
            || Vec::with_capacity(skin.len()),
            |distances: &mut Vec<(f64, usize)>, point| {
                distances.clear();
                distances.extend(
                    skin.iter()
                        .enumerate()
                        .map(|(v, s)| (s.distance_squared(*point), v)),
                );
                let mut near = nearest_with_ties(distances, take);
                near.sort_unstable();
                near
            },
        )
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

    /// The vertices tied at the cut of a neighbourhood are all in it: of 40 points on a circle
    /// around the point (at one distance, each with its own round-off) all 40, and of points at
    /// 1, 2, … either side, the pair at the cut's distance joins as a pair. The skin is searched
    /// whole, however large.
    #[test]
    fn a_neighbourhood_keeps_every_vertex_tied_at_its_cut() {
        let circle: Vec<DVec3> = (0..40)
            .map(|i| {
                let angle = std::f64::consts::TAU * i as f64 / 40.0;
                DVec3::new(angle.cos(), angle.sin(), 0.0) * 0.7 + DVec3::splat(0.1)
            })
            .collect();
        let near = skin_neighbourhoods(&[DVec3::splat(0.1)], &circle);
        assert_eq!(near[0], (0..40).collect::<Vec<_>>());
        // Two points at each distance 1, 2, … (±x): the cut falls inside the 16th pair.
        let pairs: Vec<DVec3> = (1..=40)
            .flat_map(|d| [DVec3::X * d as f64, -DVec3::X * (d as f64 * (1.0 + 1e-15))])
            .collect();
        let near = skin_neighbourhoods(&[DVec3::ZERO], &pairs);
        assert_eq!(near[0], (0..SKIN_NEIGHBOURS).collect::<Vec<_>>());
        let shifted = &pairs[1..];
        let near = skin_neighbourhoods(&[DVec3::ZERO], shifted);
        assert_eq!(near[0], (0..=SKIN_NEIGHBOURS).collect::<Vec<_>>());
        // A skin of 40,000 points far away and the 32 nearest last: found among them all.
        let mut large: Vec<DVec3> = (0..40_000)
            .map(|i| DVec3::new(10.0 + i as f64 * 1e-3, 0.0, 0.0))
            .collect();
        large.extend((0..SKIN_NEIGHBOURS).map(|i| DVec3::new(0.0, 1.0 + i as f64 * 1e-3, 0.0)));
        let near = skin_neighbourhoods(&[DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0)], &large);
        assert_eq!(
            near[0],
            (40_000..40_000 + SKIN_NEIGHBOURS).collect::<Vec<_>>()
        );
        assert_eq!(near[1], (0..SKIN_NEIGHBOURS).collect::<Vec<_>>());
    }
}
