//! The layout the CoR grid's steps share ([`super::grid`]): the tabulation grid in weight space
//! and its interpolation stencils, the joint-pair lookup, and the pair enumeration of a weight
//! row. A leaf: it imports none of the steps.

/// How the similarity tables are interpolated at a vertex's (x, y).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GridInterpolation {
    /// 2 × 2 nodes, error O(h²).
    Bilinear,
    /// 4 × 4 nodes (Catmull–Rom), error O(h³).
    Bicubic,
}

pub(super) const NONE: u32 = u32::MAX;

/// The tabulation grid: node (p, q) sits at ((p − 1)h, (q − 1)h), p, q ∈ 0..side.
#[derive(Clone, Copy)]
pub(super) struct Grid {
    pub(super) step: f64,
    /// Cells per unit (1/h, rounded up).
    pub(super) cells: usize,
    pub(super) side: usize,
    pub(super) interpolation: GridInterpolation,
}

impl Grid {
    /// Stencil of (x, y): up to 16 (node index, weight) pairs, as `count`.
    #[inline]
    pub(super) fn stencil(&self, x: f64, y: f64, out: &mut [(usize, f64); 16]) -> usize {
        let axis = |v: f64| {
            let s = v / self.step;
            let cell = (s.floor().max(0.0) as usize).min(self.cells - 1);
            (cell, s - cell as f64)
        };
        let (cx, tx) = axis(x);
        let (cy, ty) = axis(y);
        match self.interpolation {
            GridInterpolation::Bilinear => {
                let wx = [1.0 - tx, tx];
                let wy = [1.0 - ty, ty];
                let mut n = 0;
                for (dx, &u) in wx.iter().enumerate() {
                    for (dy, &v) in wy.iter().enumerate() {
                        out[n] = ((cx + 1 + dx) * self.side + cy + 1 + dy, u * v);
                        n += 1;
                    }
                }
                n
            }
            GridInterpolation::Bicubic => {
                let wx = catmull_rom(tx);
                let wy = catmull_rom(ty);
                let mut n = 0;
                for (dx, &u) in wx.iter().enumerate() {
                    for (dy, &v) in wy.iter().enumerate() {
                        out[n] = ((cx + dx) * self.side + cy + dy, u * v);
                        n += 1;
                    }
                }
                n
            }
        }
    }

    pub(super) fn node_position(&self, node: usize) -> (f64, f64) {
        let (p, q) = (node / self.side, node % self.side);
        ((p as f64 - 1.0) * self.step, (q as f64 - 1.0) * self.step)
    }
}

/// Catmull–Rom weights of nodes −1, 0, 1, 2 at t ∈ [0, 1] (they sum to 1).
#[inline]
pub(super) fn catmull_rom(t: f64) -> [f64; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// Calls `f(a, b)` for each pair of positions a < b in a weight row whose weights are positive.
#[inline]
pub(super) fn for_each_pair(weights: &[f64], mut f: impl FnMut(usize, usize)) {
    for (a, &wa) in weights.iter().enumerate() {
        if wa > 0.0 {
            for (b, &wb) in weights.iter().enumerate().skip(a + 1) {
                if wb > 0.0 {
                    f(a, b);
                }
            }
        }
    }
}

/// Joint-pair key (`j_a·#J + j_b`) → pair index ([`NONE`] when no triangle has the pair): a
/// dense `#J²` table for skeletons of up to [`DENSE_PAIR_JOINTS`] joints (≤ 64 MiB), a binary
/// search in the sorted keys above (`#J²` u32 would be 16 GiB at 65,536 joints).
pub(super) enum PairLookup<'a> {
    Dense(Vec<u32>),
    Sorted(&'a [u32]),
}

/// Largest joint count with a dense [`PairLookup`] table.
const DENSE_PAIR_JOINTS: usize = 4096;

impl<'a> PairLookup<'a> {
    /// `sorted_keys`: the pair keys present, ascending and distinct.
    pub(super) fn new(sorted_keys: &'a [u32], num_joints: usize) -> Self {
        if num_joints > DENSE_PAIR_JOINTS {
            return Self::Sorted(sorted_keys);
        }
        let mut table = vec![NONE; num_joints * num_joints];
        for (p, &key) in sorted_keys.iter().enumerate() {
            table[key as usize] = p as u32;
        }
        Self::Dense(table)
    }

    pub(super) fn get(&self, key: usize) -> u32 {
        match self {
            Self::Dense(table) => table[key],
            Self::Sorted(keys) => u32::try_from(key)
                .ok()
                .and_then(|k| keys.binary_search(&k).ok())
                .map_or(NONE, |p| p as u32),
        }
    }
}
