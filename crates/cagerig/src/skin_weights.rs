//! Skinning weights Ω (`#V × #J`, sparse rows) in compressed-row storage.

use crate::error::{RigError, Warning};

/// Most joints a skinning weight matrix may have: the per-frame kernels store joint indices in
/// 16 bits (like glTF's `JOINTS_0`).
pub const MAX_JOINTS: usize = 1 << 16;

/// Rows whose sum differs from 1 by more than this are renormalised and reported.
pub const ROW_SUM_TOLERANCE: f64 = 1e-9;

/// Skinning weights Ω: for every mesh vertex the joints that influence it and their weights.
///
/// Compressed sparse rows: row `v` holds `joints[row_start[v]..row_start[v+1]]` (ascending joint
/// index, no duplicates, no zeros) and the matching `weights`. After [`SkinWeights::from_triplets`]
/// every non-empty row sums to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinWeights {
    num_joints: usize,
    row_start: Vec<u32>,
    joints: Vec<u32>,
    weights: Vec<f64>,
}

impl SkinWeights {
    /// Builds Ω from `(vertex, joint, weight)` entries in any order.
    ///
    /// Negative or non-finite weights are rejected. Duplicates are summed, zeros dropped, rows
    /// renormalised to sum to 1; each of these is reported as a [`Warning`], as are vertices
    /// with no influence.
    pub fn from_triplets(
        num_vertices: usize,
        num_joints: usize,
        triplets: impl IntoIterator<Item = (usize, usize, f64)>,
    ) -> Result<(Self, Vec<Warning>), RigError> {
        if num_joints > MAX_JOINTS {
            return Err(RigError::TooManyJoints {
                joints: num_joints,
                max: MAX_JOINTS,
            });
        }
        let mut entries: Vec<(u32, u32, f64)> = Vec::new();
        let mut zeros = 0usize;
        for (vertex, joint, weight) in triplets {
            if vertex >= num_vertices {
                return Err(RigError::IndexOutOfRange {
                    what: "skinning weight vertex",
                    index: vertex,
                    len: num_vertices,
                });
            }
            if joint >= num_joints {
                return Err(RigError::IndexOutOfRange {
                    what: "skinning weight joint",
                    index: joint,
                    len: num_joints,
                });
            }
            if !crate::error::is_input_value(weight) || weight < 0.0 {
                return Err(RigError::InvalidWeight {
                    vertex,
                    joint,
                    weight,
                });
            }
            if weight == 0.0 {
                zeros += 1;
                continue;
            }
            entries.push((vertex as u32, joint as u32, weight));
        }
        entries.sort_by_key(|&(v, j, _)| (v, j));
        let mut duplicates = 0usize;
        let mut merged: Vec<(u32, u32, f64)> = Vec::with_capacity(entries.len());
        for e in entries {
            match merged.last_mut() {
                Some(last) if last.0 == e.0 && last.1 == e.1 => {
                    last.2 += e.2;
                    duplicates += 1;
                }
                _ => merged.push(e),
            }
        }
        let mut row_start = vec![0u32; num_vertices + 1];
        for &(v, _, _) in &merged {
            row_start[v as usize + 1] += 1;
        }
        for v in 0..num_vertices {
            row_start[v + 1] += row_start[v];
        }
        let joints: Vec<u32> = merged.iter().map(|e| e.1).collect();
        let mut weights: Vec<f64> = merged.iter().map(|e| e.2).collect();

        let mut renormalised = 0usize;
        let mut worst_sum = 1.0f64;
        let mut unweighted = 0usize;
        let mut first_unweighted = None;
        for v in 0..num_vertices {
            let range = row_start[v] as usize..row_start[v + 1] as usize;
            if range.is_empty() {
                unweighted += 1;
                first_unweighted.get_or_insert(v);
                continue;
            }
            let sum: f64 = weights[range.clone()].iter().sum();
            if (sum - 1.0).abs() > ROW_SUM_TOLERANCE {
                renormalised += 1;
                if (sum - 1.0).abs() > (worst_sum - 1.0).abs() {
                    worst_sum = sum;
                }
            }
            if sum != 1.0 {
                weights[range].iter_mut().for_each(|w| *w /= sum);
            }
        }
        let mut warnings = Vec::new();
        if renormalised > 0 {
            warnings.push(Warning::WeightsRenormalised {
                rows: renormalised,
                worst_sum,
            });
        }
        if let Some(first) = first_unweighted {
            warnings.push(Warning::UnweightedVertices {
                count: unweighted,
                first,
            });
        }
        if duplicates > 0 {
            warnings.push(Warning::DuplicateWeightEntries { count: duplicates });
        }
        if zeros > 0 {
            warnings.push(Warning::ZeroWeightEntries { count: zeros });
        }
        Ok((
            Self {
                num_joints,
                row_start,
                joints,
                weights,
            },
            warnings,
        ))
    }

    /// Builds Ω from dense rows (`#V` rows of `#J` weights).
    pub fn from_dense(rows: &[Vec<f64>]) -> Result<(Self, Vec<Warning>), RigError> {
        let num_joints = rows.first().map_or(0, Vec::len);
        SkinWeights::from_triplets(
            rows.len(),
            num_joints,
            rows.iter().enumerate().flat_map(|(v, r)| {
                r.iter()
                    .enumerate()
                    .filter(|(_, w)| **w != 0.0)
                    .map(move |(j, w)| (v, j, *w))
            }),
        )
    }

    /// Number of mesh vertices `#V` (rows of Ω).
    pub fn num_vertices(&self) -> usize {
        self.row_start.len() - 1
    }

    /// Number of joints `#J` (columns of Ω).
    pub fn num_joints(&self) -> usize {
        self.num_joints
    }

    /// Number of stored non-zeros.
    pub fn num_entries(&self) -> usize {
        self.weights.len()
    }

    /// Joints and weights influencing vertex `v` (ascending joint index).
    #[inline]
    pub fn row(&self, v: usize) -> (&[u32], &[f64]) {
        let range = self.row_start[v] as usize..self.row_start[v + 1] as usize;
        (&self.joints[range.clone()], &self.weights[range])
    }

    /// ω_vj (zero when not stored).
    pub fn get(&self, v: usize, j: usize) -> f64 {
        let (joints, weights) = self.row(v);
        joints
            .iter()
            .position(|&k| k as usize == j)
            .map_or(0.0, |i| weights[i])
    }

    /// The joint with the largest weight on vertex `v` (lowest index on ties), if any.
    pub fn heaviest(&self, v: usize) -> Option<usize> {
        let (joints, weights) = self.row(v);
        let mut best: Option<(usize, f64)> = None;
        for (&j, &w) in joints.iter().zip(weights) {
            if best.is_none_or(|(_, bw)| w > bw) {
                best = Some((j as usize, w));
            }
        }
        best.map(|(j, _)| j)
    }

    /// Largest number of influences on one vertex.
    pub fn max_influences(&self) -> usize {
        self.row_start
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0)
    }

    /// Raw CSR arrays `(row_start, joints, weights)` for kernels that stream over Ω.
    pub fn csr(&self) -> (&[u32], &[u32], &[f64]) {
        (&self.row_start, &self.joints, &self.weights)
    }

    /// Ω from raw CSR arrays that already satisfy the invariants (ascending unique joints below
    /// `num_joints`, positive weights, rows summing to 1); for kernels that derive Ω from a valid Ω.
    pub(crate) fn from_csr_unchecked(
        num_joints: usize,
        row_start: Vec<u32>,
        joints: Vec<u32>,
        weights: Vec<f64>,
    ) -> Self {
        debug_assert_eq!(row_start.last().map(|&r| r as usize), Some(joints.len()));
        debug_assert_eq!(joints.len(), weights.len());
        debug_assert!(joints.iter().all(|&j| (j as usize) < num_joints));
        Self {
            num_joints,
            row_start,
            joints,
            weights,
        }
    }

    /// Ω restricted to the given vertices (rows in the given order).
    pub fn select_rows(&self, rows: &[usize]) -> Self {
        let mut row_start = Vec::with_capacity(rows.len() + 1);
        row_start.push(0u32);
        let mut joints = Vec::new();
        let mut weights = Vec::new();
        for &v in rows {
            let (j, w) = self.row(v);
            joints.extend_from_slice(j);
            weights.extend_from_slice(w);
            row_start.push(joints.len() as u32);
        }
        Self {
            num_joints: self.num_joints,
            row_start,
            joints,
            weights,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renormalises_merges_and_reports() {
        let (w, warnings) = SkinWeights::from_triplets(
            3,
            2,
            [
                (0, 1, 0.25),
                (0, 0, 0.25),
                (0, 1, 0.5),
                (1, 0, 0.0),
                (2, 1, 1.0),
            ],
        )
        .unwrap();
        assert_eq!(w.row(0).0, &[0, 1]);
        assert!((w.get(0, 0) - 0.25).abs() < 1e-15 && (w.get(0, 1) - 0.75).abs() < 1e-15);
        assert!(w.row(1).0.is_empty());
        assert_eq!(w.heaviest(0), Some(1));
        assert!(warnings.contains(&Warning::UnweightedVertices { count: 1, first: 1 }));
        assert!(warnings.contains(&Warning::DuplicateWeightEntries { count: 1 }));
        assert!(warnings.contains(&Warning::ZeroWeightEntries { count: 1 }));

        let (w, warnings) = SkinWeights::from_triplets(1, 2, [(0, 0, 0.2), (0, 1, 0.6)]).unwrap();
        assert!((w.get(0, 1) - 0.75).abs() < 1e-15);
        assert_eq!(
            warnings,
            vec![Warning::WeightsRenormalised {
                rows: 1,
                worst_sum: 0.8
            }]
        );
    }

    #[test]
    fn rejects_negative_nan_and_out_of_range() {
        assert!(matches!(
            SkinWeights::from_triplets(1, 1, [(0, 0, -0.1)]),
            Err(RigError::InvalidWeight { .. })
        ));
        assert!(matches!(
            SkinWeights::from_triplets(1, 1, [(0, 0, f64::NAN)]),
            Err(RigError::InvalidWeight { .. })
        ));
        assert!(matches!(
            SkinWeights::from_triplets(1, 1, [(0, 3, 1.0)]),
            Err(RigError::IndexOutOfRange { index: 3, .. })
        ));
        assert!(matches!(
            SkinWeights::from_triplets(1, MAX_JOINTS + 1, [(0, 0, 1.0)]),
            Err(RigError::TooManyJoints {
                joints: 65537,
                max: 65536
            })
        ));
    }
}
