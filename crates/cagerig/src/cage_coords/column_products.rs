//! The per-frame column products of Φ: `out = [out +] Σ_k Φ[:, k]·d_k` over row tiles, and the
//! same sums for chosen rows (bit for bit).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Rows per parallel task in the per-frame products.
pub(super) const ROW_BLOCK: usize = 8192;

/// Rows per structure-of-arrays accumulator tile inside a row block (3 × 16 KiB of f64 sums):
/// long runs of each column (16 KiB of f64, 8 KiB of f32) keep the hardware prefetchers ahead;
/// 512-row tiles measured 15–30 % slower at 133k × 74 on the project machine.
pub(super) const LANE_BLOCK: usize = 2048;

/// `out = [out +] Σ column(k)·d_k` over `terms` = (k, d_k), `out` being `#V` and `column(k)`
/// the `#V` weights of cage vertex k; see [`super::CageCoords::apply`]. Sums are f64 whatever
/// the storage of the weights and of `out`.
pub(super) fn accumulate_columns<'a, W, P, I>(
    column: impl Fn(usize) -> &'a [W] + Send + Sync,
    terms: I,
    add_to_out: bool,
    out: &mut [P],
) where
    W: Weight + 'a,
    P: TilePoint,
    I: Iterator<Item = (usize, DVec3)> + Clone + Send + Sync,
{
    out.par_chunks_mut(ROW_BLOCK)
        .enumerate()
        .for_each(|(block, chunk)| {
            let block_start = block * ROW_BLOCK;
            for (tile, tile_out) in chunk.chunks_mut(LANE_BLOCK).enumerate() {
                let start = block_start + tile * LANE_BLOCK;
                let len = tile_out.len();
                let mut sums = TileSums::default();
                if add_to_out {
                    sums.load(tile_out);
                }
                for_each_group(terms.clone(), |group| match group {
                    Group::Eight(g) => sums.add_eight_columns(
                        g.map(|(k, _)| &column(k)[start..start + len]),
                        g.map(|(_, d)| d),
                    ),
                    Group::Four(g) => sums.add_four_columns(
                        g.map(|(k, _)| &column(k)[start..start + len]),
                        g.map(|(_, d)| d),
                    ),
                    Group::One((k, d)) => sums.add_column(&column(k)[start..start + len], d),
                });
                sums.store(tile_out);
            }
        });
}

/// Rows `rows` of `Σ column(k)·d_k` over `terms` into `out` (`rows.len()`): the same operations
/// in the same order as [`accumulate_columns`] without `add_to_out`, so the same bits as those
/// rows of its output. O(#rows · #terms).
pub(super) fn rows_of_columns<'a, W, I>(
    column: impl Fn(usize) -> &'a [W],
    terms: I,
    rows: &[usize],
    out: &mut [DVec3],
) where
    W: Weight + 'a,
    I: Iterator<Item = (usize, DVec3)> + Clone,
{
    debug_assert_eq!(rows.len(), out.len());
    for (&row, o) in rows.iter().zip(out.iter_mut()) {
        let mut sum = DVec3::ZERO;
        for_each_group(terms.clone(), |group| match group {
            Group::Eight(g) => {
                sum += eight_terms(g.map(|(k, _)| column(k)[row].widen()), g.map(|(_, d)| d));
            }
            Group::Four(g) => {
                sum += four_terms(g.map(|(k, _)| column(k)[row].widen()), g.map(|(_, d)| d));
            }
            Group::One((k, d)) => sum += column(k)[row].widen() * d,
        });
        *o = sum;
    }
}

/// Columns of one pass over the tile sums: eight while eight remain, then four if four remain,
/// then one at a time (58 cage columns: 7 × 8 + 2).
enum Group {
    Eight([(usize, DVec3); 8]),
    Four([(usize, DVec3); 4]),
    One((usize, DVec3)),
}

/// Calls `f` on the groups of `terms` in order (the order both products follow).
#[inline(always)]
fn for_each_group<I: Iterator<Item = (usize, DVec3)>>(mut terms: I, mut f: impl FnMut(Group)) {
    let mut pending = [(0usize, DVec3::ZERO); 8];
    loop {
        let mut n = 0;
        while n < 8 {
            match terms.next() {
                Some(term) => {
                    pending[n] = term;
                    n += 1;
                }
                None => break,
            }
        }
        if n == 8 {
            f(Group::Eight(pending));
            continue;
        }
        let mut rest = &pending[..n];
        if rest.len() >= 4 {
            f(Group::Four([rest[0], rest[1], rest[2], rest[3]]));
            rest = &rest[4..];
        }
        for &term in rest {
            f(Group::One(term));
        }
        return;
    }
}

/// `Σ_c w_c d_c` for four columns, summed as a pairwise tree.
#[inline(always)]
fn four_terms(w: [f64; 4], d: [DVec3; 4]) -> DVec3 {
    (w[0] * d[0] + w[1] * d[1]) + (w[2] * d[2] + w[3] * d[3])
}

/// `Σ_c w_c d_c` for eight columns, summed as a pairwise tree.
#[inline(always)]
fn eight_terms(w: [f64; 8], d: [DVec3; 8]) -> DVec3 {
    ((w[0] * d[0] + w[1] * d[1]) + (w[2] * d[2] + w[3] * d[3]))
        + ((w[4] * d[4] + w[5] * d[5]) + (w[6] * d[6] + w[7] * d[7]))
}

/// A point of the products' output: f64, or f32 (the display path), rounded once from the f64
/// sums.
pub(super) trait TilePoint: Copy + Send + Sync {
    fn load(self) -> DVec3;
    fn store(sum: DVec3) -> Self;
}

impl TilePoint for DVec3 {
    #[inline(always)]
    fn load(self) -> DVec3 {
        self
    }
    #[inline(always)]
    fn store(sum: DVec3) -> Self {
        sum
    }
}

impl TilePoint for Vec3 {
    #[inline(always)]
    fn load(self) -> DVec3 {
        self.as_dvec3()
    }
    #[inline(always)]
    fn store(sum: DVec3) -> Self {
        sum.as_vec3()
    }
}

/// A stored coordinate: f64, or f32 widened exactly to f64.
pub(super) trait Weight: Copy + Send + Sync {
    fn widen(self) -> f64;
}

impl Weight for f64 {
    #[inline(always)]
    fn widen(self) -> f64 {
        self
    }
}

impl Weight for f32 {
    #[inline(always)]
    fn widen(self) -> f64 {
        f64::from(self)
    }
}

/// Structure-of-arrays sums of up to [`LANE_BLOCK`] points.
struct TileSums {
    x: [f64; LANE_BLOCK],
    y: [f64; LANE_BLOCK],
    z: [f64; LANE_BLOCK],
}

impl Default for TileSums {
    fn default() -> Self {
        Self {
            x: [0.0; LANE_BLOCK],
            y: [0.0; LANE_BLOCK],
            z: [0.0; LANE_BLOCK],
        }
    }
}

impl TileSums {
    fn load<P: TilePoint>(&mut self, points: &[P]) {
        for (i, p) in points.iter().enumerate() {
            let p = p.load();
            (self.x[i], self.y[i], self.z[i]) = (p.x, p.y, p.z);
        }
    }

    fn store<P: TilePoint>(&self, points: &mut [P]) {
        for (i, p) in points.iter_mut().enumerate() {
            *p = P::store(DVec3::new(self.x[i], self.y[i], self.z[i]));
        }
    }

    /// `sums[i] += column[i] · d` for the first `column.len()` points.
    fn add_column<W: Weight>(&mut self, column: &[W], d: DVec3) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports the enabled feature (checked just above).
                return unsafe { self.add_column_avx2(column, d) };
            }
        }
        self.add_column_generic(column, d)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn add_column_avx2<W: Weight>(&mut self, column: &[W], d: DVec3) {
        self.add_column_generic(column, d)
    }

    /// `sums[i] += Σ_c columns[c][i] · d_c` for four columns of equal length.
    fn add_four_columns<W: Weight>(&mut self, columns: [&[W]; 4], d: [DVec3; 4]) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU supports the enabled feature (checked just above).
                return unsafe { self.add_four_columns_avx512(columns, d) };
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: as above.
                return unsafe { self.add_four_columns_avx2(columns, d) };
            }
        }
        self.add_four_columns_generic(columns, d)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn add_four_columns_avx512<W: Weight>(&mut self, columns: [&[W]; 4], d: [DVec3; 4]) {
        self.add_four_columns_generic(columns, d)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn add_four_columns_avx2<W: Weight>(&mut self, columns: [&[W]; 4], d: [DVec3; 4]) {
        self.add_four_columns_generic(columns, d)
    }

    /// `sums[i] += Σ_c columns[c][i] · d_c` for eight columns of equal length (half the passes
    /// over the sums of four: the sums' traffic, not Φ's, bounded the four-column product).
    fn add_eight_columns<W: Weight>(&mut self, columns: [&[W]; 8], d: [DVec3; 8]) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU supports the enabled feature (checked just above).
                return unsafe { self.add_eight_columns_avx512(columns, d) };
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: as above.
                return unsafe { self.add_eight_columns_avx2(columns, d) };
            }
        }
        self.add_eight_columns_generic(columns, d)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn add_eight_columns_avx512<W: Weight>(&mut self, columns: [&[W]; 8], d: [DVec3; 8]) {
        self.add_eight_columns_generic(columns, d)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn add_eight_columns_avx2<W: Weight>(&mut self, columns: [&[W]; 8], d: [DVec3; 8]) {
        self.add_eight_columns_generic(columns, d)
    }

    #[inline(always)]
    fn add_eight_columns_generic<W: Weight>(&mut self, columns: [&[W]; 8], d: [DVec3; 8]) {
        let n = columns[0].len().min(LANE_BLOCK);
        let c = columns.map(|c| &c[..n]);
        let (x, y, z) = (&mut self.x[..n], &mut self.y[..n], &mut self.z[..n]);
        for i in 0..n {
            let w = [
                c[0][i].widen(),
                c[1][i].widen(),
                c[2][i].widen(),
                c[3][i].widen(),
                c[4][i].widen(),
                c[5][i].widen(),
                c[6][i].widen(),
                c[7][i].widen(),
            ];
            // The order of operations of `eight_terms`, per coordinate.
            let tree = |a: fn(DVec3) -> f64| {
                ((w[0] * a(d[0]) + w[1] * a(d[1])) + (w[2] * a(d[2]) + w[3] * a(d[3])))
                    + ((w[4] * a(d[4]) + w[5] * a(d[5])) + (w[6] * a(d[6]) + w[7] * a(d[7])))
            };
            x[i] += tree(|v| v.x);
            y[i] += tree(|v| v.y);
            z[i] += tree(|v| v.z);
        }
    }

    #[inline(always)]
    fn add_four_columns_generic<W: Weight>(&mut self, columns: [&[W]; 4], d: [DVec3; 4]) {
        let n = columns[0].len().min(LANE_BLOCK);
        let [c0, c1, c2, c3] = columns.map(|c| &c[..n]);
        let (x, y, z) = (&mut self.x[..n], &mut self.y[..n], &mut self.z[..n]);
        for i in 0..n {
            let (w0, w1, w2, w3) = (c0[i].widen(), c1[i].widen(), c2[i].widen(), c3[i].widen());
            x[i] += (w0 * d[0].x + w1 * d[1].x) + (w2 * d[2].x + w3 * d[3].x);
            y[i] += (w0 * d[0].y + w1 * d[1].y) + (w2 * d[2].y + w3 * d[3].y);
            z[i] += (w0 * d[0].z + w1 * d[1].z) + (w2 * d[2].z + w3 * d[3].z);
        }
    }

    #[inline(always)]
    fn add_column_generic<W: Weight>(&mut self, column: &[W], d: DVec3) {
        let n = column.len().min(LANE_BLOCK);
        let (x, y, z) = (&mut self.x[..n], &mut self.y[..n], &mut self.z[..n]);
        for i in 0..n {
            let w = column[i].widen();
            x[i] += w * d.x;
            y[i] += w * d.y;
            z[i] += w * d.z;
        }
    }
}
