//! Automatic cages: a closed, embedded, outward cage around any triangle mesh, with a target
//! vertex or triangle count, a guaranteed margin and a public validator.
//!
//! Method (after lazy cages, Sellán et al. 2022, and nested cages, Sacht et al. 2015):
//! 1. [`weld`] — weld the input by position and find its connected pieces (for the checks);
//! 2. [`distance_grid`] — sample the distance to the mesh on a grid (exactly where a
//!    Lipschitz bound cannot decide) and fill from outside at distance `offset`: the solid
//!    includes cavities, the inside of open or self-intersecting meshes and gaps narrower than
//!    2·offset between pieces;
//! 3. [`marching_tets`] — extract the solid's boundary by marching tetrahedra: a closed
//!    2-manifold, embedded, oriented outward, farther than offset − h√3 from the mesh;
//! 4. [`simplify`] — collapse edges in quadric-error order down to the target, rejecting every
//!    collapse that would break manifoldness, flip a triangle, come within `margin` of the mesh
//!    (mesh BVH), intersect the cage (triangle hash) or sweep over a piece of the mesh;
//!    then flip the shared edge of nearly coplanar triangles where that lifts a poor one
//!    ([`edge_flips`], under the same constraints: needles on flat parts become fair triangles);
//! 5. [`offset_search`] — try increasing offsets, from a tight one whose surface is verified
//!    exactly ([`surface_clearance`]) or else the tightest the grid guarantees, and keep the
//!    first whose cage reaches the target and passes [`validate`].
//!
//! With a skeleton, [`generate_rig_cage`] lays the cage out by the body ([`CageLayout`],
//! the default [`CageLayout::Skeleton`]): before step 3 the solid is cut between body parts
//! whose dominant joints lie on different branches of the skeleton ([`limb_separation`]: no
//! webbing between the legs, or between an arm and the torso), on a grid fine enough to resolve
//! the gaps between limbs, and step 4 orders the collapses with a [`skeleton_guide`] (rings of
//! vertices around the articulations).
//!
//! Every step keeps the invariants, so a cage that reaches the target passes the validator by
//! construction; the validator runs anyway and any failure is reported, never returned as a cage.

pub mod bvh;
pub mod collapse_checks;
pub mod distance_grid;
pub mod edge_flips;
pub mod geometry;
pub mod layout;
pub mod limb_separation;
pub mod marching_tets;
pub mod offset_search;
pub mod quadric;
pub mod simplify;
pub mod skeleton_guide;
pub mod surface_clearance;
pub mod triangle_hash;
pub mod validate;
pub mod weld;

use thiserror::Error;

pub use layout::{CageLayout, UnknownCageLayout};
pub use limb_separation::{BodyParts, BodyPartsError};
pub use offset_search::{
    CageRig, GeneratedCage, generate_cage, generate_guided_cage, generate_rig_cage,
};
pub use skeleton_guide::CageGuide;
pub use validate::{
    CHECK_NAMES, CageReport, CageRequirements, Check, check_coordinates, validate_cage_geometry,
};

/// Default target vertex count of `cagerig cage`.
pub const DEFAULT_VERTICES: usize = 100;
/// Default margin, × bbox diagonal of the mesh (see [`CageOptions::margin`]).
pub const DEFAULT_MARGIN: f64 = 0.005;
/// Fewest vertices a cage may be asked for.
pub const MIN_VERTICES: usize = 8;

/// Size of the cage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CageTarget {
    /// About this many cage vertices.
    Vertices(usize),
    /// About this many cage triangles (converted with F = 2V − 4).
    Faces(usize),
}

impl CageTarget {
    /// The target as a vertex count (a genus-0 cage has F = 2V − 4).
    pub fn vertices(self) -> usize {
        match self {
            Self::Vertices(n) => n,
            Self::Faces(f) => f / 2 + 2,
        }
    }
}

/// Options of [`generate_cage`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CageOptions {
    /// Size of the cage to reach.
    pub target: CageTarget,
    /// Least distance from the mesh to the cage, × bbox diagonal of the mesh. The default
    /// 0.5 % keeps every mesh vertex well away from the cage surface, where mean value
    /// coordinates become peaked (their gradient grows like 1/distance) and their f32 rounding
    /// loses digits, while still letting the cage hug concave regions; the Arm's hand-made
    /// cage comes to 0.075 %.
    pub margin: f64,
    /// How the cage is laid out around a rigged character ([`generate_rig_cage`]; without a
    /// skeleton every layout is the offset one).
    pub layout: CageLayout,
}

impl Default for CageOptions {
    fn default() -> Self {
        Self {
            target: CageTarget::Vertices(DEFAULT_VERTICES),
            margin: DEFAULT_MARGIN,
            layout: CageLayout::default(),
        }
    }
}

/// Why no cage was produced.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CageGenError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// All vertices of the mesh coincide.
    #[error("the mesh has no extent: all its vertices coincide")]
    NoExtent,
    /// A mesh vertex has a NaN or infinite coordinate.
    #[error("mesh vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// The vertex index.
        vertex: usize,
    },
    /// The target is below [`MIN_VERTICES`].
    #[error("a cage needs at least {minimum} vertices (asked for {requested})")]
    TargetTooSmall {
        /// The target vertex count asked for.
        requested: usize,
        /// The fewest vertices allowed ([`MIN_VERTICES`]).
        minimum: usize,
    },
    /// The margin is not finite or not in `[0, 0.1)`.
    #[error("the margin must be a finite fraction of the diagonal in [0, 0.1); got {margin}")]
    InvalidMargin {
        /// The margin asked for, × bbox diagonal of the mesh.
        margin: f64,
    },
    /// The filled solid stayed in several pieces at every offset tried.
    #[error(
        "the mesh's parts lie too far apart for one connected cage: {pieces} separate pieces remain at the largest offset tried ({offset_percent:.1} % of the diagonal); make a cage per part"
    )]
    SeparatePieces {
        /// Number of separate surface pieces at the last offset tried.
        pieces: usize,
        /// That offset, in % of the bbox diagonal of the mesh.
        offset_percent: f64,
    },
    /// Simplification stopped above the target at every offset tried.
    #[error(
        "could not simplify to {target} vertices without crossing the mesh or the cage itself: the best attempt stopped at {reached} vertices (offset {offset_percent:.2} % of the diagonal); ask for about {reached} vertices or a smaller margin"
    )]
    TargetNotReached {
        /// The target vertex count.
        target: usize,
        /// The fewest vertices any attempt reached.
        reached: usize,
        /// The offset of that attempt, in % of the bbox diagonal of the mesh.
        offset_percent: f64,
    },
    /// The skeleton layout's body parts could not be built from the rig.
    #[error("the rig's body parts: {0}")]
    BodyParts(#[from] BodyPartsError),
    /// Every cage that reached the target failed [`validate`].
    #[error("the generated cage failed validation at every offset; last failures: {failures:?}")]
    ValidationFailed {
        /// The failed checks of the last attempt, one message each.
        failures: Vec<String>,
    },
}
