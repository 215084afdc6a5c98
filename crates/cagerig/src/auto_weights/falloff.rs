//! Per-vertex weights from per-joint distances: an inverse-power falloff, the strongest
//! `max_influences` kept, continuously.
//!
//! For vertex v with distances d_j (each at least `floor`), `w_j = (d_min / d_j)^p`. The
//! `k = max_influences` largest are kept and the (k+1)-th largest is subtracted from each of
//! them before normalising, so a joint's weight fades to exactly zero as it leaves the top k
//! instead of jumping (the weights stay continuous across the surface). Weights below
//! [`PRUNE`] of the row are dropped, and the row is normalised to sum to 1.

use rayon::prelude::*;

/// Weights below this fraction of their row's sum are dropped.
pub const PRUNE: f64 = 1e-4;

/// Sparse rows `(joint, weight)` (`#V` rows, weights > 0 summing to 1, at most
/// `max_influences` each, joints ascending) from `distances[k][v]`, the distance of vertex v
/// to joint `joints[k]` (`#deforming joints × #V`, finite, ≥ 0).
pub fn falloff_rows(
    joints: &[usize],
    distances: &[Vec<f64>],
    num_vertices: usize,
    max_influences: usize,
    exponent: f64,
    floor: f64,
) -> Vec<Vec<(usize, f64)>> {
    (0..num_vertices)
        .into_par_iter()
        .map(|v| {
            let d: Vec<f64> = distances.iter().map(|row| row[v].max(floor)).collect();
            row_weights(joints, &d, max_influences, exponent)
        })
        .collect()
}

/// One row of [`falloff_rows`] from the distances `d` (`#deforming joints`, each ≥ floor > 0).
fn row_weights(
    joints: &[usize],
    d: &[f64],
    max_influences: usize,
    exponent: f64,
) -> Vec<(usize, f64)> {
    let d_min = d.iter().copied().fold(f64::INFINITY, f64::min);
    if !d_min.is_finite() || d.is_empty() {
        return Vec::new();
    }
    let mut w: Vec<(usize, f64)> = joints
        .iter()
        .zip(d)
        .map(|(&j, &dj)| (j, (d_min / dj).powf(exponent)))
        .collect();
    w.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let k = max_influences.min(w.len());
    let cut = w.get(k).map_or(0.0, |x| x.1);
    w.truncate(k);
    for x in &mut w {
        x.1 -= cut;
    }
    let mut sum: f64 = w.iter().map(|x| x.1).sum();
    if sum <= 0.0 {
        // The k+1 strongest are tied: share equally among the k kept.
        w.iter_mut().for_each(|x| x.1 = 1.0);
        sum = w.len() as f64;
    }
    w.retain(|x| x.1 > PRUNE * sum);
    let kept: f64 = w.iter().map(|x| x.1).sum();
    w.iter_mut().for_each(|x| x.1 /= kept);
    w.sort_by_key(|x| x.0);
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn nearest_joint_dominates_and_equal_distances_share() {
        let r = row_weights(&[0, 1, 2], &[1.0, 2.0, 8.0], 4, 2.0);
        assert_eq!(r.len(), 3);
        assert!(r[0].1 > r[1].1 && r[1].1 > r[2].1);
        let r = row_weights(&[3, 7], &[2.0, 2.0], 4, 4.0);
        assert_eq!(r, vec![(3, 0.5), (7, 0.5)]);
    }

    #[test]
    fn the_fifth_joint_fades_out_continuously() {
        // Joint 4's distance moves past joint 3's: its weight goes to zero without a jump.
        let joints = [0, 1, 2, 3, 4];
        let before = row_weights(&joints, &[1.0, 1.5, 2.0, 3.0, 3.0 + 1e-9], 4, 2.0);
        let after = row_weights(&joints, &[1.0, 1.5, 2.0, 3.0 + 1e-9, 3.0], 4, 2.0);
        let get = |r: &[(usize, f64)], j| r.iter().find(|x| x.0 == j).map_or(0.0, |x| x.1);
        for j in joints {
            assert!((get(&before, j) - get(&after, j)).abs() < 1e-6, "joint {j}");
        }
    }

    proptest! {
        #[test]
        fn rows_are_a_partition_of_unity_with_few_influences(
            d in proptest::collection::vec(0.01f64..100.0, 1..12),
            k in 1usize..6,
            p in 0.5f64..8.0,
        ) {
            let joints: Vec<usize> = (0..d.len()).collect();
            let r = row_weights(&joints, &d, k, p);
            prop_assert!(!r.is_empty() && r.len() <= k);
            let sum: f64 = r.iter().map(|x| x.1).sum();
            prop_assert!((sum - 1.0).abs() < 1e-12);
            prop_assert!(r.iter().all(|x| x.1 > 0.0 && x.1.is_finite()));
            prop_assert!(r.windows(2).all(|w| w[0].0 < w[1].0));
            // The nearest joint is among the kept ones with the largest weight.
            let nearest = (0..d.len()).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap();
            let top = r.iter().map(|x| x.1).fold(0.0, f64::max);
            prop_assert!(r.iter().any(|x| x.0 == nearest && x.1 == top)
                || d.iter().filter(|&&x| x == d[nearest]).count() > 1);
        }
    }
}
