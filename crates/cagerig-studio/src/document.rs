//! The open document: a rig session, its animation keys and its undo history. Every edit of
//! the UI, of an edit script or of the timeline goes through [`Document::execute`] (one undo
//! step) or through a gesture (one session event per mouse move, one undo step per drag).

use std::time::Instant;

use cagerig::RigError;
use cagerig::playback::AnimationPlayer;
use cagerig::script::{EditScript, EditStep, ScriptError, resolve_joint};
use cagerig::session::{EditableState, RigSession, SyncLocks};
use cagerig::skinning::SkinningMethod;
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::history::History;
use crate::keys::{KeyError, Keys, Track};
use crate::rig_open::RigSource;

/// What undo restores: the rig's editable state and the keys.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    pub rig: EditableState,
    pub keys: Keys,
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
    ResetPose,
    SetLocks(SyncLocks),
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
            Command::ResetPose => "reset pose".into(),
            Command::SetLocks(_) => "sync locks".into(),
            Command::SetKey { track, .. } => format!("set {track:?} key").to_lowercase(),
            Command::DeleteKey { track, .. } => format!("delete {track:?} key").to_lowercase(),
            Command::MoveKey { track, .. } => format!("move {track:?} key").to_lowercase(),
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
    history: History<Snapshot>,
    gesture: Option<Gesture>,
    player: Option<AnimationPlayer>,
    /// Bumped on every change of the rig (the current view re-uploads).
    pub revision: u64,
    /// Bumped when the rest pose (M, S, C) may have changed (the rest view re-uploads).
    pub rest_revision: u64,
    /// Bumped on every change worth saving (autosave compares it).
    pub edits: u64,
    /// Milliseconds of the last session event (the sync chain).
    pub last_sync_ms: f64,
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
        }
    }

    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            rig: self.session.editable_state(),
            keys: self.keys.clone(),
        }
    }

    /// Restores a snapshot (undo, redo, cancelled gesture, session file).
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<(), DocError> {
        snapshot.keys.validate(&self.session)?;
        let t = Instant::now();
        self.session.restore_editable_state(&snapshot.rig)?;
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

    fn changed(&mut self) {
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
            Command::ResetPose => s.reset_pose(),
            Command::SetLocks(locks) => s.set_sync_locks(*locks),
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
mod tests {
    use super::*;
    use crate::rig_open::open_rig;

    fn doc() -> Document {
        let source = RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        };
        let opened = open_rig(&source).unwrap();
        Document::new(source, opened.session)
    }

    #[test]
    fn undo_and_redo_restore_the_exact_state() {
        let mut d = doc();
        let s0 = d.snapshot();
        d.execute(&Command::RotateJoint {
            joint: 1,
            axis: DVec3::Z,
            angle: 0.5,
        })
        .unwrap();
        let s1 = d.snapshot();
        d.execute(&Command::MovePosedCage {
            vertices: vec![2, 3],
            offsets: vec![DVec3::new(0.0, 0.1, 0.0)],
        })
        .unwrap();
        let s2 = d.snapshot();
        assert!(d.undo().unwrap());
        assert_eq!(d.snapshot(), s1);
        assert!(d.undo().unwrap());
        assert_eq!(d.snapshot(), s0);
        assert!(!d.undo().unwrap());
        assert!(d.redo().unwrap());
        assert!(d.redo().unwrap());
        assert_eq!(d.snapshot(), s2);
    }

    #[test]
    fn a_drag_is_one_undo_step_and_cancel_restores() {
        let mut d = doc();
        let s0 = d.snapshot();
        d.begin_gesture("drag");
        for _ in 0..5 {
            d.gesture_event(&Command::MoveRestCage {
                vertices: vec![0],
                offsets: vec![DVec3::new(0.01, 0.0, 0.0)],
            })
            .unwrap();
        }
        d.end_gesture();
        assert_eq!(d.history().undo_len(), 1);
        d.begin_gesture("drag 2");
        d.gesture_event(&Command::MoveRestCage {
            vertices: vec![1],
            offsets: vec![DVec3::new(0.0, 0.05, 0.0)],
        })
        .unwrap();
        let before_cancel = d.gesture_start().unwrap().clone();
        d.cancel_gesture().unwrap();
        assert_eq!(d.snapshot(), before_cancel);
        assert_eq!(d.history().undo_len(), 1);
        d.undo().unwrap();
        assert_eq!(d.snapshot(), s0);
    }

    #[test]
    fn a_failed_command_changes_nothing_and_records_nothing() {
        let mut d = doc();
        let s0 = d.snapshot();
        let err = d
            .execute(&Command::MoveRestCage {
                vertices: vec![10_000],
                offsets: vec![DVec3::X],
            })
            .unwrap_err();
        assert!(err.to_string().contains("10000"), "{err}");
        assert_eq!(d.snapshot(), s0);
        assert_eq!(d.history().undo_len(), 0);
    }

    #[test]
    fn keys_are_undoable() {
        let mut d = doc();
        d.execute(&Command::SetKey {
            track: Track::Cage,
            time: 0.5,
        })
        .unwrap();
        assert_eq!(d.keys.len(Track::Cage), 1);
        d.undo().unwrap();
        assert_eq!(d.keys.len(Track::Cage), 0);
        d.redo().unwrap();
        assert_eq!(d.keys.len(Track::Cage), 1);
    }

    #[test]
    fn a_script_matches_the_library_run_of_the_same_script() {
        let text = r#"{"skinning":"dqs","steps":[
            {"op":"rotate_joint","joint":1,"axis":[0,0,1],"degrees":40},
            {"op":"move_rest_cage","vertices":[0,1],"offset":[0,0.2,0]},
            {"op":"move_posed_cage","vertices":[5],"offset":[0.1,0,0]}]}"#;
        let script = EditScript::parse(text).unwrap();
        let mut d = doc();
        d.run_script(&script).unwrap();
        assert_eq!(d.history().undo_len(), 4);
        let mut reference = doc();
        reference.session.set_skinning(SkinningMethod::Dqs).unwrap();
        for k in 0..script.steps.len() {
            script.run_step(k, &mut reference.session).unwrap();
        }
        for (a, b) in d
            .session
            .posed_mesh()
            .iter()
            .zip(reference.session.posed_mesh())
        {
            assert!(a.distance(*b) < 1e-12);
        }
        assert_eq!(d.session.rest_cage(), reference.session.rest_cage());
    }
}
