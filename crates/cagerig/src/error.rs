//! Errors and warnings raised when a rig is validated at the boundary (import, assembly).

use thiserror::Error;

/// Largest magnitude accepted for any number a rig is built from (coordinates, weights, cage
/// coordinates, offsets, angles, times): far beyond any real rig, and small enough that the
/// sums and products of the method (ΦC, Ω row sums, squared distances, solid angles) cannot
/// overflow f64. Larger values are rejected where they enter (file, line, value).
pub const MAX_INPUT_MAGNITUDE: f64 = 1e12;

/// True when `x` is finite and at most [`MAX_INPUT_MAGNITUDE`] in magnitude.
pub fn is_input_value(x: f64) -> bool {
    x.is_finite() && x.abs() <= MAX_INPUT_MAGNITUDE
}

/// The first component of `v` that is not an input value ([`is_input_value`]).
pub fn first_bad_component(v: glam::DVec3) -> Option<f64> {
    v.to_array().into_iter().find(|&x| !is_input_value(x))
}

/// A request too large for the memory of this machine (see [`crate::memory_estimate`]).
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "{what}: about {vertices} {rows} × {cage_vertices} cage vertices would need about \
     {needed_gib:.1} GiB{}, but {limit_gib:.1} GiB {limit}; ask for less",
    phi_note(*.phi_gib)
)]
pub struct MemoryNeed {
    pub what: String,
    /// Rows of the request (`vertices` of the mesh, or of a table named by `rows`).
    pub vertices: u64,
    /// What the rows are: "vertices", or e.g. "grid nodes" for an intermediate table.
    pub rows: &'static str,
    pub cage_vertices: u64,
    pub needed_gib: f64,
    /// Φ's share of `needed_gib`, when the request is a whole session.
    pub phi_gib: Option<f64>,
    pub limit_gib: f64,
    /// "are available" or "is the limit" (when the available memory is unknown).
    pub limit: &'static str,
}

fn phi_note(phi_gib: Option<f64>) -> String {
    phi_gib.map_or_else(String::new, |g| {
        format!(" (cage coordinates Φ alone: {g:.1} GiB)")
    })
}

/// A structural problem that makes a rig unusable. Every variant names the offending element.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RigError {
    #[error(
        "skinning weights for {joints} joints: at most {max} joints are supported (16-bit joint \
         indices, as in glTF)"
    )]
    TooManyJoints { joints: usize, max: usize },
    #[error("{0}")]
    TooLarge(Box<MemoryNeed>),
    #[error("{what}: index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        what: &'static str,
        index: usize,
        len: usize,
    },
    #[error("{what} {index} has a non-finite coordinate")]
    NonFinite { what: &'static str, index: usize },
    #[error(
        "{what} {index} has the value {value}: expected a finite number of magnitude at most 1e12"
    )]
    ValueOutOfBounds {
        what: &'static str,
        index: usize,
        value: f64,
    },
    #[error("joint {joint} ({name}) has unknown parent {parent}")]
    UnknownParent {
        joint: usize,
        name: String,
        parent: usize,
    },
    #[error("joint {joint} ({name}) is its own ancestor: the hierarchy has a cycle")]
    Cycle { joint: usize, name: String },
    #[error("joints {first} and {second} share the name {name:?}")]
    DuplicateJointName {
        name: String,
        first: usize,
        second: usize,
    },
    #[error(
        "skinning weight of vertex {vertex} for joint {joint} is {weight}: weights must be finite, non-negative and at most 1e12"
    )]
    InvalidWeight {
        vertex: usize,
        joint: usize,
        weight: f64,
    },
    #[error("{what}: expected {expected} but got {actual}")]
    SizeMismatch {
        what: &'static str,
        expected: usize,
        actual: usize,
    },
    #[error("cage edge ({a}, {b}) is on an open boundary: it belongs to triangle {triangle} only")]
    CageOpenBoundary { a: u32, b: u32, triangle: usize },
    #[error("cage edge ({a}, {b}) is non-manifold: it is shared by {count} triangles")]
    CageNonManifoldEdge { a: u32, b: u32, count: usize },
    #[error(
        "cage triangles {first} and {second} have inconsistent orientation across edge ({a}, {b})"
    )]
    CageInconsistentOrientation {
        a: u32,
        b: u32,
        first: usize,
        second: usize,
    },
    #[error("cage triangle {triangle} is degenerate (area {area:e})")]
    CageDegenerateTriangle { triangle: usize, area: f64 },
    #[error("cage triangle {triangle} repeats a vertex")]
    CageRepeatedVertex { triangle: usize },
    #[error(
        "{count} of {total} mesh vertices are outside the cage (farthest: vertex {worst_vertex}, \
         {worst_distance:.3e} from the cage surface); expected the cage to enclose the mesh \
         (accept it explicitly to let mean value coordinates extrapolate)"
    )]
    MeshOutsideCage {
        count: usize,
        total: usize,
        worst_vertex: usize,
        worst_distance: f64,
    },
    #[error("the cage has no triangles")]
    EmptyCage,
    #[error(
        "the event was refused and the rig left as it was: it would have moved {what} {index} to \
         {value:?}, which is not a finite position of magnitude at most 1e15"
    )]
    EventRefused {
        what: &'static str,
        index: usize,
        value: [f64; 3],
    },
    #[error("{what} is singular or too ill-conditioned to factorise")]
    Singular { what: &'static str },
    #[error("{0}")]
    Invalid(String),
}

/// Something that was accepted but changed or is suspicious; shown to the user by `info`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Warning {
    /// Rows of Ω that did not sum to 1 and were rescaled.
    WeightsRenormalised { rows: usize, worst_sum: f64 },
    /// Vertices with no skinning influence at all (they stay at rest under skinning).
    UnweightedVertices { count: usize, first: usize },
    /// Several weight entries for the same (vertex, joint) pair; they were summed.
    DuplicateWeightEntries { count: usize },
    /// Zero weights listed explicitly; they were dropped.
    ZeroWeightEntries { count: usize },
    /// The cage had inward-facing triangles (negative volume); all triangles were flipped.
    CageOrientationFlipped { signed_volume: f64 },
    /// Max-entropy projection of a joint fell back to least squares (see `coords::mec`).
    MecFallback {
        joint: usize,
        name: String,
        reason: String,
    },
    /// Anything else worth telling the user.
    Note { message: String },
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Warning::WeightsRenormalised { rows, worst_sum } => write!(
                f,
                "{rows} skinning-weight rows did not sum to 1 and were renormalised (worst sum {worst_sum})"
            ),
            Warning::UnweightedVertices { count, first } => write!(
                f,
                "{count} vertices have no skinning influence (first: vertex {first})"
            ),
            Warning::DuplicateWeightEntries { count } => {
                write!(
                    f,
                    "{count} duplicate (vertex, joint) weight entries were summed"
                )
            }
            Warning::ZeroWeightEntries { count } => {
                write!(f, "{count} explicit zero weights were dropped")
            }
            Warning::CageOrientationFlipped { signed_volume } => write!(
                f,
                "the cage faced inwards (signed volume {signed_volume}); its triangles were flipped"
            ),
            Warning::MecFallback {
                joint,
                name,
                reason,
            } => write!(
                f,
                "joint {joint} ({name}): max-entropy projection fell back to least squares: {reason}"
            ),
            Warning::Note { message } => f.write_str(message),
        }
    }
}
