//! CageRev for Green coordinates (C'→C): the rest-cage change δ that makes CageUp return the
//! grabbed current cage C'_t = C'_0 + ∂C' exactly (grabbed vertices on their targets, the others
//! where they were).
//!
//! Green CageUp ([`super`]) returns a stationary point of ½‖F_R(C') − M'_R‖²,
//! i.e. `J(C')ᵀ (F_R(C') − M'_R) = 0` with J the Jacobian of the fitting rows F_R. So C'_t is
//! CageUp's answer exactly when the new skinned rows satisfy
//!
//! `G(δ) = J_tᵀ (M'_R(C₀ + δ) − F_R(C'_t)) = 0`,  `J_t = J(C'_t)` (fixed for the grab).
//!
//! Under LBS with the pose's rotations fixed, the chain C → (M_R = F_R(C), A(C)) → M'_R is
//! affine in M_R and the rest joints A (Eq. 15–18), so
//!
//! `M'_R(C₀ + δ) = M'_R(C₀) + R̃ (F_R(C₀ + δ) − F_R(C₀)) + K_A (A(C₀ + δ) − A(C₀))`
//!
//! with R̃ the blended linear parts of the rows' LBS transforms and `K_A = Ω̃ ∂T/∂A`
//! (`3#R × 3#J`), the skeleton's part (SkelUp moves the joints, which moves the translations;
//! zero while SkelUp is locked): both depend on the pose only and are built once per pose
//! ([`GreenCageReverser::prepare`]). SkelUp is `A(C) = Ψ_φ C + Ψ_ψ g(C)` (G5), rows of the same
//! form as F_R. Newton's method ([`crate::sync::newton`]) solves G(δ) = 0 with its exact Jacobian
//! `J_tᵀ (R̃ J(C₀ + δ) + K_A J_A(C₀ + δ))` from δ = 0, J_A the Jacobian of A (`3#J × 3#C`); a
//! large grab that stalls is split into pieces. For MVC (ψ = 0, Ψ_ψ = 0, J = Φ̃) this is Eq. 19
//! in its least-squares form.
//!
//! A fit regularised towards the carried cage P ([`super::prior`]) is stationary where
//! `J(C')ᵀ (F_R(C') − M'_R) + W (C' − P) = 0`, so
//!
//! `G(δ) = J_tᵀ (M'_R(C₀ + δ) − F_R(C'_t)) + W (P(C₀ + δ) − C'_t)`,
//!
//! with P affine in C and in the joint translations for a fixed pose (the translations affine
//! in A): `P(C₀ + δ) = P(C₀) + (∂P/∂C) δ + (∂P/∂t)(∂t/∂A)(A(C₀ + δ) − A(C₀))` exactly, both
//! matrices built once per pose ([`GreenCageReverser::prepare_prior`]). Its Jacobian adds
//! `W (∂P/∂C + (∂P/∂t)(∂t/∂A) J_A)`.
//!
//! W includes the fold terms of the triangles the prior's hat turns: they depend on the pose
//! alone, so W is that of the grab's pose, fixed for the grab.
//!
//! The prior's reach terms ½ Σ_k β_k |C'_k − a_k|² (β_k and the choice of a_k depend on the pose
//! alone) add `B (a(C₀ + δ) − C'_t)` to G: a_k = P_k, or the skinned anchor
//! `Q_k = Σ_j ω_kj (L_j C_k + t_j)`, whose change is `L̄_k δ_k + Σ_j ω_kj (∂t_j/∂A) ΔA` exactly
//! (L̄_k = Σ_j ω_kj L_j), and their derivatives to its Jacobian.

use faer::{Accum, Mat, MatMut, MatRef, Par};
use glam::{DMat3, DVec3};

use super::prior::{anchor_jacobians, prior_jacobians};
use super::{GRADIENT_TOLERANCE, GreenCageFit, rows_jacobian_into, rows_of};
use crate::error::RigError;
use crate::sync::newton::{NewtonReport, NewtonSolver, solve_by_continuation};

/// Precomputed Green CageRev for one pose (see the module docs).
#[derive(Debug, Clone)]
pub struct GreenCageReverser {
    num_cage: usize,
    /// R̃_r of every fitting row, `#R`.
    row_linear: Vec<DMat3>,
    /// K_A = Ω̃ ∂T/∂A, `3#R × 3#J` (zero while SkelUp is locked).
    skeleton_rows: Mat<f64>,
    /// SkelUp's Ψ_φ (`#J × #C`) and Ψ_ψ (`#J × #F`): A(C) = Ψ_φ C + Ψ_ψ g(C).
    joint_vertex_rows: Mat<f64>,
    joint_face_rows: Mat<f64>,
    /// The skinning transforms' linear parts K_A and R̃ were built for (`#J`), and whether
    /// SkelUp was locked then.
    pose_key: Vec<DMat3>,
    skel_up_locked: bool,
    ready: bool,
    solver: NewtonSolver,
    tolerance: f64,
    /// J_t (`3#R × 3#C`, built only when the solver refactors: the residual's J_tᵀ r is taken
    /// without it), R̃ J (`3#R × 3#C`), J_A (`3#J × 3#C`), J_tᵀ K_A (`3#C × 3#J`, at each
    /// factorisation) and J_tᵀ(R̃ J + K_A J_A) (`3#C × 3#C`).
    target_jacobian: Mat<f64>,
    /// ∂g_f/∂x at C'_t per face and corner (`#F`): J_t's face part, for J_tᵀ r.
    target_blocks: Vec<[DMat3; 3]>,
    /// φ_Rᵀ r (`#C × 3`) and ψ_Rᵀ r (`#F × 3`).
    vertex_sums: Mat<f64>,
    face_sums: Mat<f64>,
    chain_jacobian: Mat<f64>,
    joint_jacobian: Mat<f64>,
    projected_skeleton: Mat<f64>,
    system: Mat<f64>,
    /// A(C₀) and A(C₀ + δ), `#J`.
    start_joints: Vec<DVec3>,
    posed_target: Vec<DVec3>,
    rows_target: Vec<DVec3>,
    /// C₀ + δ and g(C₀ + δ) as `#C × 3` and `#F × 3` row-major tables, F_R(C₀ + δ) (`#R × 3`),
    /// A(C₀ + δ) (`#J × 3`), ΔA (`3#J`) and K_A ΔA (`3#R`): the residual's products.
    flat_moved: Vec<f64>,
    flat_g: Vec<f64>,
    trial_rows: Mat<f64>,
    trial_joint_rows: Mat<f64>,
    joint_change: Vec<f64>,
    row_skeleton: faer::Col<f64>,
    /// The residual rows r (`#R × 3`, row-major) for the products.
    flat_rows: Vec<f64>,
    g: Vec<DVec3>,
    moved: Vec<DVec3>,
    moved_for_jacobian: Vec<DVec3>,
    /// The regularised fit's terms (see the module docs), when the fit has a prior.
    prior: Option<ReverserPrior>,
}

/// CageRev's terms of a regularised fit, for one pose (see the module docs).
#[derive(Debug, Clone)]
struct ReverserPrior {
    /// W ⊗ I₃, `3#C × 3#C`, with W (`cage_weight`, `#C × #C`) that of the pose, fold terms
    /// included ([`super::prior`]).
    weight: Mat<f64>,
    cage_weight: Mat<f64>,
    /// β_k of the pose and whether vertex k is anchored on its skinned Q_k, `#C` each
    /// ([`super::prior`]).
    reach_weights: Vec<f64>,
    anchored: Vec<bool>,
    /// ∂Q_k/∂C_k = Σ_j ω_kj L_j of the anchored vertices (`#C`, identity elsewhere) and
    /// (∂Q/∂t)(∂t/∂A) (`3#C × 3#J`, zero rows for vertices not anchored and while SkelUp is
    /// locked).
    anchor_blocks: Vec<DMat3>,
    anchor_joint_rows: Mat<f64>,
    /// a(C₀) − C'_t of the current piece (`3#C`).
    anchor_start: Vec<f64>,
    /// ∂P/∂C (`3#C × 3#C`) and (∂P/∂t)(∂t/∂A) (`3#C × 3#J`, zero while SkelUp is locked).
    cage_rows: Mat<f64>,
    joint_rows: Mat<f64>,
    /// P(C₀) − C'_t of the current piece, then P(C₀ + δ) − C'_t (`3#C`), and δ (`3#C`).
    start: Vec<f64>,
    change: faer::Col<f64>,
    delta: Vec<f64>,
    /// ∂P/∂C + (∂P/∂t)(∂t/∂A) J_A, `3#C × 3#C`.
    system: Mat<f64>,
}

/// The state a grab starts from.
#[derive(Debug, Clone, Copy)]
pub struct GrabState<'a> {
    /// The rest cage C₀, `#C`.
    pub rest_cage: &'a [DVec3],
    /// F_R(C₀): the rest skin's fitting rows, `#R`.
    pub rest_rows: &'a [DVec3],
    /// M'_R(C₀): the skinned fitting rows CageUp fitted, `#R`.
    pub posed_rows: &'a [DVec3],
    /// C'_0: CageUp's converged current cage, `#C`.
    pub posed_cage: &'a [DVec3],
}

impl GreenCageReverser {
    /// For `num_cage` cage vertices, `num_faces` faces, `num_rows` fitting rows, `num_joints`
    /// joints and the cage size (bounding-box diagonal, for the tolerance).
    pub fn new(
        num_cage: usize,
        num_faces: usize,
        num_rows: usize,
        num_joints: usize,
        cage_size: f64,
    ) -> Self {
        Self {
            num_cage,
            row_linear: vec![DMat3::IDENTITY; num_rows],
            skeleton_rows: Mat::zeros(3 * num_rows, 3 * num_joints),
            joint_vertex_rows: Mat::zeros(num_joints, num_cage),
            joint_face_rows: Mat::zeros(num_joints, num_faces),
            pose_key: vec![DMat3::ZERO; num_joints],
            skel_up_locked: false,
            ready: false,
            solver: NewtonSolver::new(num_cage),
            tolerance: GRADIENT_TOLERANCE * cage_size.max(f64::MIN_POSITIVE),
            target_jacobian: Mat::zeros(3 * num_rows, 3 * num_cage),
            target_blocks: vec![[DMat3::ZERO; 3]; num_faces],
            vertex_sums: Mat::zeros(num_cage, 3),
            face_sums: Mat::zeros(num_faces, 3),
            chain_jacobian: Mat::zeros(3 * num_rows, 3 * num_cage),
            joint_jacobian: Mat::zeros(3 * num_joints, 3 * num_cage),
            projected_skeleton: Mat::zeros(3 * num_cage, 3 * num_joints),
            system: Mat::zeros(3 * num_cage, 3 * num_cage),
            start_joints: vec![DVec3::ZERO; num_joints],
            posed_target: vec![DVec3::ZERO; num_cage],
            rows_target: vec![DVec3::ZERO; num_rows],
            flat_moved: vec![0.0; 3 * num_cage],
            flat_g: vec![0.0; 3 * num_faces],
            trial_rows: Mat::zeros(num_rows, 3),
            trial_joint_rows: Mat::zeros(num_joints, 3),
            joint_change: vec![0.0; 3 * num_joints],
            row_skeleton: faer::Col::zeros(3 * num_rows),
            flat_rows: vec![0.0; 3 * num_rows],
            g: vec![DVec3::ZERO; num_faces],
            moved: vec![DVec3::ZERO; num_cage],
            moved_for_jacobian: vec![DVec3::ZERO; num_cage],
            prior: None,
        }
    }

    /// The regularised fit's terms for the pose of the last [`Self::prepare`] (after it): with
    /// the joints' linear parts `joint_linear` (`#J`) and ∂t_j/∂A_l (`translation_jacobian`,
    /// `#J × #J` blocks, row-major by j). Drops them when `fit` has no prior.
    pub fn prepare_prior(
        &mut self,
        fit: &GreenCageFit,
        joint_linear: &[DMat3],
        translation_jacobian: &[DMat3],
    ) {
        let Some(prior) = fit.prior() else {
            self.prior = None;
            return;
        };
        let n = 3 * self.num_cage;
        let nj = joint_linear.len();
        let terms = self.prior.get_or_insert_with(|| ReverserPrior {
            weight: Mat::zeros(n, n),
            cage_weight: Mat::zeros(n / 3, n / 3),
            reach_weights: vec![0.0; n / 3],
            anchored: vec![false; n / 3],
            anchor_blocks: vec![DMat3::IDENTITY; n / 3],
            anchor_joint_rows: Mat::zeros(n, 3 * nj),
            anchor_start: vec![0.0; n],
            cage_rows: Mat::zeros(n, n),
            joint_rows: Mat::zeros(n, 3 * nj),
            start: vec![0.0; n],
            change: faer::Col::zeros(n),
            delta: vec![0.0; n],
            system: Mat::zeros(n, n),
        });
        prior.reach_weights_in(
            joint_linear,
            &mut terms.reach_weights,
            &mut terms.anchored,
            &mut terms.cage_weight,
        );
        for k in 0..self.num_cage {
            for m in 0..self.num_cage {
                for a in 0..3 {
                    terms.weight[(3 * k + a, 3 * m + a)] = terms.cage_weight[(k, m)];
                }
            }
        }
        anchor_jacobians(
            prior,
            joint_linear,
            translation_jacobian,
            self.skel_up_locked,
            &terms.anchored,
            &mut terms.anchor_blocks,
            &mut terms.anchor_joint_rows,
        );
        prior_jacobians(
            prior,
            joint_linear,
            translation_jacobian,
            self.skel_up_locked,
            &mut terms.cage_rows,
            &mut terms.joint_rows,
        );
    }

    /// Takes SkelUp's coordinates: row j of Ψ_φ (`#C`) and of Ψ_ψ (`#F`, or empty for a SkelUp
    /// without face part, A = Ψ_φ C) from `joint_row(j)`.
    pub fn set_joint_coords<'a>(&mut self, joint_row: impl Fn(usize) -> (&'a [f64], &'a [f64])) {
        for j in 0..self.joint_vertex_rows.nrows() {
            let (vertex, face) = joint_row(j);
            for (k, &w) in vertex.iter().enumerate().take(self.num_cage) {
                self.joint_vertex_rows[(j, k)] = w;
            }
            for f in 0..self.joint_face_rows.ncols() {
                self.joint_face_rows[(j, f)] = face.get(f).copied().unwrap_or(0.0);
            }
        }
        self.ready = false;
    }

    /// Forgets the pose K_A, R̃ and the prior's terms were built for: the next grab rebuilds
    /// them (after the fit's regulariser was switched).
    pub fn invalidate(&mut self) {
        self.ready = false;
    }

    /// Whether K_A and R̃ were built for the pose whose skinning transforms have these linear
    /// parts (`#J`) and for this SkelUp lock.
    pub fn is_ready_for(
        &self,
        pose_linear: impl Iterator<Item = DMat3>,
        skel_up_locked: bool,
    ) -> bool {
        self.ready
            && self.skel_up_locked == skel_up_locked
            && self.pose_key.iter().copied().eq(pose_linear)
    }

    /// Stores R̃ (`#R`), K_A (`3#R × 3#J`, filled by `fill_skeleton_rows`; left zero when
    /// `skel_up_locked`) and the pose key (`#J`).
    pub fn prepare(
        &mut self,
        row_linear: impl Iterator<Item = DMat3>,
        pose_linear: impl Iterator<Item = DMat3>,
        skel_up_locked: bool,
        fill_skeleton_rows: impl FnOnce(&mut Mat<f64>),
    ) {
        for (r, m) in self.row_linear.iter_mut().zip(row_linear) {
            *r = m;
        }
        for (k, m) in self.pose_key.iter_mut().zip(pose_linear) {
            *k = m;
        }
        self.skel_up_locked = skel_up_locked;
        self.skeleton_rows.fill(0.0);
        if !skel_up_locked {
            fill_skeleton_rows(&mut self.skeleton_rows);
        }
        self.ready = true;
        // The factors of the previous grab stay: see `solve_piece`.
    }

    /// The rest-cage change δ (`rest_delta`, `#C`) that makes CageUp return C'_0 + `posed_delta`
    /// (`#C`, zero for untouched vertices), from the state `at`. Requires [`Self::prepare`] for
    /// the pose.
    pub fn solve(
        &mut self,
        fit: &GreenCageFit,
        at: GrabState<'_>,
        posed_delta: &[DVec3],
        rest_delta: &mut [DVec3],
    ) -> Result<NewtonReport, RigError> {
        if !self.ready {
            return Err(RigError::Invalid(
                "the Green reverse cage deformer was not prepared for the current pose".into(),
            ));
        }
        rest_delta.iter_mut().for_each(|d| *d = DVec3::ZERO);
        if fit.prior().is_some() != self.prior.is_some() {
            return Err(RigError::Invalid(
                "the Green reverse cage deformer was not prepared for the fit's prior".into(),
            ));
        }
        fit.normals().apply(at.rest_cage, &mut self.g);
        rows_of(
            &self.joint_vertex_rows,
            &self.joint_face_rows,
            at.rest_cage,
            &self.g,
            &mut self.start_joints,
        );
        let mut total = self.solve_piece(fit, &at, posed_delta, 1.0, rest_delta)?;
        if total.residual > self.tolerance {
            let tolerance = self.tolerance;
            solve_by_continuation(tolerance, &mut total, |a, first| {
                if first {
                    rest_delta.iter_mut().for_each(|d| *d = DVec3::ZERO);
                }
                self.solve_piece(fit, &at, posed_delta, a, rest_delta)
            })?;
        }
        Ok(total)
    }

    /// Newton on G(δ) = 0 for the fraction `a` of the grab, from `rest_delta` as given.
    fn solve_piece(
        &mut self,
        fit: &GreenCageFit,
        at: &GrabState<'_>,
        posed_delta: &[DVec3],
        a: f64,
        rest_delta: &mut [DVec3],
    ) -> Result<NewtonReport, RigError> {
        for ((t, p), d) in self
            .posed_target
            .iter_mut()
            .zip(at.posed_cage)
            .zip(posed_delta)
        {
            *t = *p + a * *d;
        }
        fit.rows_of(&self.posed_target, &mut self.g, &mut self.rows_target);
        if let (Some(terms), Some(fit_prior)) = (&mut self.prior, fit.prior()) {
            for (((start, anchor_start), (p, a)), t) in terms
                .start
                .chunks_exact_mut(3)
                .zip(terms.anchor_start.chunks_exact_mut(3))
                .zip(fit_prior.target().iter().zip(fit_prior.anchors()))
                .zip(&self.posed_target)
            {
                start.copy_from_slice(&(*p - *t).to_array());
                anchor_start.copy_from_slice(&(*a - *t).to_array());
            }
        }
        for (f, blocks) in self.target_blocks.iter_mut().enumerate() {
            *blocks = fit.normals().face_jacobian(&self.posed_target, f);
        }
        // J_t itself only if the solver refactors (below).
        let mut target_jacobian_built = false;
        // The factors of the previous piece or grab stay. They are those of a nearby G (J_t, R̃,
        // K_A and C move a little between the grabs of a drag, or across a small skeleton edit),
        // so chord steps from them converge, and far cheaper than a new Jacobian (`3#C × 3#R ×
        // 3#C` products); the solver refactors by itself when a step leaves more than
        // `CHORD_RATE` of the residual. The residual is exact, so the answer is the same to the
        // tolerance either way.
        let n = 3 * self.num_cage;
        let rest_cage = at.rest_cage;
        let vertex_rows = fit.vertex_rows();
        let face_rows = fit.face_rows();
        let normals = fit.normals();
        let row_linear = &self.row_linear;
        let skeleton_rows = &self.skeleton_rows;
        let row_skeleton = &mut self.row_skeleton;
        let (flat_moved, flat_g) = (&mut self.flat_moved, &mut self.flat_g);
        let (trial_rows, trial_joint_rows) = (&mut self.trial_rows, &mut self.trial_joint_rows);
        let joint_change = &mut self.joint_change;
        let flat_rows = &mut self.flat_rows;
        let (joint_vertex_rows, joint_face_rows) = (&self.joint_vertex_rows, &self.joint_face_rows);
        let start_joints = &self.start_joints;
        let joint_jacobian = &mut self.joint_jacobian;
        let projected_skeleton = &mut self.projected_skeleton;
        let target_jacobian = &mut self.target_jacobian;
        let (target_blocks, posed_target) = (&self.target_blocks, &self.posed_target);
        let (vertex_sums, face_sums) = (&mut self.vertex_sums, &mut self.face_sums);
        let chain_jacobian = &mut self.chain_jacobian;
        let system = &mut self.system;
        let rows_target = &self.rows_target;
        let g = &mut self.g;
        let moved = &mut self.moved;
        let moved_for_jacobian = &mut self.moved_for_jacobian;
        // Shared by both closures below (one runs at a time).
        let prior = std::cell::RefCell::new(self.prior.as_mut());
        self.solver.solve(
            rest_delta,
            self.tolerance,
            |delta, out| {
                // r = M'_R(C₀) + R̃ (F_R(C₀ + δ) − F_R(C₀)) + K_A (A(C₀ + δ) − A(C₀))
                //     − F_R(C'_t); out = J_tᵀ r.
                for ((m, c), d) in moved.iter_mut().zip(rest_cage).zip(delta) {
                    *m = *c + *d;
                }
                normals.apply(moved, g);
                // F_R(C₀ + δ) = φ_R C + ψ_R g and A(C₀ + δ) = Ψ_φ C + Ψ_ψ g as products over
                // `#· × 3` tables, then K_A ΔA.
                flatten(moved, flat_moved);
                flatten(g, flat_g);
                let x = MatRef::from_row_major_slice(flat_moved, moved.len(), 3);
                let gx = MatRef::from_row_major_slice(flat_g, g.len(), 3);
                rows_times(vertex_rows, face_rows, x, gx, trial_rows.as_mut());
                rows_times(
                    joint_vertex_rows,
                    joint_face_rows,
                    x,
                    gx,
                    trial_joint_rows.as_mut(),
                );
                for (j, start) in start_joints.iter().enumerate() {
                    for c in 0..3 {
                        joint_change[3 * j + c] = trial_joint_rows[(j, c)] - start[c];
                    }
                }
                faer::linalg::matmul::matmul(
                    row_skeleton.as_mat_mut(),
                    Accum::Replace,
                    skeleton_rows.as_ref(),
                    MatRef::from_column_major_slice(joint_change, joint_change.len(), 1),
                    1.0,
                    Par::Seq,
                );
                for (i, rotation) in row_linear.iter().enumerate() {
                    let trial =
                        DVec3::new(trial_rows[(i, 0)], trial_rows[(i, 1)], trial_rows[(i, 2)]);
                    let skeleton = DVec3::new(
                        row_skeleton[3 * i],
                        row_skeleton[3 * i + 1],
                        row_skeleton[3 * i + 2],
                    );
                    let change =
                        at.posed_rows[i] + *rotation * (trial - at.rest_rows[i]) + skeleton
                            - rows_target[i];
                    flat_rows[3 * i] = change.x;
                    flat_rows[3 * i + 1] = change.y;
                    flat_rows[3 * i + 2] = change.z;
                }
                // J_tᵀ r = φ_Rᵀ r + Σ_f (∂g_f/∂x)ᵀ (ψ_Rᵀ r)_f at C'_t, as two products (a
                // row-by-row dot product is one long dependency chain per entry) and the faces'
                // 3 × 3 blocks: the dense J_t would take 0.3 ms to build at every grab.
                let r = MatRef::from_row_major_slice(flat_rows, row_linear.len(), 3);
                transpose_times(vertex_rows, r, vertex_sums.as_mut());
                transpose_times(face_rows, r, face_sums.as_mut());
                for (k, o) in out.iter_mut().enumerate() {
                    *o = DVec3::new(
                        vertex_sums[(k, 0)],
                        vertex_sums[(k, 1)],
                        vertex_sums[(k, 2)],
                    );
                }
                for (f, (triangle, blocks)) in
                    normals.triangles().iter().zip(target_blocks).enumerate()
                {
                    let sum = DVec3::new(face_sums[(f, 0)], face_sums[(f, 1)], face_sums[(f, 2)]);
                    for (&corner, block) in triangle.iter().zip(blocks) {
                        out[corner as usize] += block.transpose() * sum;
                    }
                }
                // + W (P(C₀ + δ) − C'_t), P(C₀ + δ) = P(C₀) + ∂P/∂C δ + ∂P/∂A ΔA.
                if let Some(terms) = prior.borrow_mut().as_mut() {
                    flatten(delta, &mut terms.delta);
                    faer::linalg::matmul::matmul(
                        terms.change.as_mat_mut(),
                        Accum::Replace,
                        terms.cage_rows.as_ref(),
                        MatRef::from_column_major_slice(&terms.delta, terms.delta.len(), 1),
                        1.0,
                        Par::Seq,
                    );
                    faer::linalg::matmul::matmul(
                        terms.change.as_mat_mut(),
                        Accum::Add,
                        terms.joint_rows.as_ref(),
                        MatRef::from_column_major_slice(joint_change, joint_change.len(), 1),
                        1.0,
                        Par::Seq,
                    );
                    for (c, s) in terms.change.iter_mut().zip(&terms.start) {
                        *c += *s;
                    }
                    for (k, o) in out.iter_mut().enumerate() {
                        let mut pull = [0.0; 3];
                        for (a, p) in pull.iter_mut().enumerate() {
                            let row = terms.weight.row(3 * k + a);
                            *p = row
                                .iter()
                                .zip(terms.change.iter())
                                .fold(0.0, |acc, (w, c)| acc + w * c);
                        }
                        *o += DVec3::from_array(pull);
                    }
                    // + B (a(C₀ + δ) − C'_t): a_k = P_k, or the skinned
                    // Q_k(C₀ + δ) = Q_k(C₀) + L̄_k δ_k + (∂Q_k/∂A) ΔA.
                    for (k, o) in out.iter_mut().enumerate() {
                        let beta = terms.reach_weights[k];
                        if beta == 0.0 {
                            continue;
                        }
                        let change = if terms.anchored[k] {
                            let mut change = DVec3::from_slice(&terms.anchor_start[3 * k..])
                                + terms.anchor_blocks[k] * delta[k];
                            for (a, c) in change.as_mut().iter_mut().enumerate() {
                                let row = terms.anchor_joint_rows.row(3 * k + a);
                                *c += row
                                    .iter()
                                    .zip(joint_change.iter())
                                    .fold(0.0, |acc, (w, d)| acc + w * d);
                            }
                            change
                        } else {
                            DVec3::new(
                                terms.change[3 * k],
                                terms.change[3 * k + 1],
                                terms.change[3 * k + 2],
                            )
                        };
                        *o += beta * change;
                    }
                }
                let largest = out.iter().fold(0.0f64, |m, o| m.max(o.abs().max_element()));
                if largest.is_finite() {
                    largest
                } else {
                    f64::INFINITY
                }
            },
            |delta, out| {
                for ((m, c), d) in moved_for_jacobian.iter_mut().zip(rest_cage).zip(delta) {
                    *m = *c + *d;
                }
                if !target_jacobian_built {
                    fit.jacobian_into(posed_target, target_jacobian);
                    target_jacobian_built = true;
                }
                fit.jacobian_into(moved_for_jacobian, chain_jacobian);
                // J_tᵀ K_A (`3#C × 3#J`), only when the solver refactors.
                transpose_times(
                    target_jacobian,
                    skeleton_rows.as_ref(),
                    projected_skeleton.as_mut(),
                );
                // R̃ J, row block by row block; the system J_tᵀ R̃ J + (J_tᵀ K_A) J_A.
                for col in 0..n {
                    let mut column = chain_jacobian.col_mut(col);
                    for (i, rotation) in row_linear.iter().enumerate() {
                        let v = DVec3::new(column[3 * i], column[3 * i + 1], column[3 * i + 2]);
                        let w = *rotation * v;
                        column[3 * i] = w.x;
                        column[3 * i + 1] = w.y;
                        column[3 * i + 2] = w.z;
                    }
                }
                transpose_times(target_jacobian, chain_jacobian.as_ref(), system.as_mut());
                rows_jacobian_into(
                    joint_vertex_rows,
                    joint_face_rows,
                    normals,
                    moved_for_jacobian,
                    joint_jacobian,
                );
                faer::linalg::matmul::matmul(
                    system.as_mut(),
                    Accum::Add,
                    projected_skeleton.as_ref(),
                    joint_jacobian.as_ref(),
                    1.0,
                    Par::Seq,
                );
                // + W (∂P/∂C + ∂P/∂A J_A).
                if let Some(terms) = prior.borrow_mut().as_mut() {
                    terms.system.copy_from(&terms.cage_rows);
                    faer::linalg::matmul::matmul(
                        terms.system.as_mut(),
                        Accum::Add,
                        terms.joint_rows.as_ref(),
                        joint_jacobian.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                    faer::linalg::matmul::matmul(
                        system.as_mut(),
                        Accum::Add,
                        terms.weight.as_ref(),
                        terms.system.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                    // + B ∂a/∂δ: ∂P_k/∂δ, or L̄_k on the diagonal + (∂Q_k/∂A) J_A.
                    for k in 0..terms.reach_weights.len() {
                        let beta = terms.reach_weights[k];
                        if beta == 0.0 {
                            continue;
                        }
                        for a in 0..3 {
                            let r = 3 * k + a;
                            if terms.anchored[k] {
                                for b in 0..3 {
                                    system[(r, 3 * k + b)] +=
                                        beta * terms.anchor_blocks[k].col(b)[a];
                                }
                                for col in 0..n {
                                    let derivative =
                                        (0..joint_jacobian.nrows()).fold(0.0, |acc, l| {
                                            acc + terms.anchor_joint_rows[(r, l)]
                                                * joint_jacobian[(l, col)]
                                        });
                                    system[(r, col)] += beta * derivative;
                                }
                            } else {
                                for col in 0..n {
                                    system[(r, col)] += beta * terms.system[(r, col)];
                                }
                            }
                        }
                    }
                }
                for c in 0..n {
                    let column = system.col(c);
                    for r in 0..n {
                        out[c * n + r] = column[r];
                    }
                }
            },
        )
    }
}

/// `points` (`n`) as an `n × 3` row-major table.
fn flatten(points: &[DVec3], out: &mut [f64]) {
    for (p, o) in points.iter().zip(out.chunks_exact_mut(3)) {
        o.copy_from_slice(&p.to_array());
    }
}

/// `out = vertex_rows · x + face_rows · g` (`#rows × 3`), sequential.
fn rows_times(
    vertex_rows: &Mat<f64>,
    face_rows: &Mat<f64>,
    x: MatRef<'_, f64>,
    g: MatRef<'_, f64>,
    mut out: MatMut<'_, f64>,
) {
    use faer::linalg::matmul::matmul;
    matmul(out.as_mut(), Accum::Replace, vertex_rows, x, 1.0, Par::Seq);
    matmul(out, Accum::Add, face_rows, g, 1.0, Par::Seq);
}

/// `out = aᵀ · rhs`, sequential: the sizes (at most `3#C × 3#R × 3#C`) are too small for
/// threads to pay.
fn transpose_times(a: &Mat<f64>, rhs: MatRef<'_, f64>, out: MatMut<'_, f64>) {
    faer::linalg::matmul::matmul(out, Accum::Replace, a.transpose(), rhs, 1.0, Par::Seq);
}
