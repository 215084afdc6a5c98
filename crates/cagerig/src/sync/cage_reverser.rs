//! CageRev, C'→C (Section 4.3, Eqs. 15–19): turn an edit ∂C' of the current cage into the
//! rest-cage edit ∂C that reproduces it through the loop C → S → S' → C'.
//!
//! With the rotations {T_j^r} fixed, the whole chain is linear in C (Eq. 15):
//! `A = ΨC`, `M̃ = Φ̃C`, `M̃' = R̃ M̃ + Ω̃ T`, `C' = P M̃'` with P the CageUp map (Φ̃⁻¹ for MaxVol,
//! Φ̃⁺ in least-squares mode). Joint offsets change the translations through Eq. 16–18,
//! `∂T = B_topo⁻¹ A_R ∂A`, which we evaluate root-first down the hierarchy instead of inverting
//! B_topo: root `∂T_r = (I − T_r^r) ∂a_r`, child `∂T_j = ∂T_f − (T_j^r − T_f^r) ∂a_j`.
//! The `3#C × 3#C` system (Eq. 19, premultiplied by P so it is square and exact in both fit modes)
//!
//! `P (R̃ Φ̃ + Ω̃ B_topo⁻¹ A_R Ψ) ∂C = ∂C'`
//!
//! is factorised (LU with partial pivoting) lazily on the first grab after the skeleton pose
//! changed, and reused for every grab until the next skeleton edit. Exact under LBS: after the
//! full update the grabbed C' vertices land on their targets and the others do not move.

use faer::Mat;
use glam::{DMat3, DVec3};

use crate::error::RigError;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_updater::check_triangular_condition;

/// Everything the reverse map needs that does not change with the pose.
#[derive(Debug, Clone)]
pub struct CageReverser {
    num_cage: usize,
    /// Φ̃, `#R × #C` row-major (the CageUp rows of Φ).
    row_coords: Vec<f64>,
    /// Ω̃: skinning weights of the CageUp rows.
    row_weights: SkinWeights,
    /// Ψ, `#J × #C` row-major.
    joint_coords: Vec<f64>,
    /// P, `#C × #R` (column-major faer matrix, from the CageUpdater).
    cage_from_rows: Mat<f64>,
    parents: Vec<Option<usize>>,
    order: Vec<usize>,
    factor: Option<Factor>,
    /// Scratch for the per-grab solve (3#C).
    rhs: Vec<f64>,
}

#[derive(Debug, Clone)]
struct Factor {
    /// Packed LU factors (unit lower L below the diagonal, U on and above), `n × n` column-major.
    lu: Mat<f64>,
    /// Row permutation: row `i` of P·S is row `perm[i]` of S.
    perm: Vec<usize>,
}

impl CageReverser {
    /// Gathers the pose-independent parts. `rows` are the CageUp rows, `cage_from_rows` its P
    /// (`#C × #R`), `joint_coords` is Ψ (`#J` rows of `#C`).
    pub fn new(
        cage_coords: &crate::cage_coords::CageCoords,
        rows: &[usize],
        cage_from_rows: &Mat<f64>,
        skin_weights: &SkinWeights,
        joint_coords: impl Fn(usize) -> Vec<f64>,
        skeleton: &Skeleton,
    ) -> Result<Self, RigError> {
        let num_cage = cage_coords.num_cage_vertices();
        if cage_from_rows.nrows() != num_cage || cage_from_rows.ncols() != rows.len() {
            return Err(RigError::SizeMismatch {
                what: "CageUp map columns",
                expected: rows.len(),
                actual: cage_from_rows.ncols(),
            });
        }
        let mut row_coords = Vec::with_capacity(rows.len() * num_cage);
        for &r in rows {
            row_coords.extend((0..num_cage).map(|k| cage_coords.get(r, k)));
        }
        let mut psi = Vec::with_capacity(skeleton.len() * num_cage);
        for j in 0..skeleton.len() {
            let row = joint_coords(j);
            if row.len() != num_cage {
                return Err(RigError::SizeMismatch {
                    what: "joint coordinate row length",
                    expected: num_cage,
                    actual: row.len(),
                });
            }
            psi.extend(row);
        }
        Ok(Self {
            num_cage,
            row_coords,
            row_weights: skin_weights.select_rows(rows),
            joint_coords: psi,
            cage_from_rows: cage_from_rows.clone(),
            parents: (0..skeleton.len()).map(|j| skeleton.parent(j)).collect(),
            order: skeleton.topological_order().to_vec(),
            factor: None,
            rhs: vec![0.0; 3 * num_cage],
        })
    }

    /// Drops the factorisation: call after every skeleton pose change.
    pub fn invalidate(&mut self) {
        self.factor = None;
    }

    /// Whether a factorisation for the current pose is held.
    pub fn is_factorised(&self) -> bool {
        self.factor.is_some()
    }

    /// Builds and factorises the Eq. 19 system for the rotations `T_j^r` of the current pose
    /// (`joint_rotations`, `#J`, the linear parts of posed_from_rest).
    pub fn refactor(&mut self, joint_rotations: &[DMat3]) -> Result<(), RigError> {
        let nc = self.num_cage;
        let nj = self.parents.len();
        let nr = self.row_weights.num_vertices();
        // E_j(k): ∂T_j = E_j(k) ∂c_k (3×3 per joint and cage vertex), root-first.
        let mut e = vec![DMat3::ZERO; nj * nc];
        for &j in &self.order {
            let rot_j = joint_rotations[j];
            for k in 0..nc {
                let psi = self.joint_coords[j * nc + k];
                e[j * nc + k] = match self.parents[j] {
                    None => (DMat3::IDENTITY - rot_j) * psi,
                    Some(f) => e[f * nc + k] - (rot_j - joint_rotations[f]) * psi,
                };
            }
        }
        // G = R̃Φ̃ + Ω̃ E as #R × (9 #C): entry (i, 9k + 3a + b) = G_block(i,k)[a][b].
        let mut g = Mat::<f64>::zeros(nr, 9 * nc);
        for i in 0..nr {
            let (joints, weights) = self.row_weights.row(i);
            let mut rot_i = DMat3::ZERO;
            for (&j, &w) in joints.iter().zip(weights) {
                rot_i += joint_rotations[j as usize] * w;
            }
            for k in 0..nc {
                let mut block = rot_i * self.row_coords[i * nc + k];
                for (&j, &w) in joints.iter().zip(weights) {
                    block += e[j as usize * nc + k] * w;
                }
                for a in 0..3 {
                    for b in 0..3 {
                        // glam is column-major: block.col(b)[a] is entry (a, b).
                        g[(i, 9 * k + 3 * a + b)] = block.col(b)[a];
                    }
                }
            }
        }
        let pg = &self.cage_from_rows * &g; // #C × 9#C
        let n = 3 * nc;
        let system = Mat::<f64>::from_fn(n, n, |r, c| {
            let (kp, a) = (r / 3, r % 3);
            let (k, b) = (c / 3, c % 3);
            pg[(kp, 9 * k + 3 * a + b)]
        });
        let lu = system.partial_piv_lu();
        check_triangular_condition(lu.U().diagonal().column_vector().iter().copied())?;
        let l = lu.L();
        let u = lu.U();
        let packed = Mat::<f64>::from_fn(n, n, |r, c| if r > c { l[(r, c)] } else { u[(r, c)] });
        let (fwd, _) = lu.P().arrays();
        self.factor = Some(Factor {
            lu: packed,
            perm: fwd.to_vec(),
        });
        Ok(())
    }

    /// Solves Eq. 19 for the rest-cage offsets ∂C (`#C`, written to `rest_cage_delta`) that
    /// produce the current-cage offsets `posed_cage_delta` (`#C`; zero for untouched vertices).
    /// Requires [`CageReverser::refactor`] for the current pose. No allocation.
    pub fn solve(
        &mut self,
        posed_cage_delta: &[DVec3],
        rest_cage_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        let factor = self.factor.as_ref().ok_or(RigError::Invalid(
            "the reverse cage deformer was not factorised for the current pose".into(),
        ))?;
        let n = 3 * self.num_cage;
        // b = P_perm · ∂C'
        for (i, r) in self.rhs.iter_mut().enumerate() {
            let src = factor.perm[i];
            *r = posed_cage_delta[src / 3][src % 3];
        }
        let lu = &factor.lu;
        // Forward substitution with unit lower L.
        for c in 0..n {
            let x = self.rhs[c];
            if x != 0.0 {
                let col = lu.col(c);
                for r in c + 1..n {
                    self.rhs[r] -= col[r] * x;
                }
            }
        }
        // Back substitution with U.
        for c in (0..n).rev() {
            let col = lu.col(c);
            let x = self.rhs[c] / col[c];
            self.rhs[c] = x;
            for r in 0..c {
                self.rhs[r] -= col[r] * x;
            }
        }
        for (k, d) in rest_cage_delta.iter_mut().enumerate() {
            *d = DVec3::new(self.rhs[3 * k], self.rhs[3 * k + 1], self.rhs[3 * k + 2]);
        }
        Ok(())
    }
}
