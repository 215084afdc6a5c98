//! The open document: a rig session, its animation keys and its undo history. Every edit of
//! the UI, of an edit script or of the timeline goes through [`Document::execute`] (one undo
//! step) or through a gesture (one session event per mouse move, one undo step per drag).

use web_time::Instant;

use cagerig::RigError;
use cagerig::playback::AnimationPlayer;
use cagerig::script::{EditScript, EditStep, ScriptError, resolve_joint};
use cagerig::session::{EditableState, RigSession, SyncLocks};
use cagerig::skinning::SkinningMethod;
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::binding::BindJob;
use crate::history::History;
use crate::keys::{KeyError, Keys, Track};
use crate::rig_open::RigSource;
use crate::skeleton_draft::{DraftError, Mirror, SkeletonDraft};

/// What undo restores: the rig's editable state, the keys, the skeleton being built, and
/// which binding (skeleton and weights) the rig has.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    pub rig: EditableState,
    pub keys: Keys,
    /// The skeleton being built or changed in the rest view, not bound yet.
    #[serde(default)]
    pub draft: Option<SkeletonDraft>,
    /// The binding in force (session files carry a binding apart: see `session_file`).
    #[serde(skip)]
    pub binding: BindingKey,
}

/// Which binding of the document a state belongs to: 0 is the rig as opened; each Bind makes
/// a new one. `rigged` is false for the placeholder rig of a mesh opened with no skeleton.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BindingKey {
    pub id: u64,
    pub rigged: bool,
}

impl Default for BindingKey {
    fn default() -> Self {
        Self {
            id: 0,
            rigged: true,
        }
    }
}

/// An edit of the skeleton in the rest view (it changes the draft; Bind applies it).
#[derive(Debug, Clone, PartialEq)]
pub enum SkeletonEdit {
    /// A joint at `position` below `parent` (a root when `None`).
    Add {
        position: DVec3,
        parent: Option<usize>,
        mirror: Option<Mirror>,
    },
    Move {
        joint: usize,
        position: DVec3,
        mirror: Option<Mirror>,
    },
    Delete {
        joint: usize,
        mirror: bool,
    },
    SetParent {
        joint: usize,
        parent: Option<usize>,
    },
    Rename {
        joint: usize,
        name: String,
    },
    /// Drops the changes since the last bind.
    Discard,
}

impl SkeletonEdit {
    fn label(&self) -> &'static str {
        match self {
            SkeletonEdit::Add { .. } => "add joint",
            SkeletonEdit::Move { .. } => "move joint",
            SkeletonEdit::Delete { .. } => "delete joint",
            SkeletonEdit::SetParent { .. } => "re-parent joint",
            SkeletonEdit::Rename { .. } => "rename joint",
            SkeletonEdit::Discard => "discard skeleton changes",
        }
    }
}

/// One user action on the document.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// S': rotate joint `joint` by `angle` radians about the world `axis` through the joint.
    RotateJoint {
        joint: usize,
        axis: DVec3,
        angle: f64,
    },
    /// S': set the local rotation of a joint (numeric entry).
    SetJointRotation {
        joint: usize,
        rotation: DQuat,
    },
    /// C: move rest-cage vertices (one offset per vertex, or one for all).
    MoveRestCage {
        vertices: Vec<usize>,
        offsets: Vec<DVec3>,
    },
    /// C': move current-cage vertices (CageRev).
    MovePosedCage {
        vertices: Vec<usize>,
        offsets: Vec<DVec3>,
    },
    SetSkinning(SkinningMethod),
    /// Rebind with other cage coordinates (MVC ↔ Green), keeping every edit.
    SetCoords(cagerig::CoordsKind),
    /// Switch CageUp's fit of the current cage ([`cagerig::CageFitKind`]); C' is refitted.
    SetCageFit(cagerig::CageFitKind),
    /// Green rigs: rebind with another face term
    /// ([`cagerig::coords::stretched_normals::FaceTermKind`]), keeping every edit.
    SetGreenFaceTerm(cagerig::coords::stretched_normals::FaceTermKind),
    ResetPose,
    SetLocks(SyncLocks),
    /// Green rigs: refuse an edit whose CageUp finds no current cage, or keep it with C'
    /// unfitted ([`cagerig::session::UnfittedCagePolicy`]).
    SetUnfittedCage(cagerig::session::UnfittedCagePolicy),
    /// Key the current pose (skeleton track) or the current rest cage (cage track).
    SetKey {
        track: Track,
        time: f64,
    },
    DeleteKey {
        track: Track,
        index: usize,
    },
    MoveKey {
        track: Track,
        index: usize,
        time: f64,
    },
    /// Build or change the skeleton in the rest view.
    EditSkeleton(SkeletonEdit),
}

impl Command {
    /// Label shown in the Edit menu's undo / redo entries.
    pub fn label(&self) -> String {
        match self {
            Command::RotateJoint { .. } | Command::SetJointRotation { .. } => "rotate joint".into(),
            Command::MoveRestCage { .. } => "move rest cage".into(),
            Command::MovePosedCage { .. } => "move current cage".into(),
            Command::SetSkinning(m) => format!("skinning {}", m.label()),
            Command::SetCoords(k) => format!("{} coordinates", k.label()),
            Command::SetCageFit(k) => format!("{} cage fit", k.name()),
            Command::SetGreenFaceTerm(k) => format!("{} face term", k.name()),
            Command::ResetPose => "reset pose".into(),
            Command::SetLocks(_) => "sync locks".into(),
            Command::SetUnfittedCage(policy) => match policy {
                cagerig::session::UnfittedCagePolicy::Refuse => "refuse unfitted current cages",
                cagerig::session::UnfittedCagePolicy::KeepEvent => "keep unfitted current cages",
            }
            .into(),
            Command::SetKey { track, .. } => format!("set {track:?} key").to_lowercase(),
            Command::DeleteKey { track, .. } => format!("delete {track:?} key").to_lowercase(),
            Command::MoveKey { track, .. } => format!("move {track:?} key").to_lowercase(),
            Command::EditSkeleton(edit) => edit.label().into(),
        }
    }
}

#[derive(Debug, Error)]
pub enum DocError {
    #[error("{0}")]
    Rig(#[from] RigError),
    #[error("{0}")]
    Key(#[from] KeyError),
    #[error("{0}")]
    Script(#[from] ScriptError),
    #[error("no {0:?} key {1}")]
    NoKey(Track, usize),
    #[error("{0}")]
    Skeleton(#[from] DraftError),
    #[error(
        "the mesh has no skeleton yet: add joints in the rest view (Skeleton panel: \
         \"Add joints by clicking\"), then Bind"
    )]
    NotRigged,
    #[error(
        "the skeleton has changes that are not bound yet: Bind them (Skeleton panel) or \
         discard them to pose"
    )]
    SkeletonPending,
    #[error("binding {0} is no longer in memory")]
    NoBinding(u64),
    #[error("{0}")]
    Bind(String),
}

struct Gesture {
    label: String,
    before: Snapshot,
    changed: bool,
}

/// A rig being edited.
pub struct Document {
    pub source: RigSource,
    pub session: RigSession,
    pub keys: Keys,
    pub(crate) history: History<Snapshot>,
    gesture: Option<Gesture>,
    pub(crate) player: Option<AnimationPlayer>,
    /// Bumped on every change of the rig (the current view re-uploads).
    pub revision: u64,
    /// Bumped when the rest pose (M, S, C) may have changed (the rest view re-uploads).
    pub rest_revision: u64,
    /// Bumped on every change worth saving (autosave compares it).
    pub edits: u64,
    /// Milliseconds of the last session event (the sync chain).
    pub last_sync_ms: f64,
    /// The skeleton being built or changed in the rest view, not bound yet.
    pub draft: Option<SkeletonDraft>,
    /// The binding in force.
    pub(crate) binding: BindingKey,
    /// The sessions of the other bindings in the history (undo / redo of a Bind).
    pub(crate) stored_bindings: std::collections::HashMap<u64, RigSession>,
    pub(crate) last_binding_id: u64,
    /// A bind running in the background.
    pub(crate) bind_job: Option<BindJob>,
    /// X mirror of skeleton edits: joints off the middle plane get `.L` / `.R` twins.
    pub mirror_x: bool,
    /// Which tip joints (no child) get weight at Bind.
    pub bind_tips: cagerig::auto_weights::TipJoints,
}

impl Document {
    pub fn new(source: RigSource, session: RigSession) -> Self {
        Self {
            source,
            session,
            keys: Keys::default(),
            history: History::default(),
            gesture: None,
            player: None,
            revision: 0,
            rest_revision: 0,
            edits: 0,
            last_sync_ms: 0.0,
            draft: None,
            binding: BindingKey::default(),
            stored_bindings: Default::default(),
            last_binding_id: 0,
            bind_job: None,
            mirror_x: false,
            bind_tips: Default::default(),
        }
    }

    /// A document on the placeholder rig of a mesh opened with no skeleton (`rigged` false):
    /// its skeleton is empty until the first Bind.
    pub fn with_rigged(mut self, rigged: bool) -> Self {
        self.binding.rigged = rigged;
        self
    }

    /// Whether the rig has a bound skeleton (false for a mesh opened with no skeleton).
    pub fn rigged(&self) -> bool {
        self.binding.rigged
    }

    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            rig: self.session.editable_state(),
            keys: self.keys.clone(),
            draft: self.draft.clone(),
            binding: self.binding,
        }
    }

    /// Restores a snapshot (undo, redo, cancelled gesture, session file).
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<(), DocError> {
        let t = Instant::now();
        let previous = self.binding;
        if snapshot.binding != self.binding {
            self.switch_binding(snapshot.binding)?;
        }
        let restored = snapshot
            .keys
            .validate(&self.session)
            .map_err(DocError::from)
            .and_then(|()| {
                self.session
                    .restore_editable_state(&snapshot.rig)
                    .map_err(DocError::from)
            });
        if let Err(e) = restored {
            if previous != self.binding {
                // Back to the binding in force before (its session is stored, as is).
                let _ = self.switch_binding(previous);
            }
            return Err(e);
        }
        self.draft = snapshot.draft.clone();
        self.last_sync_ms = t.elapsed().as_secs_f64() * 1e3;
        if self.keys != snapshot.keys {
            self.keys = snapshot.keys.clone();
            self.player = None;
        }
        self.changed();
        Ok(())
    }

    /// Restores `snapshot` as one undo step (e.g. keys imported from a file).
    pub fn restore_as_step(&mut self, label: &str, snapshot: &Snapshot) -> Result<(), DocError> {
        let before = self.snapshot();
        self.restore(snapshot)?;
        if self.snapshot() != before {
            self.history.record(label, before);
        }
        Ok(())
    }

    pub(crate) fn changed(&mut self) {
        self.revision += 1;
        self.rest_revision += 1;
        self.edits += 1;
    }

    /// A change of the current pose only (S', M', C'): the rest view keeps its buffers.
    fn pose_changed(&mut self) {
        self.revision += 1;
        self.edits += 1;
    }

    /// Runs one command as one undo step.
    pub fn execute(&mut self, command: &Command) -> Result<(), DocError> {
        let before = self.snapshot();
        self.apply(command)?;
        if self.snapshot() != before {
            self.history.record(command.label(), before);
        }
        Ok(())
    }

    /// Runs `command` on the rig without touching the history.
    fn apply(&mut self, command: &Command) -> Result<(), DocError> {
        let t = Instant::now();
        if matches!(
            command,
            Command::RotateJoint { .. }
                | Command::SetJointRotation { .. }
                | Command::SetKey {
                    track: Track::Skeleton,
                    ..
                }
        ) {
            self.check_posable()?;
        }
        let s = &mut self.session;
        match command {
            Command::RotateJoint { joint, axis, angle } => s.rotate_joint(*joint, *axis, *angle)?,
            Command::SetJointRotation { joint, rotation } => {
                let mut rotations = s.posed_local_rotations().to_vec();
                if *joint >= rotations.len() {
                    return Err(RigError::Invalid(format!(
                        "joint {joint} does not exist (the rig has {} joints)",
                        rotations.len()
                    ))
                    .into());
                }
                rotations[*joint] = *rotation;
                let scales = s.posed_local_scales().to_vec();
                let offsets = s.translation_offsets().to_vec();
                s.set_local_pose(&cagerig::pose::LocalPose {
                    rotations: &rotations,
                    scales: Some(&scales),
                    translation_offsets: &offsets,
                    roots_only: false,
                })?;
            }
            Command::MoveRestCage { vertices, offsets } => s.move_rest_cage(vertices, offsets)?,
            Command::MovePosedCage { vertices, offsets } => {
                s.move_posed_cage(vertices, offsets)?;
            }
            Command::SetSkinning(method) => s.set_skinning(*method)?,
            Command::SetCoords(kind) => {
                let mut state = s.editable_state();
                state.coords = *kind;
                s.restore_editable_state(&state)?;
                // A new binding: the player's keyframes belong to the old one.
                self.player = None;
            }
            Command::SetCageFit(kind) => s.set_cage_fit(*kind)?,
            Command::SetGreenFaceTerm(kind) => {
                let mut state = s.editable_state();
                state.green_face_term = *kind;
                s.restore_editable_state(&state)?;
                // A new binding: the player's keyframes belong to the old one.
                self.player = None;
            }
            Command::ResetPose => s.reset_pose(),
            Command::SetLocks(locks) => s.set_sync_locks(*locks),
            Command::SetUnfittedCage(policy) => s.set_unfitted_cage_policy(*policy),
            Command::SetKey { track, time } => {
                match track {
                    Track::Skeleton => self.keys.set_skeleton_key(*time, &self.session),
                    Track::Cage => self.keys.set_cage_key(*time, &self.session),
                };
                self.player = None;
            }
            Command::DeleteKey { track, index } => {
                if !self.keys.delete(*track, *index) {
                    return Err(DocError::NoKey(*track, *index));
                }
                self.player = None;
            }
            Command::MoveKey { track, index, time } => {
                if *index >= self.keys.len(*track) {
                    return Err(DocError::NoKey(*track, *index));
                }
                self.keys.move_key(*track, *index, *time)?;
                self.player = None;
            }
            Command::EditSkeleton(edit) => self.edit_skeleton(edit)?,
        }
        if !matches!(
            command,
            Command::SetKey { .. } | Command::DeleteKey { .. } | Command::MoveKey { .. }
        ) {
            self.last_sync_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        match command {
            Command::RotateJoint { .. }
            | Command::SetJointRotation { .. }
            | Command::ResetPose
            | Command::SetSkinning(_) => self.pose_changed(),
            _ => self.changed(),
        }
        Ok(())
    }

    /// Starts a drag: its events become one undo step when it ends.
    pub fn begin_gesture(&mut self, label: impl Into<String>) {
        if self.gesture.is_none() {
            self.gesture = Some(Gesture {
                label: label.into(),
                before: self.snapshot(),
                changed: false,
            });
        }
    }

    pub fn in_gesture(&self) -> bool {
        self.gesture.is_some()
    }

    /// One event of the drag (one session event).
    pub fn gesture_event(&mut self, command: &Command) -> Result<(), DocError> {
        self.apply(command)?;
        if let Some(g) = &mut self.gesture {
            g.changed = true;
        }
        Ok(())
    }

    /// Ends the drag, recording one undo step if anything changed.
    pub fn end_gesture(&mut self) {
        if let Some(g) = self.gesture.take()
            && g.changed
            && self.snapshot() != g.before
        {
            self.history.record(g.label, g.before);
        }
    }

    /// Cancels the drag: back to the state before it (Esc, right click).
    pub fn cancel_gesture(&mut self) -> Result<(), DocError> {
        match self.gesture.take() {
            Some(g) if g.changed => self.restore(&g.before),
            _ => Ok(()),
        }
    }

    /// The state when the current gesture started.
    pub fn gesture_start(&self) -> Option<&Snapshot> {
        self.gesture.as_ref().map(|g| &g.before)
    }

    /// Undo; `Ok(false)` when there is nothing to undo.
    pub fn undo(&mut self) -> Result<bool, DocError> {
        self.end_gesture();
        let now = self.snapshot();
        let Some(state) = self.history.undo(now) else {
            return Ok(false);
        };
        if let Err(e) = self.restore(&state) {
            self.history.put_back_undo();
            return Err(e);
        }
        Ok(true)
    }

    /// Redo; `Ok(false)` when there is nothing to redo.
    pub fn redo(&mut self) -> Result<bool, DocError> {
        self.end_gesture();
        let now = self.snapshot();
        let Some(state) = self.history.redo(now) else {
            return Ok(false);
        };
        self.restore(&state)?;
        Ok(true)
    }

    pub fn history(&self) -> &History<Snapshot> {
        &self.history
    }

    /// Applies an edit script through [`Document::execute`] (validated first, one undo step
    /// per step), as `cagerig edit` runs it.
    pub fn run_script(&mut self, script: &EditScript) -> Result<(), DocError> {
        script.validate(&self.session)?;
        if let Some(method) = script.skinning {
            self.execute(&Command::SetSkinning(method))?;
        }
        for (i, step) in script.steps.iter().enumerate() {
            let command = match step {
                EditStep::RotateJoint {
                    joint,
                    axis,
                    degrees,
                } => Command::RotateJoint {
                    joint: resolve_joint(&self.session, joint).map_err(|message| {
                        ScriptError::Step {
                            step: i + 1,
                            message,
                        }
                    })?,
                    axis: DVec3::from_array(*axis),
                    angle: degrees.to_radians(),
                },
                EditStep::MoveRestCage { vertices, offset } => Command::MoveRestCage {
                    vertices: vertices.clone(),
                    offsets: vec![DVec3::from_array(*offset)],
                },
                EditStep::MovePosedCage { vertices, offset } => Command::MovePosedCage {
                    vertices: vertices.clone(),
                    offsets: vec![DVec3::from_array(*offset)],
                },
                EditStep::SetSkinning { method } => Command::SetSkinning(*method),
                EditStep::ResetPose {} => Command::ResetPose,
            };
            self.execute(&command).map_err(|e| match e {
                DocError::Rig(source) => DocError::Script(ScriptError::Rig {
                    step: i + 1,
                    source,
                }),
                other => other,
            })?;
        }
        Ok(())
    }

    /// Playback: samples both tracks at `time` (no undo step). `Ok(false)` without keys.
    pub fn sample(&mut self, time: f64) -> Result<bool, DocError> {
        if self.keys.is_empty() {
            return Ok(false);
        }
        if self.player.is_none() {
            self.player = self.keys.player(&self.session)?;
        }
        let Some(player) = &mut self.player else {
            return Ok(false);
        };
        let t = Instant::now();
        player.apply(time, &mut self.session)?;
        self.last_sync_ms = t.elapsed().as_secs_f64() * 1e3;
        self.revision += 1;
        if !self.keys.cage.is_empty() {
            self.rest_revision += 1;
        }
        Ok(true)
    }
}

#[cfg(test)]
#[path = "document_tests.rs"]
mod tests;
