//! The regulariser of the Green CageUp: C' stays close to the rest cage carried by the
//! skeleton while it fits the rows.
//!
//! With P (`#C`) the carried cage of the mean value rigs' regularised fit
//! ([`crate::sync::cage_prior`]: every rest cage vertex carried by the mean motion of its
//! nearest rest-skin vertices, built here on the vertex coordinates φ) and
//! W = λ(LᵀL + εI) (`#C × #C`, symmetric positive definite: L the cage's uniform graph
//! Laplacian, λ chosen once per binding from the fitting rows, below), the fit minimises
//!
//! `E(C') = ½ ‖F_R(C') − M'_R‖² + ½ Σ_axes (C' − P)ᵀ W (C' − P)`.
//!
//! Its gradient adds W(C' − P) and its Hessian W ⊗ I₃ (constant): the fit keeps its stationary
//! point form, and CageRev ([`super::reverser`]) inverts it with P(C) affine in the rest cage
//! and the rest joints for a fixed pose. At the rest pose P = C (the skinning transforms are the
//! identity and Σ_j ω_ij = 1), so C' = C stays the exact answer.
//!
//! **λ** = [`GREEN_PRIOR_STRENGTH`] · tr(J₀ᵀJ₀) / (3 tr(LᵀL + εI)), with J₀ the Jacobian of the
//! rows F_R at the binding cage (φ_R ⊗ I₃ + (ψ_R ⊗ I₃)·∂g/∂C): the mean value rigs' rule
//! (λ₀ · tr(Φ̃ᵀΦ̃) / tr R) on the Green map's own Gauss–Newton scale, with a stronger λ₀. The
//! neighbourhoods of P are expressed in mean value coordinates of their skin vertices
//! ([`crate::sync::cage_prior::NeighbourCoords::MeanValue`]), since φC alone is not the skin.

use faer::Mat;
use glam::{DAffine3, DMat3, DVec3};

use super::rows::row_dots;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_prior::{
    BindingJoints, CagePrior, NeighbourCoords, laplacian_regulariser, regularised_maps,
};

/// The regulariser's data (see the module docs).
#[derive(Debug, Clone)]
pub struct FitPrior {
    prior: CagePrior,
    /// W = λ(LᵀL + εI), `#C × #C`.
    weight: Mat<f64>,
    /// P of the current event (`#C`).
    target: Vec<DVec3>,
    /// P of the current solve (a continuation's piece blends `last` and `target`), `#C`.
    active: Vec<DVec3>,
    /// P of the last converged solution, `#C`.
    last: Vec<DVec3>,
}

/// λ₀ of the Green fit's λ (module docs), about four times the mean value rigs'
/// ([`crate::sync::cage_prior::PRIOR_STRENGTH`]). The Green map follows a folding cage
/// triangle through its face terms, so its rows pull C' from the body harder. Over the default
/// automatic cages of the Fox (Walk, Run) and CesiumMan, λ₀ = 13 gives the least worst spread
/// of those tried (9 to 22; CesiumMan 1.55, against 1.63 at 9 and 1.67 at 22) and keeps the
/// deviation within 0.056 of the diagonal (0.061 at 9); `docs/green-coordinates.md`.
pub const GREEN_PRIOR_STRENGTH: f64 = 13.0;

impl FitPrior {
    /// From the carried-cage prior (its neighbourhoods), R = LᵀL + εI (`#C × #C`) of the cage and
    /// tr(J₀ᵀJ₀) of the rows at the binding cage (`rows_scale`, see the module docs for λ); P
    /// starts at `rest_cage` (`#C`).
    pub fn new(
        prior: CagePrior,
        regulariser: &Mat<f64>,
        rest_cage: &[DVec3],
        rows_scale: f64,
    ) -> Self {
        let trace: f64 = (0..regulariser.nrows()).map(|k| regulariser[(k, k)]).sum();
        let strength = GREEN_PRIOR_STRENGTH * rows_scale / (3.0 * trace);
        Self {
            prior,
            weight: Mat::from_fn(regulariser.nrows(), regulariser.ncols(), |r, c| {
                strength * regulariser[(r, c)]
            }),
            target: rest_cage.to_vec(),
            active: rest_cage.to_vec(),
            last: rest_cage.to_vec(),
        }
    }

    /// The prior of a Green fit for a binding: the carried cage of the rest cage `rest_cage`
    /// (`#C`) and its `triangles`, with neighbourhoods on the rest skin `rest_mesh` (`#V`) and Ω
    /// `skin_weights` (`#V × #J`), the binding skeleton `binding_joints` (`#J`), and λ from the
    /// fit's `rows_scale` ([`super::GreenCageFit::binding_rows_scale`]; the fitting rows `rows`
    /// of the vertex coordinates φ `vertex_coords`, `#V × #C`, are read for the neighbourhoods'
    /// rows alone). The one rule of every Green binding (module docs).
    #[expect(
        clippy::too_many_arguments,
        reason = "the binding's parts, each named in the docs"
    )]
    pub fn for_binding(
        vertex_coords: &CageCoords,
        rows: &[usize],
        rest_cage: &[DVec3],
        triangles: &[[u32; 3]],
        rest_mesh: &[DVec3],
        skin_weights: &SkinWeights,
        binding_joints: &BindingJoints,
        rows_scale: f64,
    ) -> Result<Self, RigError> {
        let maps = regularised_maps(
            vertex_coords,
            rows,
            rest_cage,
            triangles,
            rest_mesh,
            skin_weights,
            binding_joints,
            NeighbourCoords::MeanValue,
        )?;
        let regulariser = laplacian_regulariser(rest_cage.len(), triangles)?;
        Ok(Self::new(maps.prior, &regulariser, rest_cage, rows_scale))
    }

    /// W = λ(LᵀL + εI), `#C × #C`.
    pub fn weight(&self) -> &Mat<f64> {
        &self.weight
    }

    /// P of the current event, `#C`.
    pub fn target(&self) -> &[DVec3] {
        &self.target
    }

    /// The carried-cage prior (its neighbourhoods and ∂P/∂C).
    pub fn carried(&self) -> &CagePrior {
        &self.prior
    }

    /// Sets P: `rest_cage` (`#C`) carried by the skinning transforms `posed_from_rest` (`#J`).
    pub(super) fn carry(&mut self, posed_from_rest: &[DAffine3], rest_cage: &[DVec3]) {
        self.prior.carry(posed_from_rest, rest_cage);
        self.target.copy_from_slice(self.prior.carried_cage());
        self.active.copy_from_slice(&self.target);
    }

    /// Wd for d = x − P of the current solve (`x`: `#C`) into `pulls` (`#C`).
    fn pulls(&self, x: &[DVec3], pulls: &mut [DVec3]) {
        row_dots(&self.weight, x, &self.active, pulls);
    }

    /// ½ Σ_axes dᵀWd for d = x − P of the current solve (`x`: `#C`), with `pulls` (`#C`) as
    /// scratch. No allocation.
    pub(super) fn energy(&self, x: &[DVec3], pulls: &mut [DVec3]) -> f64 {
        self.pulls(x, pulls);
        let mut energy = 0.0;
        for ((pull, xk), pk) in pulls.iter().zip(x).zip(&self.active) {
            energy += 0.5 * pull.dot(*xk - *pk);
        }
        energy
    }

    /// `normal_matrix` (`3#C × 3#C`) += W ⊗ I₃.
    pub(super) fn add_to_hessian(&self, normal_matrix: &mut Mat<f64>) {
        let n = self.weight.nrows();
        for k in 0..n {
            for m in 0..n {
                let w = self.weight[(k, m)];
                for a in 0..3 {
                    normal_matrix[(3 * k + a, 3 * m + a)] += w;
                }
            }
        }
    }

    /// P of the current solve: the blend (1 − a)·P_last + a·P_target (a continuation's piece).
    pub(super) fn blend(&mut self, a: f64) {
        for ((active, last), target) in self.active.iter_mut().zip(&self.last).zip(&self.target) {
            *active = last.lerp(*target, a);
        }
    }

    /// After a converged solve: the current P becomes the last solution's.
    pub(super) fn keep_as_last(&mut self) {
        self.last.copy_from_slice(&self.target);
    }

    /// `cage` (`#C`) becomes the last solution's P (it is the fit's answer for its own rows and
    /// that P).
    pub(super) fn restart_from(&mut self, cage: &[DVec3]) {
        self.last.copy_from_slice(cage);
    }

    /// ½ Σ_axes dᵀWd and gradient += Wd for d = x − P of the current solve (`x`, `gradient`:
    /// `#C`), with `pulls` (`#C`) as scratch. No allocation.
    pub(super) fn add_to_gradient(
        &self,
        x: &[DVec3],
        gradient: &mut [DVec3],
        pulls: &mut [DVec3],
    ) -> f64 {
        self.pulls(x, pulls);
        let mut energy = 0.0;
        for (k, (out, pull)) in gradient.iter_mut().zip(pulls.iter()).enumerate() {
            *out += *pull;
            energy += 0.5 * pull.dot(x[k] - self.active[k]);
        }
        energy
    }
}

/// ∂P/∂C for a fixed pose and fixed joint translations (`3#C × 3#C`, row 3k + a, column 3m + b)
/// and ∂P/∂A through the translations (`3#C × 3#J`): P_k depends on t_j by a_kj I, and
/// ∂t_j/∂A_l is `translation_jacobian[j·#J + l]` (`#J × #J` blocks). Used by CageRev.
pub(crate) fn prior_jacobians(
    prior: &FitPrior,
    joint_linear: &[DMat3],
    translation_jacobian: &[DMat3],
    skel_up_locked: bool,
    cage_rows: &mut Mat<f64>,
    joint_rows: &mut Mat<f64>,
) {
    let nc = prior.target.len();
    let nj = joint_linear.len();
    let zero_translations = vec![DMat3::ZERO; nj * nc];
    let mut by_entry = vec![0.0; nc * 9 * nc];
    let mut pose = prior.prior.pose_scratch();
    prior.prior.pose(joint_linear, &mut pose);
    prior
        .prior
        .jacobian(joint_linear, &zero_translations, &mut pose, &mut by_entry);
    // Entry (k, 9m + 3a + b) (row-major) is entry (a, b) of block (k, m).
    for k in 0..nc {
        for m in 0..nc {
            for a in 0..3 {
                for b in 0..3 {
                    cage_rows[(3 * k + a, 3 * m + b)] = by_entry[k * 9 * nc + 9 * m + 3 * a + b];
                }
            }
        }
    }
    joint_rows.fill(0.0);
    if skel_up_locked {
        return;
    }
    for (k, j, share) in prior.prior.joint_shares() {
        for l in 0..nj {
            let block = translation_jacobian[j * nj + l] * share;
            for b in 0..3 {
                let column = block.col(b);
                for a in 0..3 {
                    joint_rows[(3 * k + a, 3 * l + b)] += column[a];
                }
            }
        }
    }
}
