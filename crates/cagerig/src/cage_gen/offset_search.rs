//! The offset search of cage generation (see the module docs of [`crate::cage_gen`]): grid
//! spacing from the target, then offsets from the tightest the grid guarantees upwards until a
//! cage reaches the target and passes the validator.

use web_time::Instant;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::bvh::{Aabb, TriangleBvh};
use super::distance_grid::{SampleGrid, fill_from_outside};
use super::layout::CageLayout;
use super::limb_separation::{BodyParts, cut_between_parts, dominant_joints_by_bones};
use super::marching_tets::extract_surface;
use super::simplify::{CollapseConstraints, StopAt, simplify};
use super::skeleton_guide::CageGuide;
use super::surface_clearance::{TIGHT_OFFSET_SPACINGS, check_start_surface, vertex_clearances};
use super::validate::{
    CageReport, CageRequirements, count_pieces, mesh_primitives, validate_cage_geometry,
};
use super::weld::{piece_representatives, weld_by_position};
use super::{CageGenError, CageOptions, CageTarget, MIN_VERTICES};
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;

/// Grid samples of the starting surface per target cage vertex (sets the spacing h):
/// enough for the quadric order to pick the cage's features, few enough to stay fast (the
/// marching-tetrahedra surface has about ten vertices per sample area h²). With the verified
/// tight first offset ([`super::surface_clearance`]) 8 gives the Arm a tighter cage than 20 at
/// the guaranteed offset did (mean distance 1.86 % vs 1.89 % of the diagonal, volume −13 %),
/// in a third of the collapses.
pub const SURFACE_SAMPLES_PER_CAGE_VERTEX: f64 = 8.0;
/// Extra padding of the sample grid, in spacings, so that the offset surface of a face lying
/// on the mesh's bounding box (a flat sole, a plate) does not fall on a grid plane: there the
/// field is clamped to ±[`super::distance_grid::MIN_FIELD`]·h and marching tetrahedra emit
/// clusters of near-coincident vertices joined by slivers, which block simplification. An
/// irrational fraction (2 − φ) keeps the coincidence away for every offset.
pub const GRID_SHIFT_SPACINGS: f64 = 0.381_966_011_250_105;
/// Growth of the offset between attempts.
pub const OFFSET_GROWTH: f64 = 1.5;
/// Largest offset tried, × diagonal.
pub const MAX_OFFSET: f64 = 0.5;
/// Cage self-separation kept during simplification, × diagonal.
pub const SEPARATION: f64 = 1e-6;

/// Grid spacing of the skeleton layout, × the offset layout's: fine enough that the cut
/// between two limbs (a sheet `SLAB_SPACINGS` thick, at least `keep` from either skin) fits
/// in the gaps of a character's limbs.
pub const SKELETON_SPACING_FACTOR: f64 = 0.5;
/// Thickness of the cut between two separable body parts, in grid spacings
/// ([`super::limb_separation`]).
pub const SLAB_SPACINGS: f64 = 2.0;
/// Least distance of a limb cut from the skin beyond the margin, in grid spacings: the first
/// attempt's surface is verified exactly ([`check_start_surface`]); when it fails the cut moves
/// out by [`KEEP_STEP_SPACINGS`] up to [`GUARANTEED_SPACINGS`], which the grid guarantees.
pub const KEEP_SPACINGS: f64 = 0.5;
/// Step of the limb cut's `keep` distance, and of the offset beyond it, after a starting
/// surface fails its exact check, in grid spacings.
pub const KEEP_STEP_SPACINGS: f64 = 0.5;
/// First offset of the skeleton layout above the margin, in grid spacings: beyond `keep`, so
/// that the solid has room to be cut between limbs.
pub const SKELETON_OFFSET_SPACINGS: f64 = 1.25;
/// Offset above which the limb cut's `keep` distance is verified rather than guaranteed, in
/// grid spacings (as [`TIGHT_OFFSET_SPACINGS`]).
const GUARANTEED_SPACINGS: f64 = 1.75;

/// The rig a cage is generated for: its skeleton S and, when it has them, its skinning
/// weights Ω (whose heaviest joint per vertex decides the body parts; without them, the
/// nearest bone does).
#[derive(Debug, Clone, Copy)]
pub struct CageRig<'a> {
    /// The rest skeleton S.
    pub skeleton: &'a Skeleton,
    /// Skinning weights Ω (`#V` rows), if the rig has them.
    pub weights: Option<&'a SkinWeights>,
}

/// Figures of one generation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GenerationStats {
    /// Offset of the accepted surface, × diagonal.
    pub offset_fraction: f64,
    /// Grid spacing h, × diagonal.
    pub spacing_fraction: f64,
    /// Points of the sample grid of the accepted attempt.
    pub grid_points: usize,
    /// Exact nearest-triangle queries of the accepted attempt.
    pub exact_distance_queries: usize,
    /// Vertices of the marching-tetrahedra surface before simplification.
    pub surface_vertices: usize,
    /// Edge collapses of the simplification.
    pub collapses: usize,
    /// Candidate collapse positions rejected by the geometric constraints.
    pub rejected_positions: usize,
    /// Edge flips after the collapses (needles on flat parts replaced by fair triangles).
    pub flips: usize,
    /// Connected pieces of the (welded) mesh.
    pub mesh_pieces: usize,
    /// One line per offset tried.
    pub attempts: Vec<String>,
    /// Seconds spent per stage, summed over the offsets tried.
    pub stage_seconds: StageSeconds,
    /// Total wall-clock seconds of the generation.
    pub seconds: f64,
    /// The layout used ([`CageLayout::Offset`] when the rig had no skeleton).
    pub layout: CageLayout,
    /// Body parts of the skeleton layout (joints that dominate a skin vertex); 0 otherwise.
    pub body_parts: usize,
    /// Grid points cut between limbs in the accepted attempt.
    pub cut_points: usize,
    /// Articulation rings that guided the simplification.
    pub articulation_rings: usize,
}

/// Seconds per stage of [`generate_cage`] (summed over the offsets tried).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StageSeconds {
    /// Welding, pieces and the mesh BVH.
    pub setup: f64,
    /// Distance sampling and the fill from outside.
    pub distance_grid: f64,
    /// Marching tetrahedra and the piece count.
    pub surface: f64,
    /// Constrained edge collapses.
    pub simplify: f64,
    /// [`validate_cage_geometry`].
    pub validate: f64,
}

/// A cage that passed [`validate_cage_geometry`], its report and how it was made. It goes
/// through serde whole (the web page generates a cage in a worker and hands it to the page).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GeneratedCage {
    /// The cage C.
    pub cage: TriMesh,
    /// Its validation report.
    pub report: CageReport,
    /// Figures of the generation.
    pub stats: GenerationStats,
}

/// Generates a cage for `mesh` (see [`crate::cage_gen`]).
pub fn generate_cage(mesh: &TriMesh, options: &CageOptions) -> Result<GeneratedCage, CageGenError> {
    generate_guided_cage(mesh, options, &CageGuide::default())
}

/// [`generate_cage`] with the collapse order guided by `guide` (see [`super::skeleton_guide`]).
pub fn generate_guided_cage(
    mesh: &TriMesh,
    options: &CageOptions,
    guide: &CageGuide,
) -> Result<GeneratedCage, CageGenError> {
    generate(mesh, options, guide, None)
}

/// A cage for a rigged character: with a skeleton and [`CageLayout::Skeleton`], limbs are
/// kept apart by the skin's dominant joints ([`super::limb_separation`]) on a grid
/// [`SKELETON_SPACING_FACTOR`] as fine, and articulation rings guide the simplification
/// ([`super::skeleton_guide`]); otherwise [`generate_cage`].
pub fn generate_rig_cage(
    mesh: &TriMesh,
    options: &CageOptions,
    rig: Option<CageRig<'_>>,
) -> Result<GeneratedCage, CageGenError> {
    let rig = match (options.layout, rig) {
        (CageLayout::Skeleton, Some(rig)) if !rig.skeleton.is_empty() => rig,
        (CageLayout::Skeleton | CageLayout::Offset, _) => return generate_cage(mesh, options),
    };
    let dominant: Vec<usize> = match rig.weights {
        Some(w) if w.num_vertices() == mesh.num_vertices() && w.num_entries() > 0 => {
            let by_bones = dominant_joints_by_bones(mesh, rig.skeleton);
            (0..mesh.num_vertices())
                .map(|v| w.heaviest(v).unwrap_or(by_bones[v]))
                .collect()
        }
        Some(_) | None => dominant_joints_by_bones(mesh, rig.skeleton),
    };
    let parts = BodyParts::new(mesh, rig.skeleton, &dominant)?;
    let guide = CageGuide::from_skeleton(rig.skeleton);
    generate(mesh, options, &guide, Some(&parts))
}

fn generate(
    mesh: &TriMesh,
    options: &CageOptions,
    guide: &CageGuide,
    parts: Option<&BodyParts>,
) -> Result<GeneratedCage, CageGenError> {
    let start = Instant::now();
    if let Some(vertex) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(CageGenError::NonFinite { vertex });
    }
    if mesh.triangles.is_empty() {
        return Err(CageGenError::NoTriangles);
    }
    let target = options.target.vertices();
    if target < MIN_VERTICES {
        return Err(CageGenError::TargetTooSmall {
            requested: target,
            minimum: MIN_VERTICES,
        });
    }
    if !(0.0..0.1).contains(&options.margin) {
        return Err(CageGenError::InvalidMargin {
            margin: options.margin,
        });
    }
    let (lo, hi) = mesh.bounding_box();
    let diag = (hi - lo).length();
    if diag <= 0.0 {
        return Err(CageGenError::NoExtent);
    }
    let bounds = Aabb { min: lo, max: hi };
    let margin = options.margin * diag;
    let welded = weld_by_position(&mesh.positions, 0.0);
    let reps = piece_representatives(mesh.num_vertices(), &mesh.triangles, &welded);
    let piece_points: Vec<DVec3> = reps.iter().map(|&v| mesh.positions[v]).collect();
    let bvh = TriangleBvh::new(mesh_primitives(mesh));
    let mut stage_seconds = StageSeconds::default();
    let mut stage_start = Instant::now();
    let mut lap = |stage: &mut f64| {
        let now = Instant::now();
        *stage += (now - stage_start).as_secs_f64();
        stage_start = now;
    };
    lap(&mut stage_seconds.setup);
    let area: f64 = (0..mesh.num_triangles())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let longest = (hi - lo).max_element();
    let spacing_factor = if parts.is_some() {
        SKELETON_SPACING_FACTOR
    } else {
        1.0
    };
    let mut spacing = spacing_factor
        * (area / (SURFACE_SAMPLES_PER_CAGE_VERTEX * target as f64))
            .sqrt()
            .clamp(longest / 200.0, longest / 16.0);
    let requirements = CageRequirements {
        margin,
        target_vertices: matches!(options.target, CageTarget::Vertices(_)).then_some(target),
        target_faces: match options.target {
            CageTarget::Faces(f) => Some(f),
            CageTarget::Vertices(_) => None,
        },
    };
    let stop = match options.target {
        CageTarget::Vertices(n) => StopAt::Vertices(n),
        CageTarget::Faces(f) => StopAt::Faces(f),
    };
    let constraints = CollapseConstraints {
        mesh: &bvh,
        margin,
        separation: SEPARATION * diag,
        piece_points: &piece_points,
    };
    let mut attempts = Vec::new();
    let mut best_reached: Option<(usize, f64)> = None;
    let mut last_pieces: Option<(usize, f64)> = None;
    let mut last_failures = Vec::new();
    let mut refinements = 0;
    let mut keep_spacings = KEEP_SPACINGS;
    // Offset ≥ margin + h√3 guarantees the starting surface keeps the margin (marching_tets);
    // a tighter one is tried first and its surface verified (surface_clearance).
    let guaranteed = |spacing: f64| margin + spacing * 3f64.sqrt() * 1.01;
    let first_offset_spacings = if parts.is_some() {
        SKELETON_OFFSET_SPACINGS
    } else {
        TIGHT_OFFSET_SPACINGS
    };
    let mut offset = margin + spacing * first_offset_spacings;
    while offset <= MAX_OFFSET * diag {
        let grid = SampleGrid::around(
            bounds,
            spacing,
            offset + (2.0 + GRID_SHIFT_SPACINGS) * spacing,
        );
        let grid_points = grid.num_points();
        let mut field = fill_from_outside(grid, &bvh, bounds, offset);
        let queries = field.exact_queries;
        let cut_points = parts.map_or(0, |parts| {
            cut_between_parts(
                &mut field,
                &bvh,
                parts,
                offset,
                margin + keep_spacings * spacing,
                SLAB_SPACINGS * spacing,
            )
        });
        lap(&mut stage_seconds.distance_grid);
        let surface = extract_surface(&field);
        drop(field);
        let surface_vertices = surface.positions.len();
        let pieces = count_pieces(&surface.triangles, surface_vertices);
        lap(&mut stage_seconds.surface);
        let offset_percent = 100.0 * offset / diag;
        if pieces != 1 {
            attempts.push(format!(
                "offset {offset_percent:.2} %: {pieces} separate surface pieces"
            ));
            last_pieces = Some((pieces, offset_percent));
            offset *= OFFSET_GROWTH;
            continue;
        }
        if surface_vertices < target + target / 2 && refinements < 3 {
            // Too coarse to simplify down to the target: refine the grid at the same offset.
            attempts.push(format!(
                "offset {offset_percent:.2} %: surface has only {surface_vertices} vertices; halving the spacing"
            ));
            spacing *= 0.5;
            refinements += 1;
            offset = offset.max(margin + spacing * TIGHT_OFFSET_SPACINGS);
            continue;
        }
        let clearances = vertex_clearances(&surface, &bvh);
        if (offset < guaranteed(spacing) || cut_points > 0)
            && let Err(why) =
                check_start_surface(&surface, &clearances, &bvh, margin, &piece_points)
        {
            if cut_points > 0 && keep_spacings < GUARANTEED_SPACINGS {
                // Cut farther from the skin, with the offset beyond the cut so that there is
                // still solid to cut.
                keep_spacings = (keep_spacings + KEEP_STEP_SPACINGS).min(GUARANTEED_SPACINGS);
                offset = offset.max(margin + (keep_spacings + KEEP_STEP_SPACINGS) * spacing);
                attempts.push(format!(
                    "offset {offset_percent:.2} %: starting surface rejected ({why}); cutting limbs apart from margin + {keep_spacings:.2}·h, offset {:.2} %",
                    100.0 * offset / diag
                ));
                lap(&mut stage_seconds.surface);
                continue;
            }
            if offset >= guaranteed(spacing) {
                attempts.push(format!(
                    "offset {offset_percent:.2} %: starting surface rejected ({why})"
                ));
                offset *= OFFSET_GROWTH;
                lap(&mut stage_seconds.surface);
                continue;
            }
            attempts.push(format!(
                "offset {offset_percent:.2} %: starting surface rejected ({why}); trying the offset the grid guarantees"
            ));
            offset = guaranteed(spacing);
            lap(&mut stage_seconds.surface);
            continue;
        }
        lap(&mut stage_seconds.surface);
        let simplified = simplify(surface, clearances, guide, stop, constraints);
        lap(&mut stage_seconds.simplify);
        let reached = simplified.positions.len();
        if !simplified.reached {
            attempts.push(format!(
                "offset {offset_percent:.2} %: simplification stopped at {reached} vertices"
            ));
            if best_reached.is_none_or(|(r, _)| reached < r) {
                best_reached = Some((reached, offset_percent));
            }
            offset *= OFFSET_GROWTH;
            continue;
        }
        let cage = TriMesh {
            positions: simplified.positions,
            triangles: simplified.triangles,
        };
        let report = validate_cage_geometry(&cage, mesh, &requirements);
        lap(&mut stage_seconds.validate);
        if !report.passed() {
            last_failures = report.failures();
            attempts.push(format!(
                "offset {offset_percent:.2} %: validation failed: {}",
                last_failures.join("; ")
            ));
            offset *= OFFSET_GROWTH;
            continue;
        }
        attempts.push(format!(
            "offset {offset_percent:.2} %: {reached} vertices, validated"
        ));
        let stats = GenerationStats {
            offset_fraction: offset / diag,
            spacing_fraction: spacing / diag,
            grid_points,
            exact_distance_queries: queries,
            surface_vertices,
            collapses: simplified.collapses,
            rejected_positions: simplified.rejections,
            flips: simplified.flips,
            mesh_pieces: reps.len(),
            attempts,
            stage_seconds,
            seconds: start.elapsed().as_secs_f64(),
            layout: if parts.is_some() {
                CageLayout::Skeleton
            } else {
                CageLayout::Offset
            },
            body_parts: parts.map_or(0, |p| p.joints.len()),
            cut_points,
            articulation_rings: guide.planes.len(),
        };
        return Ok(GeneratedCage {
            cage,
            report,
            stats,
        });
    }
    if !last_failures.is_empty() {
        return Err(CageGenError::ValidationFailed {
            failures: last_failures,
        });
    }
    if let Some((reached, offset_percent)) = best_reached {
        return Err(CageGenError::TargetNotReached {
            target,
            reached,
            offset_percent,
        });
    }
    let (pieces, offset_percent) = last_pieces.unwrap_or((0, 100.0 * offset / diag));
    Err(CageGenError::SeparatePieces {
        pieces,
        offset_percent,
    })
}
