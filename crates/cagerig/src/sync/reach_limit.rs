//! The reach limit of the regularised CageUp: each current-cage vertex stays as near its patch
//! of skin as the rest cage is to the body.
//!
//! The regularised fit `C'_fit = K M̃' + Q P` ([`super::cage_prior`]) still follows rows that no
//! cage of the rig can reproduce. A finger turned 90° out of a palm that a coarse cage wraps in
//! one part with its neighbours is the typical case: its rows reach the cage vertex through
//! small coordinates, and matching them pulls that vertex far off the body (2.7× the rest
//! cage's distance on the Arm's generated 58-vertex cage). Every cage vertex k therefore blends
//! the fit back toward the prior by a factor s_k ∈ [0, 1]:
//!
//! ```text
//! C'_k = s_k C'_fit,k + (1 − s_k) P_k.
//! ```
//!
//! s_k is the largest s ∈ [0, 1] with `dist(P̂_k + s (Ĉ'_k − P̂_k), N̂'_k) ≤ ρ`, or, when no s
//! qualifies, the s nearest N̂'_k. Hats are the binding rig posed by the current joints' linear
//! parts L_j: the binding cage C₀ and skin M₀, and the binding skeleton posed as the prior's
//! rotation sees it (T̂_j, [`super::cage_prior`]). N̂'_k is the posed neighbourhood of the
//! prior (its [`crate::nearest_vertices::SKIN_NEIGHBOURS`] rest-skin vertices) and ρ the rest reach
//! max_k dist(C₀_k, N_k): the farthest any rest cage vertex is from its neighbourhood. Distances
//! are compared with ρ to [`crate::nearest_vertices::TIE_TOLERANCE`]: a vertex at exactly the rest
//! reach in a part that moved rigidly (on a symmetric cage, every vertex of the ring that
//! attains ρ) stays whole whatever the round-off of its pose.
//!
//! **The fold guard** (mean value rigs, [`HatFit::Exact`]). The fit can turn a thin cage
//! triangle over while its corners stay within reach. Their hat is the fit itself, so every
//! triangle that the blend turns against P̂ gets its corners' factors lowered, each no further
//! than its blend stays within reach, until its normal faces P̂'s again
//! ([`ReachLimit::unfold`]).
//!
//! **Skinned anchors** (Green rigs, [`crate::sync::green_cage_fit::prior`]). A neighbourhood
//! that spans two parts moving apart (the legs in a walk) carries its cage vertex between them:
//! P̂_k itself is then out of reach, and no blend toward it brings the vertex back. With
//! skinned anchors such a vertex is measured, and pulled, toward
//! Q̂_k = Σ_j ω_kj (L_j C₀_k + t̂_j) instead, the cage vertex skinned with the weights ω_k of its
//! nearest binding-skin vertex, which stays about as near that vertex as at rest. Mean value
//! rigs keep P̂_k (their CageRev rows are those of the blend toward P).
//!
//! **Turned triangles** (Green rigs). The Green fit is not a blend, so the hat's triangles are
//! not measured for a guard here: the limit reports how far the hat turns each triangle against
//! P̂ ([`ReachScratch::turns`], 0 while it faces P̂'s by at least [`UNFOLD_MARGIN`], 1 once
//! turned over), and the Green prior stiffens those triangles' edges
//! ([`crate::sync::green_cage_fit::prior`]).
//!
//! **Guarantees kept.** s depends on the linear parts only, never on C, so for a fixed pose C'
//! stays linear in C and CageRev stays exact: row k of Eq. 19 becomes
//! `s_k (K G_rows + Q G_prior)_k + (1 − s_k) (G_prior)_k`
//! ([`super::cage_reverser::CageReverser`]). At rest and under one rigid motion of every joint
//! Ĉ' = P̂, every s_k is 1 and C' is the fit (C at rest, the moved cage under the motion). Where
//! the fit stays within reach, s_k = 1 and C' is the fit bit for bit.

use faer::Mat;
use glam::{DMat3, DVec3};

use crate::cage_gen::geometry::area_normal;
use crate::nearest_vertices::TIE_TOLERANCE;
use crate::skin_weights::SkinWeights;
use crate::sync::small_products::accumulate_product;

/// What the reach limit keeps of the binding (see the module docs), and its scratch.
#[derive(Debug, Clone)]
pub struct ReachLimit {
    /// C₀, `#C`.
    binding_cage: Vec<DVec3>,
    /// ξ_k C₀ (the neighbourhoods' centroids on the binding cage), `#C`.
    binding_centroids: Vec<DVec3>,
    /// β_kj C₀, one per (k, j) entry of the prior.
    binding_joint_moments: Vec<DVec3>,
    /// The fitting rows on the binding skin M₀ (`#R`) and their weights (`#R × #J`).
    row_points: Vec<DVec3>,
    row_weights: SkinWeights,
    /// The neighbourhoods' vertices on M₀, concatenated, with their weights; cage vertex k's are
    /// `neighbour_start[k]..neighbour_start[k + 1]`.
    neighbour_points: Vec<DVec3>,
    neighbour_weights: SkinWeights,
    neighbour_start: Vec<usize>,
    /// ρ.
    reach: f64,
    /// The weights of each cage vertex's nearest binding-skin vertex (`#C × #J`): the skinned
    /// anchor Q_k = Σ_j ω_kj T_j C_k ([`HatFit::VertexPart`]).
    anchor_weights: SkinWeights,
    /// What the hat fit is to the rig's own fit: it decides the fold guard and the anchors.
    hat: HatFit,
    /// The cage's triangles, for the fold guard.
    triangles: Vec<[u32; 3]>,
}

/// What the reach limit's hat fit Ĉ' is to the rig's own CageUp, and so what the limit may
/// conclude from it (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HatFit {
    /// The fit itself on the binding rig (mean value rigs: C'_fit = K M̃' + Q P is linear, so
    /// the hat is the fit up to the translations). A triangle the hat turns against P̂ is one the
    /// fit turns, and the fold guard lowers its factors; vertices blend toward P̂.
    Exact,
    /// The fit of the vertex part φ_R C₀ only (Green rigs, whose fit also follows the
    /// normals' part): a proxy that says where the fit leaves the body and which triangles it
    /// tends to turn, not the fit's own triangles. No fold guard: the hat's turns are reported
    /// for the Green prior's edge terms instead; vertices whose P̂_k is itself out of reach are
    /// anchored on their skinned Q̂_k.
    VertexPart,
}

/// Scratch of [`ReachLimit::factors`]: P̂ and Ĉ' (`#C`), ŷ of the rows (`#R`), the fold
/// guard's floors (`#C`) and the hat's turns (`#F`).
#[derive(Debug, Clone, Default)]
pub struct ReachScratch {
    carried: Vec<DVec3>,
    posed_rows: Vec<DVec3>,
    fitted: Vec<DVec3>,
    floors: Vec<f64>,
    /// How far the hat fit turns each cage triangle against P̂ (`#F`, [`hat_turn`]; computed
    /// for [`HatFit::VertexPart`] only, 0 otherwise).
    turns: Vec<f64>,
}

impl ReachScratch {
    /// How far the last hat fit turned each cage triangle against P̂, in [0, 1] (`#F`,
    /// [`hat_turn`]; 0 unless the hat is [`HatFit::VertexPart`]).
    pub(crate) fn turns(&self) -> &[f64] {
        &self.turns
    }
}

/// The (k, j) entries of the prior that carry P̂ (the joints' shares of each cage vertex's
/// translation), in the prior's order.
pub(crate) struct PriorEntry {
    pub(crate) cage_vertex: usize,
    pub(crate) joint: usize,
    /// a_kj.
    pub(crate) share: f64,
}

impl ReachLimit {
    /// The limit for the binding cage `binding_cage` (C₀, `#C`) and skin `binding_mesh` (M₀,
    /// `#V`) with weights `skin_weights` (`#V × #J`); `rows` are the fitting rows; `neighbours`
    /// the prior's neighbourhood of each cage vertex;
    /// `binding_centroids` and `binding_joint_moments` the prior's ξC₀ and β_kj C₀;
    /// `triangles` the cage's faces.
    #[expect(
        clippy::too_many_arguments,
        reason = "the binding's parts, each named in the docs"
    )]
    pub(crate) fn new(
        binding_cage: &[DVec3],
        triangles: &[[u32; 3]],
        binding_mesh: &[DVec3],
        skin_weights: &SkinWeights,
        rows: &[usize],
        neighbours: &[Vec<usize>],
        binding_centroids: Vec<DVec3>,
        binding_joint_moments: Vec<DVec3>,
    ) -> Self {
        let nc = binding_cage.len();
        let mut neighbour_start = Vec::with_capacity(nc + 1);
        neighbour_start.push(0);
        let mut all: Vec<usize> = Vec::new();
        let mut reach = 0.0f64;
        let mut nearest_vertices = Vec::with_capacity(nc);
        for (k, near) in neighbours.iter().enumerate() {
            all.extend_from_slice(near);
            neighbour_start.push(all.len());
            let (nearest, vertex) = near
                .iter()
                .map(|&v| (binding_mesh[v].distance(binding_cage[k]), v))
                .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a });
            nearest_vertices.push(vertex);
            if nearest.is_finite() {
                reach = reach.max(nearest);
            }
        }
        Self {
            binding_cage: binding_cage.to_vec(),
            binding_centroids,
            binding_joint_moments,
            row_points: rows.iter().map(|&r| binding_mesh[r]).collect(),
            row_weights: skin_weights.select_rows(rows),
            neighbour_points: all.iter().map(|&v| binding_mesh[v]).collect(),
            neighbour_weights: skin_weights.select_rows(&all),
            neighbour_start,
            reach,
            anchor_weights: skin_weights.select_rows(&nearest_vertices),
            hat: HatFit::Exact,
            triangles: triangles.to_vec(),
        }
    }

    /// The weights of each cage vertex's nearest binding-skin vertex, `#C × #J`: Q_k =
    /// Σ_j ω_kj T_j C_k.
    pub(crate) fn anchor_weights(&self) -> &SkinWeights {
        &self.anchor_weights
    }

    /// The hat fit reads the rows as `vertex_part` (`#R`, φ_R C₀ in the rows' order): a Green
    /// rig's [`HatFit::VertexPart`].
    pub(crate) fn use_vertex_part_hat(&mut self, vertex_part: Vec<DVec3>) {
        debug_assert_eq!(vertex_part.len(), self.row_points.len());
        self.row_points = vertex_part;
        self.hat = HatFit::VertexPart;
    }

    /// Scratch sized for this limit.
    pub fn scratch(&self) -> ReachScratch {
        let nc = self.binding_cage.len();
        ReachScratch {
            carried: vec![DVec3::ZERO; nc],
            posed_rows: vec![DVec3::ZERO; self.row_points.len()],
            fitted: vec![DVec3::ZERO; nc],
            floors: vec![0.0; nc],
            turns: vec![0.0; self.triangles.len()],
        }
    }

    /// ρ: the rest reach.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// s (`factors`, `#C`) for the joints' linear parts `joint_linear` (`#J`), with the
    /// prior's carried rotations A_k (`rotations`, `#C`) and the binding skeleton's posed
    /// translations t̂_j (`translations`, `#J`) for those linear parts, its (k, j) `entries`,
    /// and the fit's K `cage_from_rows` (`#C × #R`) and Q `cage_from_prior` (`#C × #C`). No
    /// allocation with a [`Self::scratch`].
    #[expect(
        clippy::too_many_arguments,
        reason = "the prior's parts of the pose, each named"
    )]
    pub(crate) fn factors(
        &self,
        joint_linear: impl Fn(usize) -> DMat3,
        rotations: &[DMat3],
        translations: &[DVec3],
        entries: impl Iterator<Item = PriorEntry>,
        cage_from_rows: &Mat<f64>,
        cage_from_prior: &Mat<f64>,
        scratch: &mut ReachScratch,
        factors: &mut [f64],
        anchored: &mut [bool],
    ) {
        let ReachScratch {
            carried,
            posed_rows,
            fitted,
            floors,
            turns,
        } = scratch;
        let posed = |weights: &SkinWeights, i: usize, x: DVec3| {
            skinned_by_linear_parts(weights, i, x, &joint_linear, translations)
        };
        // P̂ = Σ_j (L_j β_kj C₀ + a_kj t̂_j) + A_k (C₀_k − ξ_k C₀).
        carried.iter_mut().for_each(|p| *p = DVec3::ZERO);
        for (entry, moment) in entries.zip(&self.binding_joint_moments) {
            carried[entry.cage_vertex] +=
                joint_linear(entry.joint) * *moment + entry.share * translations[entry.joint];
        }
        for (k, p) in carried.iter_mut().enumerate() {
            *p += rotations[k] * (self.binding_cage[k] - self.binding_centroids[k]);
        }
        // Ĉ' = K ŷ + Q P̂.
        for (i, y) in posed_rows.iter_mut().enumerate() {
            *y = posed(&self.row_weights, i, self.row_points[i]);
        }
        fitted.iter_mut().for_each(|c| *c = DVec3::ZERO);
        accumulate_product(cage_from_rows, posed_rows, fitted);
        accumulate_product(cage_from_prior, carried, fitted);
        match self.hat {
            HatFit::Exact => {
                anchored.iter_mut().for_each(|a| *a = false);
                self.factors_of(&joint_linear, translations, carried, fitted, factors);
                for (k, floor) in floors.iter_mut().enumerate() {
                    *floor = reach_floor(
                        carried[k],
                        fitted[k] - carried[k],
                        self.posed_neighbours(k, &posed),
                        self.reach,
                        factors[k],
                    );
                }
                self.unfold(carried, fitted, floors, factors);
            }
            HatFit::VertexPart => {
                for (turn, tri) in turns.iter_mut().zip(&self.triangles) {
                    let [a, b, c] = tri.map(|v| v as usize);
                    *turn = hat_turn(
                        [carried[a], carried[b], carried[c]],
                        [fitted[a], fitted[b], fitted[c]],
                    );
                }
                for (k, is_anchored) in anchored.iter_mut().enumerate() {
                    *is_anchored =
                        !within_reach(carried[k], self.posed_neighbours(k, &posed), self.reach);
                    if *is_anchored {
                        carried[k] = posed(&self.anchor_weights, k, self.binding_cage[k]);
                    }
                }
                self.factors_of(&joint_linear, translations, carried, fitted, factors);
            }
        }
    }

    /// Lowers the factors (`#C`) of the corners of every cage triangle that the blend
    /// P̂_k + s_k (Ĉ'_k − P̂_k) of `carried` and `fitted` (`#C`) turns against P̂ (module docs).
    /// Each corner is lowered at most to its floor (`floors`, `#C`): the lowest factor down to
    /// which its blend stays within reach, so that the guard never trades a fold for a handle
    /// off the body. The corners' factors move toward their floors by the same share 1 − t, t the
    /// largest in [0, 1] that keeps the triangle's normal facing P̂'s by at least
    /// [`UNFOLD_MARGIN`] of P̂'s squared area; a triangle still turned with every corner at its
    /// floor is left alone. A pass over the triangles repeats while one changed, at most
    /// [`UNFOLD_PASSES`] times; the corners of triangles still turned after that go to their
    /// floors.
    fn unfold(&self, carried: &[DVec3], fitted: &[DVec3], floors: &[f64], factors: &mut [f64]) {
        let corner = |k: usize, s: f64| carried[k] + s * (fitted[k] - carried[k]);
        // The triangle's facing less its bound, with its corners' factors at a share t of the
        // way from their floors.
        let facing = |tri: &[u32; 3], factors: &[f64], t: f64| {
            let [a, b, c] = tri.map(|v| v as usize);
            let reference = area_normal([carried[a], carried[b], carried[c]]);
            let scaled = |k: usize| floors[k] + t * (factors[k] - floors[k]);
            let blended = area_normal([
                corner(a, scaled(a)),
                corner(b, scaled(b)),
                corner(c, scaled(c)),
            ]);
            blended.dot(reference) - UNFOLD_MARGIN * reference.length_squared()
        };
        // Whether the guard lowers `tri`: turned now, and not at its corners' floors.
        let turned = |tri: &[u32; 3], factors: &[f64]| {
            facing(tri, factors, 1.0) < 0.0 && facing(tri, factors, 0.0) >= 0.0
        };
        for _ in 0..UNFOLD_PASSES {
            let mut changed = false;
            for tri in &self.triangles {
                if !turned(tri, factors) {
                    continue;
                }
                let t = first_crossing(|t| facing(tri, factors, t));
                for &v in tri {
                    let v = v as usize;
                    factors[v] = floors[v] + t * (factors[v] - floors[v]);
                }
                changed = true;
            }
            if !changed {
                return;
            }
        }
        loop {
            let mut changed = false;
            for tri in &self.triangles {
                if turned(tri, factors) {
                    for &v in tri {
                        let v = v as usize;
                        changed |= factors[v] != floors[v];
                        factors[v] = floors[v];
                    }
                }
            }
            if !changed {
                return;
            }
        }
    }

    /// Cage vertex k's neighbourhood, posed by `posed` (weights, vertex, point).
    fn posed_neighbours<'a>(
        &'a self,
        k: usize,
        posed: &'a impl Fn(&SkinWeights, usize, DVec3) -> DVec3,
    ) -> impl Iterator<Item = DVec3> + Clone + 'a {
        (self.neighbour_start[k]..self.neighbour_start[k + 1])
            .map(move |v| posed(&self.neighbour_weights, v, self.neighbour_points[v]))
    }

    /// s (`factors`, `#C`) of the fitted cage `fitted` (`#C`) against the carried cage
    /// `carried` (`#C`), with the neighbourhoods posed by the linear parts `joint_linear` and
    /// the translations `translations` (`#J`).
    pub(crate) fn factors_of(
        &self,
        joint_linear: &impl Fn(usize) -> DMat3,
        translations: &[DVec3],
        carried: &[DVec3],
        fitted: &[DVec3],
        factors: &mut [f64],
    ) {
        let posed = |weights: &SkinWeights, i: usize, x: DVec3| {
            skinned_by_linear_parts(weights, i, x, &joint_linear, translations)
        };
        for (k, s) in factors.iter_mut().enumerate() {
            let neighbours = self.posed_neighbours(k, &posed);
            *s = largest_factor_within(carried[k], fitted[k] - carried[k], neighbours, self.reach);
        }
    }
}

/// How far the hat fit turns a cage triangle against the carried one, in [0, 1]: with
/// f = n(Ĉ'_t)·n(P̂_t) / |n(P̂_t)|² (`hat` against `carried`, n the area normal), 0 while
/// f ≥ [`UNFOLD_MARGIN`], rising linearly to 1 at f = 0 and staying 1 beyond (turned over).
/// Continuous in the pose; 0 for a degenerate carried triangle.
fn hat_turn(carried: [DVec3; 3], hat: [DVec3; 3]) -> f64 {
    let reference = area_normal(carried);
    let scale = reference.length_squared();
    if scale == 0.0 {
        return 0.0;
    }
    let facing = area_normal(hat).dot(reference) / scale;
    ((UNFOLD_MARGIN - facing) / UNFOLD_MARGIN).clamp(0.0, 1.0)
}

/// The share of P̂'s squared area (times four) by which a blended cage triangle's normal must
/// face P̂'s: below it the fold guard lowers the triangle's factors ([`ReachLimit::unfold`]).
const UNFOLD_MARGIN: f64 = 0.25;
/// Passes of the fold guard before the corners of triangles still turned go to their floors.
const UNFOLD_PASSES: usize = 8;

/// The first t ∈ (0, 1] where `f` (positive at 0, negative at 1) turns negative: the first sign
/// change of 16 even samples, then bisected to round-off; a t where `f` ≥ 0.
fn first_crossing(f: impl Fn(f64) -> f64) -> f64 {
    const SAMPLES: usize = 16;
    let mut low = 0.0;
    let mut high = 1.0;
    for i in 1..=SAMPLES {
        let t = i as f64 / SAMPLES as f64;
        if f(t) < 0.0 {
            high = t;
            break;
        }
        low = t;
    }
    for _ in 0..60 {
        let mid = 0.5 * (low + high);
        if mid <= low || mid >= high {
            break;
        }
        if f(mid) < 0.0 {
            high = mid;
        } else {
            low = mid;
        }
    }
    low
}

/// `x` skinned with row `i` of `weights` by the joints' linear parts `joint_linear` and the
/// translations `translations` (`#J`): Σ_j ω_ij (L_j x + t_j).
fn skinned_by_linear_parts(
    weights: &SkinWeights,
    i: usize,
    x: DVec3,
    joint_linear: &impl Fn(usize) -> DMat3,
    translations: &[DVec3],
) -> DVec3 {
    let (joints, w) = weights.row(i);
    joints.iter().zip(w).fold(DVec3::ZERO, |acc, (&j, &w)| {
        let j = j as usize;
        acc + w * (joint_linear(j) * x + translations[j])
    })
}

/// Whether `p` is within `reach` of one of `points` (to [`TIE_TOLERANCE`] of ρ²).
fn within_reach(p: DVec3, mut points: impl Iterator<Item = DVec3>, reach: f64) -> bool {
    let reach_squared = reach * reach * (1.0 + TIE_TOLERANCE);
    points.any(|y| (p - y).length_squared() <= reach_squared)
}

/// The largest s ∈ [0, 1] with min_y |p + s d − y| ≤ `reach` over `points` (to
/// [`TIE_TOLERANCE`] of ρ²), or the s ∈ [0, 1] nearest them when none qualifies (1 when there
/// are no points).
fn largest_factor_within(
    p: DVec3,
    d: DVec3,
    points: impl Iterator<Item = DVec3> + Clone,
    reach: f64,
) -> f64 {
    if within_reach(p + d, points.clone(), reach) {
        return 1.0;
    }
    let reach_squared = reach * reach * (1.0 + TIE_TOLERANCE);
    let a = d.length_squared();
    if a == 0.0 {
        return 1.0;
    }
    let mut largest: Option<f64> = None;
    let (mut nearest, mut nearest_at) = (f64::INFINITY, 1.0);
    for y in points {
        let e = p - y;
        if let Some((low, high)) = reach_interval(e, d, a, reach_squared)
            && high >= 0.0
            && low <= 1.0
        {
            let s = high.min(1.0);
            largest = Some(largest.map_or(s, |l: f64| l.max(s)));
        }
        // The point of the path nearest y.
        let b = 2.0 * d.dot(e);
        let s = (-b / (2.0 * a)).clamp(0.0, 1.0);
        let distance = (e + s * d).length_squared();
        if distance < nearest || (distance == nearest && s > nearest_at) {
            (nearest, nearest_at) = (distance, s);
        }
    }
    largest.unwrap_or(nearest_at)
}

/// The interval [low, high] of σ where |e + σ d|² ≤ `reach_squared` (e = p − y, a = |d|² > 0):
/// the roots of a σ² + b σ + c, or None where the path never comes within reach of y.
fn reach_interval(e: DVec3, d: DVec3, a: f64, reach_squared: f64) -> Option<(f64, f64)> {
    let b = 2.0 * d.dot(e);
    let c = e.length_squared() - reach_squared;
    let discriminant = b * b - 4.0 * a * c;
    (discriminant >= 0.0).then(|| {
        let root = discriminant.sqrt();
        ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a))
    })
}

/// The lowest s' ≤ `s` such that every point p + σ d with σ ∈ [s', s] is within `reach` of one
/// of `points` (to [`TIE_TOLERANCE`] of ρ²): the fold guard's floor. `s` itself when p + s d is
/// out of reach.
fn reach_floor(
    p: DVec3,
    d: DVec3,
    points: impl Iterator<Item = DVec3> + Clone,
    reach: f64,
    s: f64,
) -> f64 {
    let reach_squared = reach * reach * (1.0 + TIE_TOLERANCE);
    let a = d.length_squared();
    if a == 0.0 {
        return if within_reach(p, points, reach) {
            0.0
        } else {
            s
        };
    }
    // Each point's interval [low, high] of σ within reach; the floor walks down through the
    // intervals that overlap, from s.
    let mut floor = s;
    loop {
        let mut lowered = floor;
        for y in points.clone() {
            if let Some((low, high)) = reach_interval(p - y, d, a, reach_squared)
                && low <= floor
                && floor <= high
            {
                lowered = lowered.min(low.max(0.0));
            }
        }
        if lowered >= floor {
            return floor;
        }
        floor = lowered;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hat's turn of one triangle in the z = 0 plane: 0 while it faces the carried one by
    /// at least the margin, linear to 1 at a right angle (zero facing), 1 when turned over, 0
    /// for a degenerate carried triangle.
    #[test]
    fn the_hats_turn_rises_linearly_from_the_margin_to_a_fold() {
        let carried = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(hat_turn(carried, carried), 0.0);
        // The third corner moved along y scales the facing by its height.
        let lifted = |h: f64| [DVec3::ZERO, DVec3::X, DVec3::new(0.3, h, 0.0)];
        assert_eq!(hat_turn(carried, lifted(UNFOLD_MARGIN)), 0.0);
        assert!((hat_turn(carried, lifted(0.5 * UNFOLD_MARGIN)) - 0.5).abs() < 1e-15);
        assert_eq!(hat_turn(carried, lifted(0.0)), 1.0);
        assert_eq!(hat_turn(carried, lifted(-2.0)), 1.0);
        // Tilted out of the plane by 90°: no facing left.
        let tilted = [DVec3::ZERO, DVec3::X, DVec3::Z];
        assert_eq!(hat_turn(carried, tilted), 1.0);
        let degenerate = [DVec3::ZERO, DVec3::X, 2.0 * DVec3::X];
        assert_eq!(hat_turn(degenerate, carried), 0.0);
    }

    /// One triangle in the z = 0 plane whose fit swaps two corners' sides of the third: the
    /// guard scales the three factors to the turn where the normal keeps a quarter of the
    /// carried one's, and leaves an unturned fit alone.
    #[test]
    fn the_fold_guard_stops_a_turning_triangle_before_it_folds() {
        let limit = |triangles: &[[u32; 3]]| ReachLimit {
            binding_cage: Vec::new(),
            binding_centroids: Vec::new(),
            binding_joint_moments: Vec::new(),
            row_points: Vec::new(),
            row_weights: SkinWeights::from_csr_unchecked(0, vec![0], Vec::new(), Vec::new()),
            neighbour_points: Vec::new(),
            neighbour_weights: SkinWeights::from_csr_unchecked(0, vec![0], Vec::new(), Vec::new()),
            neighbour_start: Vec::new(),
            reach: 1.0,
            anchor_weights: SkinWeights::from_csr_unchecked(0, vec![0], Vec::new(), Vec::new()),
            hat: HatFit::Exact,
            triangles: triangles.to_vec(),
        };
        let guard = limit(&[[0, 1, 2]]);
        let carried = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // Corner 1 moves from x = 1 to x = −1: the normal's z is 1 − 2s, ¼ at s = 3/8.
        let fitted = [DVec3::ZERO, -DVec3::X, DVec3::Y];
        let mut factors = [1.0; 3];
        guard.unfold(&carried, &fitted, &[0.0; 3], &mut factors);
        for s in factors {
            assert!((s - 0.375).abs() < 1e-12, "{factors:?}");
        }
        let unturned = [DVec3::ZERO, 2.0 * DVec3::X, DVec3::Y];
        let mut factors = [1.0, 0.5, 1.0];
        guard.unfold(&carried, &unturned, &[0.0; 3], &mut factors);
        assert_eq!(factors, [1.0, 0.5, 1.0]);
        // Corner 1 may not go below 0.8 (the reach): the others alone do not unturn the
        // triangle, so it is left alone.
        let mut factors = [1.0; 3];
        guard.unfold(&carried, &fitted, &[0.0, 0.8, 0.0], &mut factors);
        assert_eq!(factors, [1.0; 3]);
        // Floor 0.25 on corner 1: the normal's z, 1 − 2(0.25 + 0.75t), reaches ¼ at t = 1/6.
        let mut factors = [1.0; 3];
        guard.unfold(&carried, &fitted, &[0.0, 0.25, 0.0], &mut factors);
        let t = 1.0 / 6.0;
        for (s, floor) in factors.into_iter().zip([0.0, 0.25, 0.0]) {
            assert!(
                (s - (floor + t * (1.0 - floor))).abs() < 1e-12,
                "{factors:?}"
            );
        }
    }

    /// The floor walks down through overlapping intervals within reach, and stops at a gap.
    #[test]
    fn the_reach_floor_follows_the_path_back_while_within_reach() {
        // Path along x from 0 to 10; points at x = 2 and x = 4 with reach 1.5: within reach on
        // [0.5, 5.5] (overlapping), then a gap; a point at 9: [7.5, 10.5].
        let points = [2.0, 4.0, 9.0].map(|x| DVec3::new(x, 0.0, 0.0));
        let floor = |s: f64| {
            reach_floor(
                DVec3::ZERO,
                DVec3::new(10.0, 0.0, 0.0),
                points.into_iter(),
                1.5,
                s,
            )
        };
        assert!((floor(0.5) - 0.05).abs() < 1e-9, "{}", floor(0.5));
        assert!((floor(1.0) - 0.75).abs() < 1e-9, "{}", floor(1.0));
        assert_eq!(floor(0.6), 0.6, "out of reach at s = 0.6 (x = 6)");
    }

    #[test]
    fn a_fit_within_reach_is_kept_whole() {
        let points = [DVec3::ZERO, DVec3::X];
        let s = largest_factor_within(DVec3::Y, DVec3::new(0.5, 0.0, 0.0), points.into_iter(), 1.5);
        assert_eq!(s, 1.0);
    }

    #[test]
    fn a_fit_leaving_the_body_stops_at_the_reach() {
        // p one unit above the origin, moving straight up: within reach 2 up to s = 1/3 of 3.
        let points = [DVec3::ZERO];
        let s = largest_factor_within(DVec3::Y, DVec3::new(0.0, 3.0, 0.0), points.into_iter(), 2.0);
        assert!((s - 1.0 / 3.0).abs() < 1e-9, "{s}");
    }

    /// A fit at exactly the rest reach, computed with round-off on either side of it (a cage
    /// vertex of a rigidly moved part whose rest distance is ρ), is kept whole.
    #[test]
    fn a_fit_at_the_reach_to_round_off_is_kept_whole() {
        let points = [DVec3::ZERO];
        for reach in [2.0 * (1.0 - 4e-16), 2.0, 2.0 * (1.0 + 4e-16)] {
            let s = largest_factor_within(DVec3::Y, DVec3::Y, points.into_iter(), reach);
            assert_eq!(s, 1.0, "reach {reach}");
        }
    }

    #[test]
    fn out_of_reach_everywhere_takes_the_nearest_point_of_the_path() {
        // The path from (−2, 5, 0) to (2, 5, 0) passes 5 above the point: nearest at s = ½.
        let points = [DVec3::ZERO];
        let s = largest_factor_within(
            DVec3::new(-2.0, 5.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            points.into_iter(),
            1.0,
        );
        assert!((s - 0.5).abs() < 1e-15, "{s}");
    }

    #[test]
    fn the_largest_qualifying_factor_over_several_points_is_taken() {
        // Reach 1 around x = 0 and x = 4 on a path from x = −0.5 to x = 9.5: the second
        // interval ends at x = 5, s = 0.55.
        let points = [DVec3::ZERO, DVec3::new(4.0, 0.0, 0.0)];
        let s = largest_factor_within(
            DVec3::new(-0.5, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            points.into_iter(),
            1.0,
        );
        assert!((s - 0.55).abs() < 1e-9, "{s}");
    }
}
