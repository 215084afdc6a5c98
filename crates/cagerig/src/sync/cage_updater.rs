//! CageUp, S'→C' (Section 4.1, Eq. 8): fit the current cage C' to the current skin M'.
//!
//! C' is obtained from a few selected rows of M' (the MaxVol rows, `#C` of them) by a linear map
//! `P` computed once: `P = Φ̃⁻¹` for the square MaxVol system (exact interpolation of the selected
//! vertices), or `P = Φ̃⁺` (least squares, `(Φ̃ᵀΦ̃)⁻¹Φ̃ᵀ` via QR) when more rows are used.
//! Per frame, C' = P · M̃' is a small dense product (`#C × #R` by `#R × 3`), with no allocation.
//!
//! [`CageUpdater::regularised`] turns the paper's fit into the regularised one
//! ([`super::cage_prior`]): C' = K·M̃' + Q·P(C, S'), still linear in both targets.

use faer::Mat;
use glam::{DMat3, DVec3};

use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_fit_kind::CageFitKind;
use crate::sync::cage_prior::{BindingJoints, CagePrior, RegularisedMaps, regularised_maps};
use crate::sync::small_products::{accumulate_column, accumulate_product};

/// Reciprocal condition estimate below which a cage-fitting system is rejected as singular.
pub const MIN_RECIPROCAL_CONDITION: f64 = 1e-13;

/// How C' is fitted to the selected mesh rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CageFitMode {
    /// Square system Φ̃ C' = M̃' on exactly `#C` rows (the paper's MaxVol relaxation, Eq. 8).
    #[default]
    Interpolate,
    /// Least squares on `#R ≥ #C` rows: C' = argmin ‖Φ̃ C' − M̃'‖².
    LeastSquares,
}

/// The CageUp operator: maps the posed positions of `rows` to the posed cage C'.
#[derive(Debug, Clone)]
pub struct CageUpdater {
    rows: Vec<usize>,
    mode: CageFitMode,
    /// The rows' map of CageUp, `#C × #R`, column-major: P = Φ̃⁻¹ or Φ̃⁺ for the paper's fit,
    /// K = H⁻¹Φ̃ᵀ for the regularised one (C' = K·M̃' + Q·P).
    cage_from_rows: Mat<f64>,
    /// The regularised fit's prior (P's neighbourhoods and Q); `None` for the paper's fit.
    prior: Option<CagePrior>,
    /// Φ̃⁻¹ or Φ̃⁺ (`#C × #R`) when `cage_from_rows` is K: the rest cage whose ΦC reproduces
    /// given rows ([`Self::apply_rows`]).
    interpolant: Option<Mat<f64>>,
}

impl CageUpdater {
    /// Factorises the fitting system for the given mesh rows of Φ (`#V × #C`).
    pub fn new(
        cage_coords: &CageCoords,
        rows: Vec<usize>,
        mode: CageFitMode,
    ) -> Result<Self, RigError> {
        let num_cage = cage_coords.num_cage_vertices();
        let num_vertices = cage_coords.num_vertices();
        if let Some(&bad) = rows.iter().find(|&&r| r >= num_vertices) {
            return Err(RigError::IndexOutOfRange {
                what: "cage-fitting row",
                index: bad,
                len: num_vertices,
            });
        }
        let selected = cage_coords.select_rows(&rows);
        let cage_from_rows = match mode {
            CageFitMode::Interpolate => {
                if rows.len() != num_cage {
                    return Err(RigError::SizeMismatch {
                        what: "number of interpolated rows (must equal the cage vertex count)",
                        expected: num_cage,
                        actual: rows.len(),
                    });
                }
                // Sequential: rayon dispatch cost more than this #C × #C factorisation
                // (Arm: 0.24 ms with 2 threads, 0.06 ms with 1).
                let lu = crate::coords::maxvol::SeqLu::new(selected);
                check_triangular_condition(lu.diagonal())?;
                lu.inverse()
            }
            CageFitMode::LeastSquares => {
                if rows.len() < num_cage {
                    return Err(RigError::SizeMismatch {
                        what: "number of least-squares rows (at least the cage vertex count)",
                        expected: num_cage,
                        actual: rows.len(),
                    });
                }
                let qr = selected.qr();
                let r = qr.thin_R();
                check_triangular_condition(r.diagonal().column_vector().iter().copied())?;
                let q = qr.compute_thin_Q();
                // P = R⁻¹ Qᵀ: solve R · P = Qᵀ by back substitution.
                let mut p = q.transpose().to_owned();
                faer::linalg::triangular_solve::solve_upper_triangular_in_place(
                    r,
                    p.as_mut(),
                    faer::Par::Seq,
                );
                p
            }
        };
        crate::vector_registers::clear_upper_halves();
        Ok(Self {
            rows,
            mode,
            cage_from_rows,
            prior: None,
            interpolant: None,
        })
    }

    /// The regularised fit on the same rows ([`super::cage_prior`]): `cage_coords` is Φ
    /// (`#V × #C`) of the rest skin `rest_mesh` (`#V`) in `rest_cage` (`#C`, with its
    /// `cage_triangles`), `skin_weights` Ω (`#V × #J`), `binding_joints` the skeleton of the
    /// binding (`#J`). [`Self::apply_rows`] keeps the paper's map.
    pub fn regularised(
        self,
        cage_coords: &CageCoords,
        rest_cage: &[DVec3],
        cage_triangles: &[[u32; 3]],
        rest_mesh: &[DVec3],
        skin_weights: &SkinWeights,
        binding_joints: &BindingJoints,
    ) -> Result<Self, RigError> {
        let RegularisedMaps {
            cage_from_rows,
            prior,
        } = regularised_maps(
            cage_coords,
            &self.rows,
            rest_cage,
            cage_triangles,
            rest_mesh,
            skin_weights,
            binding_joints,
            crate::sync::cage_prior::NeighbourCoords::Fitting,
        )?;
        Ok(Self {
            rows: self.rows,
            mode: self.mode,
            cage_from_rows,
            prior: Some(prior),
            interpolant: Some(self.cage_from_rows),
        })
    }

    /// The paper's fit on the same rows (a copy of this one when it is the paper's).
    pub fn paper(&self) -> Self {
        Self {
            rows: self.rows.clone(),
            mode: self.mode,
            cage_from_rows: self.interpolant().clone(),
            prior: None,
            interpolant: None,
        }
    }

    /// Which fit this is.
    pub fn fit_kind(&self) -> CageFitKind {
        match self.prior {
            Some(_) => CageFitKind::Regularised,
            None => CageFitKind::Paper,
        }
    }

    /// The regularised fit's prior (P's neighbourhoods and Q); `None` for the paper's fit.
    pub fn prior(&self) -> Option<&CagePrior> {
        self.prior.as_ref()
    }

    /// CageUp: C' (`posed_cage`, `#C`) from the posed fitting rows `posed_rows` (`#R`): P·M̃'
    /// for the paper's fit; K·M̃' + Q·P(C, S') for the regularised one, with the skinning
    /// transforms `posed_from_rest` (`#J`) and the rest cage `rest_cage` (`#C`). No allocation.
    pub fn fit(
        &mut self,
        posed_rows: &[DVec3],
        posed_from_rest: &[glam::DAffine3],
        rest_cage: &[DVec3],
        posed_cage: &mut [DVec3],
    ) {
        posed_cage.iter_mut().for_each(|c| *c = DVec3::ZERO);
        accumulate_product(&self.cage_from_rows, posed_rows, posed_cage);
        if let Some(prior) = &mut self.prior {
            prior.carry(posed_from_rest, rest_cage);
            accumulate_product(prior.cage_from_prior(), prior.carried_cage(), posed_cage);
            prior.limit_reach(posed_from_rest, &self.cage_from_rows, posed_cage);
        }
    }

    /// The reach factors s (`#C`) the regularised fit applied in the pose whose skinning
    /// transforms have the linear parts `joint_linear` (`#J`), when its last fit was in that
    /// pose; `None` otherwise and for the paper's fit. CageRev's rows take them
    /// ([`crate::sync::cage_reverser::CageReverser::refactor`]).
    pub fn reach_factors_in_pose(&self, joint_linear: &[DMat3]) -> Option<&[f64]> {
        self.prior.as_ref()?.reach_factors_in_pose(joint_linear)
    }

    /// The mesh rows the fit uses (`#R`).
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// How C' is fitted: interpolation of `#C` rows or least squares.
    pub fn mode(&self) -> CageFitMode {
        self.mode
    }

    /// CageUp's map of the rows, `#C × #R`: P = Φ̃⁻¹ or Φ̃⁺ for the paper's fit, K for the
    /// regularised one.
    pub fn cage_from_rows(&self) -> &Mat<f64> {
        &self.cage_from_rows
    }

    /// The cage whose ΦC reproduces the rows: Φ̃⁻¹ or Φ̃⁺ (`#C × #R`), whatever the fit.
    pub fn interpolant(&self) -> &Mat<f64> {
        self.interpolant.as_ref().unwrap_or(&self.cage_from_rows)
    }

    /// `cage` (`#C`) = [`Self::interpolant`] · `rows` (`#R`): for the paper's fit from the full
    /// mesh (`#V`, reading only the selected rows) this is CageUp without a prior.
    pub fn apply(&self, mesh: &[DVec3], cage: &mut [DVec3]) {
        cage.iter_mut().for_each(|c| *c = DVec3::ZERO);
        for (r, &row) in self.rows.iter().enumerate() {
            accumulate_column(self.interpolant(), r, mesh[row], cage);
        }
    }

    /// `cage` (`#C`) = [`Self::interpolant`] · `rows` (`#R`, e.g. a ghost mesh): the rest cage
    /// whose ΦC interpolates (or fits) the rows; the paper's CageUp of posed rows.
    pub fn apply_rows(&self, rows: &[DVec3], cage: &mut [DVec3]) {
        cage.iter_mut().for_each(|c| *c = DVec3::ZERO);
        accumulate_product(self.interpolant(), rows, cage);
    }
}

/// Rejects a triangular factor whose diagonal spans more than 1/MIN_RECIPROCAL_CONDITION.
pub(crate) fn check_triangular_condition(
    diagonal: impl Iterator<Item = f64>,
) -> Result<(), RigError> {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for d in diagonal {
        lo = lo.min(d.abs());
        hi = hi.max(d.abs());
    }
    if lo.is_nan() || lo <= MIN_RECIPROCAL_CONDITION * hi || !lo.is_finite() {
        return Err(RigError::Singular {
            what: "the cage-fitting system",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Φ of a 1D-like toy: 4 "cage vertices" (tetrahedron corners) and points given by
    /// barycentric rows; fitting recovers the cage exactly from any 4 independent rows.
    fn toy() -> (CageCoords, Vec<DVec3>) {
        let rows = vec![
            vec![0.7, 0.1, 0.1, 0.1],
            vec![0.1, 0.7, 0.1, 0.1],
            vec![0.1, 0.1, 0.7, 0.1],
            vec![0.1, 0.1, 0.1, 0.7],
            vec![0.25, 0.25, 0.25, 0.25],
            vec![0.4, 0.4, 0.1, 0.1],
        ];
        let cage = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 1.0),
            DVec3::new(1.0, 1.0, 4.0),
        ];
        (CageCoords::from_rows(&rows, 4).unwrap(), cage)
    }

    #[test]
    fn interpolation_and_least_squares_recover_an_exact_cage() {
        let (phi, cage) = toy();
        let mut mesh = vec![DVec3::ZERO; phi.num_vertices()];
        phi.apply(&cage, &mut mesh);
        for (rows, mode) in [
            (vec![0, 1, 2, 3], CageFitMode::Interpolate),
            (vec![5, 1, 2, 3], CageFitMode::Interpolate),
            ((0..6).collect(), CageFitMode::LeastSquares),
        ] {
            let up = CageUpdater::new(&phi, rows, mode).unwrap();
            let mut fitted = vec![DVec3::ZERO; 4];
            up.apply(&mesh, &mut fitted);
            assert!(
                crate::mesh::max_distance(&fitted, &cage) < 1e-12,
                "{mode:?}"
            );
        }
    }

    #[test]
    fn rejects_singular_and_wrong_sizes() {
        let (phi, _) = toy();
        assert!(CageUpdater::new(&phi, vec![0, 1, 2, 4], CageFitMode::Interpolate).is_ok());
        // Row 2 is the mean of rows 0 and 1: a dependent set.
        let dependent = CageCoords::from_rows(
            &[
                vec![0.5, 0.5, 0.0, 0.0],
                vec![0.0, 0.0, 0.5, 0.5],
                vec![0.25, 0.25, 0.25, 0.25],
                vec![0.0, 1.0, 0.0, 0.0],
            ],
            4,
        )
        .unwrap();
        assert!(matches!(
            CageUpdater::new(&dependent, vec![0, 1, 2, 3], CageFitMode::Interpolate),
            Err(RigError::Singular { .. })
        ));
        assert!(matches!(
            CageUpdater::new(&phi, vec![0, 1, 2], CageFitMode::Interpolate),
            Err(RigError::SizeMismatch { .. })
        ));
        assert!(matches!(
            CageUpdater::new(&phi, vec![0, 1, 2, 9], CageFitMode::Interpolate),
            Err(RigError::IndexOutOfRange { index: 9, .. })
        ));
    }
}
