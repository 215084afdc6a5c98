//! Barycentric coordinates: mean value (Φ), Green (φ, ψ), max-entropy (Ψ projection), MaxVol row selection.

pub mod green;
mod green_batch;
mod green_triangle;
mod lane_functions;
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
#[cfg(test)]
mod progress_tests;
pub mod stretched_normals;

/// The checks every cage-coordinates computation makes first: a cage with triangles, finite
/// points, and room for the dense `#points × columns` result (named `what` in the error).
pub(crate) fn check_coords_inputs(
    cage: &crate::mesh::TriMesh,
    points: &[glam::DVec3],
    what: &'static str,
    columns: usize,
) -> Result<(), crate::error::RigError> {
    if cage.triangles.is_empty() {
        return Err(crate::error::RigError::EmptyCage);
    }
    if let Some(index) = points.iter().position(|p| !p.is_finite()) {
        return Err(crate::error::RigError::NonFinite {
            what: "point",
            index,
        });
    }
    crate::memory_estimate::check_dense_allocation(what, points.len(), columns)
}
