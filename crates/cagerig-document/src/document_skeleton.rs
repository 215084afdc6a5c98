//! The document's skeleton building: edits of the draft in the rest view, the skeleton each
//! view shows, the background Bind and its result as one undo step, and switching between
//! the bindings of the history (undo / redo of a Bind).

use cagerig::session::RigSession;
use glam::DVec3;

use crate::binding::{BindJob, BindRequest, BindWeights, BoundRig, carry_pose};
use crate::document::{BindingKey, DocError, Document, SkeletonEdit};
use crate::keys::Keys;
use crate::offload::WeightsOffload;
use crate::saved_binding::SavedBinding;
use crate::session_file::SessionFile;
use crate::skeleton_draft::{Mirror, SkeletonDraft};

/// The skeleton a view shows: positions (`#J`, world space), parents and names.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ShownSkeleton {
    pub positions: Vec<DVec3>,
    pub parents: Vec<Option<usize>>,
    pub names: Vec<String>,
}

/// The mirror plane fraction: joints within this fraction of the rest mesh's box width from
/// its middle are on the plane.
const MIRROR_TOLERANCE: f64 = 0.02;

impl Document {
    /// Posing needs a bound skeleton with no pending changes.
    pub fn check_posable(&self) -> Result<(), DocError> {
        if !self.rigged() {
            Err(DocError::NotRigged)
        } else if self.draft.is_some() {
            Err(DocError::SkeletonPending)
        } else {
            Ok(())
        }
    }

    /// The draft as an edit starts it: the bound skeleton, or none for a mesh with no
    /// skeleton.
    fn draft_or_bound(&self) -> SkeletonDraft {
        match (&self.draft, self.rigged()) {
            (Some(d), _) => d.clone(),
            (None, true) => SkeletonDraft::from_session(&self.session),
            (None, false) => SkeletonDraft::default(),
        }
    }

    /// Applies a skeleton edit to a copy of the draft, kept only when it succeeds.
    pub(crate) fn edit_skeleton(&mut self, edit: &SkeletonEdit) -> Result<(), DocError> {
        if *edit == SkeletonEdit::Discard {
            self.draft = None;
            return Ok(());
        }
        let mut draft = self.draft_or_bound();
        match edit {
            SkeletonEdit::Add {
                position,
                parent,
                mirror,
            } => {
                draft.add_joint(*position, *parent, *mirror)?;
            }
            SkeletonEdit::Move {
                joint,
                position,
                mirror,
            } => draft.move_joint(*joint, *position, *mirror)?,
            SkeletonEdit::Delete { joint, mirror } => draft.delete_joint(*joint, *mirror)?,
            SkeletonEdit::SetParent { joint, parent } => draft.set_parent(*joint, *parent)?,
            SkeletonEdit::Rename { joint, name } => draft.rename(*joint, name)?,
            SkeletonEdit::Discard => {}
        }
        self.draft = Some(draft);
        Ok(())
    }

    /// The X mirror of this character: the plane through the middle of the rest mesh's box.
    pub fn mirror(&self) -> Mirror {
        let (lo, hi) = cagerig::mesh::bounding_box(self.session.rest_mesh());
        Mirror {
            centre_x: 0.5 * (lo.x + hi.x),
            tolerance: MIRROR_TOLERANCE * (hi.x - lo.x).max(1e-12),
        }
    }

    /// The skeleton a view shows (`rest`: the rest view, else the current one): in the rest
    /// view the draft when there is one; nothing for a mesh with no skeleton; else the rig's
    /// (rest or current).
    pub fn shown_skeleton(&self, rest: bool) -> ShownSkeleton {
        if rest && let Some(d) = &self.draft {
            return ShownSkeleton {
                positions: d.positions(),
                parents: d.parents(),
                names: d.joints.iter().map(|j| j.name.clone()).collect(),
            };
        }
        if !self.rigged() {
            return ShownSkeleton::default();
        }
        let s = &self.session;
        ShownSkeleton {
            positions: if rest {
                s.rest_joints().collect()
            } else {
                s.posed_joints().collect()
            },
            parents: s.skeleton().joints().iter().map(|j| j.parent).collect(),
            names: s
                .skeleton()
                .joints()
                .iter()
                .map(|j| j.name.clone())
                .collect(),
        }
    }

    /// Starts a bind in the background: the draft (or the bound skeleton, re-weighted) with
    /// `weights`, automatic weights computed by `offload` when given (the web page's worker).
    /// Refused while one runs.
    pub fn start_bind(
        &mut self,
        weights: BindWeights,
        offload: Option<&dyn WeightsOffload>,
    ) -> Result<(), DocError> {
        if self.bind_job.is_some() {
            return Err(DocError::Bind("a bind is already running".into()));
        }
        self.bind_job = Some(BindJob::spawn(self.bind_request(weights)?, offload));
        Ok(())
    }

    /// Binds on this thread (scripts and tests); the result is one undo step.
    pub fn bind_blocking(&mut self, weights: BindWeights) -> Result<(), DocError> {
        let bound = self
            .bind_request(weights)?
            .run(&|_| {})
            .map_err(DocError::Bind)?;
        self.finish_bind(bound)
    }

    /// The bind of the draft (or of the bound skeleton, re-weighted) with `weights`.
    fn bind_request(&self, weights: BindWeights) -> Result<BindRequest, DocError> {
        BindRequest::new(&self.session, self.draft.as_ref(), self.rigged(), weights)
            .map_err(DocError::Bind)
    }

    /// The running bind, if any (for its progress).
    pub fn bind_job(&self) -> Option<&BindJob> {
        self.bind_job.as_ref()
    }

    /// Takes the result of the background bind when it is done: `None` while it runs or
    /// when none runs, else what happened (applied as one undo step on success).
    pub fn poll_bind(&mut self) -> Option<Result<String, DocError>> {
        let result = self.bind_job.as_mut()?.poll()?;
        self.bind_job = None;
        Some(match result {
            Ok(bound) => {
                let line = format!(
                    "bound {} joints to {} vertices in {:.2} s",
                    bound.session.skeleton().len(),
                    bound.session.num_vertices(),
                    bound.seconds
                );
                let notes: Vec<String> = bound.warnings.iter().map(|w| w.to_string()).collect();
                self.finish_bind(bound).map(|()| {
                    if notes.is_empty() {
                        line
                    } else {
                        format!("{line} ({})", notes.join("; "))
                    }
                })
            }
            Err(message) => Err(DocError::Bind(message)),
        })
    }

    /// Makes `bound` the rig as one undo step: the pose and the skeleton keys are carried by
    /// joint (new joints at rest), the locks are off, the draft is gone.
    pub fn finish_bind(&mut self, bound: BoundRig) -> Result<(), DocError> {
        self.end_gesture();
        let before = self.snapshot();
        let BoundRig {
            mut session,
            origins,
            ..
        } = bound;
        let (rotations, scales, translation_offsets) = carry_pose(
            &origins,
            &before.rig.rotations,
            &before.rig.scales,
            &before.rig.translation_offsets,
        );
        let mut state = session.editable_state();
        state.rotations = rotations;
        state.scales = scales;
        state.translation_offsets = translation_offsets;
        session.restore_editable_state(&state)?;
        let keys = carry_keys(&self.keys, &origins);
        keys.validate(&session)?;
        self.adopt_binding(session);
        self.draft = None;
        self.keys = keys;
        self.history.record("bind skeleton", before);
        Ok(())
    }

    /// Makes `session` the document's rig as a new binding, the old one stored for undo,
    /// without an undo step of its own (a session file's saved binding, on opening).
    pub fn adopt_binding(&mut self, session: RigSession) {
        let old = std::mem::replace(&mut self.session, session);
        self.stored_bindings.insert(self.binding.id, old);
        self.last_binding_id += 1;
        self.binding = BindingKey {
            id: self.last_binding_id,
            rigged: true,
        };
        self.player = None;
        self.changed();
    }

    /// The session file of this document with the playhead at `time`: the source, the state
    /// and, once a skeleton was bound in the studio, that binding.
    pub fn session_file(&self, time: f64) -> SessionFile {
        let mut file = SessionFile::new(self.source.clone(), self.snapshot(), time);
        if self.binding.id != 0 {
            file.binding = Some(SavedBinding::of(&self.session));
        }
        file.versioned()
    }

    /// Puts the session of binding `key` in force, storing the current one.
    pub(crate) fn switch_binding(&mut self, key: BindingKey) -> Result<(), DocError> {
        let target = self
            .stored_bindings
            .remove(&key.id)
            .ok_or(DocError::NoBinding(key.id))?;
        let old = std::mem::replace(&mut self.session, target);
        self.stored_bindings.insert(self.binding.id, old);
        self.binding = key;
        self.player = None;
        Ok(())
    }
}

/// `keys` on the new skeleton: skeleton keys carried by joint ([`carry_pose`]), cage keys
/// as they are.
fn carry_keys(keys: &Keys, origins: &[Option<usize>]) -> Keys {
    let mut carried = keys.clone();
    for key in &mut carried.skeleton {
        let (r, s, o) = carry_pose(
            origins,
            &key.rotations,
            &key.scales,
            &key.translation_offsets,
        );
        key.rotations = r;
        key.scales = s;
        key.translation_offsets = o;
    }
    carried
}
