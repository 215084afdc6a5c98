//! Interaction with the rig: the selection, the active tool, the mouse state of the views
//! (transform in progress, box selection, hovered view and joint), numeric entry, and the
//! life of a transform as one gesture of the document (begun, one session event per mouse
//! move, confirmed or cancelled).

use cagerig::session::RigSession;
use glam::{DVec2, DVec3};

use crate::diagnostics::{Diagnostics, Log};
use crate::document::Document;
use crate::document_skeleton::ShownSkeleton;
use crate::selection::{Selection, Tool};
use crate::transform::{Transform, TransformStart};
use crate::view_state::{CURRENT, ViewState};

/// Mouse state shared by the views.
#[derive(Debug, Clone)]
pub struct Interaction {
    pub transform: Option<Transform>,
    /// Box selection: the view and the corner where it started (view pixels).
    pub box_select: Option<(usize, DVec2)>,
    /// The view under the mouse.
    pub hovered_view: Option<usize>,
    /// A joint under the mouse: (view, joint).
    pub hovered_joint: Option<(usize, usize)>,
    /// Last mouse position over the view of the transform (view pixels).
    pub last_mouse: Option<DVec2>,
    /// Screen rectangles of the views as last laid out.
    pub view_rects: [egui::Rect; 2],
}

impl Default for Interaction {
    fn default() -> Self {
        Self {
            transform: None,
            box_select: None,
            hovered_view: None,
            hovered_joint: None,
            last_mouse: None,
            view_rects: [egui::Rect::NOTHING; 2],
        }
    }
}

/// Numeric-entry fields kept between frames.
#[derive(Debug, Clone, Default)]
pub struct NumericEntry {
    /// Offset applied to the cage selection by "Move by".
    pub offset: [f64; 3],
    /// Whether the Euler drag values are being dragged (one undo step per drag).
    pub(crate) euler_dragging: bool,
}

/// Selection, tool, mouse state and numeric entry.
#[derive(Debug, Clone)]
pub struct Tools {
    pub selection: Selection,
    pub tool: Tool,
    /// A click on the mesh in the rest view adds a joint (below the selected joint).
    pub add_joints: bool,
    /// The Skeleton panel's name field: (joint, text being typed).
    pub joint_name: Option<(usize, String)>,
    pub interaction: Interaction,
    pub numeric: NumericEntry,
}

impl Default for Tools {
    fn default() -> Self {
        Self {
            selection: Selection::default(),
            tool: Tool::Move,
            add_joints: false,
            joint_name: None,
            interaction: Interaction::default(),
            numeric: NumericEntry::default(),
        }
    }
}

impl Tools {
    /// A new document: nothing selected, no mouse state (the tool and the numeric fields
    /// stay).
    pub fn reset_for_new_document(&mut self) {
        self.selection = Selection::default();
        self.interaction = Interaction::default();
    }

    /// Where the gizmo of the active selection sits in `view`, and which handles it shows
    /// (arrows and plane squares, rings).
    pub fn gizmo_pivot(
        &self,
        session: &RigSession,
        skeleton: &ShownSkeleton,
        view: usize,
    ) -> Option<(DVec3, bool, bool)> {
        if let Some(t) = &self.interaction.transform {
            return (t.view == view).then_some((t.pivot, false, false));
        }
        if self.selection.joint_active() {
            let position = *skeleton.positions.get(self.selection.joint?)?;
            // Joints rotate in the current view and move (skeleton building) in the rest view.
            return Some((position, view != CURRENT, view == CURRENT));
        }
        if self.selection.cage.is_empty() {
            return None;
        }
        let cage = if view == CURRENT {
            session.posed_cage()
        } else {
            session.rest_cage()
        };
        let centre = self.selection.cage.iter().map(|&k| cage[k]).sum::<DVec3>()
            / self.selection.cage.len() as f64;
        let (arrows, rings) = match self.tool {
            Tool::Move | Tool::Scale => (true, false),
            Tool::Rotate => (false, true),
        };
        Some((centre, arrows, rings))
    }

    /// Starts a transform of the active selection (one undo step until it ends); false when
    /// there is nothing to transform (a refusal is logged as a warning).
    pub fn begin_transform(
        &mut self,
        doc: Option<&mut Document>,
        start: TransformStart,
        log: &mut Log,
    ) -> bool {
        let Some(doc) = doc else {
            return false;
        };
        match Transform::begin(doc, &self.selection, start) {
            Ok(Some(transform)) => {
                doc.begin_gesture(transform.gesture_label());
                self.interaction.transform = Some(transform);
                true
            }
            Ok(None) => false,
            Err(reason) => {
                log.warning(reason);
                false
            }
        }
    }

    /// Updates the transform for the mouse at `mouse` (view pixels): one session event. A
    /// failed event cancels the transform and is logged.
    pub fn update_transform(
        &mut self,
        doc: Option<&mut Document>,
        views: &ViewState,
        mouse: DVec2,
        diag: &mut Diagnostics,
    ) {
        let Some(doc) = doc else {
            return;
        };
        let Some(mut t) = self.interaction.transform.take() else {
            return;
        };
        let projection = views.projection(t.view);
        let command = t.step(&projection, &doc.session, mouse);
        self.interaction.transform = Some(t);
        if let Some(command) = command {
            match doc.gesture_event(&command) {
                Ok(()) => diag.stats.sync_ms += doc.last_sync_ms,
                Err(e) => {
                    let message = format!("{}: {e}", command.label());
                    self.cancel_transform(Some(doc), &mut diag.log);
                    diag.log.error(message);
                }
            }
        }
    }

    /// Confirms the transform (one undo step).
    pub fn confirm_transform(&mut self, doc: Option<&mut Document>) {
        if self.interaction.transform.take().is_some()
            && let Some(doc) = doc
        {
            doc.end_gesture();
        }
    }

    /// Cancels the transform: back to the state before it.
    pub fn cancel_transform(&mut self, doc: Option<&mut Document>, log: &mut Log) {
        if self.interaction.transform.take().is_some()
            && let Some(doc) = doc
            && let Err(e) = doc.cancel_gesture()
        {
            log.error(format!("cancelling the transform: {e}"));
        }
    }
}
