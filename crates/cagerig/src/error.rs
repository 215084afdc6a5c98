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

/// `x` as a person reads it in a message: plain digits between 1e-4 and 1e15 in magnitude,
/// scientific notation outside (`1e308`, not 309 digits), `NaN`/`inf` as such.
pub fn number_text(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (x.is_finite() && (1e-4..1e15).contains(&a)) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A vector as `[x, y, z]` with each component by [`number_text`].
pub fn vector_text(v: glam::DVec3) -> String {
    format!(
        "[{}, {}, {}]",
        number_text(v.x),
        number_text(v.y),
        number_text(v.z)
    )
}

/// A serde error message in a script's terms: Rust type names (`usize`, `f64`, `u32`) become
/// what the value means to a person.
pub fn plain_serde_message(message: &str) -> String {
    message
        .replace("expected usize", "expected an index (a whole number ≥ 0)")
        .replace("expected u32", "expected an index (a whole number ≥ 0)")
        .replace("expected u64", "expected a whole number ≥ 0")
        .replace("expected f64", "expected a number")
        .replace("expected f32", "expected a number")
        .replace(
            "expected an array of length 3",
            "expected three numbers [x, y, z]",
        )
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
    /// What was requested (e.g. "CoR similarity tables"), shown first in the message.
    pub what: String,
    /// Rows of the request (`vertices` of the mesh, or of a table named by `rows`).
    pub vertices: u64,
    /// What the rows are: "vertices", or e.g. "grid nodes" for an intermediate table.
    pub rows: &'static str,
    /// Cage vertices `#C` of the request (the columns of Φ or of the table).
    pub cage_vertices: u64,
    /// Estimated memory the request needs, in GiB.
    pub needed_gib: f64,
    /// Φ's share of `needed_gib`, when the request is a whole session.
    pub phi_gib: Option<f64>,
    /// Memory available now, in GiB; when unknown, the fixed limit (0 after a refused
    /// allocation).
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
    /// Ω has more joint columns than a 16-bit joint index can address.
    #[error(
        "skinning weights for {joints} joints: at most {max} joints are supported (16-bit joint \
         indices, as in glTF)"
    )]
    TooManyJoints {
        /// Joints `#J` of the skinning weights.
        joints: usize,
        /// Largest number of joints supported.
        max: usize,
    },
    /// The request would not fit in the memory of this machine.
    #[error("{0}")]
    TooLarge(Box<MemoryNeed>),
    /// An index (vertex, joint, triangle corner…) points past the end of what it indexes.
    #[error("{what}: index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// What the index refers to (e.g. "triangle vertex", "skinning weight joint").
        what: &'static str,
        /// The out-of-range index.
        index: usize,
        /// Number of elements it may index (valid indices are `0..len`).
        len: usize,
    },
    /// A position or transform has a NaN or infinite component.
    #[error("{what} {index} has a non-finite coordinate")]
    NonFinite {
        /// What the element is (e.g. "vertex", "joint rest transform").
        what: &'static str,
        /// The index of the element.
        index: usize,
    },
    /// A number is non-finite or exceeds [`MAX_INPUT_MAGNITUDE`] in magnitude.
    #[error(
        "{what} {index} has the value {value}: expected a finite number of magnitude at most 1e12"
    )]
    ValueOutOfBounds {
        /// What the element is (e.g. "vertex", "joint position", "cage coordinate row").
        what: &'static str,
        /// The index of the element.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A joint names a parent index that is not a joint of the skeleton.
    #[error("joint {joint} ({name}) has unknown parent {parent}")]
    UnknownParent {
        /// The joint index.
        joint: usize,
        /// The joint name.
        name: String,
        /// The parent index it names.
        parent: usize,
    },
    /// The parent links of the skeleton form a cycle instead of a tree.
    #[error("joint {joint} ({name}) is its own ancestor: the hierarchy has a cycle")]
    Cycle {
        /// The index of a joint on the cycle.
        joint: usize,
        /// The joint name.
        name: String,
    },
    /// Two joints share a name (names must be unique to be addressed).
    #[error("joints {first} and {second} share the name {name:?}")]
    DuplicateJointName {
        /// The shared name.
        name: String,
        /// The index of the first joint with that name.
        first: usize,
        /// The index of the second joint with that name.
        second: usize,
    },
    /// An Ω entry is non-finite, negative or larger than [`MAX_INPUT_MAGNITUDE`].
    #[error(
        "skinning weight of vertex {vertex} for joint {joint} is {weight}: weights must be finite, non-negative and at most 1e12"
    )]
    InvalidWeight {
        /// The vertex index (row of Ω).
        vertex: usize,
        /// The joint index (column of Ω).
        joint: usize,
        /// The offending weight.
        weight: f64,
    },
    /// A DQ blend weight (blended skinning, `b_v` of vertex v) is not a finite number in [0, 1].
    #[error(
        "DQ blend weight of vertex {vertex} is {weight}: expected a finite number in [0, 1] \
         (0 skins the vertex with LBS, 1 with DQS)"
    )]
    InvalidDqBlendWeight {
        /// The vertex index.
        vertex: usize,
        /// The offending weight.
        weight: f64,
    },
    /// The blended skinning method was asked of a rig without DQ blend weights.
    #[error(
        "the rig has no per-vertex DQ blend weights: the blended (LBS/DQS blend) skinning method \
         needs one weight in [0, 1] per mesh vertex (FBX skins carry them: Maya's \"weight \
         blended\" skin clusters; an OBJ rig reads them from <stem>_dqBlendWeights.txt beside \
         its mesh); expected a rig with DQ blend weights, or choose lbs, dqs or cor"
    )]
    NoDqBlendWeights,
    /// The external skinning method was asked of a session built without one.
    #[error(
        "the session has no external skinning method: expected one passed in \
         SessionOptions::external_skinning, or choose lbs, dqs, cor or blended"
    )]
    NoExternalSkinning,
    /// The external skinning method could not bind the rig.
    #[error("the external skinning method {name:?} could not bind the rig: {message}")]
    ExternalSkinning {
        /// The method's name ([`crate::session::SkinningBackend::name`]).
        name: String,
        /// Why, in the method's words.
        message: String,
    },
    /// Two sizes that must agree (e.g. rows of Φ and vertices of M) differ.
    #[error("{what}: expected {expected} but got {actual}")]
    SizeMismatch {
        /// What was counted (e.g. "skinning weight rows (mesh vertices)").
        what: &'static str,
        /// The size it must have.
        expected: usize,
        /// The size it has.
        actual: usize,
    },
    /// A cage edge has a single adjacent triangle: the cage is not closed.
    #[error("cage edge ({a}, {b}) is on an open boundary: it belongs to triangle {triangle} only")]
    CageOpenBoundary {
        /// First cage vertex index of the edge.
        a: u32,
        /// Second cage vertex index of the edge.
        b: u32,
        /// The only triangle on the edge.
        triangle: usize,
    },
    /// A cage edge is shared by more than two triangles.
    #[error("cage edge ({a}, {b}) is non-manifold: it is shared by {count} triangles")]
    CageNonManifoldEdge {
        /// First cage vertex index of the edge.
        a: u32,
        /// Second cage vertex index of the edge.
        b: u32,
        /// Number of triangles sharing the edge.
        count: usize,
    },
    /// Two cage triangles traverse their shared edge in the same direction.
    #[error(
        "cage triangles {first} and {second} have inconsistent orientation across edge ({a}, {b})"
    )]
    CageInconsistentOrientation {
        /// First cage vertex index of the edge.
        a: u32,
        /// Second cage vertex index of the edge.
        b: u32,
        /// The first triangle on the edge.
        first: usize,
        /// The second triangle on the edge, oriented against the first.
        second: usize,
    },
    /// A cage triangle has (near-)zero area relative to the cage's bounding box.
    #[error("cage triangle {triangle} is degenerate (area {area:e})")]
    CageDegenerateTriangle {
        /// The triangle index.
        triangle: usize,
        /// Its area, in squared model units.
        area: f64,
    },
    /// A cage triangle uses the same vertex at two corners.
    #[error("cage triangle {triangle} repeats a vertex")]
    CageRepeatedVertex {
        /// The triangle index.
        triangle: usize,
    },
    /// Vertices of the rest mesh M lie outside the rest cage C.
    #[error(
        "{count} of {total} mesh vertices are outside the cage (farthest: vertex {worst_vertex}, \
         {worst_distance:.3e} from the cage surface); expected the cage to enclose the mesh: \
         enlarge the cage, or accept it as it is with `--allow-outside-cage` (mean value \
         coordinates then extrapolate outside)"
    )]
    MeshOutsideCage {
        /// Number of mesh vertices outside the cage.
        count: usize,
        /// Number of mesh vertices `#V`.
        total: usize,
        /// The vertex index farthest outside the cage.
        worst_vertex: usize,
        /// Its distance to the cage surface, in model units.
        worst_distance: f64,
    },
    /// The cage has no triangles.
    #[error("the cage has no triangles")]
    EmptyCage,
    /// A vertex's blended LBS transform `Σ_j ω_vj T_j^r` is singular, so no rest point skins to
    /// a given posed point ([`crate::skinning::LinearBlendSkinning::rest_preimage`]).
    #[error(
        "vertex {vertex}: its blended LBS transform is singular (determinant {determinant:e}), so \
         no rest point skins to its posed position; expected its joints' rotations not to cancel \
         out (such as a half-half blend of opposite half-turns)"
    )]
    SingularBlend {
        /// The mesh vertex.
        vertex: usize,
        /// The determinant of its blended linear part.
        determinant: f64,
    },
    /// An edit would have produced a non-finite or out-of-bounds state; it was rolled back.
    #[error(
        "the event was refused and the rig left as it was: it would have moved {what} {index} to \
         {value:?}, which is not a finite position of magnitude at most 1e15"
    )]
    EventRefused {
        /// What would have moved (e.g. "current cage vertex", "rest joint").
        what: &'static str,
        /// The index of that element.
        index: usize,
        /// The position it would have moved to (world space).
        value: [f64; 3],
    },
    /// Green coordinates: CageUp found no current cage fitting this state (see
    /// `docs/green-coordinates.md`: where the fitted cage folds a face, Lipman's stretched normal
    /// jumps, and the fit has no solution beyond the fold).
    #[error(
        "the event was refused and the rig left as it was: Green CageUp found no current cage \
         fitting it (the fit stopped with a gradient of {:.3e}, expected at most {:.3e}; {}); \
         try a smaller step, or mean value coordinates for this pose",
        .0.residual,
        .0.limit,
        green_fit_cause(.0.face, .0.area_ratio)
    )]
    GreenFitFailed(UnfittedCage),
    /// Green coordinates: a grab of the current cage while it is not CageUp's fit of the pose
    /// (kept under [`crate::session::UnfittedCagePolicy::KeepEvent`]).
    #[error(
        "the current cage C' cannot be grabbed in this pose: {0}; CageRev needs C' to be \
         CageUp's fit of the skin, so go back to a pose the Green cage follows (an earlier step \
         or the rest pose), or bind with mean value coordinates"
    )]
    PosedCageUnfitted(UnfittedCage),
    /// Green coordinates: CageRev found no rest cage that makes CageUp return the grabbed
    /// current cage.
    #[error(
        "the grab was refused and the rig left as it was: Green CageRev found no rest cage \
         making the current cage land where it was dragged (Newton stopped at a residual of \
         {residual:.3e} after {iterations} steps, expected at most {limit:.3e}); try a smaller \
         drag"
    )]
    GreenGrabFailed {
        /// max |G| where Newton stopped.
        residual: f64,
        /// The tolerance it had to reach.
        limit: f64,
        /// Newton steps taken.
        iterations: usize,
    },
    /// A matrix could not be factorised (singular or too ill-conditioned).
    #[error("{what} is singular or too ill-conditioned to factorise")]
    Singular {
        /// What could not be factorised (e.g. "MaxVol submatrix" of Φ).
        what: &'static str,
    },
    /// Any other invalid input, described by the message.
    #[error("{0}")]
    Invalid(String),
}

impl RigError {
    /// Whether the error is about the rest cage C itself (its validation, or the mesh outside
    /// it), so that a front end can name the cage's file in its message.
    pub fn concerns_cage(&self) -> bool {
        matches!(
            self,
            Self::CageOpenBoundary { .. }
                | Self::CageNonManifoldEdge { .. }
                | Self::CageInconsistentOrientation { .. }
                | Self::CageDegenerateTriangle { .. }
                | Self::CageRepeatedVertex { .. }
                | Self::MeshOutsideCage { .. }
                | Self::EmptyCage
        )
    }
}

/// Something that was accepted but changed or is suspicious; shown to the user by `info`.
/// Serialised by kind (to cross to and from the web page's worker as it is).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Warning {
    /// Rows of Ω that did not sum to 1 and were rescaled.
    WeightsRenormalised {
        /// Number of rows rescaled.
        rows: usize,
        /// The row sum farthest from 1 before rescaling.
        worst_sum: f64,
    },
    /// Vertices with no skinning influence at all (they stay at rest under skinning).
    UnweightedVertices {
        /// Number of vertices with an all-zero row of Ω.
        count: usize,
        /// The first such vertex index.
        first: usize,
    },
    /// Several weight entries for the same (vertex, joint) pair; they were summed.
    DuplicateWeightEntries {
        /// Number of duplicate entries summed.
        count: usize,
    },
    /// Zero weights listed explicitly; they were dropped.
    ZeroWeightEntries {
        /// Number of zero entries dropped.
        count: usize,
    },
    /// The cage had inward-facing triangles (negative volume); all triangles were flipped.
    CageOrientationFlipped {
        /// Signed volume of the cage as given (negative).
        signed_volume: f64,
    },
    /// Max-entropy projection of a joint fell back to least squares (see `coords::mec`).
    MecFallback {
        /// The joint index.
        joint: usize,
        /// The joint name.
        name: String,
        /// Why the max-entropy projection failed.
        reason: String,
    },
    /// Anything else worth telling the user.
    Note {
        /// The message shown to the user.
        message: String,
    },
    /// A known, harmless fact about the input (e.g. coordinates given for another kind of
    /// binding and recomputed): shown as a note, never as a warning.
    Info {
        /// The message shown to the user.
        message: String,
    },
}

/// How loudly a [`Warning`] is shown: [`Warning::severity`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Information: the input was accepted as it is meant (front ends print `note:`).
    Note,
    /// Something changed or suspicious that the user should look at (`warning:`).
    Warning,
}

/// Weight rows whose sum is off 1 by at most this much were only rounded when written (the
/// paper's Arm: 0.99907): their renormalisation is a [`Severity::Note`].
pub const WEIGHT_ROUNDING_TOLERANCE: f64 = 1e-2;

impl Warning {
    /// Whether this is information ([`Severity::Note`]) or something to look at
    /// ([`Severity::Warning`]).
    pub fn severity(&self) -> Severity {
        match self {
            Warning::WeightsRenormalised { worst_sum, .. } => {
                if (worst_sum - 1.0).abs() <= WEIGHT_ROUNDING_TOLERANCE {
                    Severity::Note
                } else {
                    Severity::Warning
                }
            }
            Warning::ZeroWeightEntries { .. } | Warning::Info { .. } => Severity::Note,
            Warning::UnweightedVertices { .. }
            | Warning::DuplicateWeightEntries { .. }
            | Warning::CageOrientationFlipped { .. }
            | Warning::MecFallback { .. }
            | Warning::Note { .. } => Severity::Warning,
        }
    }

    /// `"note"` or `"warning"`: the word front ends print before the message.
    pub fn label(&self) -> &'static str {
        match self.severity() {
            Severity::Note => "note",
            Severity::Warning => "warning",
        }
    }
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
            Warning::Note { message } | Warning::Info { message } => f.write_str(message),
        }
    }
}

/// Accepted names as a sentence: `"a"`, `"a or b"`, `"a, b or c"` (the messages of the kinds'
/// parsers: skinning methods, coordinates).
pub(crate) fn names_sentence(names: &[&str]) -> String {
    match names.split_last() {
        Some((last, [])) => (*last).to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// A fitted Green cage triangle whose signed area falls below this fraction of its binding area
/// counts as folded in [`RigError::GreenFitFailed`]'s message.
pub const GREEN_FOLD_AREA_RATIO: f64 = 0.05;

/// Why a Green CageUp found no current cage C' for a state: where the fit stopped. An event
/// that ends so is refused ([`RigError::GreenFitFailed`]) or, under
/// [`crate::session::UnfittedCagePolicy::KeepEvent`], kept with C' marked unfitted
/// ([`crate::session::RigSession::posed_cage_unfitted`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnfittedCage {
    /// max |Jᵀr| where the fit stopped.
    pub residual: f64,
    /// The tolerance it had to reach.
    pub limit: f64,
    /// The cage triangle with the smallest signed area ratio at the stopping point.
    pub face: usize,
    /// That triangle's signed area over its binding area (negative: turned over). Below
    /// [`GREEN_FOLD_AREA_RATIO`] the messages blame the fold; above it, no triangle folded and
    /// the messages say so.
    pub area_ratio: f64,
}

impl std::fmt::Display for UnfittedCage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "CageUp found no current cage fitting the skin (the fit stopped with a gradient of \
             {:.3e}, expected at most {:.3e}; {})",
            self.residual,
            self.limit,
            green_fit_cause(self.face, self.area_ratio)
        )
    }
}

/// The cause [`RigError::GreenFitFailed`] names: the folded triangle, or that none folded.
fn green_fit_cause(face: usize, area_ratio: f64) -> String {
    if area_ratio < GREEN_FOLD_AREA_RATIO {
        format!(
            "the closest cage folds cage triangle {face}, whose signed area fell to \
             {area_ratio:.2e} of its rest area — a Green cage cannot follow the skin past a \
             folded triangle"
        )
    } else {
        format!(
            "no cage triangle folded (the most squeezed, triangle {face}, kept {area_ratio:.2e} \
             of its rest area): the fit stalled short of a stationary point for this pose"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_as_people_write_them() {
        assert_eq!(number_text(1e308), "1e308");
        assert_eq!(number_text(-2.5), "-2.5");
        assert_eq!(number_text(0.0), "0");
        assert_eq!(number_text(1e-9), "1e-9");
        assert_eq!(number_text(f64::INFINITY), "inf");
        assert_eq!(
            vector_text(glam::DVec3::new(1e300, 0.5, 0.0)),
            "[1e300, 0.5, 0]"
        );
        assert_eq!(
            plain_serde_message("invalid type: floating point `1.5`, expected usize"),
            "invalid type: floating point `1.5`, expected an index (a whole number ≥ 0)"
        );
    }

    /// A Green fit that stalls blames a fold only when a triangle folded: a triangle that keeps
    /// 86 % of its area (an FBX character at its first animation sample) is not reported as
    /// "folds cage triangle 154, whose area fell to 8.61e-1".
    #[test]
    fn a_stalled_green_fit_blames_a_fold_only_when_a_triangle_folded() {
        let failed = |area_ratio| {
            RigError::GreenFitFailed(UnfittedCage {
                residual: 4.3e-5,
                limit: 7.3e-9,
                face: 154,
                area_ratio,
            })
            .to_string()
        };
        let squeezed = failed(0.861);
        assert!(
            squeezed.contains("no cage triangle folded") && squeezed.contains("triangle 154"),
            "{squeezed}"
        );
        assert!(!squeezed.contains("folds cage triangle"), "{squeezed}");
        for ratio in [0.01, -0.3] {
            let folded = failed(ratio);
            assert!(folded.contains("folds cage triangle 154"), "{folded}");
        }
    }
}
