//! The regulariser of the Green CageUp: C' stays close to the rest cage carried by the
//! skeleton while it fits the rows, and within reach of the body.
//!
//! With P (`#C`) the carried cage of the mean value rigs' regularised fit
//! ([`crate::sync::cage_prior`]: every rest cage vertex carried by the mean motion of its
//! nearest rest-skin vertices, built here on the vertex coordinates φ) and
//! W = λ(LᵀL + εI) (`#C × #C`, symmetric positive definite: L the cage's uniform graph
//! Laplacian, λ chosen once per binding from the fitting rows, below), the fit minimises
//!
//! `E(C') = ½ ‖F_R(C') − M'_R‖² + ½ Σ_axes (C' − P)ᵀ W (C' − P) + ½ Σ_k β_k |C'_k − a_k|²`.
//!
//! Its gradient adds W(C' − P) + B(C' − a) and its Hessian (W + B) ⊗ I₃ (constant for a pose,
//! B = diag β): the fit keeps its stationary point form, and CageRev ([`super::reverser`])
//! inverts it with P(C) and a(C) affine in the rest cage and the rest joints for a fixed pose.
//! At the rest pose P = C (the skinning transforms are the identity and Σ_j ω_ij = 1) and
//! every β_k is 0, so C' = C stays the exact answer. W is λ(LᵀL + εI) plus the fold terms
//! below, which depend on the pose alone.
//!
//! **λ** = [`GREEN_PRIOR_STRENGTH`] · tr(J₀ᵀJ₀) / (3 tr(LᵀL + εI)), with J₀ the Jacobian of the
//! rows F_R at the binding cage (φ_R ⊗ I₃ + (ψ_R ⊗ I₃)·∂g/∂C): the mean value rigs' rule
//! (λ₀ · tr(Φ̃ᵀΦ̃) / tr R) on the Green map's own Gauss–Newton scale, with a stronger λ₀. The
//! neighbourhoods of P are expressed in mean value coordinates of their skin vertices
//! ([`crate::sync::cage_prior::NeighbourCoords::MeanValue`]), since φC alone is not the skin.
//!
//! **The reach terms** β_k, a_k are the Green form of the mean value rigs' reach limit
//! ([`crate::sync::reach_limit`]), which blends C'_k back toward P_k after a linear fit. A
//! blend after a Gauss–Newton fit is not a stationary point, so here the limit is a weight in
//! the energy, decided by the pose alone:
//! - the reach factor s_k is the reach limit's, for the hat fit `K ŷ + Q P̂` of the *vertex
//!   part* of the rows: the binding rig's φ_R C₀ posed by the joints' linear parts, mapped back
//!   by the mean value rigs' K and Q built on φ_R (at rest it returns C₀);
//! - β_k = [`REACH_GAIN`] · h · (1/max(s_k, 0.1) − 1), with h the mean diagonal entry of
//!   J₀ᵀJ₀ + W ⊗ I₃: 0 where the hat fit stays within reach (s_k = 1), and in a quadratic model
//!   with stiffness h the weight that blends the fit by s_k toward a_k. The floor keeps β_k
//!   within 9h, so that CageRev's Newton still reaches the fit's round-off floor;
//! - a_k = P_k, except where the carried P̂_k is itself out of reach of its posed
//!   neighbourhood (a neighbourhood that spans two parts moving apart, such as the legs of a
//!   walk, carries its cage vertex between them): there a_k = Q_k = Σ_j ω_kj T_j C_k, the rest
//!   cage vertex skinned with the weights of its nearest rest-skin vertex, which stays as near
//!   that vertex as it was at rest.
//!
//! **The fold terms.** A thin cage triangle can turn over in the fit while its corners stay
//! within reach (one of the Fox Run's 196 at three samples, facing the carried cage's at cos
//! −0.8 to −0.003). The hat fit above turns the same triangles: the reach limit reports how
//! far, turn_t ∈ [0, 1] (0 while the hat's normal faces P̂'s by a quarter of its squared area,
//! 1 once turned over; [`crate::sync::reach_limit`]). Each such triangle adds
//! ½ γ_t Σ_(i,j) |(C'_j − C'_i) − (P_j − P_i)|² over its three edges, γ_t = [`FOLD_GAIN`]·h·turn_t:
//! the triangle keeps the carried triangle's shape while the fit may still move it whole. The
//! term is (C' − P)ᵀ(γ_t L_t)(C' − P) with L_t the graph Laplacian of the triangle's edges, so
//! it joins W: still symmetric positive definite, quadratic in C' − P, and 0 at rest whatever
//! the rest cage (C' = P = C there). CageRev takes the same W for the grab's pose. A barrier
//! on the facing itself was tried and is not used (`docs/green-coordinates.md`): measured
//! against P̂ it does not vanish at rest once the rest cage is edited, and measured against P
//! it is not convex.
//!
//! Where every s_k is 1 (no vertex would leave the body), B = 0 and the fit is bit for bit the
//! fit without reach terms, and where no triangle turns W is λ(LᵀL + εI). On CesiumMan's walk
//! with its default automatic cage the reach terms take the worst spread from 1.55 to 1.38
//! (`docs/green-coordinates.md`).

use faer::Mat;
use glam::{DAffine3, DMat3, DVec3};

use super::rows::row_dots;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_prior::{
    BindingJoints, CagePrior, NeighbourCoords, laplacian_regulariser, regularised_maps,
};
use crate::sync::small_products::accumulate_product;

/// The regulariser's data (see the module docs).
#[derive(Debug, Clone)]
pub struct FitPrior {
    prior: CagePrior,
    /// λ(LᵀL + εI), `#C × #C`: W without the fold terms.
    base_weight: Mat<f64>,
    /// The cage's triangles (`#F`), for the fold terms.
    triangles: Vec<[u32; 3]>,
    /// Whether `weight` holds fold terms (else it equals `base_weight`).
    folded: bool,
    /// W of the current pose, `#C × #C`: λ(LᵀL + εI) plus the fold terms.
    weight: Mat<f64>,
    /// K of the vertex part's hat fit (`#C × #R`), which decides the reach factors s_k.
    hat_from_rows: Mat<f64>,
    /// h: the mean diagonal entry of J₀ᵀJ₀ + W ⊗ I₃, the scale of the reach weights.
    stiffness: f64,
    /// β_k of the current event (`#C`): the reach weights, 0 where the hat fit stays within
    /// reach.
    reach_weights: Vec<f64>,
    /// Whether vertex k is anchored on its skinned Q_k in the current event, and its anchor
    /// a_k (Q_k, or P_k when not anchored), `#C` each.
    anchored: Vec<bool>,
    anchors: Vec<DVec3>,
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
/// automatic cages of the Fox (Walk, Run) and CesiumMan, fitted without the reach terms, λ₀ = 13
/// gives the least worst spread of those tried (9 to 22; CesiumMan 1.55, against 1.63 at 9 and
/// 1.67 at 22) and keeps the deviation within 0.056 of the diagonal (0.061 at 9);
/// `docs/green-coordinates.md`.
pub const GREEN_PRIOR_STRENGTH: f64 = 13.0;

/// g of the reach weights β_k = g·h·(1/s_k − 1) (module docs). Over the characters of
/// `docs/green-coordinates.md`, 1 holds CesiumMan's walk to spread 1.38 with deviation 0.052 of
/// the diagonal; 3 and 10 give spread 1.37 and 1.48 but deviation 0.069 and 0.089 (the anchored
/// vertices leave the rigidly carried reference the deviation measures against).
pub const REACH_GAIN: f64 = 1.0;

/// g of the fold terms γ_t = g·h·turn_t (module docs). On the Fox's Run with its default
/// automatic cage, 1 holds every triangle of C' facing the carried cage's (one of 196 turned at
/// three samples without the terms); 3 to 30 lower the worst deviation by at most 1.2 %
/// (`docs/green-coordinates.md`).
pub const FOLD_GAIN: f64 = 1.0;

/// The reach factor below which s_k counts as this value, so that β_k stays finite.
const SMALLEST_REACH_FACTOR: f64 = 0.1;

/// β_k for the reach factor `factor` (s_k) and the fit's `stiffness` (h): 0 at s_k = 1.
fn reach_weight(stiffness: f64, factor: f64) -> f64 {
    if factor >= 1.0 {
        0.0
    } else {
        REACH_GAIN * stiffness * (1.0 / factor.max(SMALLEST_REACH_FACTOR) - 1.0)
    }
}

impl FitPrior {
    /// From the carried-cage prior (its neighbourhoods), R = LᵀL + εI (`#C × #C`) of the cage and
    /// tr(J₀ᵀJ₀) of the rows at the binding cage (`rows_scale`, see the module docs for λ); P
    /// starts at `rest_cage` (`#C`).
    pub fn new(
        prior: CagePrior,
        hat_from_rows: Mat<f64>,
        regulariser: &Mat<f64>,
        rest_cage: &[DVec3],
        triangles: &[[u32; 3]],
        rows_scale: f64,
    ) -> Self {
        let nc = regulariser.nrows();
        let trace: f64 = (0..nc).map(|k| regulariser[(k, k)]).sum();
        let strength = GREEN_PRIOR_STRENGTH * rows_scale / (3.0 * trace);
        let weight = Mat::from_fn(regulariser.nrows(), regulariser.ncols(), |r, c| {
            strength * regulariser[(r, c)]
        });
        Self {
            prior,
            base_weight: weight.clone(),
            triangles: triangles.to_vec(),
            folded: false,
            hat_from_rows,
            stiffness: (rows_scale + 3.0 * strength * trace) / (3.0 * nc as f64),
            reach_weights: vec![0.0; nc],
            anchored: vec![false; nc],
            anchors: rest_cage.to_vec(),
            weight,
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
        let mut prior = maps.prior;
        // The hat fit K ŷ + Q P̂ maps the posed vertex part φ_R C₀ back to C₀ at rest.
        let mut vertex_part = vec![DVec3::ZERO; rows.len()];
        accumulate_product(
            &vertex_coords.select_rows(rows),
            rest_cage,
            &mut vertex_part,
        );
        prior.use_vertex_part_hat(vertex_part);
        Ok(Self::new(
            prior,
            maps.cage_from_rows,
            &regulariser,
            rest_cage,
            triangles,
            rows_scale,
        ))
    }

    /// W of the current event, `#C × #C`: λ(LᵀL + εI) plus the fold terms of the triangles
    /// the hat fit turns in its pose (module docs).
    pub fn weight(&self) -> &Mat<f64> {
        &self.weight
    }

    /// How far the hat fit turns each cage triangle in the current event, in [0, 1] (`#F`):
    /// the fold terms' turn_t (module docs).
    pub fn turns(&self) -> &[f64] {
        self.prior.carried_turns()
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
        let (factors, anchored) = self
            .prior
            .carried_reach_factors(posed_from_rest, &self.hat_from_rows);
        for (weight, &s) in self.reach_weights.iter_mut().zip(factors) {
            *weight = reach_weight(self.stiffness, s);
        }
        self.anchored.copy_from_slice(anchored);
        let turns = self.prior.carried_turns();
        if self.folded || turns.iter().any(|&t| t != 0.0) {
            self.folded = fold_weight(
                &self.base_weight,
                &self.triangles,
                turns,
                self.stiffness,
                &mut self.weight,
            );
        }
        let anchor_weights = self.prior.anchor_weights();
        for (k, anchor) in self.anchors.iter_mut().enumerate() {
            *anchor = if self.anchored[k] {
                skinned_anchor(anchor_weights, k, posed_from_rest, rest_cage[k])
            } else {
                self.target[k]
            };
        }
    }

    /// β_k of the current event (`#C`, module docs).
    pub fn reach_weights(&self) -> &[f64] {
        &self.reach_weights
    }

    /// β_k (`weights`, `#C`), the anchored vertices (`anchored`, `#C`) and W (`weight`,
    /// `#C × #C`) in the pose with the joints' linear parts `joint_linear` (`#J`): what
    /// [`Self::carry`] sets in that pose, for CageRev. Copied from the last carry when it was
    /// in that pose (they depend on the linear parts alone); computed otherwise, allocating
    /// its scratch (once per pose).
    pub(crate) fn reach_weights_in(
        &self,
        joint_linear: &[DMat3],
        weights: &mut [f64],
        anchored: &mut [bool],
        weight: &mut Mat<f64>,
    ) {
        if self.prior.reach_factors_in_pose(joint_linear).is_some() {
            weights.copy_from_slice(&self.reach_weights);
            anchored.copy_from_slice(&self.anchored);
            weight.copy_from(&self.weight);
        } else {
            self.compute_reach_weights_in(joint_linear, weights, anchored, weight);
        }
    }

    /// [`Self::reach_weights_in`] computed for the pose, whatever the last carry.
    pub(crate) fn compute_reach_weights_in(
        &self,
        joint_linear: &[DMat3],
        weights: &mut [f64],
        anchored: &mut [bool],
        weight: &mut Mat<f64>,
    ) {
        let mut pose = self.prior.pose_scratch();
        self.prior.pose(joint_linear, &mut pose);
        self.prior
            .reach_factors(joint_linear, &self.hat_from_rows, &mut pose);
        for (weight, &s) in weights.iter_mut().zip(pose.reach_factors()) {
            *weight = reach_weight(self.stiffness, s);
        }
        anchored.copy_from_slice(pose.reach_anchored());
        fold_weight(
            &self.base_weight,
            &self.triangles,
            pose.reach_turns(),
            self.stiffness,
            weight,
        );
    }

    /// Whether vertex k is anchored on its skinned Q_k in the current event (`#C`).
    pub fn anchored(&self) -> &[bool] {
        &self.anchored
    }

    /// a_k of the current event (`#C`): Q_k where the vertex is anchored, P_k elsewhere.
    pub fn anchors(&self) -> &[DVec3] {
        &self.anchors
    }

    /// The gradient (W(x − P) + B(x − a), into `pulls`, `#C`) and the energy
    /// ½ Σ_axes (x − P)ᵀW(x − P) + ½ Σ_k β_k |x_k − a_k|² of the prior at `x` (`#C`), with P
    /// that of the current solve. No allocation.
    fn pulls(&self, x: &[DVec3], pulls: &mut [DVec3]) -> f64 {
        row_dots(&self.weight, x, &self.active, pulls);
        let mut energy = 0.0;
        for ((pull, xk), pk) in pulls.iter().zip(x).zip(&self.active) {
            energy += 0.5 * pull.dot(*xk - *pk);
        }
        for (((pull, &beta), xk), ak) in pulls
            .iter_mut()
            .zip(&self.reach_weights)
            .zip(x)
            .zip(&self.anchors)
        {
            if beta != 0.0 {
                let d = *xk - *ak;
                *pull += beta * d;
                energy += 0.5 * beta * d.length_squared();
            }
        }
        energy
    }

    /// The prior's energy at `x` (`#C`, see [`Self::pulls`]), with `pulls` (`#C`) as scratch.
    /// No allocation.
    pub(super) fn energy(&self, x: &[DVec3], pulls: &mut [DVec3]) -> f64 {
        self.pulls(x, pulls)
    }

    /// `normal_matrix` (`3#C × 3#C`) += (W + B) ⊗ I₃.
    pub(super) fn add_to_hessian(&self, normal_matrix: &mut Mat<f64>) {
        let n = self.weight.nrows();
        for k in 0..n {
            for m in 0..n {
                let w = self.weight[(k, m)];
                for a in 0..3 {
                    normal_matrix[(3 * k + a, 3 * m + a)] += w;
                }
            }
            let beta = self.reach_weights[k];
            if beta != 0.0 {
                for a in 0..3 {
                    normal_matrix[(3 * k + a, 3 * k + a)] += beta;
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

    /// The prior's energy at `x` (`#C`, see [`Self::pulls`]) and its gradient added to
    /// `gradient` (`#C`), with `pulls` (`#C`) as scratch. No allocation.
    pub(super) fn add_to_gradient(
        &self,
        x: &[DVec3],
        gradient: &mut [DVec3],
        pulls: &mut [DVec3],
    ) -> f64 {
        let energy = self.pulls(x, pulls);
        for (out, pull) in gradient.iter_mut().zip(pulls.iter()) {
            *out += *pull;
        }
        energy
    }
}

/// Q_k = Σ_j ω_kj T_j C_k: the rest cage vertex `rest_vertex` (C_k) skinned by the skinning
/// transforms `posed_from_rest` (`#J`) with the weights of its nearest rest-skin vertex (row k
/// of `anchor_weights`).
/// W of a pose (`out`, `#C × #C`): `base` (λ(LᵀL + εI)) plus, on every cage triangle t the hat
/// fit turns (`turns`, `#F`, from `triangles`), [`FOLD_GAIN`]·h·turn_t times the graph
/// Laplacian of its three edges: the quadratic form of
/// ½ γ_t Σ_(i,j) |(x_j − x_i) − (P_j − P_i)|² (module docs). Returns whether a triangle is
/// turned. No allocation.
fn fold_weight(
    base: &Mat<f64>,
    triangles: &[[u32; 3]],
    turns: &[f64],
    stiffness: f64,
    out: &mut Mat<f64>,
) -> bool {
    out.copy_from(base);
    let mut turned = false;
    for (tri, &turn) in triangles.iter().zip(turns) {
        if turn == 0.0 {
            continue;
        }
        turned = true;
        let gamma = FOLD_GAIN * stiffness * turn;
        for e in 0..3 {
            let (i, j) = (tri[e] as usize, tri[(e + 1) % 3] as usize);
            out[(i, i)] += gamma;
            out[(j, j)] += gamma;
            out[(i, j)] -= gamma;
            out[(j, i)] -= gamma;
        }
    }
    turned
}

fn skinned_anchor(
    anchor_weights: &SkinWeights,
    k: usize,
    posed_from_rest: &[DAffine3],
    rest_vertex: DVec3,
) -> DVec3 {
    let (joints, weights) = anchor_weights.row(k);
    joints
        .iter()
        .zip(weights)
        .fold(DVec3::ZERO, |acc, (&j, &w)| {
            acc + w * posed_from_rest[j as usize].transform_point3(rest_vertex)
        })
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
        add_translation_rows(translation_jacobian, k, j, share, joint_rows);
    }
}

/// The skinned anchors' derivatives for CageRev in the pose with the joints' linear parts
/// `joint_linear` (`#J`): Q_k = Σ_j ω_kj (L_j C_k + t_j), so ∂Q_k/∂C_k = L̄_k = Σ_j ω_kj L_j
/// (`blocks`, `#C`; identity where `anchored` is false) and ∂Q_k/∂A = Σ_j ω_kj ∂t_j/∂A
/// (`joint_rows`, `3#C × 3#J`, zero rows where not anchored and while SkelUp is locked), with
/// ∂t_j/∂A_l = `translation_jacobian[j·#J + l]`.
pub(crate) fn anchor_jacobians(
    prior: &FitPrior,
    joint_linear: &[DMat3],
    translation_jacobian: &[DMat3],
    skel_up_locked: bool,
    anchored: &[bool],
    blocks: &mut [DMat3],
    joint_rows: &mut Mat<f64>,
) {
    let anchor_weights = prior.prior.anchor_weights();
    joint_rows.fill(0.0);
    for (k, block) in blocks.iter_mut().enumerate() {
        *block = DMat3::IDENTITY;
        if !anchored[k] {
            continue;
        }
        let (joints, weights) = anchor_weights.row(k);
        *block = joints
            .iter()
            .zip(weights)
            .fold(DMat3::ZERO, |acc, (&j, &w)| {
                acc + joint_linear[j as usize] * w
            });
        if skel_up_locked {
            continue;
        }
        for (&j, &w) in joints.iter().zip(weights) {
            add_translation_rows(translation_jacobian, k, j as usize, w, joint_rows);
        }
    }
}

/// `joint_rows` (`3#C × 3#J`) rows of cage vertex k += `share` · ∂t_j/∂A: the block row of
/// `translation_jacobian` (`#J × #J` blocks, ∂t_j/∂A_l at `j·#J + l`) for joint j.
fn add_translation_rows(
    translation_jacobian: &[DMat3],
    k: usize,
    j: usize,
    share: f64,
    joint_rows: &mut Mat<f64>,
) {
    let nj = joint_rows.ncols() / 3;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing the edge (1, 2) over four vertices: a turned triangle adds
    /// g·h·turn times its edges' graph Laplacian to W, so that (x − P)ᵀ W (x − P) gains
    /// γ Σ_edges |Δx_j − Δx_i|², a move of the whole triangle costs nothing more, and an
    /// unturned pose leaves W as it was.
    #[test]
    fn the_fold_terms_are_the_turned_triangles_edge_laplacians() {
        let base = Mat::from_fn(4, 4, |r, c| if r == c { 2.0 } else { 0.0 });
        let triangles = [[0, 1, 2], [1, 3, 2]];
        let stiffness = 3.0;
        let mut weight = Mat::zeros(4, 4);
        assert!(!fold_weight(
            &base,
            &triangles,
            &[0.0, 0.0],
            stiffness,
            &mut weight
        ));
        assert_eq!(weight, base);
        assert!(fold_weight(
            &base,
            &triangles,
            &[0.5, 0.0],
            stiffness,
            &mut weight
        ));
        let gamma = FOLD_GAIN * stiffness * 0.5;
        let quadratic = |d: [f64; 4]| {
            let mut q = 0.0;
            for r in 0..4 {
                for c in 0..4 {
                    q += d[r] * weight[(r, c)] * d[c];
                }
            }
            q
        };
        let d = [0.3, -1.0, 0.5, 7.0];
        let base_part: f64 = d.iter().map(|x| 2.0 * x * x).sum();
        let edges = (d[1] - d[0]).powi(2) + (d[2] - d[1]).powi(2) + (d[0] - d[2]).powi(2);
        assert!((quadratic(d) - base_part - gamma * edges).abs() < 1e-12);
        // Moving the turned triangle whole (vertex 3 apart) costs only the base part.
        let whole = [1.5, 1.5, 1.5, 0.0];
        assert!((quadratic(whole) - 3.0 * 2.0 * 1.5 * 1.5).abs() < 1e-12);
        for r in 0..4 {
            for c in 0..4 {
                assert_eq!(weight[(r, c)], weight[(c, r)]);
            }
        }
    }
}
