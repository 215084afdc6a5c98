//! Steps 1–3 of the CoR grid ([`super::grid`]): the rest triangles of every joint pair (j, k)
//! aggregated into bins of their weights (a_t, b_t) = (ω_tj, ω_tk), each bin keeping
//! Σ α_t a_t b_t, the α a b-weighted mean (ā, b̄) and the bin coordinates Σ α_t a_t b_t Φ_t
//! (Φ_t = mean of the corner rows of Φ).
//!
//! The bin coordinates are `#bins × #C`, one cage column at a time. Each column streams the
//! triangle entries in triangle order (the order they were generated in), so that the three
//! corner values of Φ come from nearby rows and each bin's sum is scattered into a column of
//! `#bins` values that stays in cache, instead of gathering per-triangle sums in bin order.

use faer::MatRef;
use glam::DVec3;
use rayon::prelude::*;

use super::grid_layout::for_each_pair;
use crate::SkinWeights;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::memory_estimate::{check_table_allocation, zeroed_table};

/// The binned triangles of every joint pair (pair p: the p-th key that [`bin_triangles`]
/// returns beside them).
pub(super) struct TriangleBins {
    /// The bins of pair p are `pair_bin_starts[p]..pair_bin_starts[p + 1]` (`#pairs + 1`).
    pub(super) pair_bin_starts: Vec<usize>,
    /// Per bin: (Σ α a b, ā, b̄) (`#bins`).
    pub(super) bins: Vec<(f64, f64, f64)>,
    /// Σ α a b Φ_t per bin, `#bins × #C` column-major.
    bin_coords: Vec<f64>,
}

impl TriangleBins {
    pub(super) fn num_bins(&self) -> usize {
        self.bins.len()
    }

    /// Σ α a b Φ_t of `bins` (a range of bin indices), `bins.len() × #C`.
    pub(super) fn bin_coords(&self, bins: std::ops::Range<usize>) -> MatRef<'_, f64> {
        let all = MatRef::from_column_major_slice(
            &self.bin_coords,
            self.num_bins(),
            self.bin_coords
                .len()
                .checked_div(self.num_bins())
                .unwrap_or(0),
        );
        all.subrows(bins.start, bins.len())
    }
}

/// An entry as the bin coordinates stream it, in triangle order.
#[derive(Clone, Copy)]
struct StreamEntry {
    triangle: u32,
    bin: u32,
    mass: f64,
}

/// Bins the rest triangles (`rest_positions` M: `#V`, `triangles`: `#F`) of every joint pair of
/// the skinning weights Ω (`#V × #J`) at `1 / bin_resolution` (≤ 65535 bins per axis) and sums
/// the cage coordinates Φ (`#V × #C`) of each bin. Triangles of zero or undefined area are left
/// out. Returns the joint-pair keys `j·#J + k` (j < k) present, ascending (`#pairs`), and
/// their bins.
pub(super) fn bin_triangles(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    cage_coords: &CageCoords,
    bin_resolution: f64,
) -> Result<(Vec<u32>, TriangleBins), RigError> {
    let TriangleEntries {
        mut keys,
        mut stream,
        weights_ab,
    } = triangle_entries(rest_positions, triangles, weights, bin_resolution)?;
    keys.par_sort_unstable_by_key(|&(key, _)| key);

    // Bins: ranges of equal keys; pairs: ranges of bins with equal pair keys. Each entry of the
    // stream learns its bin.
    let mut num_bins = 0usize;
    let mut pair_keys: Vec<u32> = Vec::new();
    let mut pair_bin_starts = Vec::new();
    for (e, &(key, index)) in keys.iter().enumerate() {
        if e == 0 || key != keys[e - 1].0 {
            let pair_key = (key >> 32) as u32;
            if pair_keys.last() != Some(&pair_key) {
                pair_keys.push(pair_key);
                pair_bin_starts.push(num_bins);
            }
            num_bins += 1;
        }
        // At most one bin per entry, and entries are counted in u32.
        stream[index as usize].bin = (num_bins - 1) as u32;
    }
    pair_bin_starts.push(num_bins);
    drop(keys);

    // Per bin (Σ α a b, ā, b̄), summed in triangle order.
    let mut bins = vec![(0.0, 0.0, 0.0); num_bins];
    for (s, &(a, b)) in stream.iter().zip(&weights_ab) {
        let bin = &mut bins[s.bin as usize];
        bin.0 += s.mass;
        bin.1 += s.mass * a;
        bin.2 += s.mass * b;
    }
    drop(weights_ab);
    for (m, ma, mb) in &mut bins {
        (*ma, *mb) = (*ma / *m, *mb / *m);
    }

    let num_cage = cage_coords.num_cage_vertices();
    let mut bin_coords = zeroed_table("CoR bin coordinates", num_bins, "bins", num_cage)?;
    if num_bins > 0 {
        let num_vertices = cage_coords.num_vertices();
        check_table_allocation(
            "CoR bin coordinate scratch",
            num_vertices + num_bins,
            "rows",
            COLUMN_BLOCK * rayon::current_num_threads(),
        )?;
        bin_coords
            .par_chunks_mut(num_bins * COLUMN_BLOCK)
            .enumerate()
            .for_each_init(
                || (Vec::new(), Vec::new()),
                |(phi_rows, sums), (block, out)| {
                    let first = block * COLUMN_BLOCK;
                    let columns = out.len() / num_bins;
                    // Φ's columns of the block, row-major (missing columns are zero).
                    phi_rows.clear();
                    phi_rows.resize(num_vertices, [0.0; COLUMN_BLOCK]);
                    for q in 0..columns {
                        for (row, &value) in phi_rows.iter_mut().zip(cage_coords.column(first + q))
                        {
                            row[q] = value;
                        }
                    }
                    sums.clear();
                    sums.resize(num_bins, [0.0; COLUMN_BLOCK]);
                    accumulate_bins(&stream, triangles, phi_rows, sums);
                    for (q, column) in out.chunks_exact_mut(num_bins).enumerate() {
                        for (value, sum) in column.iter_mut().zip(sums.iter()) {
                            *value = sum[q] / 3.0;
                        }
                    }
                },
            );
    }
    Ok((
        pair_keys,
        TriangleBins {
            pair_bin_starts,
            bins,
            bin_coords,
        },
    ))
}

/// Cage columns per pass over the entries: independent sums per bin (a bin's sum is a chain of
/// dependent additions in memory), and a quarter of the passes.
const COLUMN_BLOCK: usize = 2;

/// `sums[bin] += mass · Σ corners of phi_rows` over the stream, in its order.
fn accumulate_bins(
    stream: &[StreamEntry],
    triangles: &[[u32; 3]],
    phi_rows: &[[f64; COLUMN_BLOCK]],
    sums: &mut [[f64; COLUMN_BLOCK]],
) {
    let (mut last, mut corner_sum) = (u32::MAX, [0.0; COLUMN_BLOCK]);
    for s in stream {
        if s.triangle != last {
            let [i, j, k] = triangles[s.triangle as usize];
            let (pi, pj, pk) = (
                phi_rows[i as usize],
                phi_rows[j as usize],
                phi_rows[k as usize],
            );
            for q in 0..COLUMN_BLOCK {
                corner_sum[q] = pi[q] + pj[q] + pk[q];
            }
            last = s.triangle;
        }
        let sum = &mut sums[s.bin as usize];
        for q in 0..COLUMN_BLOCK {
            sum[q] += s.mass * corner_sum[q];
        }
    }
}

/// The (triangle, joint pair) entries, in triangle order.
struct TriangleEntries {
    /// (`pair_key << 32 | bin_a << 16 | bin_b`, entry index), pair_key = j·#J + k.
    keys: Vec<(u64, u32)>,
    /// Triangle, mass α_t a_t b_t (and bin, not yet known).
    stream: Vec<StreamEntry>,
    /// (a_t, b_t).
    weights_ab: Vec<(f64, f64)>,
}

/// Triangles per task of the entry generation.
const TRIANGLE_CHUNK: usize = 4096;

/// Calls `f(pair_key, a_t, b_t, α_t)` for triangle `t` and each joint pair j < k with
/// a_t = ω_tj > 0 and b_t = ω_tk > 0 (ω_t: mean of the corner rows), when its area α_t is
/// positive. `joints` and `row` are scratch.
fn for_each_triangle_pair(
    rest_positions: &[DVec3],
    weights: &SkinWeights,
    [i, j, k]: [u32; 3],
    scratch: &mut (Vec<u32>, Vec<f64>),
    mut f: impl FnMut(u64, f64, f64, f64),
) {
    let (pi, pj, pk) = (
        rest_positions[i as usize],
        rest_positions[j as usize],
        rest_positions[k as usize],
    );
    let area = 0.5 * (pj - pi).cross(pk - pi).length();
    if area.is_nan() || area <= 0.0 {
        return;
    }
    let num_joints = weights.num_joints() as u64;
    let (joints, row) = scratch;
    // ω_t: merged corner rows / 3 (ascending joints).
    joints.clear();
    row.clear();
    for v in [i, j, k] {
        let (js, ws) = weights.row(v as usize);
        for (&jj, &w) in js.iter().zip(ws) {
            match joints.binary_search(&jj) {
                Ok(p) => row[p] += w / 3.0,
                Err(p) => {
                    joints.insert(p, jj);
                    row.insert(p, w / 3.0);
                }
            }
        }
    }
    for_each_pair(row, |x, y| {
        let pair_key = joints[x] as u64 * num_joints + joints[y] as u64;
        f(pair_key, row[x], row[y], area);
    });
}

/// Per triangle of positive area and joint pair j < k with a_t, b_t > 0: its entry, in triangle
/// order. Counted first, then written in place (no copies of the entry arrays).
fn triangle_entries(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    bin_resolution: f64,
) -> Result<TriangleEntries, RigError> {
    let counts: Vec<usize> = triangles
        .par_chunks(TRIANGLE_CHUNK)
        .map_init(
            || (Vec::new(), Vec::new()),
            |scratch, tris| {
                let mut count = 0;
                for &t in tris {
                    for_each_triangle_pair(rest_positions, weights, t, scratch, |_, _, _, _| {
                        count += 1;
                    });
                }
                count
            },
        )
        .collect();
    let total: usize = counts.iter().sum();
    if u32::try_from(total).is_err() {
        return Err(RigError::Invalid(format!(
            "CoR centres: {total} (triangle, joint pair) entries, more than the 2^32 the grid \
             indexes"
        )));
    }
    let mut entries = TriangleEntries {
        keys: vec![(0, 0); total],
        stream: vec![
            StreamEntry {
                triangle: 0,
                bin: 0,
                mass: 0.0,
            };
            total
        ],
        weights_ab: vec![(0.0, 0.0); total],
    };
    // Each chunk's slices of the three arrays.
    let mut tasks = Vec::with_capacity(counts.len());
    let (mut keys, mut stream, mut weights_ab) = (
        &mut entries.keys[..],
        &mut entries.stream[..],
        &mut entries.weights_ab[..],
    );
    let mut first = 0;
    for &count in &counts {
        let (k, k_rest) = keys.split_at_mut(count);
        let (s, s_rest) = stream.split_at_mut(count);
        let (w, w_rest) = weights_ab.split_at_mut(count);
        tasks.push((first, k, s, w));
        (keys, stream, weights_ab) = (k_rest, s_rest, w_rest);
        first += count;
    }
    let bin = |v: f64| ((v * bin_resolution).round() as u64).min(0xFFFF);
    tasks.into_par_iter().enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |scratch, (chunk, (first, keys, stream, weights_ab))| {
            let mut e = 0;
            let start = chunk * TRIANGLE_CHUNK;
            let tris = &triangles[start..(start + TRIANGLE_CHUNK).min(triangles.len())];
            for (t, &tri) in tris.iter().enumerate() {
                let triangle = (start + t) as u32;
                for_each_triangle_pair(
                    rest_positions,
                    weights,
                    tri,
                    scratch,
                    |pair, a, b, area| {
                        keys[e] = (pair << 32 | bin(a) << 16 | bin(b), (first + e) as u32);
                        stream[e] = StreamEntry {
                            triangle,
                            bin: 0,
                            mass: area * a * b,
                        };
                        weights_ab[e] = (a, b);
                        e += 1;
                    },
                );
            }
        },
    );
    Ok(entries)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;

    /// Against a brute-force sum per (pair, bin) over the triangles: masses, mean weights and
    /// Σ α a b Φ_t, on a random grid mesh with rows of 1 to 4 joints, one degenerate triangle and
    /// 5 cage columns (two column blocks and a partial one).
    #[test]
    fn bins_match_a_brute_force_sum() {
        let mut random = crate::test_random::uniform(0x9e37_79b9_7f4a_7c15u64);
        let (side, num_joints, num_cage) = (12usize, 5usize, 5usize);
        let mut positions = Vec::new();
        let mut rows = Vec::new();
        for i in 0..side * side {
            let (x, y) = ((i % side) as f64, (i / side) as f64);
            positions.push(DVec3::new(x, y, 0.3 * random()));
            let mut row: Vec<f64> = (0..num_joints)
                .map(|_| if random() < 0.45 { random() } else { 0.0 })
                .collect();
            row[i % num_joints] += 0.1;
            let sum: f64 = row.iter().sum();
            rows.push(row.iter().map(|w| w / sum).collect::<Vec<_>>());
        }
        let mut triangles = Vec::new();
        for y in 0..side - 1 {
            for x in 0..side - 1 {
                let v = (y * side + x) as u32;
                let s = side as u32;
                triangles.push([v, v + 1, v + s + 1]);
                triangles.push([v, v + s + 1, v + s]);
            }
        }
        triangles.push([0, 0, 1]); // zero area: left out
        let weights = SkinWeights::from_dense(&rows).unwrap().0;
        let phi_rows: Vec<Vec<f64>> = (0..positions.len())
            .map(|_| {
                let row: Vec<f64> = (0..num_cage).map(|_| random() + 0.01).collect();
                let sum: f64 = row.iter().sum();
                row.iter().map(|v| v / sum).collect()
            })
            .collect();
        let cage_coords = CageCoords::from_rows(&phi_rows, num_cage).unwrap();
        let resolution = 16.0;

        let (pair_keys, binned) =
            bin_triangles(&positions, &triangles, &weights, &cage_coords, resolution).unwrap();

        // (pair key, bin a, bin b) → (Σ m, Σ m a, Σ m b, Σ m Φ_t).
        type BinSums = (f64, f64, f64, Vec<f64>);
        let mut expected: BTreeMap<(u64, u64, u64), BinSums> = BTreeMap::new();
        for &[i, j, k] in &triangles {
            let p = [i, j, k].map(|v| positions[v as usize]);
            let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            if area <= 0.0 {
                continue;
            }
            let omega: Vec<f64> = (0..num_joints)
                .map(|jj| [i, j, k].iter().map(|&v| rows[v as usize][jj]).sum::<f64>() / 3.0)
                .collect();
            for ja in 0..num_joints {
                for jb in ja + 1..num_joints {
                    let (a, b) = (omega[ja], omega[jb]);
                    if a <= 0.0 || b <= 0.0 {
                        continue;
                    }
                    let bin = |v: f64| (v * resolution).round() as u64;
                    let key = ((ja * num_joints + jb) as u64, bin(a), bin(b));
                    let e = expected
                        .entry(key)
                        .or_insert((0.0, 0.0, 0.0, vec![0.0; num_cage]));
                    let m = area * a * b;
                    e.0 += m;
                    e.1 += m * a;
                    e.2 += m * b;
                    for (c, sum) in e.3.iter_mut().enumerate() {
                        let corners: f64 = [i, j, k].iter().map(|&v| phi_rows[v as usize][c]).sum();
                        *sum += m * corners / 3.0;
                    }
                }
            }
        }
        assert!(expected.len() > 30, "{} bins", expected.len());
        assert_eq!(binned.num_bins(), expected.len());
        let coords = binned.bin_coords(0..binned.num_bins());
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-13 * y.abs().max(1.0);
        let mut pairs_seen = Vec::new();
        for (bin, (&(pair, _, _), (m, ma, mb, phi))) in expected.iter().enumerate() {
            let (got_m, got_a, got_b) = binned.bins[bin];
            assert!(close(got_m, *m), "bin {bin}: mass {got_m} vs {m}");
            assert!(
                close(got_a, ma / m) && close(got_b, mb / m),
                "bin {bin}: means"
            );
            for (c, &value) in phi.iter().enumerate() {
                assert!(close(coords[(bin, c)], value), "bin {bin} column {c}");
            }
            if pairs_seen.last() != Some(&pair) {
                pairs_seen.push(pair);
                let p = pairs_seen.len() - 1;
                assert_eq!(binned.pair_bin_starts[p], bin, "first bin of pair {p}");
            }
        }
        let keys: Vec<u64> = pair_keys.iter().map(|&k| u64::from(k)).collect();
        assert_eq!(keys, pairs_seen);
        assert_eq!(binned.pair_bin_starts.last(), Some(&binned.num_bins()));
    }
}
