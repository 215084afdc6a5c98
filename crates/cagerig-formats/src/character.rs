//! The format-independent result of importing a skinned character (glTF or FBX).
//!
//! Spaces, stated once: the rest skin M and the rest skeleton S are the bind shape placed in the
//! file's world space (ancestors of the skeleton composed in), in glTF's convention
//! (right-handed, +Y up, metres: FBX files are converted, see [`SpaceSummary`]), so that at
//! rest M' = M; a posed mesh at an animation time equals what a viewer of the file shows at
//! that time (LBS). A cage given for the character must be in that same space.
//!
//! Vertex order: skinned primitives in file order (glTF: nodes in index order, then the
//! primitives of each node's mesh; FBX: mesh nodes in scene order), vertices in accessor order
//! within a primitive (glTF) or polygon-vertex order (FBX); no reordering, no welding — vertex i
//! of M is the i-th vertex of that concatenation.

use cagerig::animation::SkeletonTrack;
use cagerig::{Skeleton, SkinWeights, TriMesh, Warning};
use glam::{DAffine3, DQuat, DVec3};
use serde::Serialize;

/// A skinned character read from an interchange file.
#[derive(Debug, Clone)]
pub struct ImportedCharacter {
    /// Rest skin M (world space, file vertex order; see the module doc).
    pub mesh: TriMesh,
    /// Rest skeleton S: one joint per skin joint, in the skin's joint order.
    pub skeleton: Skeleton,
    /// Ω, `#V × #J`.
    pub skin_weights: SkinWeights,
    /// A cage found in the file (a mesh node named `<name>_cage` or with `extras.cagerig_cage`).
    pub cage: Option<TriMesh>,
    /// Animations as skeleton tracks of local transforms (play them with
    /// [`cagerig::playback::PoseChannels::Full`]).
    pub animations: Vec<ImportedAnimation>,
    /// Morph targets of the skinned mesh that the animations animate (empty when none).
    pub morph_targets: MorphTargets,
    /// Joint locals `parent_from_joint` of the file's own node transforms (`#J`): the pose the
    /// file shows without animation (equal to the rest pose when its nodes are in the bind
    /// pose; an exported cagerig pose otherwise). Play it as a one-key track with
    /// [`cagerig::playback::PoseChannels::Full`].
    pub node_pose: Vec<glam::DAffine3>,
    /// What `cagerig info` lists about the file.
    pub summary: ImportSummary,
    /// The skinning method the file's authoring tool poses the character with, when the file
    /// says (FBX skin deformers: linear or rigid → LBS, dual quaternion → DQS, Maya's "weight
    /// blended" → the LBS/DQS blend); front ends use it unless the user chooses a method.
    /// `None`: the format's own (glTF: linear blend skinning).
    pub skinning: Option<cagerig::skinning::SkinningMethod>,
    /// Per-vertex DQ blend weights b (`#V`) of the blended method, when the format has them
    /// (FBX: the skin's per-vertex weights for "weight blended" skins, Maya's defaults — 0 for
    /// linear skins, 1 for dual-quaternion skins — elsewhere). Give them to the rig with
    /// [`cagerig::session::RigParts::with_dq_blend_weights`]. `None` for glTF.
    pub dq_blend_weights: Option<cagerig::skinning::DqBlendWeights>,
    /// Validation and import warnings (weights renormalised, parts not imported, …).
    pub warnings: Vec<Warning>,
}

/// Morph targets of the skinned mesh that the animations animate, as world-space displacements.
/// Empty when no animation has a morph-weight channel on the skinned node, or when more than
/// one skinned node carries targets (then morph animation is reported as not imported).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MorphTargets {
    /// `#targets`, each `#V` (zero on primitives without targets).
    pub displacements: Vec<Vec<DVec3>>,
    /// The default weights (`#targets`), already applied to the rest skin M.
    pub default_weights: Vec<f64>,
}

/// One animation of the file as a skeleton track.
#[derive(Debug, Clone)]
pub struct ImportedAnimation {
    /// Name in the file (glTF: `animation<index>` when unnamed).
    pub name: String,
    /// Last key time in seconds.
    pub duration: f64,
    /// Keys at the union of the channels' key times (plus resampled times, see `exact`).
    pub track: SkeletonTrack,
    /// True when sampling the track reproduces the file's channels at every time (LINEAR and
    /// key-aligned channels); false when STEP or CUBICSPLINE channels were resampled.
    pub exact: bool,
    /// The morph weights of [`ImportedCharacter::morph_targets`] at the track's key times
    /// (`#keys × #targets`, row-major; lerped between keys like the track), when the animation
    /// has a morph-weight channel on the skinned node. Play them as a cage track with
    /// [`crate::morph_cage_track`].
    pub morph_weights: Option<Vec<f64>>,
}

/// What `cagerig info` lists about an imported file.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ImportSummary {
    /// "glTF" or "FBX".
    pub format: String,
    /// Vertices `#V` of the rest skin M.
    pub vertices: usize,
    /// Triangles of M.
    pub triangles: usize,
    /// The skinned primitives merged into M, in vertex order.
    pub primitives: Vec<PrimitiveSummary>,
    /// Joints `#J` of the imported skeleton S.
    pub joints: usize,
    /// Every skin in the file.
    pub skins: Vec<SkinSummary>,
    /// Index into `skins` of the skin that was imported.
    pub chosen_skin: usize,
    /// Largest number of non-zero weights of a vertex (row of Ω).
    pub max_influences: usize,
    /// `influences_histogram[k]` = number of vertices with k non-zero weights.
    pub influences_histogram: Vec<usize>,
    /// Weight rows that did not sum to 1 and were renormalised.
    pub renormalised_rows: usize,
    /// The imported animations, in order.
    pub animations: Vec<AnimationSummary>,
    /// Whether a cage was found inside the file.
    pub cage_in_file: bool,
    /// The file's axes and unit and the conversion to cagerig's space.
    pub space: SpaceSummary,
}

/// Axes and unit: the file's own, and how its coordinates were converted. The space every
/// import ends in is glTF's: right-handed, +Y up, +Z front, 1 unit = 1 metre.
#[derive(Debug, Clone, Serialize)]
pub struct SpaceSummary {
    /// The file's right, up and front axes (`+X`, `-Z`, …).
    pub file_right: String,
    /// The file's up axis.
    pub file_up: String,
    /// The file's front axis.
    pub file_front: String,
    /// Metres per unit of the file.
    pub file_unit_meters: f64,
    /// Whether coordinates were converted (false: already in the convention, kept as they are).
    pub converted: bool,
    /// `world_from_file`, the conversion applied, as a column-major 4×3 affine (12 numbers:
    /// three axis columns, then the translation).
    pub world_from_file: [f64; 12],
}

impl Default for SpaceSummary {
    /// glTF's own convention, kept as it is (the specification fixes it).
    fn default() -> Self {
        Self {
            file_right: "+X".into(),
            file_up: "+Y".into(),
            file_front: "+Z".into(),
            file_unit_meters: 1.0,
            converted: false,
            world_from_file: DAffine3::IDENTITY.to_cols_array(),
        }
    }
}

impl SpaceSummary {
    /// One line for `info`: the file's axes and unit and what was done with them.
    pub fn describe(&self) -> String {
        // Nine significant digits: 0.0254, not its binary neighbour 0.025400000000000002.
        let round = |x: f64| format!("{}", format!("{x:.8e}").parse::<f64>().unwrap_or(x));
        let file = format!(
            "right {}, up {}, front {}, {} m per unit",
            self.file_right,
            self.file_up,
            self.file_front,
            round(self.file_unit_meters)
        );
        if !self.converted {
            return format!("{file} (glTF's convention; kept)");
        }
        let m = DAffine3::from_cols_array(&self.world_from_file);
        let scale = m.matrix3.determinant().abs().cbrt();
        let is_identity = max_abs_diff(&m, &DAffine3::IDENTITY) <= 1e-12;
        let conversion = if is_identity {
            "none needed".to_string()
        } else {
            let r = m.matrix3 * (1.0 / scale);
            let col = |v: DVec3| format!("({:.0} {:.0} {:.0})", v.x + 0.0, v.y + 0.0, v.z + 0.0);
            format!(
                "scale {} × axes X→{} Y→{} Z→{}",
                round(scale),
                col(r.x_axis),
                col(r.y_axis),
                col(r.z_axis)
            )
        };
        format!("file: {file}; converted to right-handed, +Y up, +Z front, metres: {conversion}")
    }
}

/// One skinned primitive (glTF) or mesh node (FBX) merged into M.
#[derive(Debug, Clone, Serialize)]
pub struct PrimitiveSummary {
    /// Where it comes from, e.g. `node 1 "fox", mesh 0 primitive 0`.
    pub source: String,
    /// First vertex of this primitive in M.
    pub first_vertex: usize,
    /// Number of its vertices.
    pub vertices: usize,
    /// Number of its triangles.
    pub triangles: usize,
    /// Whether its triangles come from an index buffer (always true for FBX).
    pub indexed: bool,
}

/// One skin of the file.
#[derive(Debug, Clone, Serialize)]
pub struct SkinSummary {
    /// Its index in the file.
    pub index: usize,
    /// Its name, if it has one.
    pub name: Option<String>,
    /// Number of its joints.
    pub joints: usize,
}

/// One imported animation.
#[derive(Debug, Clone, Serialize)]
pub struct AnimationSummary {
    /// Its index in [`ImportedCharacter::animations`].
    pub index: usize,
    /// Its name.
    pub name: String,
    /// Last key time in seconds.
    pub duration: f64,
    /// Number of keyframes of its track.
    pub keys: usize,
    /// Whether the track reproduces the file exactly (see [`ImportedAnimation::exact`]).
    pub exact: bool,
    /// Whether the animation animates morph weights (played as a cage track).
    pub morph_weights: bool,
}

impl ImportedCharacter {
    /// The animation called `selector`, or with that index.
    pub fn find_animation(&self, selector: &str) -> Option<&ImportedAnimation> {
        self.animations
            .iter()
            .find(|a| a.name == selector)
            .or_else(|| {
                selector
                    .parse::<usize>()
                    .ok()
                    .and_then(|i| self.animations.get(i))
            })
    }

    /// Histogram and max of the influences per vertex, filled into the summary.
    pub(crate) fn fill_influence_summary(&mut self) {
        let n = self.skin_weights.num_vertices();
        let mut histogram = vec![0usize; self.skin_weights.max_influences() + 1];
        for v in 0..n {
            histogram[self.skin_weights.row(v).0.len()] += 1;
        }
        self.summary.max_influences = histogram.len() - 1;
        self.summary.influences_histogram = histogram;
        self.summary.vertices = self.mesh.num_vertices();
        self.summary.triangles = self.mesh.num_triangles();
        self.summary.joints = self.skeleton.len();
        self.summary.renormalised_rows = self
            .warnings
            .iter()
            .map(|w| match w {
                Warning::WeightsRenormalised { rows, .. } => *rows,
                _ => 0,
            })
            .sum();
        self.summary.cage_in_file = self.cage.is_some();
        self.summary.animations = self
            .animations
            .iter()
            .enumerate()
            .map(|(index, a)| AnimationSummary {
                index,
                name: a.name.clone(),
                duration: a.duration,
                keys: a.track.num_keyframes(),
                exact: a.exact,
                morph_weights: a.morph_weights.is_some(),
            })
            .collect();
    }
}

/// Whether a mesh node named `name` holds the character's cage: the name ends in `_cage`
/// (`<name>_cage`). The one rule of every format's cage lookup (glTF also accepts a node marked
/// with `extras.cagerig_cage`).
pub(crate) fn is_cage_name(name: &str) -> bool {
    name.ends_with("_cage")
}

/// Column lengths within this relative spread count as one uniform scale.
const UNIFORM_SCALE_TOLERANCE: f64 = 1e-5;

/// A rest frame whose linear part is a rotation times a nearly uniform scale (the usual case;
/// f32 inverse bind matrices are orthogonal only to ~1e-7) is snapped to exactly `s·R`, so that
/// rest locals `B_parent⁻¹ B_j` decompose exactly into rotation and scale and M' = M at rest to
/// round-off. The skinning then differs from the file's own matrices by their f32 rounding
/// (≈ 1e-7 relative). Frames with a genuinely non-uniform scale are kept as they are.
pub(crate) fn snap_to_similarity(frame: DAffine3) -> DAffine3 {
    let m = frame.matrix3;
    let lengths = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
    let mean = (lengths.x + lengths.y + lengths.z) / 3.0;
    let det = m.determinant();
    if mean.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || det <= 0.0
        || (lengths - DVec3::splat(mean)).abs().max_element() > UNIFORM_SCALE_TOLERANCE * mean
    {
        return frame;
    }
    let scale = det.cbrt();
    let rotation = DQuat::from_mat3(&(m * (1.0 / scale))).normalize();
    DAffine3::from_scale_rotation_translation(DVec3::splat(scale), rotation, frame.translation)
}

/// Largest entry-wise difference of two affine transforms.
pub(crate) fn max_abs_diff(a: &DAffine3, b: &DAffine3) -> f64 {
    let (x, y) = (a.to_cols_array(), b.to_cols_array());
    x.iter()
        .zip(&y)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()))
}
