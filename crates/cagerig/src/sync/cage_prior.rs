//! The regularised CageUp ([`super::CageFitKind::Regularised`]): C' fits the skin on the fitting
//! rows and stays close to the rest cage carried by the skeleton.
//!
//! The paper's CageUp interpolates M' on the `#C` MaxVol rows, C' = Φ̃⁻¹M̃'. MaxVol bounds the
//! rebuilt skin, not C' itself: whatever part of M̃' no cage reproduces (a pose that LBS skins
//! but the cage's coordinates cannot follow, limbs merged in one cage part) is amplified through
//! Φ̃⁻¹, and C' leaves the body. Here C' minimises
//!
//! ```text
//! E(C') = ‖Φ̃ C' − M̃'‖² + λ ‖L (C' − P)‖² + λ ε ‖C' − P‖²,     P = LBS(Ω_c, S', C)
//! ```
//!
//! - Φ̃ (`#R × #C`) the fitting rows of Φ and M̃' their posed positions (or their ghost LBS);
//! - P (`#C`) the *prior*: every rest cage vertex carried by the mean motion of the skin around
//!   it. With N_k the 32 rest-skin vertices nearest to C_k (and any as near as the last, so
//!   that ties never depend on round-off; the whole skin searched, by the rule the cage quality
//!   measures use too, [`skin_neighbourhoods`]), x̄_k their rest centroid, ȳ_k
//!   the centroid of their LBS-posed positions and A_k the rotation of their mean skinning
//!   transform (see below), `P_k = ȳ_k + A_k (C_k − x̄_k)`. The centroid follows the
//!   body exactly; only the offset of the cage from it turns, so a cage vertex between two
//!   limbs stays between them;
//! - L the cage's uniform graph Laplacian (`#C × #C`, row k: c_k − mean of its neighbours), so
//!   the prior fixes the cage's local shape and the rows its placement; ε ([`PRIOR_EPSILON`])
//!   keeps the system definite on parts the rows do not see;
//! - λ = [`PRIOR_STRENGTH`] · tr(Φ̃ᵀΦ̃) / tr(LᵀL + εI), chosen once per binding from the rig.
//!
//! **The rotation A_k** is the best-fit rotation of the neighbourhood: the proper rotation R
//! maximising tr(Rᵀ H_k) (Kabsch; Horn's quaternion where H_k is a reflection), times the
//! joints' mean scale Σ_j a_kj |det L_j|^⅓, with
//!
//! ```text
//! H_k = Σ_{i ∈ N_k} (ŷ_i − ŷ̄)(x_i − x̄_k)ᵀ / #N_k + μ_k Σ_j a_kj L_j
//!     = Σ_j [ L_j D_kj + T̂_j(x̄_k) s_kjᵀ ] + μ_k Σ_j a_kj L_j.
//! ```
//!
//! ŷ_i = Σ_j ω_ij T̂_j(x_i) poses the binding skin M₀ with the *binding* skeleton under the
//! current linear parts: T̂_j(x) = q_j + L_j (x − b_j), b_j the joint's position at binding and
//! q_j = q_parent + L_parent (b_j − b_parent) (q = b at a root). So the rotation sees how the
//! parts of the neighbourhood move apart (a knee closing turns the neighbourhood; a blend of
//! the two joints' rotations alone does not), and it depends on the pose's linear parts only,
//! never on C: P stays linear in C. D_kj = Σ_i ω_ij d_i d_iᵀ and s_kj = Σ_i ω_ij d_i
//! (d_i = x_i − x̄_k, means over N_k) are moments of the binding. μ_k = [`ROTATION_BLEND`] ·
//! tr(Σ_j D_kj) keeps H_k definite where the neighbourhood is flat. At rest H_k is symmetric
//! positive definite (A_k = I); under one rigid motion R of every joint H_k = R(Σ_j D_kj + μ_k I)
//! (Σ_j s_kj = 0), so A_k = R.
//!
//! The minimiser is linear in both targets: with `R = LᵀL + εI` and `H = Φ̃ᵀΦ̃ + λR` (SPD),
//!
//! ```text
//! C' = K M̃' + Q P,     K = H⁻¹ Φ̃ᵀ  (#C × #R),     Q = λ H⁻¹ R  (#C × #C),     K Φ̃ + Q = I.
//! ```
//!
//! `K Φ̃ + Q = I` gives the guarantees: at rest (M̃' = Φ̃C, P = C) C' = C; under a rigid motion
//! of the whole skeleton C' moves rigidly. CageRev stays exact. x̄_k = ξ_k C and
//! ȳ_k = Σ_j (L_j β_kj C + a_kj t_j(C)), with ξ_k the mean of the neighbours' rows of Φ and
//! β_kj = mean_i ω_ij Φ_i, are linear in C for a fixed pose, and A_k depends on the joints'
//! linear parts only; so P is linear in C like M̃' = R̃Φ̃C + Ω̃T(C), and Eq. 19 becomes
//! `(K G_rows + Q G_prior) ∂C = ∂C'` with `G_prior` the Jacobian of P
//! ([`CagePrior::add_jacobian`], used by [`super::cage_reverser::CageReverser`]).

use faer::Mat;
use faer::linalg::solvers::Solve;
use glam::{DAffine3, DMat3, DVec3};

use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::nearest_vertices::skin_neighbourhoods;
use crate::skin_weights::SkinWeights;
use crate::sync::reach_limit::{PriorEntry, ReachLimit, ReachScratch};

/// λ₀ in λ = λ₀ · tr(Φ̃ᵀΦ̃) / tr(R): the prior weighs three times as much as the rows in
/// total (1 leaves the Fox's Run at spread 1.54, 3 at 1.47; `docs/method.md`).
pub const PRIOR_STRENGTH: f64 = 3.0;
/// ε in R = LᵀL + εI, relative to the Laplacian's scale (tr(LᵀL) / #C).
pub const PRIOR_EPSILON: f64 = 0.05;
/// μ_k / tr(Σ_j D_kj) in the carried rotation's H_k: how much of the blend of the joints'
/// linear parts H_k holds beside the neighbourhood's own motion (see the module docs). Only
/// enough to keep H_k definite against round-off where N_k is flat: a larger blend turns P away
/// from the neighbourhood's best-fit rotation, and on a thin triangle of a cage that turn alone
/// flips it (0.05 flipped one or two of the Fox's 196 cage triangles in its Walk and Run
/// against the deviation's reference, `docs/method.md`).
pub const ROTATION_BLEND: f64 = 1e-6;

/// The skeleton of the binding, whose pose under the current linear parts turns the carried
/// cage (T̂_j in the module docs): every joint's parent, an order with parents first, and each
/// joint's position at binding b_j (`#J` each).
#[derive(Debug, Clone)]
pub struct BindingJoints {
    parents: Vec<Option<usize>>,
    order: Vec<usize>,
    positions: Vec<DVec3>,
}

impl BindingJoints {
    /// `skeleton`'s hierarchy with the joint positions `positions` (`#J`, e.g. ΨC₀).
    pub fn new(
        skeleton: &crate::skeleton::Skeleton,
        positions: Vec<DVec3>,
    ) -> Result<Self, RigError> {
        if positions.len() != skeleton.len() {
            return Err(RigError::SizeMismatch {
                what: "binding joint positions for the cage prior",
                expected: skeleton.len(),
                actual: positions.len(),
            });
        }
        if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
            return Err(RigError::NonFinite {
                what: "binding joint position for the cage prior",
                index: bad,
            });
        }
        Ok(Self {
            parents: skeleton.joints().iter().map(|j| j.parent).collect(),
            order: skeleton.topological_order().to_vec(),
            positions,
        })
    }

    /// `skeleton`'s hierarchy at its rest joint positions.
    pub fn of_skeleton(skeleton: &crate::skeleton::Skeleton) -> Self {
        Self {
            parents: skeleton.joints().iter().map(|j| j.parent).collect(),
            order: skeleton.topological_order().to_vec(),
            positions: skeleton.rest_positions(),
        }
    }

    /// A chain of two joints, the second a child of the first, at `root` and `child` (tests).
    #[cfg(test)]
    pub(crate) fn two_joint_chain(root: DVec3, child: DVec3) -> Self {
        Self {
            parents: vec![None, Some(0)],
            order: vec![0, 1],
            positions: vec![root, child],
        }
    }

    /// Number of joints `#J`.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there is no joint.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// q_j − L_j b_j for every joint (`out`, `#J`): the translations of T̂_j, the binding
    /// skeleton posed by the linear parts `joint_linear` (`#J`). No allocation.
    fn posed_translations(&self, joint_linear: impl Fn(usize) -> DMat3, out: &mut [DVec3]) {
        // First the posed joint positions q_j, parents first, then q_j − L_j b_j in place.
        for &j in &self.order {
            out[j] = match self.parents[j] {
                Some(p) => out[p] + joint_linear(p) * (self.positions[j] - self.positions[p]),
                None => self.positions[j],
            };
        }
        for (j, t) in out.iter_mut().enumerate() {
            *t -= joint_linear(j) * self.positions[j];
        }
    }
}

/// One joint of a cage vertex's neighbourhood: a_kj and β_kj (see the module docs).
#[derive(Debug, Clone)]
struct NeighbourhoodJoint {
    cage_vertex: usize,
    joint: usize,
    /// a_kj = mean_i ω_ij over N_k.
    share: f64,
    /// β_kj = mean_i ω_ij Φ_i, `#C`.
    coords: Vec<f64>,
    /// D_kj = mean_i ω_ij d_i d_iᵀ on the binding skin (d_i = x_i − x̄_k).
    spread: DMat3,
    /// s_kj = mean_i ω_ij d_i on the binding skin.
    offset: DVec3,
}

/// The prior of the regularised CageUp: the neighbourhoods' moments and Q (see the module
/// docs). Built by [`regularised_maps`].
#[derive(Debug, Clone)]
pub struct CagePrior {
    /// (k, j) pairs with a_kj > 0, by cage vertex.
    joints: Vec<NeighbourhoodJoint>,
    /// ξ, `#C × #C` row-major: row k is the mean of the neighbours' rows of Φ.
    centroid_coords: Vec<f64>,
    /// Q = λH⁻¹R, `#C × #C` (column-major).
    cage_from_prior: Mat<f64>,
    /// λ.
    strength: f64,
    /// The rest cage the moments below were computed for.
    moments_cage: Vec<DVec3>,
    /// x̄_k = ξ_k C, `#C`.
    rest_centroids: Vec<DVec3>,
    /// β_kj C, one per entry of `joints`.
    joint_moments: Vec<DVec3>,
    /// P of the last fit, `#C`.
    carried: Vec<DVec3>,
    /// A_k of the last fit, `#C`.
    rotations: Vec<DMat3>,
    /// The binding skeleton posed by the linear parts (T̂_j).
    binding_joints: BindingJoints,
    /// x̄_k on the binding skin, `#C`.
    binding_centroids: Vec<DVec3>,
    /// μ_k, `#C`.
    rotation_blend: Vec<f64>,
    /// Scratch: the translations of T̂_j and the joints' scales |det L_j|^⅓, `#J` each.
    posed_translations: Vec<DVec3>,
    joint_scales: Vec<f64>,
    /// The reach limit ([`crate::sync::reach_limit`]), its scratch, and its factors s (`#C`)
    /// for the linear parts `reach_linear` (`#J`; empty before the first pose).
    reach_limit: ReachLimit,
    reach_scratch: ReachScratch,
    reach_factors: Vec<f64>,
    /// Which vertices the reach limit anchors on their skinned Q_k in that pose (`#C`).
    reach_anchored: Vec<bool>,
    reach_linear: Vec<DMat3>,
}

/// K and the prior of a regularised fit.
pub(crate) struct RegularisedMaps {
    /// K = H⁻¹Φ̃ᵀ, `#C × #R`.
    pub(crate) cage_from_rows: Mat<f64>,
    pub(crate) prior: CagePrior,
}

impl CagePrior {
    /// Q = λH⁻¹R, `#C × #C`.
    pub fn cage_from_prior(&self) -> &Mat<f64> {
        &self.cage_from_prior
    }

    /// λ, chosen at binding.
    pub fn strength(&self) -> f64 {
        self.strength
    }

    /// The (cage vertex k, joint j, a_kj) entries with a_kj > 0, by cage vertex: how the
    /// translations t_j move P_k (∂P_k/∂t_j = a_kj I).
    pub fn joint_shares(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.joints
            .iter()
            .map(|e| (e.cage_vertex, e.joint, e.share))
    }

    /// x̄_k and β_kj C for `rest_cage` (`#C`), when it changed since the last call.
    fn update_moments(&mut self, rest_cage: &[DVec3]) {
        if self.moments_cage == rest_cage {
            return;
        }
        cage_moments(
            &self.centroid_coords,
            &self.joints,
            rest_cage,
            &mut self.rest_centroids,
            &mut self.joint_moments,
        );
        self.moments_cage.copy_from_slice(rest_cage);
    }

    /// A_k into `blended` (`#C`) for the linear parts `joint_linear` (`#J`): the best-fit
    /// rotation of H_k times the mean scale Σ_j a_kj |det L_j|^⅓ (module docs), with
    /// `translations` and `scales` (`#J` each) as scratch for T̂_j and |det L_j|^⅓. No
    /// allocation.
    fn blend_rotations(
        &self,
        joint_linear: impl Fn(usize) -> DMat3,
        translations: &mut [DVec3],
        scales: &mut [f64],
        blended: &mut [DMat3],
    ) {
        self.binding_joints
            .posed_translations(&joint_linear, translations);
        for (j, s) in scales.iter_mut().enumerate() {
            *s = joint_linear(j).determinant().abs().cbrt();
        }
        let mut entries = self.joints.iter().peekable();
        for (k, b) in blended.iter_mut().enumerate() {
            let mut scale = 0.0;
            let mut motion = DMat3::ZERO;
            let mut blend = DMat3::ZERO;
            let centroid = self.binding_centroids[k];
            while let Some(entry) = entries.next_if(|e| e.cage_vertex == k) {
                let linear = joint_linear(entry.joint);
                let image = linear * centroid + translations[entry.joint];
                motion += linear * entry.spread + outer(image, entry.offset);
                blend += linear * entry.share;
                scale += entry.share * scales[entry.joint];
            }
            *b = best_rotation(motion + blend * self.rotation_blend[k]) * scale;
        }
    }

    /// P (`#C`, then read with [`Self::carried_cage`]): the rest cage `rest_cage` (`#C`)
    /// carried by the skin around it under the skinning transforms `posed_from_rest` (`#J`).
    /// CageUp adds Q·P to its fit. No allocation once the moments are computed for `rest_cage`.
    pub fn carry(&mut self, posed_from_rest: &[DAffine3], rest_cage: &[DVec3]) {
        self.update_moments(rest_cage);
        let mut rotations = std::mem::take(&mut self.rotations);
        let mut translations = std::mem::take(&mut self.posed_translations);
        let mut scales = std::mem::take(&mut self.joint_scales);
        self.blend_rotations(
            |j| posed_from_rest[j].matrix3,
            &mut translations,
            &mut scales,
            &mut rotations,
        );
        self.rotations = rotations;
        self.posed_translations = translations;
        self.joint_scales = scales;
        self.carried.iter_mut().for_each(|p| *p = DVec3::ZERO);
        for (entry, m) in self.joints.iter().zip(&self.joint_moments) {
            let t = &posed_from_rest[entry.joint];
            self.carried[entry.cage_vertex] += t.matrix3 * *m + entry.share * t.translation;
        }
        for (k, p) in self.carried.iter_mut().enumerate() {
            *p += self.rotations[k] * (rest_cage[k] - self.rest_centroids[k]);
        }
    }

    /// P (`#C`) of the last [`Self::carry`].
    pub fn carried_cage(&self) -> &[DVec3] {
        &self.carried
    }

    /// The reach limit of the fit `posed_cage` (`#C`, C'_fit = K M̃' + Q P for the pose of the
    /// last [`Self::carry`], whose skinning transforms are `posed_from_rest`, `#J`): every
    /// vertex becomes s_k C'_fit,k + (1 − s_k) P_k ([`crate::sync::reach_limit`]), with the
    /// fit's K `cage_from_rows` (`#C × #R`). The factors are computed once per pose. No
    /// allocation.
    pub fn limit_reach(
        &mut self,
        posed_from_rest: &[DAffine3],
        cage_from_rows: &Mat<f64>,
        posed_cage: &mut [DVec3],
    ) {
        self.carried_reach_factors(posed_from_rest, cage_from_rows);
        for ((c, p), &s) in posed_cage
            .iter_mut()
            .zip(&self.carried)
            .zip(&self.reach_factors)
        {
            if s < 1.0 {
                *c = s * *c + (1.0 - s) * *p;
            }
        }
    }

    /// The reach limit's factors s (`#C`) in the pose of the last [`Self::carry`] (whose
    /// skinning transforms are `posed_from_rest`, `#J`), for the fit's K `cage_from_rows`
    /// (`#C × #R`), and which vertices it anchors on their skinned Q_k (`#C`); computed once
    /// per pose ([`crate::sync::reach_limit`]). No allocation.
    pub fn carried_reach_factors(
        &mut self,
        posed_from_rest: &[DAffine3],
        cage_from_rows: &Mat<f64>,
    ) -> (&[f64], &[bool]) {
        let same_pose = self.reach_linear.len() == posed_from_rest.len()
            && self
                .reach_linear
                .iter()
                .zip(posed_from_rest)
                .all(|(a, b)| *a == b.matrix3);
        if !same_pose {
            let mut factors = std::mem::take(&mut self.reach_factors);
            let mut anchored = std::mem::take(&mut self.reach_anchored);
            let mut scratch = std::mem::take(&mut self.reach_scratch);
            self.reach_limit.factors(
                |j| posed_from_rest[j].matrix3,
                &self.rotations,
                &self.posed_translations,
                self.prior_entries(),
                cage_from_rows,
                &self.cage_from_prior,
                &mut scratch,
                &mut factors,
                &mut anchored,
            );
            self.reach_factors = factors;
            self.reach_anchored = anchored;
            self.reach_scratch = scratch;
            self.reach_linear.clear();
            self.reach_linear
                .extend(posed_from_rest.iter().map(|t| t.matrix3));
        }
        (&self.reach_factors, &self.reach_anchored)
    }

    /// How far the hat fit of the last [`Self::carried_reach_factors`] turns each cage
    /// triangle, in [0, 1] (`#F`).
    pub(crate) fn carried_turns(&self) -> &[f64] {
        self.reach_scratch.turns()
    }

    /// The reach factors s (`#C`) of the last [`Self::carried_reach_factors`] when its pose had
    /// the linear parts `joint_linear` (`#J`); `None` otherwise.
    pub fn reach_factors_in_pose(&self, joint_linear: &[DMat3]) -> Option<&[f64]> {
        (!self.reach_linear.is_empty() && self.reach_linear == joint_linear)
            .then_some(self.reach_factors.as_slice())
    }

    /// The reach limit's hat fit reads the fitting rows as `vertex_part` (`#R`, the rows of the
    /// binding rig that K maps back to its binding cage) instead of the binding skin's rows: a
    /// Green rig's vertex part φ_R C₀ ([`crate::sync::green_cage_fit::prior`],
    /// [`crate::sync::reach_limit::HatFit::VertexPart`]). Forgets the factors computed so far.
    pub(crate) fn use_vertex_part_hat(&mut self, vertex_part: Vec<DVec3>) {
        self.reach_limit.use_vertex_part_hat(vertex_part);
        self.reach_linear.clear();
    }

    /// The weights of each cage vertex's nearest rest-skin vertex, `#C × #J` (Q_k =
    /// Σ_j ω_kj T_j C_k).
    pub fn anchor_weights(&self) -> &SkinWeights {
        self.reach_limit.anchor_weights()
    }

    /// Storage for [`Self::pose`] and [`Self::jacobian`] (CageRev's per-pose work).
    pub fn pose_scratch(&self) -> PriorPose {
        let (nc, nj) = (self.carried.len(), self.binding_joints.len());
        PriorPose {
            rotations: vec![DMat3::ZERO; nc],
            translations: vec![DVec3::ZERO; nj],
            scales: vec![0.0; nj],
            reach: self.reach_limit.scratch(),
            factors: vec![1.0; nc],
            anchored: vec![false; nc],
            blocks: vec![DMat3::ZERO; nc],
        }
    }

    /// A_k and the posed binding joints' translations t̂_j for the joints' linear parts
    /// `joint_linear` (`#J`), what [`Self::carry`] uses in that pose, into `pose`; no
    /// allocation.
    pub fn pose(&self, joint_linear: &[DMat3], pose: &mut PriorPose) {
        self.blend_rotations(
            |j| joint_linear[j],
            &mut pose.translations,
            &mut pose.scales,
            &mut pose.rotations,
        );
    }

    /// The reach limit's factors s (`#C`) in the pose of the last [`Self::pose`] (whose linear
    /// parts are `joint_linear`, `#J`) with the fit's K `cage_from_rows` (`#C × #R`): what
    /// [`Self::limit_reach`] applies in that pose, for CageRev's rows of Eq. 19. Into `pose`
    /// ([`PriorPose::reach_factors`]); no allocation.
    pub fn reach_factors(
        &self,
        joint_linear: &[DMat3],
        cage_from_rows: &Mat<f64>,
        pose: &mut PriorPose,
    ) {
        pose.factors.iter_mut().for_each(|s| *s = 1.0);
        self.reach_limit.factors(
            |j| joint_linear[j],
            &pose.rotations,
            &pose.translations,
            self.prior_entries(),
            cage_from_rows,
            &self.cage_from_prior,
            &mut pose.reach,
            &mut pose.factors,
            &mut pose.anchored,
        );
    }

    /// The reach limit's ρ: the farthest a rest cage vertex is from its skin neighbourhood.
    pub fn reach(&self) -> f64 {
        self.reach_limit.reach()
    }

    /// The (k, j, a_kj) entries, for the reach limit's P̂.
    fn prior_entries(&self) -> impl Iterator<Item = PriorEntry> + '_ {
        self.joints.iter().map(|e| PriorEntry {
            cage_vertex: e.cage_vertex,
            joint: e.joint,
            share: e.share,
        })
    }

    /// ∂P/∂C for the pose with joint linear parts `joint_linear` (`#J`) and its A_k computed
    /// by [`Self::pose`] in `pose`, and the translation derivatives `translation_jacobian`
    /// (`∂t_j/∂c_m`, `#J × #C` blocks, row-major by joint; zero when the joints do not follow
    /// the cage), into `jacobian` (`#C × 9#C`, row-major): entry (k, 9m + 3a + b) is entry
    /// (a, b) of block (k, m). CageRev multiplies it by Q ([`Self::cage_from_prior`]). No
    /// allocation.
    pub fn jacobian(
        &self,
        joint_linear: &[DMat3],
        translation_jacobian: &[DMat3],
        pose: &mut PriorPose,
        jacobian: &mut [f64],
    ) {
        let nc = self.rest_centroids.len();
        let row = &mut pose.blocks;
        let mut entries = self.joints.iter().peekable();
        // ∂P_k/∂c_m = A_k (δ_km − ξ_km) + Σ_j (β_kj[m] L_j + a_kj ∂t_j/∂c_m), a row of 3×3
        // blocks at a time.
        for (k, (a, out)) in pose
            .rotations
            .iter()
            .zip(jacobian.chunks_exact_mut(9 * nc))
            .enumerate()
        {
            for (m, block) in row.iter_mut().enumerate() {
                let delta = if k == m { 1.0 } else { 0.0 };
                *block = *a * (delta - self.centroid_coords[k * nc + m]);
            }
            while let Some(entry) = entries.next_if(|e| e.cage_vertex == k) {
                let linear = joint_linear[entry.joint];
                let translations = &translation_jacobian[entry.joint * nc..(entry.joint + 1) * nc];
                for ((block, &beta), dt) in row.iter_mut().zip(&entry.coords).zip(translations) {
                    *block += linear * beta + *dt * entry.share;
                }
            }
            for (block, values) in row.iter().zip(out.chunks_exact_mut(9)) {
                // glam is column-major: the transpose's columns are the block's rows.
                values.copy_from_slice(&block.transpose().to_cols_array());
            }
        }
    }
}

/// A pose of the prior for CageRev ([`CagePrior::pose`]): A_k and s_k (`#C` each), the posed
/// binding joints' translations (`#J`), and scratch.
#[derive(Debug, Clone)]
pub struct PriorPose {
    /// A_k, `#C`.
    rotations: Vec<DMat3>,
    /// t̂_j, `#J`.
    translations: Vec<DVec3>,
    /// |det L_j|^⅓, `#J`.
    scales: Vec<f64>,
    reach: ReachScratch,
    /// The reach limit's s_k, `#C`.
    factors: Vec<f64>,
    /// Whether the reach limit anchors vertex k on its skinned Q_k, `#C`.
    anchored: Vec<bool>,
    /// One row of ∂P/∂C's `#C × #C` blocks, for [`CagePrior::jacobian`].
    blocks: Vec<DMat3>,
}

impl PriorPose {
    /// The reach limit's factors s_k (`#C`) of the last [`CagePrior::reach_factors`].
    pub fn reach_factors(&self) -> &[f64] {
        &self.factors
    }

    /// Which vertices the last [`CagePrior::reach_factors`] anchors on their skinned Q_k
    /// (`#C`; none unless the limit uses skinned anchors).
    pub fn reach_anchored(&self) -> &[bool] {
        &self.anchored
    }

    /// How far the hat fit of the last [`CagePrior::reach_factors`] turns each cage triangle,
    /// in [0, 1] (`#F`).
    pub(crate) fn reach_turns(&self) -> &[f64] {
        self.reach.turns()
    }
}

/// x̄_k = ξ_k C (`centroids`, `#C`) and β_kj C (`joint_moments`, one per entry of `joints`)
/// for the cage `cage` (`#C`), ξ `centroid_coords` (`#C × #C` row-major). No allocation.
fn cage_moments(
    centroid_coords: &[f64],
    joints: &[NeighbourhoodJoint],
    cage: &[DVec3],
    centroids: &mut [DVec3],
    joint_moments: &mut [DVec3],
) {
    let nc = cage.len();
    let dot = |row: &[f64]| {
        row.iter()
            .zip(cage)
            .fold(DVec3::ZERO, |acc, (&w, c)| acc + w * *c)
    };
    for (k, x) in centroids.iter_mut().enumerate() {
        *x = dot(&centroid_coords[k * nc..(k + 1) * nc]);
    }
    for (m, entry) in joint_moments.iter_mut().zip(joints) {
        *m = dot(&entry.coords);
    }
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// The proper rotation R maximising tr(Rᵀ h): the polar factor of `h` when det h > 0, else
/// Horn's quaternion (the eigenvector of the largest eigenvalue of his 4 × 4 matrix), which
/// flips the weakest direction of a reflection as Kabsch's SVD does. The identity for h = 0.
fn best_rotation(h: DMat3) -> DMat3 {
    let size = h.to_cols_array().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if !(size.is_finite() && size > 0.0) {
        return DMat3::IDENTITY;
    }
    let h = h * (1.0 / size);
    if h.determinant() > 1e-9 {
        let r = rotation_of(h);
        if r.determinant() > 0.5 {
            return r;
        }
    }
    horn_rotation(h)
}

/// Horn's closed form: with S = hᵀ (S_ab = Σ d_a e_b for h = Σ e dᵀ), the unit quaternion of
/// the largest eigenvalue of N(S) is the rotation maximising tr(Rᵀ h).
fn horn_rotation(h: DMat3) -> DMat3 {
    let s = |a: usize, b: usize| h.col(a)[b];
    let n = [
        [
            s(0, 0) + s(1, 1) + s(2, 2),
            s(1, 2) - s(2, 1),
            s(2, 0) - s(0, 2),
            s(0, 1) - s(1, 0),
        ],
        [
            s(1, 2) - s(2, 1),
            s(0, 0) - s(1, 1) - s(2, 2),
            s(0, 1) + s(1, 0),
            s(2, 0) + s(0, 2),
        ],
        [
            s(2, 0) - s(0, 2),
            s(0, 1) + s(1, 0),
            -s(0, 0) + s(1, 1) - s(2, 2),
            s(1, 2) + s(2, 1),
        ],
        [
            s(0, 1) - s(1, 0),
            s(2, 0) + s(0, 2),
            s(1, 2) + s(2, 1),
            -s(0, 0) - s(1, 1) + s(2, 2),
        ],
    ];
    let [w, x, y, z] = largest_eigenvector(n);
    let q = glam::DQuat::from_xyzw(x, y, z, w);
    if !(q.is_finite() && q.length() > 0.5) {
        return DMat3::IDENTITY;
    }
    DMat3::from_quat(q.normalize())
}

/// The unit eigenvector of the largest eigenvalue of the symmetric 4 × 4 matrix `a`, by
/// cyclic Jacobi rotations.
fn largest_eigenvector(mut a: [[f64; 4]; 4]) -> [f64; 4] {
    let mut v = [[0.0f64; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let scale = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    for _ in 0..32 {
        let off: f64 = (0..4)
            .flat_map(|p| (p + 1..4).map(move |q| (p, q)))
            .map(|(p, q)| a[p][q] * a[p][q])
            .sum();
        if off <= (1e-16 * scale).powi(2) {
            break;
        }
        for p in 0..4 {
            for q in p + 1..4 {
                if a[p][q] == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let sn = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - sn * akq;
                    row[q] = sn * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for (k, (apk, aqk)) in row_p.into_iter().zip(row_q).enumerate() {
                    a[p][k] = c * apk - sn * aqk;
                    a[q][k] = sn * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - sn * vq;
                    row[q] = sn * vp + c * vq;
                }
            }
        }
    }
    let best = (0..4).fold(0, |b, i| if a[i][i] > a[b][b] { i } else { b });
    [v[0][best], v[1][best], v[2][best], v[3][best]]
}

/// The rotation of `m` (its polar factor, by Newton's iteration X ← (γX + (γX)⁻ᵀ)/2 with
/// Higham's scaling γ = (‖X⁻¹‖_F / ‖X‖_F)^½, which takes a few steps even for an
/// ill-conditioned `m`), or the identity when `m` is singular.
fn rotation_of(m: DMat3) -> DMat3 {
    let squared_norm = |a: DMat3| {
        a.x_axis.length_squared() + a.y_axis.length_squared() + a.z_axis.length_squared()
    };
    let mut x = m;
    let mut change = f64::INFINITY;
    for _ in 0..32 {
        // X⁻ᵀ = [b × c, c × a, a × b] / det X for the columns a, b, c of X.
        let (a, b, c) = (x.x_axis, x.y_axis, x.z_axis);
        let cofactors = DMat3::from_cols(b.cross(c), c.cross(a), a.cross(b));
        let det = a.dot(cofactors.x_axis);
        if !(det.is_finite() && det.abs() > 1e-12) {
            return DMat3::IDENTITY;
        }
        let inverse_transpose = cofactors * (1.0 / det);
        // Higham's scaling while far from the answer; plain Newton (quadratic) near it.
        let scale = if change > 1e-2 {
            (squared_norm(inverse_transpose) / squared_norm(x))
                .sqrt()
                .sqrt()
        } else {
            1.0
        };
        let next = (x * scale + inverse_transpose * (1.0 / scale)) * 0.5;
        change = (next - x)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        x = next;
        if change < 1e-15 {
            break;
        }
    }
    if x.determinant() < 0.0 {
        DMat3::IDENTITY
    } else {
        x
    }
}

/// The coordinates that express each neighbourhood's skin vertices in the rest cage (the rows
/// of ξ and β_kj, see the module docs). P is linear in C through them, and at binding they must
/// reproduce the skin: x̄_k = ξ_k C is the neighbourhood's centroid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NeighbourCoords {
    /// The fitting coordinates themselves: mean value rigs, whose Φ reproduces the skin (M = ΦC).
    Fitting,
    /// Mean value coordinates of the neighbourhoods' skin vertices (about 32·#C of them, the
    /// ties included: [`skin_neighbourhoods`]), computed at binding: Green rigs, whose vertex
    /// part φ alone does not reproduce the skin (M = φC + ψ·g(C)), while P must stay linear in C.
    MeanValue,
}

/// Builds K and the prior for the fitting rows `rows` (their Φ̃, `#R × #C`, is read from
/// `cage_coords`), the rest cage `rest_cage` (`#C`) and its `cage_triangles`, the rest skin
/// `rest_mesh` (`#V`), Ω `skin_weights` (`#V × #J`) and the binding skeleton
/// `binding_joints` (`#J`); the neighbourhoods are expressed in `neighbour_coords`.
#[expect(
    clippy::too_many_arguments,
    reason = "the binding's parts, each named in the docs"
)]
pub(crate) fn regularised_maps(
    cage_coords: &CageCoords,
    rows: &[usize],
    rest_cage: &[DVec3],
    cage_triangles: &[[u32; 3]],
    rest_mesh: &[DVec3],
    skin_weights: &SkinWeights,
    binding_joints: &BindingJoints,
    neighbour_coords: NeighbourCoords,
) -> Result<RegularisedMaps, RigError> {
    let nc = cage_coords.num_cage_vertices();
    if rest_cage.len() != nc || rest_mesh.len() != cage_coords.num_vertices() {
        return Err(RigError::SizeMismatch {
            what: "rest cage vertices for the regularised cage fit",
            expected: nc,
            actual: rest_cage.len(),
        });
    }
    if binding_joints.len() != skin_weights.num_joints() {
        return Err(RigError::SizeMismatch {
            what: "binding joints (skinning weight columns) for the cage prior",
            expected: skin_weights.num_joints(),
            actual: binding_joints.len(),
        });
    }
    let row_coords = cage_coords.select_rows(rows);
    let Neighbourhoods {
        near,
        joints,
        centroid_coords,
        binding_centroids,
        rotation_blend,
    } = neighbourhoods(
        cage_coords,
        neighbour_coords,
        rest_cage,
        cage_triangles,
        rest_mesh,
        skin_weights,
    )?;
    let regulariser = laplacian_regulariser(nc, cage_triangles)?;
    let gram = row_coords.transpose() * &row_coords;
    let trace_gram: f64 = (0..nc).map(|k| gram[(k, k)]).sum();
    let trace_reg: f64 = (0..nc).map(|k| regulariser[(k, k)]).sum();
    let strength = PRIOR_STRENGTH * trace_gram / trace_reg;
    if !(strength.is_finite() && strength > 0.0) {
        return Err(RigError::Singular {
            what: "the regularised cage fit (the fitting rows of Φ are zero)",
        });
    }
    let system = Mat::<f64>::from_fn(nc, nc, |r, c| gram[(r, c)] + strength * regulariser[(r, c)]);
    let llt = system
        .llt(faer::Side::Lower)
        .map_err(|_| RigError::Singular {
            what: "the regularised cage fit (H = Φ̃ᵀΦ̃ + λR is not positive definite)",
        })?;
    let mut cage_from_rows = row_coords.transpose().to_owned();
    llt.solve_in_place(cage_from_rows.as_mut());
    let mut cage_from_prior = Mat::<f64>::from_fn(nc, nc, |r, c| strength * regulariser[(r, c)]);
    llt.solve_in_place(cage_from_prior.as_mut());
    let finite = |m: &Mat<f64>| m.col_iter().all(|c| c.iter().all(|x| x.is_finite()));
    if !finite(&cage_from_rows) || !finite(&cage_from_prior) {
        return Err(RigError::Singular {
            what: "the regularised cage fit",
        });
    }
    crate::vector_registers::clear_upper_halves();
    let num_entries = joints.len();
    let mut rest_centroids = vec![DVec3::ZERO; nc];
    let mut joint_moments = vec![DVec3::ZERO; num_entries];
    cage_moments(
        &centroid_coords,
        &joints,
        rest_cage,
        &mut rest_centroids,
        &mut joint_moments,
    );
    let reach_limit = ReachLimit::new(
        rest_cage,
        cage_triangles,
        rest_mesh,
        skin_weights,
        rows,
        &near,
        rest_centroids.clone(),
        joint_moments.clone(),
    );
    let prior = CagePrior {
        joints,
        centroid_coords,
        cage_from_prior,
        strength,
        moments_cage: rest_cage.to_vec(),
        rest_centroids,
        joint_moments,
        carried: vec![DVec3::ZERO; nc],
        rotations: vec![DMat3::IDENTITY; nc],
        posed_translations: vec![DVec3::ZERO; binding_joints.len()],
        joint_scales: vec![0.0; binding_joints.len()],
        binding_joints: binding_joints.clone(),
        binding_centroids,
        rotation_blend,
        reach_scratch: reach_limit.scratch(),
        reach_limit,
        reach_factors: vec![1.0; nc],
        reach_anchored: vec![false; nc],
        reach_linear: Vec::new(),
    };
    Ok(RegularisedMaps {
        cage_from_rows,
        prior,
    })
}

/// R = LᵀL + εI (`#C × #C`), L the uniform graph Laplacian of the cage's edges, ε =
/// [`PRIOR_EPSILON`] · tr(LᵀL)/#C. Errors on a cage vertex with no edge.
pub(crate) fn laplacian_regulariser(
    nc: usize,
    triangles: &[[u32; 3]],
) -> Result<Mat<f64>, RigError> {
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); nc];
    for tri in triangles {
        for e in 0..3 {
            let (a, b) = (tri[e] as usize, tri[(e + 1) % 3] as usize);
            if a >= nc || b >= nc {
                return Err(RigError::IndexOutOfRange {
                    what: "cage triangle corner",
                    index: a.max(b),
                    len: nc,
                });
            }
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
    }
    let mut laplacian = Mat::<f64>::zeros(nc, nc);
    for (k, n) in neighbours.iter_mut().enumerate() {
        n.sort_unstable();
        n.dedup();
        if n.is_empty() {
            return Err(RigError::Invalid(format!(
                "cage vertex {k} is on no cage triangle: the regularised cage fit needs every \
                 cage vertex on the surface (use --cage-fit paper, or remove the loose vertex)"
            )));
        }
        laplacian[(k, k)] = 1.0;
        let w = 1.0 / n.len() as f64;
        for &j in n.iter() {
            laplacian[(k, j)] -= w;
        }
    }
    let mut regulariser = laplacian.transpose() * &laplacian;
    let epsilon = PRIOR_EPSILON * (0..nc).map(|k| regulariser[(k, k)]).sum::<f64>() / nc as f64;
    for k in 0..nc {
        regulariser[(k, k)] += epsilon;
    }
    Ok(regulariser)
}

/// What [`neighbourhoods`] finds.
struct Neighbourhoods {
    /// N_k, `#C` lists of rest-skin vertices.
    near: Vec<Vec<usize>>,
    joints: Vec<NeighbourhoodJoint>,
    /// ξ, `#C × #C` row-major.
    centroid_coords: Vec<f64>,
    /// x̄_k on the binding skin, `#C`.
    binding_centroids: Vec<DVec3>,
    /// μ_k, `#C`.
    rotation_blend: Vec<f64>,
}

/// The neighbourhood N_k of every rest cage vertex (its 32 nearest rest-skin vertices,
/// [`skin_neighbourhoods`]) as its joints' a_kj,
/// β_kj, D_kj and s_kj, ξ (`#C × #C` row-major, row k the mean over N_k of the vertices'
/// coordinates in `neighbour_coords`), x̄_k and μ_k.
fn neighbourhoods(
    cage_coords: &CageCoords,
    neighbour_coords: NeighbourCoords,
    rest_cage: &[DVec3],
    cage_triangles: &[[u32; 3]],
    rest_mesh: &[DVec3],
    skin_weights: &SkinWeights,
) -> Result<Neighbourhoods, RigError> {
    let nv = rest_mesh.len();
    let nc = rest_cage.len();
    if skin_weights.num_vertices() != nv || nv == 0 {
        return Err(RigError::SizeMismatch {
            what: "skinning weight rows (rest skin vertices) for the cage prior",
            expected: nv,
            actual: skin_weights.num_vertices(),
        });
    }
    let near = skin_neighbourhoods(rest_cage, rest_mesh);
    // The coordinate row of each neighbour: Φ's own, or mean value coordinates of the
    // neighbours alone (row `local[v]` of `computed`).
    let computed = match neighbour_coords {
        NeighbourCoords::Fitting => None,
        NeighbourCoords::MeanValue => {
            let mut vertices: Vec<usize> = near.iter().flatten().copied().collect();
            vertices.sort_unstable();
            vertices.dedup();
            let points: Vec<DVec3> = vertices.iter().map(|&v| rest_mesh[v]).collect();
            let cage = crate::mesh::TriMesh::new(rest_cage.to_vec(), cage_triangles.to_vec())?;
            let coords = crate::coords::mvc::compute_cage_coords(&cage, &points, None)?;
            let mut local = vec![usize::MAX; nv];
            for (row, &v) in vertices.iter().enumerate() {
                local[v] = row;
            }
            Some((coords, local))
        }
    };
    let coordinate = |v: usize, m: usize| match &computed {
        None => cage_coords.get(v, m),
        Some((coords, local)) => coords.get(local[v], m),
    };
    let nj = skin_weights.num_joints();
    let mut slot = vec![usize::MAX; nj];
    let mut joints: Vec<NeighbourhoodJoint> = Vec::new();
    let mut centroid_coords = vec![0.0f64; nc * nc];
    let mut binding_centroids = vec![DVec3::ZERO; nc];
    let mut rotation_blend = vec![0.0f64; nc];
    for (k, near) in near.iter().enumerate() {
        let share = 1.0 / near.len() as f64;
        let first = joints.len();
        let centre = near.iter().map(|&v| rest_mesh[v]).sum::<DVec3>() * share;
        binding_centroids[k] = centre;
        let mut spread = 0.0;
        for &v in near {
            let d = rest_mesh[v] - centre;
            spread += share * d.length_squared();
            let centroid = &mut centroid_coords[k * nc..(k + 1) * nc];
            for (m, x) in centroid.iter_mut().enumerate() {
                *x += share * coordinate(v, m);
            }
            let (vertex_joints, weights) = skin_weights.row(v);
            for (&j, &w) in vertex_joints.iter().zip(weights) {
                let j = j as usize;
                if slot[j] == usize::MAX {
                    slot[j] = joints.len();
                    joints.push(NeighbourhoodJoint {
                        cage_vertex: k,
                        joint: j,
                        share: 0.0,
                        coords: vec![0.0; nc],
                        spread: DMat3::ZERO,
                        offset: DVec3::ZERO,
                    });
                }
                let entry = &mut joints[slot[j]];
                entry.share += share * w;
                entry.spread += outer(d, d) * (share * w);
                entry.offset += d * (share * w);
                for (m, x) in entry.coords.iter_mut().enumerate() {
                    *x += share * w * coordinate(v, m);
                }
            }
        }
        for entry in &joints[first..] {
            slot[entry.joint] = usize::MAX;
        }
        // A neighbourhood of coincident skin vertices keeps the blend of its joints alone.
        rotation_blend[k] = if spread > 0.0 {
            ROTATION_BLEND * spread
        } else {
            1.0
        };
    }
    Ok(Neighbourhoods {
        near,
        joints,
        centroid_coords,
        binding_centroids,
        rotation_blend,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::nearest_vertices::SKIN_NEIGHBOURS;

    /// A unit cube cage, 60 skin points inside it split between two joints by x, and Φ.
    fn cube_rig() -> (TriMesh, Vec<DVec3>, CageCoords, SkinWeights) {
        let cage = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE).unwrap();
        let points: Vec<DVec3> = (0..60)
            .map(|i| {
                let t = i as f64 / 60.0;
                DVec3::new(
                    0.1 + 0.8 * t,
                    0.2 + 0.6 * (t * 7.0).fract(),
                    0.3 + 0.5 * (t * 3.0).fract(),
                )
            })
            .collect();
        let phi = crate::coords::mvc::compute_cage_coords(&cage, &points, None).unwrap();
        let (omega, _) = SkinWeights::from_triplets(
            points.len(),
            2,
            points
                .iter()
                .enumerate()
                .flat_map(|(i, p)| [(i, 0, 1.0 - p.x), (i, 1, p.x)]),
        )
        .unwrap();
        (cage, points, phi, omega)
    }

    /// The cube rig's regularised maps on every third point as rows.
    fn cube_maps() -> (TriMesh, CageCoords, Vec<usize>, RegularisedMaps) {
        let (cage, points, phi, omega) = cube_rig();
        let rows: Vec<usize> = (0..points.len()).step_by(3).collect();
        let maps = regularised_maps(
            &phi,
            &rows,
            &cage.positions,
            &cage.triangles,
            &points,
            &omega,
            &BindingJoints::two_joint_chain(DVec3::ZERO, DVec3::new(0.5, 0.5, 0.5)),
            NeighbourCoords::Fitting,
        )
        .unwrap();
        (cage, phi, rows, maps)
    }

    #[test]
    fn k_phi_plus_q_is_the_identity_and_the_rest_pose_is_kept() {
        let (cage, phi, rows, mut maps) = cube_maps();
        let nc = cage.num_vertices();
        let selected = phi.select_rows(&rows);
        let sum = &maps.cage_from_rows * &selected + maps.prior.cage_from_prior();
        for r in 0..nc {
            for c in 0..nc {
                let expected = if r == c { 1.0 } else { 0.0 };
                assert!(
                    (sum[(r, c)] - expected).abs() < 1e-12,
                    "({r}, {c}): {}",
                    sum[(r, c)]
                );
            }
        }
        assert!(maps.prior.strength() > 0.0);
        // At rest the prior is the rest cage (its centroids are ΦC's), and so is C' = K·M̃ + Q·P.
        maps.prior.carry(&[DAffine3::IDENTITY; 2], &cage.positions);
        let mut posed_rows = vec![DVec3::ZERO; rows.len()];
        phi.apply_rows(&rows, &cage.positions, &mut posed_rows);
        let q = maps.prior.cage_from_prior();
        let fitted: Vec<DVec3> = (0..nc)
            .map(|k| {
                let rows_part = posed_rows
                    .iter()
                    .enumerate()
                    .fold(DVec3::ZERO, |acc, (r, p)| {
                        acc + maps.cage_from_rows[(k, r)] * *p
                    });
                let prior_part = maps
                    .prior
                    .carried_cage()
                    .iter()
                    .enumerate()
                    .fold(DVec3::ZERO, |acc, (m, p)| acc + q[(k, m)] * *p);
                rows_part + prior_part
            })
            .collect();
        assert!(crate::mesh::max_distance(&fitted, &cage.positions) < 1e-12);
        assert!(crate::mesh::max_distance(maps.prior.carried_cage(), &cage.positions) < 1e-12);
    }

    #[test]
    fn the_prior_moves_rigidly_with_a_rigid_skeleton() {
        let (cage, _, _, mut maps) = cube_maps();
        let motion = DAffine3::from_rotation_translation(
            glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.9),
            DVec3::new(3.0, -1.0, 2.0),
        );
        maps.prior.carry(&[motion, motion], &cage.positions);
        let expected: Vec<DVec3> = cage
            .positions
            .iter()
            .map(|p| motion.transform_point3(*p))
            .collect();
        assert!(crate::mesh::max_distance(maps.prior.carried_cage(), &expected) < 1e-12);
    }

    #[test]
    fn the_best_rotation_of_a_turned_symmetric_matrix_is_the_turn_even_through_a_reflection() {
        let turn = DMat3::from_axis_angle(DVec3::new(0.3, -1.0, 0.6).normalize(), 2.4);
        let close = |a: DMat3, b: DMat3| (a - b).to_cols_array().iter().all(|x| x.abs() < 1e-12);
        // Positive definite: the polar factor.
        let got = best_rotation(turn * DMat3::from_diagonal(DVec3::new(3.0, 2.0, 1.0)));
        assert!(close(got, turn), "{got:?}");
        // A reflection along the weakest axis: Kabsch flips that axis back, Horn's quaternion.
        let got = best_rotation(turn * DMat3::from_diagonal(DVec3::new(3.0, 2.0, -0.5)));
        assert!(close(got, turn), "{got:?}");
        assert_eq!(best_rotation(DMat3::ZERO), DMat3::IDENTITY);
        // Horn's path agrees with the polar factor where both apply.
        let h = turn
            * DMat3::from_cols(
                DVec3::new(2.0, 0.3, 0.1),
                DVec3::new(0.3, 1.5, -0.2),
                DVec3::new(0.1, -0.2, 0.7),
            );
        assert!(close(horn_rotation(h), rotation_of(h)));
    }

    /// The carried rotation is the best-fit rotation of the neighbourhood posed with the binding
    /// skeleton (a hinge closing turns the neighbourhood by less than the child joint): the
    /// moments D_kj, s_kj and the posed binding joints give the covariance summed point by point.
    #[test]
    fn the_carried_rotation_is_the_neighbourhoods_best_fit_rotation() {
        let (_, points, _, omega) = cube_rig();
        // `cube_maps`'s joints: the root at the origin, the child at the pivot.
        let (cage, _, _, mut maps) = cube_maps();
        let pivot = DVec3::new(0.5, 0.5, 0.5);
        // The root turns a little, the child (the x > 0.5 side) much more about the pivot.
        let root_turn = DMat3::from_rotation_y(0.2);
        let child_turn = DMat3::from_rotation_z(1.1) * root_turn;
        let root_motion = DAffine3::from_mat3_translation(root_turn, DVec3::new(0.1, 0.0, 0.0));
        let posed_pivot = root_motion.transform_point3(pivot);
        let child_motion =
            DAffine3::from_mat3_translation(child_turn, posed_pivot - child_turn * pivot);
        let motions = [root_motion, child_motion];
        maps.prior.carry(&motions, &cage.positions);
        let posed: Vec<DVec3> = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (joints, weights) = omega.row(i);
                joints
                    .iter()
                    .zip(weights)
                    .fold(DVec3::ZERO, |acc, (&j, &w)| {
                        acc + w * motions[j as usize].transform_point3(*p)
                    })
            })
            .collect();
        let mut turned = 0;
        for (k, c) in cage.positions.iter().enumerate() {
            let mut order: Vec<usize> = (0..points.len()).collect();
            order.sort_by(|&a, &b| {
                points[a]
                    .distance_squared(*c)
                    .total_cmp(&points[b].distance_squared(*c))
                    .then(a.cmp(&b))
            });
            // The nearest SKIN_NEIGHBOURS and whoever ties with the last of them.
            let distance = |i: usize| points[i].distance_squared(*c);
            let cut = distance(order[SKIN_NEIGHBOURS - 1]);
            let near: Vec<usize> = order
                .iter()
                .copied()
                .filter(|&i| distance(i) <= cut * (1.0 + 1e-9))
                .collect();
            let near = &near[..];
            let n = near.len() as f64;
            let x_bar = near.iter().map(|&i| points[i]).sum::<DVec3>() / n;
            let y_bar = near.iter().map(|&i| posed[i]).sum::<DVec3>() / n;
            let mut covariance = DMat3::ZERO;
            let mut spread = 0.0;
            let mut blend = DMat3::ZERO;
            for &i in near {
                covariance += outer(posed[i] - y_bar, points[i] - x_bar) * (1.0 / n);
                spread += (points[i] - x_bar).length_squared() / n;
                let (joints, weights) = omega.row(i);
                for (&j, &w) in joints.iter().zip(weights) {
                    blend += motions[j as usize].matrix3 * (w / n);
                }
            }
            let rotation = best_rotation(covariance + blend * (ROTATION_BLEND * spread));
            let expected = y_bar + rotation * (*c - x_bar);
            let got = maps.prior.carried_cage()[k];
            assert!(got.distance(expected) < 1e-12, "{k}: {got} vs {expected}");
            // Not the blend of the joints' rotations.
            let blended = y_bar + rotation_of(blend) * (*c - x_bar);
            if got.distance(blended) > 1e-3 {
                turned += 1;
            }
        }
        assert!(turned > 0);
    }

    #[test]
    fn polar_factor_of_a_blend_is_a_rotation() {
        let a = DMat3::from_rotation_z(0.8);
        let b = DMat3::from_rotation_x(-0.5);
        let r = rotation_of(a * 0.3 + b * 0.7);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        let rtr = r.transpose() * r;
        assert!(
            (rtr - DMat3::IDENTITY)
                .to_cols_array()
                .iter()
                .all(|x| x.abs() < 1e-12)
        );
        assert_eq!(rotation_of(a), a);
        assert_eq!(rotation_of(DMat3::ZERO), DMat3::IDENTITY);
    }

    #[test]
    fn laplacian_annihilates_constants_and_refuses_loose_vertices() {
        let cage = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE).unwrap();
        let nc = cage.num_vertices();
        let r = laplacian_regulariser(nc, &cage.triangles).unwrap();
        // L·1 = 0, so R·1 = ε·1 with ε = PRIOR_EPSILON·tr(LᵀL)/#C and tr(R) = tr(LᵀL) + #C·ε.
        let trace: f64 = (0..nc).map(|k| r[(k, k)]).sum();
        let epsilon = PRIOR_EPSILON * trace / (nc as f64 * (1.0 + PRIOR_EPSILON));
        for row in 0..nc {
            let sum: f64 = (0..nc).map(|c| r[(row, c)]).sum();
            assert!(
                (sum - epsilon).abs() < 1e-12,
                "row {row}: {sum} against {epsilon}"
            );
            for c in 0..nc {
                assert_eq!(r[(row, c)], r[(c, row)]);
            }
        }
        assert!(matches!(
            laplacian_regulariser(nc + 1, &cage.triangles),
            Err(RigError::Invalid(_))
        ));
    }
}
