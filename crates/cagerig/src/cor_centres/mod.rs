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
#[cfg(test)]
mod test_strip;

pub use cage_coords::compute_cor_cage_coords;
pub use exact::{compute_cor_centres, compute_cor_centres_factored};
pub use factored::CorCentresFactored;
pub use grid::{CorGridOptions, GridInterpolation, compute_cor_cage_coords_grid};
pub use options::{CorCentresMethod, CorCentresOptions};
pub use similarity::weight_similarity;
