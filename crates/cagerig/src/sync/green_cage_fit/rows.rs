//! The fitting rows of a Green cage map, `F_R(x) = φ_R x + ψ_R g(x)`, and their Jacobian: shared
//! by CageUp's fit ([`super::GreenCageFit`]), CageRev ([`super::reverser`])
//! and SkelUp's joints (the same form with Ψ_φ, Ψ_ψ).

use faer::Mat;
use glam::DVec3;

use crate::coords::stretched_normals::StretchedNormals;

/// The Jacobian of rows `φ x + ψ g(x)` (`vertex_rows` φ `#R × #C`, `face_rows` ψ `#R × #F`) at
/// x (`#C`): `φ ⊗ I₃ + ψ ∂g/∂x` into `out` (`3#R × 3#C`, row 3i + a, column 3k + b).
pub(crate) fn rows_jacobian_into(
    vertex_rows: &Mat<f64>,
    face_rows: &Mat<f64>,
    normals: &StretchedNormals,
    x: &[DVec3],
    out: &mut Mat<f64>,
) {
    let num_rows = vertex_rows.nrows();
    out.fill(0.0);
    for k in 0..vertex_rows.ncols() {
        let column = vertex_rows.col(k);
        for i in 0..num_rows {
            for a in 0..3 {
                out[(3 * i + a, 3 * k + a)] = column[i];
            }
        }
    }
    for (f, triangle) in normals.triangles().iter().enumerate() {
        let blocks = normals.face_jacobian(x, f);
        let column = face_rows.col(f);
        for (corner, block) in triangle.iter().zip(blocks) {
            let m = *corner as usize;
            for c in 0..3 {
                let d = block.col(c);
                let mut target = out.col_mut(3 * m + c);
                for i in 0..num_rows {
                    let w = column[i];
                    target[3 * i] += w * d.x;
                    target[3 * i + 1] += w * d.y;
                    target[3 * i + 2] += w * d.z;
                }
            }
        }
    }
}

/// out = φ_R x + ψ_R g (`#R`).
pub(crate) fn rows_of(
    vertex_rows: &Mat<f64>,
    face_rows: &Mat<f64>,
    x: &[DVec3],
    g: &[DVec3],
    out: &mut [DVec3],
) {
    out.iter_mut().for_each(|o| *o = DVec3::ZERO);
    for (k, xk) in x.iter().enumerate() {
        let column = vertex_rows.col(k);
        for (i, o) in out.iter_mut().enumerate() {
            *o += column[i] * *xk;
        }
    }
    for (f, gf) in g.iter().enumerate() {
        let column = face_rows.col(f);
        for (i, o) in out.iter_mut().enumerate() {
            *o += column[i] * *gf;
        }
    }
}
