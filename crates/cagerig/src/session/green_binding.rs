//! Binding a mesh with Green coordinates: φ and ψ of its vertices (mean value coordinates for
//! the few outside the cage) and CageUp's fitting rows of [φ ψ].

use crate::cage_coords::CageCoords;
use crate::coords::green::compute_green_coords;
use crate::coords::{maxvol, mvc};
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;
use glam::DVec3;

/// Green coordinates of the rest mesh's vertices, and how many lie outside the cage: those
/// (where Σφ ≠ 1: Green coordinates reproduce only interior points) get their mean value
/// coordinates as φ and no face terms.
pub(super) fn compute_green_coords_for_mesh(
    cage: &TriMesh,
    positions: &[DVec3],
    progress: Option<&(dyn Fn(usize) + Sync)>,
) -> Result<(crate::coords::green::GreenCoords, usize), RigError> {
    let mut coords = compute_green_coords(cage, positions, progress)?;
    let nc = cage.num_vertices();
    let outside: Vec<usize> = (0..positions.len())
        .filter(|&i| {
            let sum: f64 = (0..nc).map(|k| coords.vertex.get(i, k)).sum();
            (sum - 1.0).abs() > 1e-6
        })
        .collect();
    if outside.is_empty() {
        return Ok((coords, 0));
    }
    let points: Vec<DVec3> = outside.iter().map(|&i| positions[i]).collect();
    let mvc_rows = mvc::compute_cage_coords(cage, &points, None)?;
    let mut vertex = coords.vertex.matrix().clone();
    let mut face = coords.face.matrix().clone();
    for (r, &i) in outside.iter().enumerate() {
        for k in 0..nc {
            vertex[(i, k)] = mvc_rows.get(r, k);
        }
        for f in 0..face.ncols() {
            face[(i, f)] = 0.0;
        }
    }
    coords.vertex = CageCoords::from_matrix(vertex)?;
    coords.face = CageCoords::from_matrix(face)?;
    Ok((coords, outside.len()))
}

/// Green CageUp's fitting rows: the MaxVol rows of [φ ψ] (`#V × (#C + #F)`), or every row
/// when the mesh has no more rows than that or [φ ψ] is rank deficient — a mesh with fewer
/// distinct points than #C + #F (an unindexed glTF repeats each corner: the Fox has 290
/// distinct points of 1,728 for a cage of 100 vertices and 196 faces) — with a note saying so.
pub(super) fn green_fit_rows(
    vertex: &CageCoords,
    face: &CageCoords,
    mesh_positions: &[DVec3],
    warnings: &mut Vec<Warning>,
) -> Result<Vec<usize>, RigError> {
    let (nv, nc, nf) = (
        vertex.num_vertices(),
        vertex.num_cage_vertices(),
        face.num_cage_vertices(),
    );
    if nv <= nc + nf {
        return Ok((0..nv).collect());
    }
    let combined = faer::Mat::from_fn(nv, nc + nf, |i, k| {
        if k < nc {
            vertex.get(i, k)
        } else {
            face.get(i, k - nc)
        }
    });
    match maxvol::select_maxvol_rows(&CageCoords::from_matrix(combined)?) {
        Ok(selection) => Ok(selection.rows),
        Err(RigError::Singular { .. }) => {
            let mut distinct: Vec<[u64; 3]> = mesh_positions
                .iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect();
            distinct.sort_unstable();
            distinct.dedup();
            warnings.push(Warning::Note {
                message: format!(
                    "Green CageUp fits all {nv} mesh vertices: [φ ψ] has no {} independent rows \
                     for MaxVol (#C + #F = {nc} + {nf}; the mesh has {} distinct positions)",
                    nc + nf,
                    distinct.len()
                ),
            });
            Ok((0..nv).collect())
        }
        Err(e) => Err(e),
    }
}
