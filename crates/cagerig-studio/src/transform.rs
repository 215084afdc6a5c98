//! Interactive transforms of the selection — grab / rotate / scale of cage vertices (C in the
//! rest view, C' in the current view) and rotation of a joint (S', current view) — started by
//! a gizmo handle, by dragging a selected element, or by Blender-like keys (G / R / S, then
//! X / Y / Z, typed values, Enter / Esc). Each mouse move is one session event; the whole
//! transform is one undo step.

use cagerig::session::RigSession;
use glam::{DQuat, DVec2, DVec3};

use crate::document::{Command, Document, SkeletonEdit};
use crate::gizmo::{self, Axis, Constraint};
use crate::picking::ViewProjection;
use crate::selection::Selection;
use crate::skeleton_draft::Mirror;
use crate::view_state::{CURRENT, REST};

/// Grab, rotate or scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TransformOp {
    Grab,
    Rotate,
    Scale,
}

impl TransformOp {
    pub fn label(self) -> &'static str {
        match self {
            TransformOp::Grab => "grab",
            TransformOp::Rotate => "rotate",
            TransformOp::Scale => "scale",
        }
    }
}

/// What a transform moves.
#[derive(Debug, Clone, PartialEq)]
pub enum TransformTarget {
    /// Cage vertices and their positions when the transform started.
    Cage {
        vertices: Vec<usize>,
        start: Vec<DVec3>,
    },
    /// A joint of the current skeleton; `applied` is the world rotation applied so far.
    Joint {
        joint: usize,
        applied: DQuat,
        trackball: bool,
    },
    /// A joint of the skeleton being built (rest view), moved with its X-mirror twin when
    /// `mirror` is on; `start` is where it was.
    RestJoint {
        joint: usize,
        start: DVec3,
        mirror: Option<Mirror>,
    },
}

/// A transform in progress.
#[derive(Debug, Clone, PartialEq)]
pub struct Transform {
    /// Which view ([`CURRENT`] or [`crate::view_state::REST`]).
    pub view: usize,
    pub op: TransformOp,
    pub constraint: Constraint,
    pub target: TransformTarget,
    /// Mouse position (view pixels) when it started.
    pub start_mouse: DVec2,
    /// Started by a key: follows the mouse without a button, confirmed by a click or Enter.
    pub modal: bool,
    /// A value typed during a modal transform (distance, degrees or factor).
    pub typed: String,
    pub pivot: DVec3,
}

impl Transform {
    /// The typed value, if it parses.
    pub fn typed_value(&self) -> Option<f64> {
        let t = self.typed.trim();
        if t.is_empty() || t == "-" {
            return None;
        }
        t.parse::<f64>().ok().filter(|v| v.is_finite())
    }

    /// Sets the constraint from an axis key (X / Y / Z; with shift the plane normal to it);
    /// the same key again frees it.
    pub fn toggle_axis(&mut self, axis: Axis, plane: bool) {
        let wanted = if plane {
            Constraint::Plane(axis)
        } else {
            Constraint::Axis(axis)
        };
        self.constraint = if self.constraint == wanted {
            Constraint::Free
        } else {
            wanted
        };
    }

    /// One line for the status bar.
    pub fn describe(&self) -> String {
        let c = match self.constraint {
            Constraint::Free => String::new(),
            Constraint::Axis(a) => format!(" along {}", a.name()),
            Constraint::Plane(a) => format!(" in the plane normal to {}", a.name()),
        };
        let typed = if self.typed.is_empty() {
            String::new()
        } else {
            format!(" = {}", self.typed)
        };
        format!(
            "{}{c}{typed} — X/Y/Z constrain (Shift: plane), type a value, Enter/click confirm, \
             Esc/right-click cancel",
            self.op.label()
        )
    }
}

/// Axis a rotation turns about: the constraint's axis, or the view axis.
fn rotation_axis(constraint: Constraint, view_back: DVec3) -> DVec3 {
    match constraint {
        Constraint::Axis(a) | Constraint::Plane(a) => a.vector(),
        Constraint::Free => view_back,
    }
}

/// How a transform starts: in which view, what it does, where the mouse was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransformStart {
    pub view: usize,
    pub op: TransformOp,
    pub constraint: Constraint,
    /// Mouse position (view pixels).
    pub mouse: DVec2,
    /// Started by a key (see [`Transform::modal`]).
    pub modal: bool,
    /// A joint rotation follows the mouse as a trackball (when free and nothing is typed).
    pub trackball: bool,
}

/// Why a joint cannot be transformed so in the current-pose view.
pub const JOINTS_ROTATE_IN_THE_CURRENT_VIEW: &str = "joints are rotated in the current-pose view (R), and moved in the rest-pose view (G) to \
     change the skeleton";

/// Why a joint cannot be rotated or scaled in the rest-pose view.
pub const JOINTS_MOVE_IN_THE_REST_VIEW: &str = "in the rest-pose view joints are moved (G) to change the skeleton; rotate them in the \
     current-pose view (R)";

impl Transform {
    /// A transform of the active selection of `session`: `Ok(None)` when nothing is selected,
    /// `Err` with the reason when the selection cannot be transformed so.
    pub fn begin(
        doc: &Document,
        selection: &Selection,
        start: TransformStart,
    ) -> Result<Option<Transform>, String> {
        let session = &doc.session;
        let TransformStart {
            view,
            op,
            constraint,
            mouse,
            modal,
            trackball,
        } = start;
        let target = if selection.joint_active() {
            let Some(joint) = selection.joint else {
                return Ok(None);
            };
            let Some(&position) = doc.shown_skeleton(view == REST).positions.get(joint) else {
                return Ok(None);
            };
            match (view == CURRENT, op) {
                (true, TransformOp::Rotate) => {
                    doc.check_posable().map_err(|e| e.to_string())?;
                    TransformTarget::Joint {
                        joint,
                        applied: DQuat::IDENTITY,
                        trackball,
                    }
                }
                (true, TransformOp::Grab | TransformOp::Scale) => {
                    return Err(JOINTS_ROTATE_IN_THE_CURRENT_VIEW.into());
                }
                (false, TransformOp::Grab) => TransformTarget::RestJoint {
                    joint,
                    start: position,
                    mirror: doc.mirror_x.then(|| doc.mirror()),
                },
                (false, TransformOp::Rotate | TransformOp::Scale) => {
                    return Err(JOINTS_MOVE_IN_THE_REST_VIEW.into());
                }
            }
        } else {
            if selection.cage.is_empty() {
                return Ok(None);
            }
            let positions = if view == CURRENT {
                session.posed_cage()
            } else {
                session.rest_cage()
            };
            let vertices: Vec<usize> = selection.cage.iter().copied().collect();
            TransformTarget::Cage {
                start: vertices.iter().map(|&k| positions[k]).collect(),
                vertices,
            }
        };
        let pivot = match &target {
            TransformTarget::Cage { start, .. } => {
                start.iter().copied().sum::<DVec3>() / start.len() as f64
            }
            TransformTarget::Joint { joint, .. } => {
                session.posed_world_from_joint()[*joint].translation
            }
            TransformTarget::RestJoint { start, .. } => *start,
        };
        Ok(Some(Transform {
            view,
            op,
            constraint,
            target,
            start_mouse: mouse,
            modal,
            typed: String::new(),
            pivot,
        }))
    }

    /// The label of the transform's undo step.
    pub fn gesture_label(&self) -> String {
        match (&self.target, self.view == CURRENT) {
            (TransformTarget::Joint { .. }, _) => "rotate joint".to_string(),
            (TransformTarget::RestJoint { .. }, _) => "move joint".to_string(),
            (TransformTarget::Cage { .. }, true) => format!("{} current cage", self.op.label()),
            (TransformTarget::Cage { .. }, false) => format!("{} rest cage", self.op.label()),
        }
    }

    /// The command that brings `session` to the transform for the mouse at `mouse` (view
    /// pixels, `projection` the transform's view); `None` when nothing moves.
    pub fn step(
        &mut self,
        projection: &ViewProjection,
        session: &RigSession,
        mouse: DVec2,
    ) -> Option<Command> {
        let back = projection.camera.backward();
        let typed = self.typed_value();
        let (view, op, constraint, start_mouse, pivot) = (
            self.view,
            self.op,
            self.constraint,
            self.start_mouse,
            self.pivot,
        );
        match &mut self.target {
            TransformTarget::Cage { vertices, start } => {
                let targets: Vec<DVec3> = match op {
                    TransformOp::Grab => {
                        let d = match (typed, constraint) {
                            (Some(v), Constraint::Axis(a)) => v * a.vector(),
                            (Some(v), _) => DVec3::new(v, 0.0, 0.0),
                            (None, c) => {
                                gizmo::drag_translation(projection, pivot, c, start_mouse, mouse)
                            }
                        };
                        start.iter().map(|p| *p + d).collect()
                    }
                    TransformOp::Rotate => {
                        let axis = rotation_axis(constraint, back);
                        let angle = typed.map(f64::to_radians).unwrap_or_else(|| {
                            gizmo::drag_rotation_angle(projection, pivot, axis, start_mouse, mouse)
                        });
                        let q = DQuat::from_axis_angle(axis, angle);
                        start.iter().map(|p| pivot + q * (*p - pivot)).collect()
                    }
                    TransformOp::Scale => {
                        let f = typed.unwrap_or_else(|| {
                            gizmo::drag_scale(projection, pivot, start_mouse, mouse)
                        });
                        let s = gizmo::scale_vector(f, constraint);
                        start.iter().map(|p| pivot + s * (*p - pivot)).collect()
                    }
                };
                let current = if view == CURRENT {
                    session.posed_cage()
                } else {
                    session.rest_cage()
                };
                let offsets: Vec<DVec3> = vertices
                    .iter()
                    .zip(&targets)
                    .map(|(&k, p)| *p - current[k])
                    .collect();
                if offsets.iter().all(|o| o.length_squared() == 0.0) {
                    None
                } else if view == CURRENT {
                    Some(Command::MovePosedCage {
                        vertices: vertices.clone(),
                        offsets,
                    })
                } else {
                    Some(Command::MoveRestCage {
                        vertices: vertices.clone(),
                        offsets,
                    })
                }
            }
            TransformTarget::Joint {
                joint,
                applied,
                trackball,
            } => {
                let total = if *trackball && typed.is_none() && constraint == Constraint::Free {
                    gizmo::trackball(projection, start_mouse, mouse, 0.01)
                } else {
                    let axis = rotation_axis(constraint, back);
                    let angle = typed.map(f64::to_radians).unwrap_or_else(|| {
                        gizmo::drag_rotation_angle(projection, pivot, axis, start_mouse, mouse)
                    });
                    DQuat::from_axis_angle(axis, angle)
                };
                let delta = (total * applied.inverse()).normalize();
                let (axis, angle) = delta.to_axis_angle();
                *applied = total;
                (angle.abs() > 1e-12 && axis.is_finite()).then_some(Command::RotateJoint {
                    joint: *joint,
                    axis,
                    angle,
                })
            }
            TransformTarget::RestJoint {
                joint,
                start,
                mirror,
            } => {
                let d = match (typed, constraint) {
                    (Some(v), Constraint::Axis(a)) => v * a.vector(),
                    (Some(v), _) => DVec3::new(v, 0.0, 0.0),
                    (None, c) => gizmo::drag_translation(projection, pivot, c, start_mouse, mouse),
                };
                Some(Command::EditSkeleton(SkeletonEdit::Move {
                    joint: *joint,
                    position: *start + d,
                    mirror: *mirror,
                }))
            }
        }
    }
}

/// Whether a transform target is a joint (for overlays).
pub fn is_joint_transform(target: &TransformTarget) -> bool {
    matches!(target, TransformTarget::Joint { .. })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn transform() -> Transform {
        Transform {
            view: CURRENT,
            op: TransformOp::Grab,
            constraint: Constraint::Free,
            target: TransformTarget::Cage {
                vertices: vec![0],
                start: vec![DVec3::ZERO],
            },
            start_mouse: DVec2::ZERO,
            modal: true,
            typed: String::new(),
            pivot: DVec3::ZERO,
        }
    }

    #[test]
    fn axis_keys_toggle_between_axis_plane_and_free() {
        let mut t = transform();
        t.toggle_axis(Axis::X, false);
        assert_eq!(t.constraint, Constraint::Axis(Axis::X));
        t.toggle_axis(Axis::X, false);
        assert_eq!(t.constraint, Constraint::Free);
        t.toggle_axis(Axis::Z, true);
        assert_eq!(t.constraint, Constraint::Plane(Axis::Z));
    }

    #[test]
    fn typed_values_parse_or_are_ignored() {
        let mut t = transform();
        assert_eq!(t.typed_value(), None);
        t.typed = "-1.5".into();
        assert_eq!(t.typed_value(), Some(-1.5));
        t.typed = "-".into();
        assert_eq!(t.typed_value(), None);
        t.typed = "1e999".into();
        assert_eq!(t.typed_value(), None);
    }
}
