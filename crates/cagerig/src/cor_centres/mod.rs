//! The centres of rotation of CoR skinning as a linear function of the rest cage: the
//! precomputation beside [`crate::skinning`] (Le & Hodgins 2016, Eq. 5; CoRs = S·M = Λ·C,
//! Eq. 14).
//!
//! | file | concern |
//! |---|---|
//! | `options.rs` | options: kernel width, pruning, exact or clustered rows |
//! | `similarity.rs` | the weight similarity s(w_p, w_v) |
//! | `exact.rs` | S from Ω and M, per vertex or per cluster of equal weight rows |
//! | `factored.rs` | S = A·B, its application and product |
//! | `cage_coords.rs` | Λ = S·Φ from the factored S |
//! | `grid.rs` (+ `grid_bins.rs`, `grid_tables.rs`, `grid_rows.rs`) | Λ directly, on a grid in weight space, for large meshes |

pub mod cage_coords;
pub mod exact;
mod factored;
pub mod grid;
mod grid_bins;
mod grid_layout;
mod grid_rows;
mod grid_tables;
mod options;
mod similarity;

pub use cage_coords::compute_cor_cage_coords;
pub use exact::{compute_cor_centres, compute_cor_centres_factored};
pub use factored::CorCentresFactored;
pub use grid::{CorGridOptions, GridInterpolation, compute_cor_cage_coords_grid};
pub use options::{CorCentresMethod, CorCentresOptions};
pub use similarity::weight_similarity;

/// A test strip of `n` quads along x: the points `point(x, y)` for x = i/n and y ∈ {0, 1}
/// (`2(n + 1)`, in that order), their Ω rows `row(x, y)`, and the strip's `2n` triangles.
#[cfg(test)]
fn strip(
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
