//! Barycentric coordinates: mean value (Φ), Green (φ, ψ), max-entropy (Ψ projection), MaxVol row selection.

pub mod green;
mod green_triangle;
pub(crate) mod local_mvc;
pub mod maxvol;
mod maxvol_dominance;
mod maxvol_lu;
mod maxvol_swaps;
pub mod mec;
pub mod mec_signed;
pub mod mvc;
mod mvc_batch;
mod mvc_lanes;
mod mvc_triangle;
pub mod stretched_normals;
