//! The per-frame column products of Φ: `out = [out +] Σ_k Φ[:, k]·d_k` over row tiles, and the
//! same sums for chosen rows (bit for bit).
//!
//! **Arithmetic.** The terms go in groups of eight columns (then four, then one at a time:
//! [`Groups`]); each coordinate adds a group as `s + t`, `t` the group's own chain of fused
//! multiply-adds `t = w₀·d₀`, `t ← fma(w_c, d_c, t)`, in f64 from `s` = 0 (or the point given):
//! [`add_group`]. `mul_add` is correctly rounded on every machine, so the tiled product, the
//! rows and every instruction-set tier give the same bits. Measured at 133k × (58 + 112)
//! (`grab_bench 3 exact green`, alternating builds), M(C) took:
//! - 6.4–6.5 ms with separate products and a pairwise sum per group (16 operations per group
//!   of eight and coordinate);
//! - 6.6–6.8 ms with fused pairs summed pairwise (12);
//! - 5.9–6.1 ms with one chain of fused multiply-adds over all the columns (8), whose round-off
//!   grows with the 170 terms of the chain;
//! - 6.0–6.3 ms with a chain per group (9, kept): the round-off of a chain of eight per group,
//!   then one addition per group as before.
//!
//! A CPU without FMA (x86-64 before 2013) runs the baseline body, where `mul_add` is a libm
//! call: correct, slow. The web build (wasm32) adds the product and the sum separately instead
//! ([`chain_step`]).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::simd_dispatch::simd_dispatch;

/// Rows per parallel task in the per-frame products.
pub(super) const ROW_BLOCK: usize = 8192;

/// Rows per structure-of-arrays accumulator tile inside a row block (3 × 16 KiB of f64 sums):
/// long runs of each column (16 KiB of f64, 8 KiB of f32) keep the hardware prefetchers ahead;
/// 512-row tiles measured 15–30 % slower at 133k × 74 on the project machine.
pub(super) const LANE_BLOCK: usize = 2048;

/// `out = [out +] Σ column(k)·d_k` over the terms (k, d_k) of every part in turn, `out` being
/// `#V` and `column(k)` the `#V` weights of column k; see [`super::CageCoords::apply`]. The
/// chain of each coordinate carries over from one part to the next in f64, so the parts `[a,
/// b]` give the bits of `a` alone followed by `b` with `add_to_out`, in one pass over the rows.
/// Sums are f64 whatever the storage of the weights and of `out`.
pub(super) fn accumulate_columns<'a, W, P, I>(
    column: impl Fn(usize) -> &'a [W] + Send + Sync,
    parts: &[I],
    add_to_out: bool,
    out: &mut [P],
) where
    W: Weight + 'a,
    P: TilePoint,
    I: Iterator<Item = (usize, DVec3)> + Clone + Send + Sync,
{
    // A second output of zero-sized points: no allocation, nothing to call.
    let mut no_second = vec![(); out.len()];
    accumulate_columns_then(column, parts, add_to_out, out, &mut no_second, |_, _, _| {});
}

/// [`accumulate_columns`], then `then(first_row, tile, second_tile)` on each finished tile of
/// `out` while it is still in the core's cache, with the same rows of `second` (`#V`; of
/// zero-sized points where there is none): a consumer of M, such as skinning into M', reads it
/// there instead of from memory after the whole product.
pub(super) fn accumulate_columns_then<'a, W, P, Q, I>(
    column: impl Fn(usize) -> &'a [W] + Send + Sync,
    parts: &[I],
    add_to_out: bool,
    out: &mut [P],
    second: &mut [Q],
    then: impl Fn(usize, &[P], &mut [Q]) + Send + Sync,
) where
    W: Weight + 'a,
    P: TilePoint,
    Q: Send,
    I: Iterator<Item = (usize, DVec3)> + Clone + Send + Sync,
{
    assert_eq!(
        out.len(),
        second.len(),
        "the two outputs of a tiled product"
    );
    out.par_chunks_mut(ROW_BLOCK)
        .zip(second.par_chunks_mut(ROW_BLOCK))
        .enumerate()
        .for_each(|(block, (chunk, second_chunk))| {
            let tiles = chunk
                .chunks_mut(LANE_BLOCK)
                .zip(second_chunk.chunks_mut(LANE_BLOCK));
            for (tile, (tile_out, second_tile)) in tiles.enumerate() {
                let start = block * ROW_BLOCK + tile * LANE_BLOCK;
                tile_product(&column, parts, add_to_out, start, tile_out);
                then(start, tile_out, second_tile);
            }
        });
}

/// `then(first_row, tile, second_tile)` on the [`LANE_BLOCK`]-row tiles of a finished `out`
/// and the same rows of `second`, as [`accumulate_columns_then`] calls it.
pub(super) fn call_on_tiles<P: Sync, Q: Send>(
    out: &[P],
    second: &mut [Q],
    then: impl Fn(usize, &[P], &mut [Q]) + Send + Sync,
) {
    assert_eq!(
        out.len(),
        second.len(),
        "the two outputs of a tiled product"
    );
    out.par_chunks(LANE_BLOCK)
        .zip(second.par_chunks_mut(LANE_BLOCK))
        .enumerate()
        .for_each(|(tile, (rows, second_rows))| then(tile * LANE_BLOCK, rows, second_rows));
}

/// One tile of [`accumulate_columns`]: rows `start..start + tile_out.len()`.
#[inline(always)]
fn tile_product<'a, W, P, I>(
    column: &(impl Fn(usize) -> &'a [W] + Send + Sync),
    parts: &[I],
    add_to_out: bool,
    start: usize,
    tile_out: &mut [P],
) where
    W: Weight + 'a,
    P: TilePoint,
    I: Iterator<Item = (usize, DVec3)> + Clone + Send + Sync,
{
    let len = tile_out.len();
    let mut sums = TileSums::default();
    if add_to_out {
        sums.load(tile_out);
    }
    let columns = |k: usize| &column(k)[start..start + len];
    for terms in parts {
        for group in Groups::new(terms.clone()) {
            match group {
                Group::Eight(g) => sums.add_columns(g.map(|(k, _)| columns(k)), g.map(|t| t.1)),
                Group::Four(g) => sums.add_columns(g.map(|(k, _)| columns(k)), g.map(|t| t.1)),
                Group::One((k, d)) => sums.add_columns([columns(k)], [d]),
            }
        }
    }
    sums.store(tile_out);
}

/// The terms (`first + j`, `values[j]`) of one part of [`accumulate_columns`]: the columns
/// `first..first + values.len()` of a concatenation, with their `d`.
#[derive(Clone)]
pub(super) struct OffsetTerms<'a> {
    first: usize,
    values: std::iter::Enumerate<std::slice::Iter<'a, DVec3>>,
}

impl<'a> OffsetTerms<'a> {
    pub(super) fn new(first: usize, values: &'a [DVec3]) -> Self {
        Self {
            first,
            values: values.iter().enumerate(),
        }
    }
}

impl Iterator for OffsetTerms<'_> {
    type Item = (usize, DVec3);

    #[inline]
    fn next(&mut self) -> Option<(usize, DVec3)> {
        self.values.next().map(|(j, d)| (self.first + j, *d))
    }
}

/// The terms (`offset + columns[j]`, `values[j]`) of one part of [`accumulate_columns`]: a few
/// chosen columns of a concatenation, with their `d` (a sparse edit).
#[derive(Clone)]
pub(super) struct ScatteredTerms<'a> {
    offset: usize,
    terms: std::iter::Zip<std::slice::Iter<'a, usize>, std::slice::Iter<'a, DVec3>>,
}

impl<'a> ScatteredTerms<'a> {
    pub(super) fn new(offset: usize, columns: &'a [usize], values: &'a [DVec3]) -> Self {
        Self {
            offset,
            terms: columns.iter().zip(values),
        }
    }
}

impl Iterator for ScatteredTerms<'_> {
    type Item = (usize, DVec3);

    #[inline]
    fn next(&mut self) -> Option<(usize, DVec3)> {
        self.terms.next().map(|(k, d)| (self.offset + *k, *d))
    }
}

simd_dispatch! {
    /// Rows `rows` of `[out +] Σ column(k)·d_k` over `terms` into `out` (`rows.len()`, holding
    /// those rows of the `out` of [`accumulate_columns`] when `add_to_out`): the same groups and
    /// operations in the same order as [`accumulate_columns`], so the same bits as those rows of
    /// its output. Group by group over all the rows (independent sums side by side).
    /// O(#rows · #terms).
    pub(super) fn rows_of_columns['a, W: Weight + 'a, I: Iterator<Item = (usize, DVec3)> + Clone](
        column: &dyn Fn(usize) -> &'a [W],
        terms: I,
        add_to_out: bool,
        rows: &[usize],
        out: &mut [DVec3]
    ) => rows_of_columns_generic;
    avx512f: rows_of_columns_avx512;
    avx2_fma: rows_of_columns_avx2;
}

#[inline(always)]
fn rows_of_columns_generic<'a, W: Weight + 'a, I: Iterator<Item = (usize, DVec3)> + Clone>(
    column: &dyn Fn(usize) -> &'a [W],
    terms: I,
    add_to_out: bool,
    rows: &[usize],
    out: &mut [DVec3],
) {
    debug_assert_eq!(rows.len(), out.len());
    if !add_to_out {
        out.fill(DVec3::ZERO);
    }
    for group in Groups::new(terms) {
        match group {
            Group::Eight(g) => add_group_to_rows(column, g, rows, out),
            Group::Four(g) => add_group_to_rows(column, g, rows, out),
            Group::One(g) => add_group_to_rows(column, [g], rows, out),
        }
    }
}

/// One group of [`rows_of_columns`] over all its rows (independent sums side by side).
#[inline(always)]
fn add_group_to_rows<'a, W: Weight + 'a, const N: usize>(
    column: &dyn Fn(usize) -> &'a [W],
    group: [(usize, DVec3); N],
    rows: &[usize],
    out: &mut [DVec3],
) {
    let mut columns: [&[W]; N] = [&[]; N];
    let (mut dx, mut dy, mut dz) = ([0.0; N], [0.0; N], [0.0; N]);
    let mut c = 0;
    while c < N {
        columns[c] = column(group[c].0);
        (dx[c], dy[c], dz[c]) = (group[c].1.x, group[c].1.y, group[c].1.z);
        c += 1;
    }
    for (o, &row) in out.iter_mut().zip(rows) {
        let mut w = [0.0; N];
        let mut c = 0;
        while c < N {
            w[c] = columns[c][row].widen();
            c += 1;
        }
        *o = DVec3::new(
            add_group(o.x, &w, &dx),
            add_group(o.y, &w, &dy),
            add_group(o.z, &w, &dz),
        );
    }
}

/// `s` plus the group `Σ_c w_c d_c` (`N` = 1, 4 or 8): `s + t` with the group's own chain
/// `t = w₀·d₀`, `t ← fma(w_c, d_c, t)` for c = 1..N (see the module docs). A `while` loop, no
/// closure.
#[inline(always)]
fn add_group<const N: usize>(s: f64, w: &[f64; N], d: &[f64; N]) -> f64 {
    let mut t = w[0] * d[0];
    let mut c = 1;
    while c < N {
        t = chain_step(w[c], d[c], t);
        c += 1;
    }
    s + t
}

/// One step `w·d + t` of [`add_group`]'s chain: fused (one rounding) on native targets, so every
/// tier gives the same bits. wasm32 has no fused multiply-add instruction and `f64::mul_add` is a
/// software routine there, about 100× a multiply (it made a current-cage grab in the web studio
/// take 7–20 ms instead of 0.2–1); the web build rounds the product and the sum separately, so
/// its products differ from native ones by round-off, which the browser test bounds.
#[inline(always)]
fn chain_step(w: f64, d: f64, t: f64) -> f64 {
    #[cfg(target_arch = "wasm32")]
    {
        w * d + t
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        w.mul_add(d, t)
    }
}

/// Columns of one pass over the tile sums: eight while eight remain, then four if four remain,
/// then one at a time (58 cage columns: 7 × 8 + 2). Both products group the same way, which
/// their bits depend on ([`add_group`]).
enum Group {
    Eight([(usize, DVec3); 8]),
    Four([(usize, DVec3); 4]),
    One((usize, DVec3)),
}

/// The groups of `terms` in order (the order both products follow); an iterator, so that the
/// dispatched bodies loop over it with no closure.
struct Groups<I> {
    terms: I,
    /// The last, short read of the terms (fewer than eight), handed on from `next_left`.
    left: [(usize, DVec3); 8],
    left_len: usize,
    next_left: usize,
    done: bool,
}

impl<I: Iterator<Item = (usize, DVec3)>> Groups<I> {
    #[inline(always)]
    fn new(terms: I) -> Self {
        Self {
            terms,
            left: [(0, DVec3::ZERO); 8],
            left_len: 0,
            next_left: 0,
            done: false,
        }
    }
}

impl<I: Iterator<Item = (usize, DVec3)>> Iterator for Groups<I> {
    type Item = Group;

    #[inline(always)]
    fn next(&mut self) -> Option<Group> {
        if !self.done {
            let mut pending = [(0usize, DVec3::ZERO); 8];
            let mut n = 0;
            while n < 8 {
                match self.terms.next() {
                    Some(term) => {
                        pending[n] = term;
                        n += 1;
                    }
                    None => break,
                }
            }
            if n == 8 {
                return Some(Group::Eight(pending));
            }
            (self.done, self.left, self.left_len) = (true, pending, n);
        }
        let (left, i) = (&self.left, self.next_left);
        match self.left_len - i {
            0 => None,
            4.. => {
                self.next_left += 4;
                Some(Group::Four([
                    left[i],
                    left[i + 1],
                    left[i + 2],
                    left[i + 3],
                ]))
            }
            1..=3 => {
                self.next_left += 1;
                Some(Group::One(left[i]))
            }
        }
    }
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

    simd_dispatch! {
        /// `sums[i] = add_group(sums[i], columns[·][i], d)` over a group of columns of equal
        /// length (eight per pass: the traffic of the sums, not of Φ, bounds the product; four
        /// then one at a time for the rest).
        fn add_columns[W: Weight, const N: usize](&mut self, columns: [&[W]; N], d: [DVec3; N])
            => Self::add_columns_generic;
        avx512f: add_columns_avx512;
        avx2_fma: add_columns_avx2;
    }

    /// [`add_group`] vectorised over the points, as [`rows_of_columns`] adds it row by row (a
    /// `while` loop with no closure: `coords/mvc_lanes.rs`).
    #[inline(always)]
    fn add_columns_generic<W: Weight, const N: usize>(
        &mut self,
        columns: [&[W]; N],
        d: [DVec3; N],
    ) {
        let n = columns[0].len().min(LANE_BLOCK);
        // Each column cut to the block (so the loop below has no bounds checks), no closure.
        let mut c = columns;
        let mut q = 0;
        while q < N {
            c[q] = &columns[q][..n];
            q += 1;
        }
        let (mut dx, mut dy, mut dz) = ([0.0; N], [0.0; N], [0.0; N]);
        let mut q = 0;
        while q < N {
            (dx[q], dy[q], dz[q]) = (d[q].x, d[q].y, d[q].z);
            q += 1;
        }
        let (x, y, z) = (&mut self.x[..n], &mut self.y[..n], &mut self.z[..n]);
        for i in 0..n {
            let mut w = [0.0; N];
            let mut q = 0;
            while q < N {
                w[q] = c[q][i].widen();
                q += 1;
            }
            x[i] = add_group(x[i], &w, &dx);
            y[i] = add_group(y[i], &w, &dy);
            z[i] = add_group(z[i], &w, &dz);
        }
    }
}
