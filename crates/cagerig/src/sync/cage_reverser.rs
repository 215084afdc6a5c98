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
//! is factorised lazily on the first grab after the skeleton pose changed, and reused for every
//! grab until the next skeleton edit. Exact under LBS: after the full update the grabbed C'
//! vertices land on their targets and the others do not move.
//!
//! **Low-rank factorisation (default, MaxVol rows).** Write the system matrix of Eq. 19 as
//! `G = A₀ + U V` with `A₀ = R̃ (Φ̃ ⊗ I₃)` and the skeleton term `Ω̃ B_topo⁻¹ A_R Ψ = U V`.
//! Only *active* joints contribute to the latter: a joint whose rotation equals its parent's (a
//! root: equals the identity) has a zero block in A_R. With `D_k = R_f − R_k` (root: `I − R_k`)
//! and `W_ik = Σ_{j ∈ subtree(k)} ω_ij`, `U` has blocks `W_ik D_k` (3#R × 3#active) and
//! `V = Ψ_active ⊗ I₃`. Since `A₀⁻¹ = (P ⊗ I₃) R̃⁻¹` is known (P = Φ̃⁻¹ from CageUp, R̃ block
//! diagonal), the Woodbury identity reduces the refactorisation to an LU of the
//! `3#active × 3#active` capacitance matrix `I + V A₀⁻¹ U`: O(#C²·#active) work instead of
//! O((3#C)³). The dense `3#C × 3#C` LU is used when the rows are not square (least-squares
//! CageUp), when a blended rotation R_i is singular, or on request ([`ReverserMethod::Dense`]).
//!
//! **Regularised CageUp.** With C' = K M̃' + Q P(C, S') ([`crate::sync::cage_prior`]) the system
//! is `(K G_rows + Q G_prior) ∂C = ∂C'`, with G_rows the matrix above and G_prior the Jacobian
//! of the prior, also linear for a fixed pose; it is factorised densely. Its reach limit
//! ([`crate::sync::reach_limit`]) blends row k with (G_prior)_k by the pose's factor s_k.

use faer::Mat;
use glam::{DMat3, DVec3};

use crate::error::RigError;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use crate::sync::cage_prior::{CagePrior, PriorPose};
use crate::sync::cage_updater::check_triangular_condition;
use crate::sync::dense_lu::DenseLu;

/// How [`CageReverser::refactor`] factorises Eq. 19.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReverserMethod {
    /// Low-rank (Woodbury) factorisation when applicable, dense LU otherwise.
    #[default]
    Auto,
    /// Always the dense `3#C × 3#C` LU.
    Dense,
}

/// Blocks `D_k` with no entry above this are treated as zero (joint rotated like its parent).
const INACTIVE_JOINT_TOLERANCE: f64 = 1e-13;
/// A blended rotation with |det| below this sends the factorisation to the dense path.
const MIN_BLENDED_DETERMINANT: f64 = 1e-8;

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
    /// P (the paper's fit) or K (the regularised one), `#C × #R` (column-major faer matrix,
    /// from the CageUpdater).
    cage_from_rows: Mat<f64>,
    /// The regularised CageUp's prior (C' = K·M̃' + Q·P), [K Q] (`#C × (#R + #C)`) and the
    /// prior's pose; `None` for the paper's fit.
    prior: Option<RegularisedParts>,
    parents: Vec<Option<usize>>,
    order: Vec<usize>,
    factor: Option<Factor>,
    /// The dense `3#C × 3#C` system and its factors ([`Factor::Dense`]).
    dense_lu: DenseLu,
    /// Scratch for building the dense system: E (`#J × #C` blocks), G (`#R (+ #C) × 9#C`) and
    /// P·G or [K Q]·[G; ∂P/∂C] (`#C × 9#C`), both row-major.
    translation_jacobian: Vec<DMat3>,
    rows_jacobian: Vec<f64>,
    cage_jacobian: Vec<f64>,
    method: ReverserMethod,
    /// Scratch for the per-grab solve (3#C).
    rhs: Vec<f64>,
    /// Scratch for the low-rank solve: `#R` points, `#C` points, `3#J` numbers.
    scratch_rows: Vec<DVec3>,
    scratch_cage: Vec<DVec3>,
    scratch_small: Vec<f64>,
}

/// The regularised fit's part of Eq. 19.
#[derive(Debug, Clone)]
struct RegularisedParts {
    prior: CagePrior,
    /// [K Q], `#C × (#R + #C)`.
    stacked: Mat<f64>,
    pose: PriorPose,
}

/// A factorisation of Eq. 19 for one pose.
#[derive(Debug, Clone)]
enum Factor {
    /// In [`CageReverser::dense_lu`].
    Dense,
    LowRank(LowRank),
}

/// Woodbury form (see the module docs).
#[derive(Debug, Clone)]
struct LowRank {
    /// R_i⁻¹ of every fitted row, `#R`.
    inverse_row_rotations: Vec<DMat3>,
    /// Active joints.
    active: Vec<usize>,
    /// Y = A₀⁻¹ U, `#C × #active` blocks (row-major by cage vertex).
    y: Vec<DMat3>,
    /// LU of the capacitance matrix `I + V Y` (absent when no joint is active).
    capacitance: Option<DenseLu>,
}

impl CageReverser {
    /// Gathers the pose-independent parts of CageUp `cage_updater` on Φ `cage_coords`
    /// (`#V × #C`): its rows and map, Ω `skin_weights`, Ψ `joint_coords` (`#J` rows of `#C`).
    /// A regularised CageUp adds its prior's Jacobian, mapped by Q, to Eq. 19
    /// ([`crate::sync::cage_prior`]); it is always factorised densely.
    pub fn new(
        cage_coords: &crate::cage_coords::CageCoords,
        cage_updater: &crate::sync::cage_updater::CageUpdater,
        skin_weights: &SkinWeights,
        joint_coords: impl Fn(usize) -> Vec<f64>,
        skeleton: &Skeleton,
    ) -> Result<Self, RigError> {
        let num_cage = cage_coords.num_cage_vertices();
        let rows = cage_updater.rows();
        let rows_map = cage_updater.cage_from_rows();
        if rows_map.nrows() != num_cage || rows_map.ncols() != rows.len() {
            return Err(RigError::SizeMismatch {
                what: "CageUp map columns",
                expected: rows.len(),
                actual: rows_map.ncols(),
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
            cage_from_rows: rows_map.clone(),
            prior: cage_updater.prior().map(|prior| {
                let (nr, q) = (rows.len(), prior.cage_from_prior());
                let stacked = Mat::from_fn(num_cage, nr + num_cage, |c, r| {
                    if r < nr {
                        rows_map[(c, r)]
                    } else {
                        q[(c, r - nr)]
                    }
                });
                RegularisedParts {
                    pose: prior.pose_scratch(),
                    prior: prior.clone(),
                    stacked,
                }
            }),
            parents: (0..skeleton.len()).map(|j| skeleton.parent(j)).collect(),
            order: skeleton.topological_order().to_vec(),
            factor: None,
            dense_lu: DenseLu::new(3 * num_cage, "CageRev's system (Eq. 19)"),
            translation_jacobian: Vec::new(),
            rows_jacobian: Vec::new(),
            cage_jacobian: Vec::new(),
            method: ReverserMethod::Auto,
            rhs: vec![0.0; 3 * num_cage],
            scratch_rows: vec![DVec3::ZERO; rows.len()],
            scratch_cage: vec![DVec3::ZERO; num_cage],
            scratch_small: vec![0.0; 6 * skeleton.len().max(num_cage)],
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

    /// The factorisation method selected.
    pub fn method(&self) -> ReverserMethod {
        self.method
    }

    /// Selects the factorisation method (drops the current factorisation).
    pub fn set_method(&mut self, method: ReverserMethod) {
        self.method = method;
        self.factor = None;
    }

    /// Whether the held factorisation is the low-rank one.
    pub fn is_low_rank(&self) -> bool {
        matches!(self.factor, Some(Factor::LowRank(_)))
    }

    /// Builds and factorises the Eq. 19 system for the rotations `T_j^r` of the current pose
    /// (`joint_rotations`, `#J`, the linear parts of posed_from_rest). `joints_follow`: whether
    /// SkelUp moves the joints with the rest cage; when it is locked the skeleton term
    /// Ω̃ B_topo⁻¹ A_R Ψ is zero (a grab moves no joint) and the system is `P R̃ Φ̃`.
    /// `fitted_reach_factors`: the reach factors s (`#C`) CageUp applied in this pose, when it
    /// has them ([`crate::sync::cage_updater::CageUpdater::reach_factors_in_pose`]); the
    /// regularised fit's rows take those instead of computing them again (the same bits).
    pub fn refactor(
        &mut self,
        joint_rotations: &[DMat3],
        joints_follow: bool,
        fitted_reach_factors: Option<&[f64]>,
    ) -> Result<(), RigError> {
        let factored = self.factorise(joint_rotations, joints_follow, fitted_reach_factors);
        // The factorisations run faer on this thread.
        crate::vector_registers::clear_upper_halves();
        factored
    }

    /// The work of [`Self::refactor`].
    fn factorise(
        &mut self,
        joint_rotations: &[DMat3],
        joints_follow: bool,
        fitted_reach_factors: Option<&[f64]>,
    ) -> Result<(), RigError> {
        let square = self.row_weights.num_vertices() == self.num_cage && self.prior.is_none();
        if self.method == ReverserMethod::Auto
            && square
            && let Some(low_rank) = self.low_rank(joint_rotations, joints_follow)?
        {
            self.factor = Some(Factor::LowRank(low_rank));
            return Ok(());
        }
        self.factor = None;
        self.dense(joint_rotations, joints_follow, fitted_reach_factors)?;
        self.factor = Some(Factor::Dense);
        Ok(())
    }

    /// The Woodbury factorisation, or None if a blended rotation is singular.
    fn low_rank(
        &self,
        joint_rotations: &[DMat3],
        joints_follow: bool,
    ) -> Result<Option<LowRank>, RigError> {
        let nc = self.num_cage;
        let nr = self.row_weights.num_vertices();
        let nj = self.parents.len();
        // D_k and the active joints.
        let mut slot = vec![usize::MAX; nj];
        let mut active = Vec::new();
        let mut d = Vec::new();
        for k in (0..nj).filter(|_| joints_follow) {
            let dk = match self.parents[k] {
                None => DMat3::IDENTITY - joint_rotations[k],
                Some(f) => joint_rotations[f] - joint_rotations[k],
            };
            let max = dk
                .to_cols_array()
                .iter()
                .fold(0.0f64, |m, x| m.max(x.abs()));
            if max > INACTIVE_JOINT_TOLERANCE {
                slot[k] = active.len();
                active.push(k);
                d.push(dk);
            }
        }
        let na = active.len();
        // R_i⁻¹ and Z = R̃⁻¹ U (blocks R_i⁻¹ W_ik D_k), row-major #R × #active.
        let mut inverse_row_rotations = Vec::with_capacity(nr);
        let mut z = vec![DMat3::ZERO; nr * na];
        let mut w = vec![0.0f64; na];
        for i in 0..nr {
            let (joints, weights) = self.row_weights.row(i);
            let mut rot_i = DMat3::ZERO;
            w.iter_mut().for_each(|x| *x = 0.0);
            for (&j, &wt) in joints.iter().zip(weights) {
                rot_i += joint_rotations[j as usize] * wt;
                // W_ik accumulates ω_ij over every active ancestor k of j (j included).
                let mut k = Some(j as usize);
                while let Some(kk) = k {
                    if slot[kk] != usize::MAX {
                        w[slot[kk]] += wt;
                    }
                    k = self.parents[kk];
                }
            }
            let det = rot_i.determinant();
            if det.is_nan() || det.abs() < MIN_BLENDED_DETERMINANT {
                return Ok(None);
            }
            let inv = rot_i.inverse();
            for a in 0..na {
                z[i * na + a] = inv * d[a] * w[a];
            }
            inverse_row_rotations.push(inv);
        }
        // Y = (P ⊗ I) Z: block (c, a) = Σ_i P[c, i] Z(i, a).
        let mut y = vec![DMat3::ZERO; nc * na];
        for i in 0..nr {
            let p_col = self.cage_from_rows.col(i);
            for c in 0..nc {
                let pc = p_col[c];
                if pc != 0.0 {
                    for a in 0..na {
                        y[c * na + a] += z[i * na + a] * pc;
                    }
                }
            }
        }
        // Capacitance I + V Y: block (a, b) = δ_ab I + Σ_c Ψ_{k_a c} Y(c, b).
        let capacitance = if na == 0 {
            None
        } else {
            let mut blocks = vec![DMat3::ZERO; na * na];
            for (a, &k) in active.iter().enumerate() {
                let psi = &self.joint_coords[k * nc..(k + 1) * nc];
                for (c, &pk) in psi.iter().enumerate() {
                    if pk != 0.0 {
                        for b in 0..na {
                            blocks[a * na + b] += y[c * na + b] * pk;
                        }
                    }
                }
                blocks[a * na + a] += DMat3::IDENTITY;
            }
            let n = 3 * na;
            let mut lu = DenseLu::new(n, "CageRev's capacitance matrix (Eq. 19, low-rank form)");
            for (i, v) in lu.matrix_mut().iter_mut().enumerate() {
                let (r, c) = (i % n, i / n);
                *v = blocks[(r / 3) * na + c / 3].col(c % 3)[r % 3];
            }
            factorise_conditioned(&mut lu)?;
            Some(lu)
        };
        Ok(Some(LowRank {
            inverse_row_rotations,
            active,
            y,
            capacitance,
        }))
    }

    /// The dense `3#C × 3#C` system, factorised into [`Self::dense_lu`]. Allocates its
    /// scratch on the first call only.
    fn dense(
        &mut self,
        joint_rotations: &[DMat3],
        joints_follow: bool,
        fitted_reach_factors: Option<&[f64]>,
    ) -> Result<(), RigError> {
        let nc = self.num_cage;
        let nj = self.parents.len();
        let nr = self.row_weights.num_vertices();
        // E_j(k): ∂T_j = E_j(k) ∂c_k (3×3 per joint and cage vertex), root-first.
        let e = &mut self.translation_jacobian;
        e.resize(nj * nc, DMat3::ZERO);
        for &j in &self.order {
            let rot_j = joint_rotations[j];
            for k in 0..nc {
                let psi = if joints_follow {
                    self.joint_coords[j * nc + k]
                } else {
                    0.0
                };
                e[j * nc + k] = match self.parents[j] {
                    None => (DMat3::IDENTITY - rot_j) * psi,
                    Some(f) => e[f * nc + k] - (rot_j - joint_rotations[f]) * psi,
                };
            }
        }
        // G = R̃Φ̃ + Ω̃ E as #R × (9 #C), row-major: entry (i, 9k + 3a + b) = G_block(i,k)[a][b];
        // for the regularised fit, the prior's Jacobian ∂P/∂C below it (#C more rows).
        let prior_rows = self.prior.as_ref().map_or(0, |_| nc);
        let width = 9 * nc;
        let g = &mut self.rows_jacobian;
        g.resize((nr + prior_rows) * width, 0.0);
        for (i, g_row) in g.chunks_exact_mut(width).take(nr).enumerate() {
            let (joints, weights) = self.row_weights.row(i);
            let mut rot_i = DMat3::ZERO;
            for (&j, &w) in joints.iter().zip(weights) {
                rot_i += joint_rotations[j as usize] * w;
            }
            for (k, entries) in g_row.chunks_exact_mut(9).enumerate() {
                let mut block = rot_i * self.row_coords[i * nc + k];
                for (&j, &w) in joints.iter().zip(weights) {
                    block += e[j as usize * nc + k] * w;
                }
                // glam is column-major: the transpose's columns are the block's rows.
                entries.copy_from_slice(&block.transpose().to_cols_array());
            }
        }
        // P G (#C × 9#C), or [K Q] [G; ∂P/∂C] for the regularised fit (on this thread: a small
        // product, where the thread pool's dispatch cost more than it saved).
        let pg = &mut self.cage_jacobian;
        pg.resize(nc * width, 0.0);
        let left = match &mut self.prior {
            None => self.cage_from_rows.as_ref(),
            Some(RegularisedParts {
                prior,
                stacked,
                pose,
            }) => {
                prior.pose(joint_rotations, pose);
                prior.jacobian(joint_rotations, e, pose, &mut g[nr * width..]);
                stacked.as_ref()
            }
        };
        crate::sync::small_products::product_into(left, g, width, pg);
        if let Some(RegularisedParts { prior, pose, .. }) = &mut self.prior {
            // The reach limit: row k is s_k [K Q]_k [G; ∂P/∂C] + (1 − s_k) ∂P_k/∂C, with
            // CageUp's s of this pose when it is given.
            let factors = match fitted_reach_factors {
                Some(factors) => factors,
                None => {
                    prior.reach_factors(joint_rotations, &self.cage_from_rows, pose);
                    pose.reach_factors()
                }
            };
            let prior_jacobian = g[nr * width..].chunks_exact(width);
            for ((row, prior_row), &s) in
                pg.chunks_exact_mut(width).zip(prior_jacobian).zip(factors)
            {
                if s < 1.0 {
                    for (v, p) in row.iter_mut().zip(prior_row) {
                        *v = s * *v + (1.0 - s) * p;
                    }
                }
            }
        }
        // Entry (3k' + a, 3k + b) of the system (column-major) is entry (k', 9k + 3a + b) of
        // P·G.
        let n = 3 * nc;
        let system = self.dense_lu.matrix_mut();
        for (kp, row) in pg.chunks_exact(width).enumerate() {
            for (k, entries) in row.chunks_exact(9).enumerate() {
                for a in 0..3 {
                    for b in 0..3 {
                        system[(3 * k + b) * n + 3 * kp + a] = entries[3 * a + b];
                    }
                }
            }
        }
        factorise_conditioned(&mut self.dense_lu)
    }

    /// Solves Eq. 19 for the rest-cage offsets ∂C (`#C`, written to `rest_cage_delta`) that
    /// produce the current-cage offsets `posed_cage_delta` (`#C`; zero for untouched vertices).
    /// Requires [`CageReverser::refactor`] for the current pose. No allocation.
    pub fn solve(
        &mut self,
        posed_cage_delta: &[DVec3],
        rest_cage_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        let nc = self.num_cage;
        match &mut self.factor {
            None => Err(RigError::Invalid(
                "the reverse cage deformer was not factorised for the current pose".into(),
            )),
            Some(Factor::Dense) => {
                for (k, d) in posed_cage_delta.iter().enumerate() {
                    self.rhs[3 * k..3 * k + 3].copy_from_slice(&d.to_array());
                }
                let x = &mut self.rhs;
                self.dense_lu.solve(x);
                for (k, d) in rest_cage_delta.iter_mut().enumerate() {
                    *d = DVec3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
                }
                Ok(())
            }
            Some(Factor::LowRank(lr)) => {
                // m = R̃⁻¹ (Φ̃ ⊗ I) ∂C'
                for (i, m) in self.scratch_rows.iter_mut().enumerate() {
                    let phi = &self.row_coords[i * nc..(i + 1) * nc];
                    let sum = phi
                        .iter()
                        .zip(posed_cage_delta)
                        .fold(DVec3::ZERO, |acc, (&p, d)| acc + p * *d);
                    *m = lr.inverse_row_rotations[i] * sum;
                }
                // z = (P ⊗ I) m
                let z = &mut self.scratch_cage;
                z.iter_mut().for_each(|v| *v = DVec3::ZERO);
                for (i, m) in self.scratch_rows.iter().enumerate() {
                    let p_col = self.cage_from_rows.col(i);
                    for (c, zc) in z.iter_mut().enumerate() {
                        *zc += p_col[c] * *m;
                    }
                }
                let na = lr.active.len();
                if let Some(cap) = &mut lr.capacitance {
                    // s = (I + VY)⁻¹ V z, then x = z − Y s.
                    let w = &mut self.scratch_small[..3 * na];
                    for (a, &k) in lr.active.iter().enumerate() {
                        let psi = &self.joint_coords[k * nc..(k + 1) * nc];
                        let v = psi
                            .iter()
                            .zip(z.iter())
                            .fold(DVec3::ZERO, |acc, (&p, zc)| acc + p * *zc);
                        w[3 * a..3 * a + 3].copy_from_slice(&v.to_array());
                    }
                    cap.solve(w);
                    for (c, out) in rest_cage_delta.iter_mut().enumerate() {
                        let mut x = z[c];
                        for a in 0..na {
                            x -=
                                lr.y[c * na + a] * DVec3::new(w[3 * a], w[3 * a + 1], w[3 * a + 2]);
                        }
                        *out = x;
                    }
                } else {
                    rest_cage_delta.copy_from_slice(z);
                }
                Ok(())
            }
        }
    }
}

/// Factorises `lu` and rejects factors whose pivots span more than the cage fits' condition
/// bound ([`check_triangular_condition`]); rejected factors are invalidated.
fn factorise_conditioned(lu: &mut DenseLu) -> Result<(), RigError> {
    lu.factorise()?;
    let conditioned = check_triangular_condition(lu.pivots());
    if conditioned.is_err() {
        lu.invalidate();
    }
    conditioned
}
