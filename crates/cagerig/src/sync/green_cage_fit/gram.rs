//! The Gauss–Newton part JᵀJ of [`super::GreenCageFit`]'s Hessian, assembled from the fitting
//! rows' Gram matrices and the block-sparse ∂g/∂C instead of multiplying J by itself.

use faer::{Accum, Mat, Par};
use glam::{DMat3, DVec3};

use super::GreenCageFit;
use crate::simd_dispatch::simd_dispatch;

/// φ_Rᵀφ_R (`#C × #C`), φ_Rᵀψ_R (`#C × #F`) and ψ_Rᵀψ_R (`#F × #F`) for φ_R = `vertex_rows`
/// (`#R × #C`) and ψ_R = `face_rows` (`#R × #F`).
pub(super) fn gram_matrices(
    vertex_rows: &Mat<f64>,
    face_rows: &Mat<f64>,
) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let gram = |a: &Mat<f64>, b: &Mat<f64>| {
        let mut out = Mat::<f64>::zeros(a.ncols(), b.ncols());
        faer::linalg::matmul::matmul(
            out.as_mut(),
            Accum::Replace,
            a.transpose(),
            b.as_ref(),
            1.0,
            Par::Seq,
        );
        out
    };
    (
        gram(vertex_rows, vertex_rows),
        gram(vertex_rows, face_rows),
        gram(face_rows, face_rows),
    )
}

impl GreenCageFit {
    /// tr(J₀ᵀJ₀) at the binding cage: the rows' Gauss–Newton scale, which sets the prior's λ
    /// ([`super::prior`]). Leaves no factorisation behind.
    pub fn binding_rows_scale(&mut self) -> f64 {
        let cage = std::mem::take(&mut self.binding_cage);
        self.gauss_newton_matrix_at(&cage);
        self.binding_cage = cage;
        self.lu.invalidate();
        self.factor_damping = f64::INFINITY;
        (0..3 * self.num_cage)
            .map(|i| self.normal_matrix[(i, i)])
            .sum()
    }

    /// JᵀJ at x into `self.normal_matrix`, from the Gram matrices: with J = φ_R ⊗ I₃ + (ψ_R ⊗ I₃)·D
    /// and D = ∂g/∂C (three 3×3 blocks B_{f,m} per face f, one per corner m),
    /// JᵀJ = φ_Rᵀφ_R ⊗ I₃ + (φ_Rᵀψ_R ⊗ I₃)·D + its transpose + Dᵀ·(ψ_Rᵀψ_R ⊗ I₃)·D. No allocation.
    pub(super) fn gauss_newton_matrix_at(&mut self, x: &[DVec3]) {
        let num_cage = self.num_cage;
        for (f, blocks) in self.face_blocks.iter_mut().enumerate() {
            *blocks = self.normals.face_jacobian(x, f);
        }
        // Accumulated in 3×3 blocks (row-major `#C × #C`), written into the matrix once.
        add_normal_terms(
            self.normals.triangles(),
            &self.face_blocks,
            &self.vertex_face_gram,
            &self.face_gram,
            &mut self.face_gram_blocks,
            &mut self.hessian_blocks,
        );
        let blocks = &self.hessian_blocks;
        // φ_Rᵀφ_R ⊗ I₃ on the blocks' diagonals, then the blocks into the matrix.
        let h = &mut self.normal_matrix;
        for m in 0..num_cage {
            let gram = self.vertex_gram.col(m);
            for b in 0..3 {
                let mut column = h.col_mut(3 * m + b);
                for k in 0..num_cage {
                    let block = &blocks[k * num_cage + m];
                    let mut value = block.col(b);
                    value[b] += gram[k];
                    column[3 * k] = value.x;
                    column[3 * k + 1] = value.y;
                    column[3 * k + 2] = value.z;
                }
            }
        }
    }
}

simd_dispatch! {
    /// The terms of JᵀJ that involve the normals, by 3×3 blocks into `blocks` (row-major
    /// `#C × #C`, zeroed here): the cross terms (φ_Rᵀψ_R ⊗ I₃)·D and their transposes, and
    /// Dᵀ·(ψ_Rᵀψ_R ⊗ I₃)·D through `face_gram_blocks` (`#F × #C`, T = (ψ_Rᵀψ_R ⊗ I₃)·D), for the
    /// faces' `triangles` and their blocks B_{f,m} of D = ∂g/∂C (`face_blocks`, `#F`), with
    /// φ_Rᵀψ_R `vertex_face_gram` (`#C × #F`) and ψ_Rᵀψ_R `face_gram` (`#F × #F`). The same
    /// operations in the same order on every tier (compiled with its wider registers), so the
    /// same bits.
    fn add_normal_terms(
        triangles: &[[u32; 3]],
        face_blocks: &[[DMat3; 3]],
        vertex_face_gram: &Mat<f64>,
        face_gram: &Mat<f64>,
        face_gram_blocks: &mut [DMat3],
        blocks: &mut [DMat3]
    ) => add_normal_terms_generic;
    avx2: add_normal_terms_avx2;
}

#[inline(always)]
fn add_normal_terms_generic(
    triangles: &[[u32; 3]],
    face_blocks: &[[DMat3; 3]],
    vertex_face_gram: &Mat<f64>,
    face_gram: &Mat<f64>,
    face_gram_blocks: &mut [DMat3],
    blocks: &mut [DMat3],
) {
    let (num_cage, num_faces) = (vertex_face_gram.nrows(), face_blocks.len());
    blocks.fill(DMat3::ZERO);
    // The cross terms: block (k, m) += (φ_Rᵀψ_R)[k, f]·B_{f,m}, and block (m, k) its transpose.
    for (f, (triangle, face)) in triangles.iter().zip(face_blocks).enumerate() {
        let weights = vertex_face_gram.col(f);
        for (&corner, block) in triangle.iter().zip(face) {
            let m = corner as usize;
            let transposed = block.transpose();
            for k in 0..num_cage {
                let weight = weights[k];
                if weight != 0.0 {
                    blocks[k * num_cage + m] += *block * weight;
                    blocks[m * num_cage + k] += transposed * weight;
                }
            }
        }
    }
    // The face terms: T = (ψ_Rᵀψ_R ⊗ I₃)·D by blocks (f, m), then block (m, m') += B_{f,m}ᵀ·T(f, m').
    face_gram_blocks.fill(DMat3::ZERO);
    for f in 0..num_faces {
        let row = &mut face_gram_blocks[f * num_cage..(f + 1) * num_cage];
        let weights = face_gram.col(f);
        for (g, (triangle, face)) in triangles.iter().zip(face_blocks).enumerate() {
            // ψ_Rᵀψ_R is symmetric: column f holds row f.
            let weight = weights[g];
            if weight != 0.0 {
                for (&corner, block) in triangle.iter().zip(face) {
                    row[corner as usize] += *block * weight;
                }
            }
        }
    }
    for (f, (triangle, face)) in triangles.iter().zip(face_blocks).enumerate() {
        let row = &face_gram_blocks[f * num_cage..(f + 1) * num_cage];
        for (&corner, block) in triangle.iter().zip(face) {
            let transposed = block.transpose();
            let out = &mut blocks[corner as usize * num_cage..(corner as usize + 1) * num_cage];
            for (o, t) in out.iter_mut().zip(row) {
                *o += transposed * *t;
            }
        }
    }
}
