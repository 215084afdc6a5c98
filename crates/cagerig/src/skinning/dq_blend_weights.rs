//! The per-vertex DQ blend weights `b` (`#V`, each in [0, 1]) of the blended skinning method:
//! vertex v is skinned `(1 − b_v)·LBS + b_v·DQS` (Maya's "weight blended" skin cluster, whose
//! per-vertex "DQ blend weight" ufbx reads as `ufbx_skin_vertex.dq_weight`). Validated once here,
//! at the boundary: every consumer may assume finite values in [0, 1].

use crate::RigError;

/// Validated DQ blend weights `b` (`#V`): `0` skins a vertex with LBS, `1` with DQS.
#[derive(Debug, Clone, PartialEq)]
pub struct DqBlendWeights {
    values: Vec<f64>,
}

impl DqBlendWeights {
    /// One weight per mesh vertex (`#V`). Errors with [`RigError::InvalidDqBlendWeight`] naming
    /// the first vertex whose weight is not a finite number in [0, 1].
    pub fn new(values: Vec<f64>) -> Result<Self, RigError> {
        if let Some((vertex, &weight)) = values
            .iter()
            .enumerate()
            .find(|(_, b)| !(b.is_finite() && (0.0..=1.0).contains(*b)))
        {
            return Err(RigError::InvalidDqBlendWeight { vertex, weight });
        }
        Ok(Self { values })
    }

    /// Every vertex with the same weight `b` (`#V` copies): `0` is LBS, `1` is DQS.
    pub fn uniform(num_vertices: usize, weight: f64) -> Result<Self, RigError> {
        Self::new(vec![weight; num_vertices])
    }

    /// The weights, `#V`.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Number of vertices `#V`.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The weights of `rows` (indices into `#V`, checked by the caller), in that order.
    pub fn select_rows(&self, rows: &[usize]) -> Self {
        Self {
            values: rows.iter().map(|&r| self.values[r]).collect(),
        }
    }

    /// Fails with [`RigError::SizeMismatch`] unless there is one weight per mesh vertex.
    pub fn check_vertices(&self, num_vertices: usize) -> Result<(), RigError> {
        if self.values.len() != num_vertices {
            return Err(RigError::SizeMismatch {
                what: "DQ blend weights (one per mesh vertex)",
                expected: num_vertices,
                actual: self.values.len(),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_outside_the_unit_interval_name_their_vertex() {
        assert!(DqBlendWeights::new(vec![0.0, 0.25, 1.0]).is_ok());
        for bad in [-1e-9, 1.0 + 1e-9, f64::NAN, f64::INFINITY] {
            let err = DqBlendWeights::new(vec![0.5, 0.5, bad]).unwrap_err();
            assert!(
                matches!(err, RigError::InvalidDqBlendWeight { vertex: 2, .. }),
                "{err:?}"
            );
            let text = err.to_string();
            assert!(
                text.contains("vertex 2") && text.contains("[0, 1]"),
                "{text}"
            );
        }
    }

    #[test]
    fn rows_and_sizes() {
        let b = DqBlendWeights::new(vec![0.0, 0.1, 0.2, 0.3]).unwrap();
        assert_eq!(b.select_rows(&[3, 1]).values(), &[0.3, 0.1]);
        assert!(b.check_vertices(4).is_ok());
        let err = b.check_vertices(5).unwrap_err();
        assert!(matches!(
            err,
            RigError::SizeMismatch {
                expected: 5,
                actual: 4,
                ..
            }
        ));
        assert_eq!(DqBlendWeights::uniform(3, 1.0).unwrap().values(), &[1.0; 3]);
    }
}
