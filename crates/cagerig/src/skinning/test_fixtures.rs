//! A rig shared by the skinning kernels' tests.

use glam::DVec3;

/// 20 000 vertices over 3 joints (several chunks, so the sign table and the blocks are in use)
/// with 1, 2 or 3 influences in turn: the dense weight rows and the rest positions.
pub(super) fn twenty_thousand_vertices() -> (Vec<Vec<f64>>, Vec<DVec3>) {
    let num_vertices = 20_000;
    let rows = (0..num_vertices)
        .map(|v| match v % 3 {
            0 => vec![1.0, 0.0, 0.0],
            1 => vec![0.25, 0.0, 0.75],
            _ => vec![0.2, 0.3, 0.5],
        })
        .collect();
    let rest = (0..num_vertices)
        .map(|v| DVec3::new(v as f64 * 1e-3, (v % 7) as f64, -((v % 11) as f64)))
        .collect();
    (rows, rest)
}
