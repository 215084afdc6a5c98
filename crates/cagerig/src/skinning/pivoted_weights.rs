//! Ω as flat CSR rows plus each vertex's heaviest joint: the data of the f64 DQS and CoR
//! kernels, which align the sign of every influence's quaternion with that pivot's.

use crate::SkinWeights;

/// Ω (`#V × #J`, CSR with u32 joints) and the per-vertex pivot joint.
#[derive(Debug, Clone)]
pub(crate) struct PivotedWeights {
    pub num_joints: usize,
    /// Row v spans `row_start[v]..row_start[v + 1]` of `joints`/`weights`, `#V + 1`.
    pub row_start: Vec<u32>,
    pub joints: Vec<u32>,
    pub weights: Vec<f64>,
    /// Heaviest joint per vertex (0 for unweighted vertices, unused there), `#V`.
    pub pivot: Vec<u32>,
}

impl PivotedWeights {
    pub fn new(weights: &SkinWeights) -> Self {
        let (row_start, joints, w) = weights.csr();
        Self {
            num_joints: weights.num_joints(),
            row_start: row_start.to_vec(),
            joints: joints.to_vec(),
            weights: w.to_vec(),
            pivot: (0..weights.num_vertices())
                .map(|v| weights.heaviest(v).unwrap_or(0) as u32)
                .collect(),
        }
    }

    pub fn num_vertices(&self) -> usize {
        self.row_start.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pivot_is_the_heaviest_influence_and_rows_match() {
        let (w, _) = SkinWeights::from_dense(&[
            vec![0.2, 0.5, 0.3],
            vec![0.0, 0.0, 1.0],
            vec![0.6, 0.4, 0.0],
        ])
        .unwrap();
        let p = PivotedWeights::new(&w);
        assert_eq!(p.num_vertices(), 3);
        assert_eq!(p.num_joints, 3);
        assert_eq!(p.pivot, vec![1, 2, 0]);
        let row = |v: usize| p.row_start[v] as usize..p.row_start[v + 1] as usize;
        assert_eq!(&p.joints[row(0)], &[0, 1, 2]);
        assert_eq!(&p.joints[row(1)], &[2]);
        assert_eq!(&p.weights[row(2)], &[0.6, 0.4]);
    }
}
