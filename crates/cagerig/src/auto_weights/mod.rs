//! Automatic skinning weights Ω (`#V × #J`) from a mesh and a skeleton, computed in the volume.
//!
//! Method (geodesic voxel binding, Dionne & de Lasa, SCA 2013):
//! 1. [`hole_caps`], [`voxel_grid`] — cap the mesh's holes (up to a fraction of its size),
//!    voxelise its surface triangle by triangle and fill what it encloses (closing small gaps;
//!    a cage's interior, when given, is part of the volume), so triangle soups, several
//!    pieces, non-manifold edges and holes all work;
//! 2. [`bones`] — the deforming joints and their bone segments (joint → each child; tips by
//!    [`TipJoints`]);
//! 3. [`geodesic`] — for each deforming joint, the geodesic distance through the solid voxels
//!    from its bones, sampled at every vertex (a vertex in no reachable voxel falls back to the
//!    straight distance);
//! 4. [`falloff`] — `w_j ∝ (d_min / d_j)^p`, the `max_influences` strongest kept continuously,
//!    rows normalised.
//!
//! The result is ≥ 0, rows sum to 1, each row has at most `max_influences` entries, and a joint
//! gets weight only if it deforms ([`bones`]). See `docs/weights.md` for the figures.

pub mod bones;
pub mod falloff;
pub mod geodesic;
pub mod hole_caps;
pub mod voxel_grid;

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use rayon::prelude::*;
use thiserror::Error;

pub use bones::{BoneSegment, TipJoints};

use crate::cage_gen::geometry::closest_point_on_segment;
use crate::error::RigError;
use crate::{Skeleton, SkinWeights, TriMesh, Warning};
use geodesic::SolidVoxels;
use voxel_grid::VoxelGrid;

/// Default most influences per vertex (as glTF's `JOINTS_0`).
pub const DEFAULT_MAX_INFLUENCES: usize = 4;
/// Default voxels along the longest side of the mesh's box.
pub const DEFAULT_RESOLUTION: usize = 128;
/// Default falloff exponent p of `w ∝ (d_min / d)^p`.
pub const DEFAULT_EXPONENT: f64 = 8.0;
/// Most voxels a grid may have (a few bytes each).
pub const MAX_VOXELS: usize = 64 << 20;

/// Options of [`AutoWeights`] (serialised with serde; [`AutoWeights::new`] checks them).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AutoWeightsOptions {
    /// Most joints influencing one vertex (≥ 1).
    pub max_influences: usize,
    /// Voxels along the longest side of the mesh's box (8 … 1024): finer separates closer
    /// limbs (fingers) at the cost of time.
    pub resolution: usize,
    /// Falloff exponent p (0 < p ≤ 32): larger gives sharper transitions at the joints.
    pub exponent: f64,
    /// Which tip joints (no child) deform.
    pub tips: TipJoints,
    /// Length of a deforming tip's bone, × its parent's bone length (0 … 10).
    pub tip_length: f64,
    /// Holes up to about `2·closing + 1` voxels wide are closed before filling (0 … 8).
    pub closing: usize,
    /// Holes (boundary loops) whose box diagonal is below this fraction of the mesh's are
    /// capped before filling (0 … 1; 0 caps none).
    pub max_hole_fraction: f64,
}

impl Default for AutoWeightsOptions {
    fn default() -> Self {
        Self {
            max_influences: DEFAULT_MAX_INFLUENCES,
            resolution: DEFAULT_RESOLUTION,
            exponent: DEFAULT_EXPONENT,
            tips: TipJoints::default(),
            tip_length: 1.0,
            closing: 1,
            max_hole_fraction: hole_caps::DEFAULT_MAX_HOLE_FRACTION,
        }
    }
}

/// Why no weights were computed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AutoWeightsError {
    /// An option is out of its range.
    #[error("option {option}: expected {expected}, found {found}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// The accepted values.
        expected: &'static str,
        /// The value given.
        found: String,
    },
    /// The mesh has no triangle.
    #[error("the mesh has no triangles: expected a surface to bind ({vertices} vertices)")]
    NoTriangles {
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// All vertices of the mesh coincide.
    #[error("the mesh has no extent: all its {vertices} vertices coincide")]
    NoExtent {
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// The cage has no triangle.
    #[error("the cage has no triangles ({vertices} vertices): expected a closed cage")]
    CageHasNoTriangles {
        /// Vertices of the cage.
        vertices: usize,
    },
    /// The skeleton has no joint.
    #[error("the skeleton has no joints: expected at least one joint to bind to")]
    EmptySkeleton,
    /// No joint deforms (every bone has zero length and every tip is static).
    #[error(
        "none of the {joints} joints deforms: every bone has zero length and no tip joint is \
         set to deform (expected joints at distinct positions, or deforming tips)"
    )]
    NoDeformingJoint {
        /// Joints of the skeleton.
        joints: usize,
    },
    /// A joint listed as a deforming tip has children or does not exist.
    #[error(
        "joint {joint} was listed as a deforming tip, but expected a joint with no child among \
         the {joints} joints"
    )]
    NotATip {
        /// The joint index given.
        joint: usize,
        /// Joints of the skeleton.
        joints: usize,
    },
    /// The grid would be too large.
    #[error(
        "a {dims:?} voxel grid ({voxels} voxels) exceeds the limit of {max}; lower the \
         resolution (asked for {resolution})"
    )]
    TooManyVoxels {
        /// Voxels per axis.
        dims: [usize; 3],
        /// Voxels in all.
        voxels: usize,
        /// [`MAX_VOXELS`].
        max: usize,
        /// The resolution asked for.
        resolution: usize,
    },
    /// Most of the skeleton's bones lie outside the mesh's volume: the skeleton is in another
    /// space (offset, scale or units) than the mesh.
    #[error(
        "{outside} of the {deforming} deforming joints lie outside the mesh: {joints}; expected \
         the skeleton inside the body, in the mesh's space (the skeleton spans {skeleton_box}, \
         the mesh {mesh_box}): check that they share units, scale and origin, or move the \
         skeleton into the mesh"
    )]
    SkeletonOutsideMesh {
        /// Deforming joints whose bones cross no part of the volume.
        outside: usize,
        /// Deforming joints in all.
        deforming: usize,
        /// The farthest joints, by name, with their distance to the volume.
        joints: String,
        /// The skeleton's joints' bounding box, as text.
        skeleton_box: String,
        /// The mesh's bounding box, as text.
        mesh_box: String,
    },
    /// The weights failed validation (a bug if it happens).
    #[error("the computed weights are invalid: {0}")]
    Weights(#[from] RigError),
}

/// The stage of a computation, for a progress bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Surface voxelisation and fill (`total` = 1).
    Voxelising,
    /// Geodesic distances, one step per deforming joint.
    Distances,
    /// Falloff and normalisation (`total` = 1).
    Weights,
}

/// Progress of a computation: `done` of `total` steps of `stage`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// The current stage.
    pub stage: Stage,
    /// Steps done in this stage.
    pub done: usize,
    /// Steps in this stage.
    pub total: usize,
}

/// What a computation found besides the weights.
#[derive(Debug, Clone, PartialEq)]
pub struct AutoWeightsReport {
    /// Voxels per axis.
    pub dims: [usize; 3],
    /// Voxel edge length h, world units.
    pub spacing: f64,
    /// Voxels of the solid.
    pub solid_voxels: usize,
    /// Holes of the mesh capped before filling.
    pub capped_holes: usize,
    /// Joints that deform (ascending); the others get no weight.
    pub deforming_joints: Vec<usize>,
    /// Vertices in no solid voxel any bone reaches, weighted by straight distances.
    pub straight_distance_vertices: usize,
    /// Warnings (e.g. vertices weighted by straight distances).
    pub warnings: Vec<Warning>,
}

/// Computed weights and their report.
#[derive(Debug, Clone, PartialEq)]
pub struct AutoWeightsResult {
    /// Ω, `#V × #J` (the skeleton's joint order).
    pub weights: SkinWeights,
    /// How they were computed.
    pub report: AutoWeightsReport,
}

/// Automatic skinning weights with validated options.
#[derive(Debug, Clone, PartialEq)]
pub struct AutoWeights {
    options: AutoWeightsOptions,
}

impl AutoWeights {
    /// Validates the options.
    pub fn new(options: AutoWeightsOptions) -> Result<Self, AutoWeightsError> {
        let invalid = |option, expected, found: String| AutoWeightsError::InvalidOption {
            option,
            expected,
            found,
        };
        if options.max_influences == 0 {
            return Err(invalid("max_influences", "at least 1", "0".into()));
        }
        if !(8..=1024).contains(&options.resolution) {
            return Err(invalid(
                "resolution",
                "8 … 1024 voxels",
                options.resolution.to_string(),
            ));
        }
        if !(options.exponent.is_finite() && options.exponent > 0.0 && options.exponent <= 32.0) {
            return Err(invalid(
                "exponent",
                "a number in (0, 32]",
                options.exponent.to_string(),
            ));
        }
        if !(options.tip_length.is_finite() && (0.0..=10.0).contains(&options.tip_length)) {
            return Err(invalid(
                "tip_length",
                "a number in [0, 10]",
                options.tip_length.to_string(),
            ));
        }
        if !(0.0..=1.0).contains(&options.max_hole_fraction) {
            return Err(invalid(
                "max_hole_fraction",
                "a number in [0, 1]",
                options.max_hole_fraction.to_string(),
            ));
        }
        if options.closing > 8 {
            return Err(invalid(
                "closing",
                "0 … 8 voxels",
                options.closing.to_string(),
            ));
        }
        Ok(Self { options })
    }

    /// The options.
    pub fn options(&self) -> &AutoWeightsOptions {
        &self.options
    }

    /// Ω for `mesh` (rest skin M, any triangles) bound to `skeleton` (rest pose, same space);
    /// `cage`, when given, is a closed cage around the mesh whose interior is part of the volume.
    pub fn compute(
        &self,
        mesh: &TriMesh,
        skeleton: &Skeleton,
        cage: Option<&TriMesh>,
    ) -> Result<AutoWeightsResult, AutoWeightsError> {
        self.compute_with_progress(mesh, skeleton, cage, &|_| {})
    }

    /// [`AutoWeights::compute`], calling `progress` (from any thread) as stages advance.
    pub fn compute_with_progress(
        &self,
        mesh: &TriMesh,
        skeleton: &Skeleton,
        cage: Option<&TriMesh>,
        progress: &(dyn Fn(Progress) + Sync),
    ) -> Result<AutoWeightsResult, AutoWeightsError> {
        let o = &self.options;
        let n = mesh.num_vertices();
        if mesh.num_triangles() == 0 {
            return Err(AutoWeightsError::NoTriangles { vertices: n });
        }
        if skeleton.is_empty() {
            return Err(AutoWeightsError::EmptySkeleton);
        }
        if let Some(c) = cage
            && c.num_triangles() == 0
        {
            return Err(AutoWeightsError::CageHasNoTriangles {
                vertices: c.num_vertices(),
            });
        }
        let segments = bones::bone_segments(skeleton, &o.tips, o.tip_length).map_err(|joint| {
            AutoWeightsError::NotATip {
                joint,
                joints: skeleton.len(),
            }
        })?;
        let mut deforming: Vec<usize> = segments.iter().map(|s| s.joint).collect();
        deforming.dedup();
        if deforming.is_empty() {
            return Err(AutoWeightsError::NoDeformingJoint {
                joints: skeleton.len(),
            });
        }

        // 1. The volume.
        progress(Progress {
            stage: Stage::Voxelising,
            done: 0,
            total: 1,
        });
        let (mut lo, mut hi) = mesh.bounding_box();
        if (hi - lo).max_element() <= 0.0 {
            return Err(AutoWeightsError::NoExtent { vertices: n });
        }
        if let Some(c) = cage {
            let (clo, chi) = c.bounding_box();
            lo = lo.min(clo);
            hi = hi.max(chi);
        }
        let grid = VoxelGrid::around(lo, hi, o.resolution);
        let voxels = grid.dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if voxels.is_none_or(|v| v > MAX_VOXELS) {
            return Err(AutoWeightsError::TooManyVoxels {
                dims: grid.dims,
                voxels: voxels.unwrap_or(usize::MAX),
                max: MAX_VOXELS,
                resolution: o.resolution,
            });
        }
        let (caps, capped_holes) = if o.max_hole_fraction > 0.0 {
            hole_caps::hole_caps(&mesh.positions, &mesh.triangles, o.max_hole_fraction)
        } else {
            (Vec::new(), 0)
        };
        let surface = if caps.is_empty() {
            voxel_grid::surface_voxels(&grid, &mesh.positions, &mesh.triangles)
        } else {
            let mut positions = mesh.positions.clone();
            let mut triangles = mesh.triangles.clone();
            for cap in caps {
                let base = positions.len() as u32;
                positions.extend(cap);
                triangles.push([base, base + 1, base + 2]);
            }
            voxel_grid::surface_voxels(&grid, &positions, &triangles)
        };
        let cage_solid = cage.map(|c| {
            let s = voxel_grid::surface_voxels(&grid, &c.positions, &c.triangles);
            voxel_grid::solid_voxels(&grid, &s, 0, None)
        });
        let solid_mask =
            voxel_grid::solid_voxels(&grid, &surface, o.closing, cage_solid.as_deref());
        let solid = SolidVoxels::new(grid, &solid_mask);
        let outside_warning = skeleton_outside(skeleton, &segments, &deforming, &solid, lo, hi)?;
        progress(Progress {
            stage: Stage::Voxelising,
            done: 1,
            total: 1,
        });

        // 2–3. Geodesic distances per deforming joint, sampled at the vertices.
        let done = AtomicUsize::new(0);
        let total = deforming.len();
        let distances: Vec<Vec<f64>> = deforming
            .par_iter()
            .map(|&j| {
                let own: Vec<BoneSegment> =
                    segments.iter().filter(|s| s.joint == j).copied().collect();
                let dist = solid.distances(&solid.seeds(&own));
                let sampled = solid.sample(&dist, &mesh.positions);
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(Progress {
                    stage: Stage::Distances,
                    done: d,
                    total,
                });
                sampled
            })
            .collect();

        // Vertices no bone reaches through the volume: straight distances to the bones.
        progress(Progress {
            stage: Stage::Weights,
            done: 0,
            total: 1,
        });
        let unreached: Vec<usize> = (0..n)
            .filter(|&v| distances.iter().all(|d| !d[v].is_finite()))
            .collect();
        let mut distances = distances;
        for &v in &unreached {
            for (k, &j) in deforming.iter().enumerate() {
                distances[k][v] = straight_distance(mesh.positions[v], &segments, j);
            }
        }

        // 4. Falloff.
        let rows = falloff::falloff_rows(
            &deforming,
            &distances,
            n,
            o.max_influences,
            o.exponent,
            0.5 * solid.grid.spacing,
        );
        let triplets = rows
            .iter()
            .enumerate()
            .flat_map(|(v, row)| row.iter().map(move |&(j, w)| (v, j, w)));
        let (weights, mut warnings) = SkinWeights::from_triplets(n, skeleton.len(), triplets)?;
        warnings.extend(outside_warning);
        if let Some(&first) = unreached.first() {
            warnings.push(Warning::Note {
                message: format!(
                    "{} vertices (first: vertex {first}) lie in a part of the volume no bone \
                     reaches; they were weighted by straight distance to the bones",
                    unreached.len()
                ),
            });
        }
        progress(Progress {
            stage: Stage::Weights,
            done: 1,
            total: 1,
        });
        Ok(AutoWeightsResult {
            weights,
            report: AutoWeightsReport {
                dims: solid.grid.dims,
                spacing: solid.grid.spacing,
                solid_voxels: solid.len(),
                capped_holes,
                deforming_joints: deforming,
                straight_distance_vertices: unreached.len(),
                warnings,
            },
        })
    }
}

/// Deforming joints farther than a voxel from the volume: an error when they are most of the
/// skeleton (it is in another space than the mesh), else a warning naming them. `lo`, `hi`:
/// the volume's box.
fn skeleton_outside(
    skeleton: &Skeleton,
    segments: &[BoneSegment],
    deforming: &[usize],
    solid: &SolidVoxels,
    lo: DVec3,
    hi: DVec3,
) -> Result<Option<Warning>, AutoWeightsError> {
    let mut outside: Vec<(usize, f64)> = deforming
        .par_iter()
        .map(|&j| {
            let own: Vec<BoneSegment> = segments.iter().filter(|s| s.joint == j).copied().collect();
            (j, solid.distance_outside(&own))
        })
        .filter(|&(_, d)| d > solid.grid.spacing)
        .collect();
    if outside.is_empty() {
        return Ok(None);
    }
    outside.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let diagonal = (hi - lo).length();
    const LISTED: usize = 5;
    let mut joints = outside
        .iter()
        .take(LISTED)
        .map(|&(j, d)| {
            format!(
                "{} {:.3} away ({:.0} % of the mesh's diagonal)",
                skeleton.joint(j).name,
                d,
                100.0 * d / diagonal
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    if outside.len() > LISTED {
        joints.push_str(&format!(" and {} more", outside.len() - LISTED));
    }
    if 2 * outside.len() > deforming.len() {
        let (slo, shi) = crate::mesh::bounding_box(&skeleton.rest_positions());
        let text = |a: DVec3, b: DVec3| {
            format!(
                "[{:.3}, {:.3}, {:.3}]..[{:.3}, {:.3}, {:.3}]",
                a.x, a.y, a.z, b.x, b.y, b.z
            )
        };
        return Err(AutoWeightsError::SkeletonOutsideMesh {
            outside: outside.len(),
            deforming: deforming.len(),
            joints,
            skeleton_box: text(slo, shi),
            mesh_box: text(lo, hi),
        });
    }
    Ok(Some(Warning::Note {
        message: format!(
            "{} of the {} deforming joints lie outside the mesh: {joints}; they are weighted \
             from the nearest part of the body (move them inside for weights that follow them)",
            outside.len(),
            deforming.len()
        ),
    }))
}

/// Distance from `p` to the nearest bone segment of joint `joint`.
fn straight_distance(p: DVec3, segments: &[BoneSegment], joint: usize) -> f64 {
    segments
        .iter()
        .filter(|s| s.joint == joint)
        .map(|s| p.distance(closest_point_on_segment(p, s.start, s.end)))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests;
