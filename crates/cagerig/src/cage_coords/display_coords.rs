//! Φ rounded to f32 for the display path: the displayed rest mesh M̃ = Φ̃·C after a current-cage
//! edit, reading half the bytes of the exact product.

use glam::{DVec3, Vec3};

use super::CageCoords;
use super::column_products::accumulate_columns;

/// Φ̃: the cage coordinates Φ rounded to f32, `#V × #C`, column-major with stride `#V`.
///
/// [`DisplayCageCoords::apply`] gives M̃ = Φ̃·C summed in f64 and rounded once to f32. Against the
/// exact M = Φ·C, each point moves by at most 2⁻²⁴·Σ_k |Φ[i,k]|·|C_k| (the rounding of Φ)
/// plus half an f32 ulp of the point (the rounding of the sum); `tests/display_path.rs` bounds
/// the whole drawn mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct DisplayCageCoords {
    columns: Vec<f32>,
    num_vertices: usize,
}

impl DisplayCageCoords {
    /// Rounds Φ (`#V × #C`) to f32. `None` when the `#V · #C · 4` bytes cannot be reserved (the
    /// caller then stays on the exact product).
    pub fn try_new(coords: &CageCoords) -> Option<Self> {
        Self::try_new_concatenated(&[coords])
    }

    /// The columns of `parts` side by side, rounded to f32: `[Φ ψ]` (`#V × (#C + #F)`) for the
    /// Green display path, whose M̃ = φ̃·C + ψ̃·g is one product. `None` when the parts' row counts
    /// differ or the bytes cannot be reserved.
    pub fn try_new_concatenated(parts: &[&CageCoords]) -> Option<Self> {
        let nv = parts.first()?.num_vertices();
        if parts.iter().any(|p| p.num_vertices() != nv) {
            return None;
        }
        let nc: usize = parts.iter().map(|p| p.num_cage_vertices()).sum();
        let mut columns = Vec::new();
        columns.try_reserve_exact(nv.checked_mul(nc)?).ok()?;
        for part in parts {
            for k in 0..part.num_cage_vertices() {
                columns.extend(part.column(k).iter().map(|&w| w as f32));
            }
        }
        Some(Self {
            columns,
            num_vertices: nv,
        })
    }

    /// Number of mesh vertices `#V` (rows of Φ̃).
    pub fn num_vertices(&self) -> usize {
        self.num_vertices
    }

    /// Number of cage vertices `#C` (columns of Φ̃).
    pub fn num_cage_vertices(&self) -> usize {
        self.columns
            .len()
            .checked_div(self.num_vertices)
            .unwrap_or(0)
    }

    /// M̃ = Φ̃·C: `cage` is `#C`, `out` is `#V` (f32). Parallel over row blocks, no allocation.
    ///
    /// # Panics
    /// If `cage` is not `#C` long or `out` not `#V` long.
    pub fn apply(&self, cage: &[DVec3], out: &mut [Vec3]) {
        self.apply_concatenated(cage, &[], out);
    }

    /// M̃ = Φ̃·[`head`; `tail`] for concatenated columns ([`Self::try_new_concatenated`]): the
    /// Green display path's φ̃·C + ψ̃·g with `head` = C (`#C`) and `tail` = g (`#F`), summed in
    /// f64 and rounded once. Parallel over row blocks, no allocation.
    ///
    /// # Panics
    /// If `head` and `tail` together are not as long as the columns, or `out` not `#V` long.
    pub fn apply_concatenated(&self, head: &[DVec3], tail: &[DVec3], out: &mut [Vec3]) {
        assert_eq!(
            head.len() + tail.len(),
            self.num_cage_vertices(),
            "Φ̃·C: cage length"
        );
        assert_eq!(out.len(), self.num_vertices, "Φ̃·C: output length");
        let nv = self.num_vertices;
        accumulate_columns(
            |k| &self.columns[k * nv..(k + 1) * nv],
            &[head.iter().chain(tail).enumerate().map(|(k, c)| (k, *c))],
            false,
            out,
        );
    }
}

#[cfg(test)]
mod tests {
    use faer::Mat;

    use super::*;

    #[test]
    fn the_f32_product_is_the_exact_one_within_the_stated_bound() {
        let (nv, nc) = (5000, 6);
        // Rows of a partition of unity with negative entries, like mean value coordinates.
        let matrix = Mat::from_fn(nv, nc, |i, k| {
            let a = ((i * 37 + k * 11) % 97) as f64 / 97.0 - 0.2;
            if k + 1 == nc {
                0.0
            } else {
                a / (nc - 1) as f64
            }
        });
        let matrix = Mat::from_fn(nv, nc, |i, k| {
            let rest: f64 = (0..nc - 1).map(|c| matrix[(i, c)]).sum();
            if k + 1 == nc {
                1.0 - rest
            } else {
                matrix[(i, k)]
            }
        });
        let phi = CageCoords::from_matrix(matrix.clone()).unwrap();
        let display = DisplayCageCoords::try_new(&phi).unwrap();
        assert_eq!(
            (display.num_vertices(), display.num_cage_vertices()),
            (nv, nc)
        );
        let cage: Vec<DVec3> = (0..nc)
            .map(|k| DVec3::new(100.0 + k as f64, -3.0 * k as f64, 0.5 + (k * k) as f64))
            .collect();
        let mut exact = vec![DVec3::ZERO; nv];
        phi.apply(&cage, &mut exact);
        let mut shown = vec![Vec3::NAN; nv];
        display.apply(&cage, &mut shown);
        for i in 0..nv {
            let spread: f64 = (0..nc)
                .map(|k| matrix[(i, k)].abs() * cage[k].length())
                .sum();
            let bound = spread * 2f64.powi(-24) + exact[i].abs().max_element() * 2f64.powi(-24);
            let err = (shown[i].as_dvec3() - exact[i]).abs().max_element();
            assert!(err <= bound, "row {i}: {err:e} > {bound:e}");
        }
    }
}
