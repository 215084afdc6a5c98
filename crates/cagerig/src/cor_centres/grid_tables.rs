//! Step 5 of the CoR grid ([`super::grid`]): the similarity tables
//! `G_jk(x, y) = Σ_bins exp(−(x b̄ − y ā)²/σ²) Σ α a b Φ_t` at the grid nodes that some vertex's
//! stencil touches, one dense product (nodes × bins)·(bins × #C) per chunk of a pair's nodes.

use faer::{Accum, Par};
use rayon::prelude::*;

use super::grid_bins::TriangleBins;
use super::grid_layout::Grid;
use crate::error::RigError;
use crate::memory_estimate::zeroed_table;
use crate::simd_dispatch::simd_dispatch;

/// Table nodes evaluated per dense product (rows of the kernel matrix).
const NODE_CHUNK: usize = 256;
/// Cap on kernel matrix entries per product (8 MB).
const KERNEL_ENTRIES: usize = 1 << 20;

/// G (`#slots × #C`, row-major): the rows of pair p's nodes `pair_nodes[p]` in turn
/// (`num_slots` in all), from the binned triangles (dropped as soon as the tables are made),
/// for the kernel width σ = `sigma`.
pub(super) fn similarity_tables(
    grid: &Grid,
    pair_nodes: &[Vec<u32>],
    num_slots: usize,
    binned: TriangleBins,
    num_cage: usize,
    sigma: f64,
) -> Result<Vec<f64>, RigError> {
    let inv_sigma_sq = 1.0 / (sigma * sigma);
    let (pair_bin_starts, bins) = (&binned.pair_bin_starts, &binned.bins);
    let mut tables = zeroed_table("CoR similarity tables", num_slots, "grid nodes", num_cage)?;
    if num_cage > 0 {
        let mut tasks = Vec::new();
        let mut rest_tables: &mut [f64] = &mut tables;
        for (pair, nodes) in pair_nodes.iter().enumerate() {
            let (pair_tables, tail) = rest_tables.split_at_mut(nodes.len() * num_cage);
            rest_tables = tail;
            let pair_bins = pair_bin_starts[pair]..pair_bin_starts[pair + 1];
            let chunk = (KERNEL_ENTRIES / pair_bins.len().max(1)).clamp(16, NODE_CHUNK);
            for (c, out) in pair_tables.chunks_mut(chunk * num_cage).enumerate() {
                tasks.push((
                    pair_bins.clone(),
                    &nodes[c * chunk..][..out.len() / num_cage],
                    out,
                ));
            }
        }
        // Per thread, one kernel buffer reused across tasks (no page faults of fresh 8 MB
        // allocations); the product is written straight into the row-major tables.
        tasks.into_par_iter().for_each_init(
            Vec::<f64>::new,
            |kernel_values, (pair_bins, nodes, out)| {
                let bins = &bins[pair_bins.clone()];
                // Kernel (nodes × bins, column-major).
                let (xs, ys): (Vec<f64>, Vec<f64>) = nodes
                    .iter()
                    .map(|&n| grid.node_position(n as usize))
                    .unzip();
                kernel_values.resize(nodes.len() * bins.len(), 0.0);
                let kernel_values = &mut kernel_values[..nodes.len() * bins.len()];
                fill_kernel(kernel_values, &xs, &ys, bins, inv_sigma_sq);
                let kernel =
                    faer::MatRef::from_column_major_slice(kernel_values, nodes.len(), bins.len());
                faer::linalg::matmul::matmul(
                    faer::MatMut::from_row_major_slice_mut(out, nodes.len(), num_cage),
                    Accum::Replace,
                    kernel,
                    binned.bin_coords(pair_bins.clone()),
                    1.0,
                    Par::Seq,
                );
            },
        );
    }
    // The faer products ran on every thread of the pool.
    crate::vector_registers::clear_upper_halves_everywhere();
    Ok(tables)
}

simd_dispatch! {
    /// Kernel matrix `K_nb = exp(−(x_n b̄_b − y_n ā_b)²/σ²)` (nodes × bins, column-major) into
    /// `out`, for the bins `(mass, ā, b̄)`, vectorised for the CPU at hand.
    fn fill_kernel(
        out: &mut [f64],
        xs: &[f64],
        ys: &[f64],
        bins: &[(f64, f64, f64)],
        inv_sigma_sq: f64,
    ) => fill_kernel_generic;
    avx512f: fill_kernel_avx512;
    avx2_fma: fill_kernel_avx2;
}

#[inline(always)]
fn fill_kernel_generic(
    out: &mut [f64],
    xs: &[f64],
    ys: &[f64],
    bins: &[(f64, f64, f64)],
    inv_sigma_sq: f64,
) {
    let n = xs.len();
    for (column, &(_, a, b)) in out.chunks_exact_mut(n).zip(bins) {
        for ((k, &x), &y) in column.iter_mut().zip(xs).zip(ys) {
            let cross = x * b - y * a;
            *k = exp_non_positive(-cross * cross * inv_sigma_sq);
        }
    }
}

/// e^x for x ≤ 0 (relative error ≲ 1e-15; 0 below −700), branch- and call-free so that loops
/// vectorise.
#[inline(always)]
fn exp_non_positive(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // Adding 1.5·2^52 rounds to an integer held in the low mantissa bits.
    const SHIFTER: f64 = 6_755_399_441_055_744.0;
    let x = x.max(-700.0);
    let shifted = x * std::f64::consts::LOG2_E + SHIFTER;
    let n = shifted - SHIFTER;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    // Taylor series of e^r on |r| ≤ ln2/2 to degree 12 (remainder < 2e-17).
    let mut p = 1.0 / 479_001_600.0;
    for d in [
        39_916_800.0,
        3_628_800.0,
        362_880.0,
        40_320.0,
        5_040.0,
        720.0,
        120.0,
        24.0,
        6.0,
        2.0,
        1.0,
        1.0,
    ] {
        p = p * r + 1.0 / d;
    }
    // 2^n via the exponent bits (n ≥ −1010, a normal number): n = bits(shifted) − bits(SHIFTER).
    let exponent = shifted
        .to_bits()
        .wrapping_sub(SHIFTER.to_bits())
        .wrapping_add(1023);
    p * f64::from_bits(exponent << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_std() {
        for i in 0..=7000 {
            let x = -0.1 * i as f64;
            let (got, want) = (exp_non_positive(x), x.exp());
            assert!((got - want).abs() <= 4e-16 * want, "{x}: {got} vs {want}");
        }
        assert_eq!(exp_non_positive(0.0), 1.0);
        assert!(exp_non_positive(-1e9) < 1e-300);
    }
}
