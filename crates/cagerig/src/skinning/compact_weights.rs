//! Compact f32 copy of Ω (`#V × #J`, CSR) and the rest-space frame shared by the f32 per-frame
//! skinning kernels ([`super::lbs_f32`], [`super::dqs_f32`], [`super::cor_f32`]).
//!
//! Joint indices are u16, weights f32, the per-vertex pivot (heaviest joint, DQS/CoR sign
//! alignment) u16. Rest-space points are stored relative to a local origin `o` (the bounding-box
//! centre of the rest mesh) so that f32 coordinates stay small even for meshes far from the world
//! origin; the joint transforms are converted to `T_j ∘ translate(o)` (in f64, then rounded) so the
//! kernels output world coordinates directly.

use glam::{Affine3A, DAffine3, DVec3, Mat3A, Vec3A};

use crate::{RigError, SkinWeights};

/// Ω in f32 CSR form plus the per-vertex pivot joint.
#[derive(Debug, Clone)]
pub(crate) struct CompactWeights {
    pub num_joints: usize,
    /// `#V + 1` offsets into `joints` / `weights`.
    pub row_start: Vec<u32>,
    pub joints: Vec<u16>,
    pub weights: Vec<f32>,
    /// Heaviest joint per vertex (0 for unweighted vertices, unused there), `#V`.
    pub pivot: Vec<u16>,
}

impl CompactWeights {
    /// Errors if `#J` exceeds 65 536 (u16 joint indices).
    pub fn new(skin_weights: &SkinWeights) -> Result<Self, RigError> {
        let num_joints = skin_weights.num_joints();
        if num_joints > usize::from(u16::MAX) + 1 {
            return Err(RigError::IndexOutOfRange {
                what: "joint count for u16 joint indices",
                index: num_joints,
                len: usize::from(u16::MAX) + 1,
            });
        }
        let (row_start, joints, weights) = skin_weights.csr();
        Ok(Self {
            num_joints,
            row_start: row_start.to_vec(),
            joints: joints.iter().map(|&j| j as u16).collect(),
            weights: weights.iter().map(|&w| w as f32).collect(),
            pivot: (0..skin_weights.num_vertices())
                .map(|v| skin_weights.heaviest(v).unwrap_or(0) as u16)
                .collect(),
        })
    }

    pub fn num_vertices(&self) -> usize {
        self.row_start.len() - 1
    }
}

/// Local origin `o` of a point set: its bounding-box centre (zero when empty or non-finite).
pub(crate) fn local_origin(points: &[DVec3]) -> DVec3 {
    let (lo, hi) = crate::mesh::bounding_box(points);
    let centre = (lo + hi) * 0.5;
    if centre.is_finite() {
        centre
    } else {
        DVec3::ZERO
    }
}

/// `T ∘ translate(o)` rounded to f32: maps local rest coordinates `p − o` to world coordinates.
pub(crate) fn affine_from_local(transform: &DAffine3, origin: DVec3) -> Affine3A {
    let m = transform.matrix3;
    Affine3A {
        matrix3: Mat3A::from_cols(
            m.x_axis.as_vec3().into(),
            m.y_axis.as_vec3().into(),
            m.z_axis.as_vec3().into(),
        ),
        translation: Vec3A::from(transform.transform_point3(origin).as_vec3()),
    }
}
