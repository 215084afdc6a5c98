//! The coupled rig session: the six structures M, S, C (rest) and M', S', C' (current) kept in
//! consensus under any interleaving of the three user interactions (Section 4, Figures 3–4):
//! editing the current skeleton S', the rest cage C, or the current cage C'.
//!
//! Pose parametrisation ([`crate::pose`]): the current skeleton is given by local joint rotations,
//! local scales and translation offsets (root motion, and for imported animations the animated
//! translation of any joint); bone offsets always come from the rest skeleton. When SkelUp moves
//! the rest joints, rotations, scales and offsets are thus kept and the translations T_j^t
//! re-derived root-first (Sec. 4.2).
//! Every event ends with C' = CageUp(M') so that the loop C' → C → S → S' → C' is closed.
//!
//! The session holds the six structures and the pose, and coordinates components that own their
//! state and invariants: the rest map ([`rest_map`]: M = f(C), CageUp, CageRev, by coordinates
//! kind), SkelUp ([`SkeletonUpdater`]), the skinning ([`skinning`]: the method with its data),
//! the f32 display path ([`display_path`]) and the checkpoint of an event ([`checkpoint`]). The
//! events live in their own files (`cage_events`, `pose_events`, `cage_sync`, `green_sync`,
//! `display_events`, `state_restore`, `events`); `docs/architecture.md` draws the whole.

use glam::{DAffine3, DMat3, DQuat, DVec3};

use crate::cage_coords::CageCoords;
use crate::cage_enclosure::validate_cage_for_mesh;
use crate::error::{RigError, Warning};
use crate::mesh::TriMesh;
use crate::pose::{LocalPose, decompose_rest_local, regularise_rest_frames};
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
use crate::skinning::blended::BlendedSkinning;
use crate::skinning::lbs::LinearBlendSkinning;
use crate::sync::skeleton_updater::{JointFaceTerms, SkeletonUpdater};

mod accessors;
mod animation_sample;
mod cage_events;
mod cage_fit;
mod cage_sync;
mod checkpoint;
mod display_events;
mod display_path;
mod display_rest_map;
mod editable_state;
mod events;
mod external_skinning;
mod green;
mod green_binding;
mod green_cage_up;
mod green_sync;
mod parts;
mod pose_events;
mod rebind;
mod reskeleton;
mod rest_map;
mod skinning;
mod state_restore;
mod sync_chain;
#[cfg(test)]
mod test_rigs;
mod unfitted_cage;
use checkpoint::Checkpoint;
pub use checkpoint::MAX_STATE_MAGNITUDE;
use display_path::DisplayPath;
pub use display_path::DisplayPrecision;
pub use display_rest_map::{
    DisplayRestMap, DisplayRestMapBackend, DisplayRestMapProduct, DyadicProductCheck,
};
pub use editable_state::{EditableState, SyncLocks};
pub use external_skinning::{BoundSkinning, SkinningBackend, SkinningBindInput};
pub use green::GREEN_FIT_LIMIT;
pub use parts::{
    BindProgress, BindStage, CageFitSource, FitRows, FitRowsKind, GRID_COR_CENTRES_ABOVE,
    GivenCageCoords, PHI_C_TOLERANCE, PHI_C_TOLERANCE_F32, RigParts, SessionOptions,
    UnknownCageFitSource, UnknownFitRowsKind, centre_coords_method, compute_centre_coords,
};
use rest_map::{BoundRestMap, GivenCoords, RestMap};
use skinning::{CorSource, RigSkinning};
pub use unfitted_cage::{UnfittedCagePolicy, UnknownUnfittedCagePolicy};

/// The rest state induced by one cage-animation keyframe: C = C₀ + offsets, M = ΦC and the CoR
/// centres Λ·C, precomputed so that playback between two keys is a lerp of two meshes instead of
/// a full ΦC product (exact up to round-off: everything is linear in C). Green rigs keep g(C)
/// too: M = φC + ψ·g(C) is the lerp plus ψ times what g adds beyond its own lerp.
#[derive(Debug, Clone, PartialEq)]
pub struct RestKeyframe {
    cage: Vec<DVec3>,
    mesh: Vec<DVec3>,
    centres: Option<Vec<DVec3>>,
    /// The coordinates kind's terms of `cage` (Green: g(C), `#F`; MVC: none).
    terms: Vec<DVec3>,
}

/// A live coupled rig.
#[derive(Debug, Clone)]
pub struct RigSession {
    // Static data.
    mesh_triangles: Vec<[u32; 3]>,
    /// Unique per triangle list (see [`RigSession::topology_id`]).
    topology_id: u64,
    cage_triangles: Vec<[u32; 3]>,
    skeleton: Skeleton,
    skin_weights: SkinWeights,
    /// The rest map: M = f(C) with its CageUp and CageRev (see [`rest_map`]).
    rest_map: RestMap,
    /// SkelUp: the rest joints A = ΨC (+ Ψ_ψ·g(C) for Green rigs).
    skeleton_updater: SkeletonUpdater,
    /// The skinning component: M' from M under the method in use (see [`skinning`]).
    skinning: RigSkinning,
    /// LBS of CageUp's fitting rows: the ghost fit's target for DQS/CoR (Sec. 4.3).
    ghost_lbs: LinearBlendSkinning,
    options_fit_source: CageFitSource,
    /// Original rest cage C₀ (cage-animation offsets are relative to it).
    original_rest_cage: Vec<DVec3>,

    // Rest state.
    rest_cage: Vec<DVec3>,
    rest_mesh: Vec<DVec3>,
    rest_world_from_joint: Vec<DAffine3>,

    // Current state.
    /// Local rotations of the current pose (parent_from_joint linear part), `#J`.
    posed_local_rotation: Vec<DQuat>,
    /// Local scales s_j of the current pose, `#J`.
    posed_local_scale: Vec<DVec3>,
    /// Local scales of the rest skeleton as loaded, `#J` (kept by SkelUp, which moves positions).
    rest_local_scale: Vec<DVec3>,
    /// d_j: current local translation minus the rest bone offset, `#J` (for roots: root motion).
    translation_offset: Vec<DVec3>,
    posed_world_from_joint: Vec<DAffine3>,
    posed_from_rest: Vec<DAffine3>,
    posed_mesh: Vec<DVec3>,
    posed_cage: Vec<DVec3>,

    // Scratch.
    scratch_locals: Vec<DAffine3>,
    scratch_joints: Vec<DVec3>,
    scratch_rotations: Vec<DMat3>,
    scratch_cage_a: Vec<DVec3>,
    scratch_cage_b: Vec<DVec3>,
    scratch_touched: Vec<usize>,
    scratch_rows_rest: Vec<DVec3>,
    scratch_rows_posed: Vec<DVec3>,
    /// The small state saved before each event (see [`checkpoint`]).
    checkpoint: Checkpoint,
    /// The f32 display path, when on (see [`display_path`]).
    display: Option<Box<DisplayPath>>,
    /// Incremented whenever M (and with it the CoR centres) changes.
    rest_revision: u64,
    /// SkelUp / CageUp switched off by the user (see [`SyncLocks`]).
    locks: SyncLocks,
    /// The options the session was built with (a rebind keeps them, see [`rebind`]).
    options: SessionOptions,
}

impl RigSession {
    /// Validates the parts, computes what is missing (Φ, MaxVol rows, Ψ), builds the operators
    /// and places the rig at rest. Returns the warnings gathered on the way.
    pub fn new(parts: RigParts, options: SessionOptions) -> Result<(Self, Vec<Warning>), RigError> {
        Self::with_progress(parts, options, &|_, _, _| {})
    }

    /// [`RigSession::new`], reporting the progress of the long stages of binding to `progress`
    /// (from worker threads): the one place the kind of coordinates is decided and computed, so
    /// that a front end's progress bar needs nothing computed beforehand.
    pub fn with_progress(
        parts: RigParts,
        options: SessionOptions,
        progress: BindProgress<'_>,
    ) -> Result<(Self, Vec<Warning>), RigError> {
        let stored_options = options.clone();
        let RigParts {
            mut mesh,
            skeleton,
            skin_weights,
            cage,
            cage_coords,
            maxvol_rows,
            cor_rows,
            joint_coords,
            cor_centre_coords,
            dq_blend_weights,
        } = parts;
        let nv = mesh.num_vertices();
        if skin_weights.num_vertices() != nv {
            return Err(RigError::SizeMismatch {
                what: "skinning weight rows (mesh vertices)",
                expected: nv,
                actual: skin_weights.num_vertices(),
            });
        }
        if skin_weights.num_joints() != skeleton.len() {
            return Err(RigError::SizeMismatch {
                what: "skinning weight columns (joints)",
                expected: skeleton.len(),
                actual: skin_weights.num_joints(),
            });
        }
        let blended = dq_blend_weights
            .map(|b| BlendedSkinning::new(&skin_weights, &b))
            .transpose()?;
        if mesh.triangles.is_empty() {
            return Err(RigError::Invalid(format!(
                "the rest mesh has {nv} vertices and no triangle: expected a surface (the \
                 skeleton updater and CoR skinning need its faces)"
            )));
        }
        let (cage, mut warnings) =
            validate_cage_for_mesh(cage, &mesh.positions, options.allow_mesh_outside_cage)?;
        let (skeleton, shear_note) = regularise_rest_frames(&skeleton)?;
        warnings.extend(shear_note);
        let nc = cage.num_vertices();
        let rest_cage = cage.positions.clone();
        let localisation = options.localisation;
        let skeleton_updater_of = Box::new(
            |mesh: &TriMesh, coords: &CageCoords, face_terms: Option<JointFaceTerms<'_>>| {
                match joint_coords {
                    Some(rows) => Ok((SkeletonUpdater::from_joint_coords(&rows, nc)?, Vec::new())),
                    None => SkeletonUpdater::new(
                        mesh,
                        &skeleton,
                        &skin_weights,
                        coords,
                        face_terms,
                        &rest_cage,
                        localisation,
                    ),
                }
            },
        );
        let BoundRestMap {
            rest_map,
            skeleton_updater,
            cor_centre_coords,
        } = RestMap::bind(
            &mut mesh,
            &cage,
            GivenCoords {
                cage_coords,
                maxvol_rows,
                cor_centre_coords,
            },
            &options,
            &skin_weights,
            &skeleton,
            skeleton_updater_of,
            progress,
            &mut warnings,
        )?;
        let nj = skeleton.len();
        let nr = rest_map.rows().len();
        let ghost_lbs = LinearBlendSkinning::new(&skin_weights.select_rows(rest_map.rows()));
        let rest_world_from_joint = skeleton.rest_world_from_joint();
        let mut locals = vec![DAffine3::IDENTITY; nj];
        skeleton.locals_from_worlds(&rest_world_from_joint, &mut locals);
        let (rest_local_scale, posed_local_rotation): (Vec<DVec3>, Vec<DQuat>) = locals
            .iter()
            .enumerate()
            .map(|(j, l)| decompose_rest_local(l, j))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .unzip();
        let external_skinning = options
            .external_skinning
            .as_ref()
            .map(|backend| {
                backend
                    .bind(&SkinningBindInput {
                        rest_mesh: &mesh.positions,
                        triangles: &mesh.triangles,
                        skeleton: &skeleton,
                        skin_weights: &skin_weights,
                    })
                    .map_err(|message| RigError::ExternalSkinning {
                        name: backend.name().to_owned(),
                        message,
                    })
            })
            .transpose()?;
        let mut session = Self {
            mesh_triangles: mesh.triangles.clone(),
            topology_id: next_topology_id(),
            cage_triangles: cage.triangles.clone(),
            skinning: RigSkinning::new(
                &skin_weights,
                blended,
                external_skinning,
                CorSource {
                    rows: cor_rows,
                    given: cor_centre_coords,
                    options: options.cor_centres,
                },
            ),
            ghost_lbs,
            skeleton,
            skin_weights,
            rest_map,
            skeleton_updater,
            options: stored_options,
            options_fit_source: options.fit_source,
            original_rest_cage: rest_cage.clone(),
            rest_cage,
            rest_mesh: mesh.positions,
            rest_world_from_joint,
            posed_local_rotation,
            posed_local_scale: rest_local_scale.clone(),
            rest_local_scale,
            translation_offset: vec![DVec3::ZERO; nj],
            posed_world_from_joint: vec![DAffine3::IDENTITY; nj],
            posed_from_rest: vec![DAffine3::IDENTITY; nj],
            posed_mesh: vec![DVec3::ZERO; nv],
            // The warm start of the Green CageUp (MVC overwrites it).
            posed_cage: cage.positions.clone(),
            scratch_locals: locals,
            scratch_joints: vec![DVec3::ZERO; nj],
            scratch_rotations: vec![DMat3::IDENTITY; nj],
            scratch_cage_a: vec![DVec3::ZERO; nc],
            scratch_cage_b: vec![DVec3::ZERO; nc],
            scratch_touched: Vec::with_capacity(nc),
            scratch_rows_rest: vec![DVec3::ZERO; nr],
            scratch_rows_posed: vec![DVec3::ZERO; nr],
            checkpoint: Checkpoint::new(nc, nj),
            locks: SyncLocks::default(),
            display: None,
            rest_revision: 0,
        };
        // The method, then one pose and one fit (each later event fits once too).
        session.select_skinning(options.skinning)?;
        session.pose_and_fit();
        Ok((session, warnings))
    }
}

/// The paper tool's pose: rotations, rest scales, root motion for roots only.
fn roots_only<'a>(rotations: &'a [DQuat], root_motion: &'a [DVec3]) -> LocalPose<'a> {
    LocalPose {
        rotations,
        scales: None,
        translation_offsets: root_motion,
        roots_only: true,
    }
}

/// A new process-wide unique topology id.
fn next_topology_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}
