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
//!   it. With N_k the [`PRIOR_NEIGHBOURS`] rest-skin vertices nearest to C_k, x̄_k their rest
//!   centroid, ȳ_k the centroid of their LBS-posed positions and A_k the rotation of their mean
//!   skinning transform (the polar factor of Σ_j a_kj L_j, a_kj the mean weight of joint j on
//!   N_k and L_j its linear part, times its mean scale),
//!   `P_k = ȳ_k + A_k (C_k − x̄_k)`. The centroid follows the body exactly; only the offset of
//!   the cage from it turns, so a cage vertex between two limbs stays between them;
//! - L the cage's uniform graph Laplacian (`#C × #C`, row k: c_k − mean of its neighbours), so
//!   the prior fixes the cage's local shape and the rows its placement; ε ([`PRIOR_EPSILON`])
//!   keeps the system definite on parts the rows do not see;
//! - λ = [`PRIOR_STRENGTH`] · tr(Φ̃ᵀΦ̃) / tr(LᵀL + εI), chosen once per binding from the rig.
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
use crate::skin_weights::SkinWeights;

/// λ₀ in λ = λ₀ · tr(Φ̃ᵀΦ̃) / tr(R): the prior weighs three times as much as the rows in
/// total (1 leaves the Fox's Run at spread 1.54, 3 at 1.47; `docs/method.md`).
pub const PRIOR_STRENGTH: f64 = 3.0;
/// ε in R = LᵀL + εI, relative to the Laplacian's scale (tr(LᵀL) / #C).
pub const PRIOR_EPSILON: f64 = 0.05;
/// Rest-skin vertices around a cage vertex whose mean motion carries it ([`neighbourhoods`]).
pub const PRIOR_NEIGHBOURS: usize = 32;
/// Skin vertices searched for neighbours at most (a regular subsample of larger skins).
const PRIOR_SEARCH_VERTICES: usize = 16_384;

/// One joint of a cage vertex's neighbourhood: a_kj and β_kj (see the module docs).
#[derive(Debug, Clone)]
struct NeighbourhoodJoint {
    cage_vertex: usize,
    joint: usize,
    /// a_kj = mean_i ω_ij over N_k.
    share: f64,
    /// β_kj = mean_i ω_ij Φ_i, `#C`.
    coords: Vec<f64>,
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
        let nc = rest_cage.len();
        let dot = |row: &[f64]| {
            row.iter()
                .zip(rest_cage)
                .fold(DVec3::ZERO, |acc, (&w, c)| acc + w * *c)
        };
        for (k, x) in self.rest_centroids.iter_mut().enumerate() {
            *x = dot(&self.centroid_coords[k * nc..(k + 1) * nc]);
        }
        for (m, entry) in self.joint_moments.iter_mut().zip(&self.joints) {
            *m = dot(&entry.coords);
        }
        self.moments_cage.copy_from_slice(rest_cage);
    }

    /// A_k into `blended` (`#C`) from Σ_j a_kj L_j of `joint_linear` (`#J`): the polar
    /// factor times the mean scale Σ_j a_kj |det L_j|^⅓. No allocation.
    fn blend_rotations(&self, joint_linear: impl Fn(usize) -> DMat3, blended: &mut [DMat3]) {
        blended.iter_mut().for_each(|b| *b = DMat3::ZERO);
        let mut entries = self.joints.iter().peekable();
        for (k, b) in blended.iter_mut().enumerate() {
            let mut scale = 0.0;
            while let Some(entry) = entries.next_if(|e| e.cage_vertex == k) {
                let linear = joint_linear(entry.joint);
                *b += linear * entry.share;
                scale += entry.share * linear.determinant().abs().cbrt();
            }
            *b = rotation_of(*b) * scale;
        }
    }

    /// P (`#C`, then read with [`Self::carried_cage`]): the rest cage `rest_cage` (`#C`)
    /// carried by the skin around it under the skinning transforms `posed_from_rest` (`#J`).
    /// CageUp adds Q·P to its fit. No allocation once the moments are computed for `rest_cage`.
    pub fn carry(&mut self, posed_from_rest: &[DAffine3], rest_cage: &[DVec3]) {
        self.update_moments(rest_cage);
        let mut rotations = std::mem::take(&mut self.rotations);
        self.blend_rotations(|j| posed_from_rest[j].matrix3, &mut rotations);
        self.rotations = rotations;
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

    /// ∂P/∂C for the pose with joint linear parts `joint_linear` (`#J`) and the translation
    /// derivatives `translation_jacobian` (`∂t_j/∂c_m`, `#J × #C` blocks, row-major by joint;
    /// zero when the joints do not follow the cage), into `jacobian` (`#C × 9#C`, column-major
    /// columns): entry (k, 9m + 3a + b) is entry (a, b) of block (k, m). CageRev multiplies it by
    /// Q ([`Self::cage_from_prior`]).
    pub fn jacobian(
        &self,
        joint_linear: &[DMat3],
        translation_jacobian: &[DMat3],
        mut jacobian: faer::MatMut<'_, f64>,
    ) {
        let nc = self.rest_centroids.len();
        let mut blended = vec![DMat3::ZERO; nc];
        self.blend_rotations(|j| joint_linear[j], &mut blended);
        // ∂P_k/∂c_m = A_k (δ_km − ξ_km) + Σ_j (β_kj[m] L_j + a_kj ∂t_j/∂c_m), as 3×3 blocks
        // (k, m) in row-major order.
        let mut blocks = vec![DMat3::ZERO; nc * nc];
        for (k, a) in blended.iter().enumerate() {
            let row = &mut blocks[k * nc..(k + 1) * nc];
            for (m, block) in row.iter_mut().enumerate() {
                let delta = if k == m { 1.0 } else { 0.0 };
                *block = *a * (delta - self.centroid_coords[k * nc + m]);
            }
        }
        for entry in &self.joints {
            let linear = joint_linear[entry.joint];
            let row = &mut blocks[entry.cage_vertex * nc..(entry.cage_vertex + 1) * nc];
            let translations = &translation_jacobian[entry.joint * nc..(entry.joint + 1) * nc];
            for ((block, &beta), dt) in row.iter_mut().zip(&entry.coords).zip(translations) {
                *block += linear * beta + *dt * entry.share;
            }
        }
        // Column 9m + 3a + b holds entry (a, b) of the blocks (·, m): written column by column.
        for m in 0..nc {
            for a in 0..3 {
                for b in 0..3 {
                    let mut column = jacobian.as_mut().col_mut(9 * m + 3 * a + b);
                    for k in 0..nc {
                        column[k] = blocks[k * nc + m].col(b)[a];
                    }
                }
            }
        }
    }
}

/// The rotation of `m` (its polar factor, by Newton's iteration X ← (X + X⁻ᵀ)/2), or the
/// identity when `m` is singular.
fn rotation_of(m: DMat3) -> DMat3 {
    let mut x = m;
    for _ in 0..32 {
        let det = x.determinant();
        if !(det.is_finite() && det.abs() > 1e-12) {
            return DMat3::IDENTITY;
        }
        let next = (x + x.inverse().transpose()) * 0.5;
        let change = (next - x)
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

/// Builds K and the prior for the fitting rows `rows` (their Φ̃, `#R × #C`, is read from
/// `cage_coords`), the rest cage `rest_cage` (`#C`) and its `cage_triangles`, the rest skin
/// `rest_mesh` (`#V`) and Ω `skin_weights` (`#V × #J`).
pub(crate) fn regularised_maps(
    cage_coords: &CageCoords,
    rows: &[usize],
    rest_cage: &[DVec3],
    cage_triangles: &[[u32; 3]],
    rest_mesh: &[DVec3],
    skin_weights: &SkinWeights,
) -> Result<RegularisedMaps, RigError> {
    let nc = cage_coords.num_cage_vertices();
    if rest_cage.len() != nc || rest_mesh.len() != cage_coords.num_vertices() {
        return Err(RigError::SizeMismatch {
            what: "rest cage vertices for the regularised cage fit",
            expected: nc,
            actual: rest_cage.len(),
        });
    }
    let row_coords = cage_coords.select_rows(rows);
    let (joints, centroid_coords) =
        neighbourhoods(cage_coords, rest_cage, rest_mesh, skin_weights)?;
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
    let mut prior = CagePrior {
        joints,
        centroid_coords,
        cage_from_prior,
        strength,
        moments_cage: vec![DVec3::NAN; nc],
        rest_centroids: vec![DVec3::ZERO; nc],
        joint_moments: vec![DVec3::ZERO; num_entries],
        carried: vec![DVec3::ZERO; nc],
        rotations: vec![DMat3::IDENTITY; nc],
    };
    prior.update_moments(rest_cage);
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

/// The neighbourhood N_k of every rest cage vertex (its [`PRIOR_NEIGHBOURS`] nearest rest-skin
/// vertices, among a regular subsample of at most 16,384 for larger skins) as its joints' a_kj
/// and β_kj, and ξ (`#C × #C` row-major, row k the mean of Φ over N_k).
fn neighbourhoods(
    cage_coords: &CageCoords,
    rest_cage: &[DVec3],
    rest_mesh: &[DVec3],
    skin_weights: &SkinWeights,
) -> Result<(Vec<NeighbourhoodJoint>, Vec<f64>), RigError> {
    let nv = rest_mesh.len();
    let nc = rest_cage.len();
    if skin_weights.num_vertices() != nv || nv == 0 {
        return Err(RigError::SizeMismatch {
            what: "skinning weight rows (rest skin vertices) for the cage prior",
            expected: nv,
            actual: skin_weights.num_vertices(),
        });
    }
    let stride = nv.div_ceil(PRIOR_SEARCH_VERTICES).max(1);
    let candidates: Vec<usize> = (0..nv).step_by(stride).collect();
    let take = PRIOR_NEIGHBOURS.min(candidates.len());
    let share = 1.0 / take as f64;
    let nj = skin_weights.num_joints();
    let mut distances: Vec<(f64, usize)> = Vec::with_capacity(candidates.len());
    let mut slot = vec![usize::MAX; nj];
    let mut joints: Vec<NeighbourhoodJoint> = Vec::new();
    let mut centroid_coords = vec![0.0f64; nc * nc];
    for (k, c) in rest_cage.iter().enumerate() {
        distances.clear();
        distances.extend(
            candidates
                .iter()
                .map(|&v| (rest_mesh[v].distance_squared(*c), v)),
        );
        if take < distances.len() {
            distances
                .select_nth_unstable_by(take - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
        let first = joints.len();
        let mut near: Vec<usize> = distances[..take].iter().map(|d| d.1).collect();
        near.sort_unstable();
        for &v in &near {
            let centroid = &mut centroid_coords[k * nc..(k + 1) * nc];
            for (m, x) in centroid.iter_mut().enumerate() {
                *x += share * cage_coords.get(v, m);
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
                    });
                }
                let entry = &mut joints[slot[j]];
                entry.share += share * w;
                for (m, x) in entry.coords.iter_mut().enumerate() {
                    *x += share * w * cage_coords.get(v, m);
                }
            }
        }
        for entry in &joints[first..] {
            slot[entry.joint] = usize::MAX;
        }
    }
    Ok((joints, centroid_coords))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;

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
