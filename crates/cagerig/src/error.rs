//! Errors and warnings raised when a rig is validated at the boundary (import, assembly).

use thiserror::Error;

/// A structural problem that makes a rig unusable. Every variant names the offending element.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RigError {
    #[error("{what}: index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        what: &'static str,
        index: usize,
        len: usize,
    },
    #[error("{what} {index} has a non-finite coordinate")]
    NonFinite { what: &'static str, index: usize },
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
        "skinning weight of vertex {vertex} for joint {joint} is {weight}: weights must be finite and non-negative"
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
    #[error("the cage has no triangles")]
    EmptyCage,
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
