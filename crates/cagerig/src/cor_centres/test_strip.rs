//! A test fixture shared by the CoR-centre tests: a strip of quads with its skinning weights.

/// A test strip of `n` quads along x: the points `point(x, y)` for x = i/n and y ∈ {0, 1}
/// (`2(n + 1)`, in that order), their Ω rows `row(x, y)`, and the strip's `2n` triangles.
pub(super) fn strip(
    n: usize,
    point: impl Fn(f64, f64) -> glam::DVec3,
    row: impl Fn(f64, f64) -> Vec<f64>,
) -> (
    Vec<glam::DVec3>,
    Vec<[u32; 3]>,
    crate::skin_weights::SkinWeights,
) {
    let mut p = Vec::new();
    let mut rows = Vec::new();
    for i in 0..=n {
        let x = i as f64 / n as f64;
        for y in [0.0, 1.0] {
            p.push(point(x, y));
            rows.push(row(x, y));
        }
    }
    let mut tris = Vec::new();
    for i in 0..n as u32 {
        let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
        tris.push([a, b, c]);
        tris.push([a, c, d]);
    }
    let (weights, _) = crate::skin_weights::SkinWeights::from_dense(&rows)
        .unwrap_or_else(|e| panic!("the strip's rows are weights: {e}"));
    (p, tris, weights)
}
