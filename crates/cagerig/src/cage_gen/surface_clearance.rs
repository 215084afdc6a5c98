//! Distances of the starting surface to the mesh, and the exact check that lets the offset
//! search start tighter than the marching-tetrahedra guarantee.
//!
//! [`super::marching_tets`] guarantees the margin only for offsets ≥ margin + h√3 (a surface
//! point may lie anywhere in a tetrahedron of diameter h√3 around a sample farther than the
//! offset). In practice the surface follows the offset level set far more closely, so the
//! search first tries offset = margin + [`TIGHT_OFFSET_SPACINGS`]·h and accepts that surface only
//! if [`check_start_surface`] proves, exactly, what the guarantee would have given: every
//! surface triangle at least the margin from every mesh triangle (so the surface never meets the
//! mesh and each mesh piece lies wholly on one side) and every mesh piece inside (winding number
//! 1). Otherwise it falls back to the guaranteed offset.

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::TriangleBvh;
use super::marching_tets::Surface;
use crate::mesh::winding_number;

/// Offset of the first, verified attempt above the margin, in grid spacings (the guarantee
/// needs √3 ≈ 1.73): enough for the linear interpolation's sagitta over convex parts, where
/// the level set bends most within a tetrahedron.
pub const TIGHT_OFFSET_SPACINGS: f64 = 0.75;

/// Distance of every surface vertex to the mesh (`#surface vertices`), exact.
pub fn vertex_clearances(surface: &Surface, mesh: &TriangleBvh) -> Vec<f64> {
    surface
        .positions
        .par_iter()
        .map(|&p| mesh.nearest_distance(p, f64::INFINITY))
        .collect()
}

/// Checks that `surface` (closed, embedded, one piece) keeps `margin` from the mesh (`mesh`,
/// with the surface vertices' distances `clearances`) and encloses each mesh piece (one point
/// each in `piece_points`); `Err` says what failed.
pub fn check_start_surface(
    surface: &Surface,
    clearances: &[f64],
    mesh: &TriangleBvh,
    margin: f64,
    piece_points: &[DVec3],
) -> Result<(), String> {
    let too_close = surface
        .triangles
        .par_iter()
        .filter(|tri| {
            let corners = tri.map(|v| surface.positions[v as usize]);
            let distances = tri.map(|v| clearances[v as usize]);
            !mesh.clear_of(corners, distances, margin)
        })
        .count();
    if too_close > 0 {
        return Err(format!(
            "{too_close} surface triangle(s) closer than the margin to the mesh"
        ));
    }
    let outside = piece_points
        .par_iter()
        .filter(|&&p| {
            (winding_number(&surface.positions, &surface.triangles, p) - 1.0).abs() > 1e-6
        })
        .count();
    if outside > 0 {
        return Err(format!(
            "{outside} of {} mesh piece(s) not inside the surface",
            piece_points.len()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cage_gen::bvh::Aabb;
    use crate::cage_gen::distance_grid::{SampleGrid, fill_from_outside};
    use crate::cage_gen::marching_tets::extract_surface;

    fn ball_surface(offset: f64, h: f64) -> (Surface, TriangleBvh) {
        let t = [DVec3::ZERO, DVec3::X * 1e-3, DVec3::Y * 1e-3];
        let bvh = TriangleBvh::new(vec![t]);
        let bounds = Aabb::of_triangle(&t);
        let grid = SampleGrid::around(bounds, h, offset + 2.0 * h);
        let field = fill_from_outside(grid, &bvh, bounds, offset);
        (extract_surface(&field), bvh)
    }

    #[test]
    fn tight_surface_passes_and_a_margin_beyond_it_fails() {
        let (h, margin) = (0.1, 0.3);
        let (surface, bvh) = ball_surface(margin + TIGHT_OFFSET_SPACINGS * h, h);
        let clearances = vertex_clearances(&surface, &bvh);
        let inside = [DVec3::ZERO];
        assert_eq!(
            check_start_surface(&surface, &clearances, &bvh, margin, &inside),
            Ok(())
        );
        let least = clearances.iter().copied().fold(f64::INFINITY, f64::min);
        let err = check_start_surface(&surface, &clearances, &bvh, least * 1.001, &inside);
        assert!(err.unwrap_err().contains("closer than the margin"));
        let far = [DVec3::splat(5.0)];
        let err = check_start_surface(&surface, &clearances, &bvh, margin, &far);
        assert!(err.unwrap_err().contains("not inside"));
    }
}
