//! CageRev for Green coordinates (C'→C): the rest-cage change δ that makes CageUp return the
//! grabbed current cage C'_t = C'_0 + ∂C' exactly (grabbed vertices on their targets, the others
//! where they were).
//!
//! Green CageUp ([`super::green_cage_fit`]) returns a stationary point of ½‖F_R(C') − M'_R‖²,
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
//! form as F_R. Newton's method ([`super::newton`]) solves G(δ) = 0 with its exact Jacobian
//! `J_tᵀ (R̃ J(C₀ + δ) + K_A J_A(C₀ + δ))` from δ = 0, J_A the Jacobian of A (`3#J × 3#C`); a
//! large grab that stalls is split into pieces. For MVC (ψ = 0, Ψ_ψ = 0, J = Φ̃) this is Eq. 19
//! in its least-squares form.

use faer::{Accum, Mat, MatMut, MatRef, Par};
use glam::{DMat3, DVec3};

use super::green_cage_fit::{GRADIENT_TOLERANCE, GreenCageFit, rows_jacobian_into, rows_of};
use super::newton::{NewtonReport, NewtonSolver, solve_by_continuation};
use crate::error::RigError;

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
    /// J_t (`3#R × 3#C`), R̃ J (`3#R × 3#C`), J_A (`3#J × 3#C`), J_tᵀ K_A (`3#C × 3#J`, at each
    /// factorisation) and J_tᵀ(R̃ J + K_A J_A) (`3#C × 3#C`).
    target_jacobian: Mat<f64>,
    chain_jacobian: Mat<f64>,
    joint_jacobian: Mat<f64>,
    projected_skeleton: Mat<f64>,
    system: Mat<f64>,
    /// A(C₀) and A(C₀ + δ), `#J`.
    start_joints: Vec<DVec3>,
    trial_joints: Vec<DVec3>,
    posed_target: Vec<DVec3>,
    rows_target: Vec<DVec3>,
    rows_trial: Vec<DVec3>,
    /// K_A ΔA per fitting row, `#R`.
    row_skeleton: Vec<DVec3>,
    /// The residual rows r (`3#R`) and J_tᵀ r (`3#C`) as columns for the product.
    flat_rows: faer::Col<f64>,
    flat_gradient: faer::Col<f64>,
    g: Vec<DVec3>,
    moved: Vec<DVec3>,
    moved_for_jacobian: Vec<DVec3>,
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
            chain_jacobian: Mat::zeros(3 * num_rows, 3 * num_cage),
            joint_jacobian: Mat::zeros(3 * num_joints, 3 * num_cage),
            projected_skeleton: Mat::zeros(3 * num_cage, 3 * num_joints),
            system: Mat::zeros(3 * num_cage, 3 * num_cage),
            start_joints: vec![DVec3::ZERO; num_joints],
            trial_joints: vec![DVec3::ZERO; num_joints],
            posed_target: vec![DVec3::ZERO; num_cage],
            rows_target: vec![DVec3::ZERO; num_rows],
            rows_trial: vec![DVec3::ZERO; num_rows],
            row_skeleton: vec![DVec3::ZERO; num_rows],
            flat_rows: faer::Col::zeros(3 * num_rows),
            flat_gradient: faer::Col::zeros(3 * num_cage),
            g: vec![DVec3::ZERO; num_faces],
            moved: vec![DVec3::ZERO; num_cage],
            moved_for_jacobian: vec![DVec3::ZERO; num_cage],
        }
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
        fit.jacobian_into(&self.posed_target, &mut self.target_jacobian);
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
        let (flat_rows, flat_gradient) = (&mut self.flat_rows, &mut self.flat_gradient);
        let (joint_vertex_rows, joint_face_rows) = (&self.joint_vertex_rows, &self.joint_face_rows);
        let (start_joints, trial_joints) = (&self.start_joints, &mut self.trial_joints);
        let joint_jacobian = &mut self.joint_jacobian;
        let projected_skeleton = &mut self.projected_skeleton;
        let target_jacobian = &self.target_jacobian;
        let chain_jacobian = &mut self.chain_jacobian;
        let system = &mut self.system;
        let rows_target = &self.rows_target;
        let rows_trial = &mut self.rows_trial;
        let g = &mut self.g;
        let moved = &mut self.moved;
        let moved_for_jacobian = &mut self.moved_for_jacobian;
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
                rows_of(vertex_rows, face_rows, moved, g, rows_trial);
                rows_of(joint_vertex_rows, joint_face_rows, moved, g, trial_joints);
                for (t, s) in trial_joints.iter_mut().zip(start_joints) {
                    *t -= *s;
                }
                // K_A ΔA, column by column (the columns are contiguous; each row sums the
                // joints in the same order as row by row would).
                row_skeleton.iter_mut().for_each(|s| *s = DVec3::ZERO);
                for (j, d) in trial_joints.iter().enumerate() {
                    for (c, value) in d.to_array().into_iter().enumerate() {
                        if value != 0.0 {
                            let column = skeleton_rows.col(3 * j + c);
                            for (i, s) in row_skeleton.iter_mut().enumerate() {
                                *s += value
                                    * DVec3::new(
                                        column[3 * i],
                                        column[3 * i + 1],
                                        column[3 * i + 2],
                                    );
                            }
                        }
                    }
                }
                for (i, skeleton) in row_skeleton.iter().enumerate() {
                    let change = at.posed_rows[i]
                        + row_linear[i] * (rows_trial[i] - at.rest_rows[i])
                        + *skeleton
                        - rows_target[i];
                    flat_rows[3 * i] = change.x;
                    flat_rows[3 * i + 1] = change.y;
                    flat_rows[3 * i + 2] = change.z;
                }
                // J_tᵀ r as one product (a row-by-row dot product is one long dependency
                // chain per entry).
                target_transpose_times(
                    target_jacobian,
                    flat_rows.as_mat(),
                    flat_gradient.as_mat_mut(),
                );
                let mut largest: f64 = 0.0;
                for (k, o) in out.iter_mut().enumerate() {
                    *o = DVec3::new(
                        flat_gradient[3 * k],
                        flat_gradient[3 * k + 1],
                        flat_gradient[3 * k + 2],
                    );
                    largest = largest.max(o.abs().max_element());
                }
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
                fit.jacobian_into(moved_for_jacobian, chain_jacobian);
                // J_tᵀ K_A (`3#C × 3#J`), only when the solver refactors.
                target_transpose_times(
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
                target_transpose_times(target_jacobian, chain_jacobian.as_ref(), system.as_mut());
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

/// `out = J_tᵀ · rhs`: J_t is `target_jacobian` (`3#R × 3#C`),
/// `rhs` has `3#R` rows. Sequential: the sizes (at most `3#C × 3#R × 3#C`) are too small for
/// threads to pay.
fn target_transpose_times(target_jacobian: &Mat<f64>, rhs: MatRef<'_, f64>, out: MatMut<'_, f64>) {
    faer::linalg::matmul::matmul(
        out,
        Accum::Replace,
        target_jacobian.transpose(),
        rhs,
        1.0,
        Par::Seq,
    );
}
