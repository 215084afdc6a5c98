//! Asynchronous playback of a skeleton track and a cage track on a [`RigSession`] (Section 5,
//! Figures 9–11): each track has its own keyframe times; a sample at time t sets the rest cage
//! C = C₀ + offsets(t) and the joint rotations of the skeleton track, then SkelUp moves the
//! bones with the cage before skinning and CageUp.
//!
//! Skeleton keys are local transforms `parent_from_joint`. With [`PoseChannels::RotationsAndRootMotion`]
//! (the paper tool's model, the default) only their rotations are used, plus the translation of
//! each root relative to the rest skeleton as loaded (root motion). With [`PoseChannels::Full`]
//! (imported glTF/FBX animations) rotation, scale and the translation offset of every joint from
//! its rest bone offset are used (see [`crate::pose`]). Either way bone offsets come from the
//! current rest skeleton, which follows the cage.

use glam::{DAffine3, DQuat, DVec3};

use crate::animation::{CageTrack, SkeletonTrack, bracket};
use crate::error::RigError;
use crate::pose::{LocalPose, rotation_of};
use crate::session::{RestKeyframe, RigSession};

/// Which parts of the skeleton keys drive the pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PoseChannels {
    /// Local rotations and root translation (the paper tool's model; non-root translations and
    /// scales in the keys are ignored).
    #[default]
    RotationsAndRootMotion,
    /// Local rotation, scale and translation of every joint: an imported animation plays exactly
    /// as in its file (translation as an offset from the rest bone, kept when SkelUp moves it).
    Full,
}

/// Plays tracks on a session; holds the per-frame buffers (no allocation per sample).
#[derive(Debug, Clone)]
pub struct AnimationPlayer {
    skeleton_track: Option<SkeletonTrack>,
    cage_track: Option<CageTrack>,
    /// C, M = ΦC and CoR centres of every cage keyframe (per-keyframe cache: a sample between
    /// two keys lerps two meshes instead of recomputing ΦC).
    cage_keys: Vec<RestKeyframe>,
    /// Whether `cage_keys` hold CoR centres (rebuilt when the session gains CoR data).
    keys_have_centres: bool,
    /// Local translations of the rest skeleton as loaded, `#J` (roots: world translation).
    original_local_translation: Vec<DVec3>,
    channels: PoseChannels,
    /// SkelUp held while sampling (see [`AnimationPlayer::holding_rest_skeleton`]).
    hold_rest_skeleton: bool,
    locals: Vec<DAffine3>,
    rotations: Vec<DQuat>,
    scales: Vec<DVec3>,
    /// d_j of [`crate::pose`] (roots only in the paper tool's model: root motion).
    translation_offsets: Vec<DVec3>,
}

impl AnimationPlayer {
    /// Checks the tracks against the session's rig (joint and cage vertex counts); the paper
    /// tool's pose channels.
    pub fn new(
        session: &RigSession,
        skeleton_track: Option<SkeletonTrack>,
        cage_track: Option<CageTrack>,
    ) -> Result<Self, RigError> {
        Self::with_channels(
            session,
            skeleton_track,
            cage_track,
            PoseChannels::RotationsAndRootMotion,
        )
    }

    /// As [`AnimationPlayer::new`], with the given use of the skeleton keys.
    pub fn with_channels(
        session: &RigSession,
        skeleton_track: Option<SkeletonTrack>,
        cage_track: Option<CageTrack>,
        channels: PoseChannels,
    ) -> Result<Self, RigError> {
        let nj = session.skeleton().len();
        let nc = session.rest_cage().len();
        if let Some(t) = &skeleton_track
            && t.num_joints() != nj
        {
            return Err(RigError::SizeMismatch {
                what: "joints in the skeleton animation",
                expected: nj,
                actual: t.num_joints(),
            });
        }
        if let Some(t) = &cage_track
            && t.num_cage_vertices() != nc
        {
            return Err(RigError::SizeMismatch {
                what: "vertices in the cage animation",
                expected: nc,
                actual: t.num_cage_vertices(),
            });
        }
        let cage_keys = match &cage_track {
            Some(track) => track
                .offsets()
                .iter()
                .map(|o| session.rest_keyframe(o))
                .collect::<Result<Vec<_>, _>>()?,
            None => Vec::new(),
        };
        let mut locals = vec![DAffine3::IDENTITY; nj];
        session
            .skeleton()
            .locals_from_worlds(&session.skeleton().rest_world_from_joint(), &mut locals);
        Ok(Self {
            keys_have_centres: session.cor_centres().is_some(),
            cage_keys,
            skeleton_track,
            cage_track,
            original_local_translation: locals.iter().map(|l| l.translation).collect(),
            channels,
            hold_rest_skeleton: false,
            rotations: locals.iter().map(|l| rotation_of(&l.matrix3)).collect(),
            scales: session.rest_local_scales().to_vec(),
            locals,
            translation_offsets: vec![DVec3::ZERO; nj],
        })
    }

    /// With `hold`, samples do not run SkelUp: the rest joints stay where they are while the
    /// cage track moves the rest cage. For skeleton keys that already contain the motion SkelUp
    /// gave the rest joints when they were made — a cagerig glTF export with a cage track, whose
    /// joint nodes carry `T_j(t)·B_j(0)` — so that the joints do not move twice. The session's
    /// own SkelUp lock is left as it was (the rest skeleton then stays where playback left it
    /// until the next rest-cage edit re-runs SkelUp).
    pub fn holding_rest_skeleton(mut self, hold: bool) -> Self {
        self.hold_rest_skeleton = hold;
        self
    }

    /// Last keyframe time over both tracks.
    pub fn duration(&self) -> f64 {
        let last = |times: &[f64]| times.last().copied().unwrap_or(0.0);
        let s = self
            .skeleton_track
            .as_ref()
            .map_or(0.0, |t| last(t.times()));
        let c = self.cage_track.as_ref().map_or(0.0, |t| last(t.times()));
        s.max(c)
    }

    /// Samples both tracks at `t` seconds (clamped to each track's range) and runs the full
    /// sync on the session.
    pub fn apply(&mut self, t: f64, session: &mut RigSession) -> Result<(), RigError> {
        let hold = self.hold_rest_skeleton && !session.sync_locks().skel_up;
        if hold {
            session.set_skel_up_lock_quietly(true);
        }
        let result = self.apply_sample(t, session);
        if hold {
            session.set_skel_up_lock_quietly(false);
        }
        result
    }

    fn apply_sample(&mut self, t: f64, session: &mut RigSession) -> Result<(), RigError> {
        let full = self.channels == PoseChannels::Full;
        if let Some(track) = &self.skeleton_track {
            track.sample(t, &mut self.locals);
            for (j, local) in self.locals.iter().enumerate() {
                if full {
                    let (scale, rotation, _) = local.to_scale_rotation_translation();
                    self.rotations[j] = rotation.normalize();
                    self.scales[j] = scale;
                } else {
                    self.rotations[j] = DQuat::from_mat3(&local.matrix3).normalize();
                }
                self.translation_offsets[j] = if full || session.skeleton().parent(j).is_none() {
                    local.translation - self.original_local_translation[j]
                } else {
                    DVec3::ZERO
                };
            }
        }
        let pose = LocalPose {
            rotations: &self.rotations,
            scales: full.then_some(self.scales.as_slice()),
            translation_offsets: &self.translation_offsets,
            roots_only: !full,
        };
        match &self.cage_track {
            Some(track) => {
                if self.keys_have_centres != session.cor_centres().is_some() {
                    self.cage_keys = track
                        .offsets()
                        .iter()
                        .map(|o| session.rest_keyframe(o))
                        .collect::<Result<Vec<_>, _>>()?;
                    self.keys_have_centres = session.cor_centres().is_some();
                }
                let b = bracket(track.times(), t);
                session.set_animation_sample_between_local(
                    &self.cage_keys[b.lo],
                    &self.cage_keys[b.hi],
                    b.a,
                    &pose,
                )
            }
            None => session.set_animation_sample_local(None, &pose),
        }
    }
}
