//! What the mouse hits in a view: the nearest on screen of the visible joints (drawn on top)
//! and the cage vertices not hidden by the skin, and the cage vertices inside a box.

use cagerig::session::RigSession;
use cagerig_render::rig_scene::Layers;
use glam::{DVec2, DVec3};

use crate::document::Document;
use crate::picking::{Occluder, ViewProjection, pick_box, pick_nearest};
use crate::selection::Picked;
use crate::view_state::{CURRENT, REST, ViewState};

/// Pixels within which a click picks a cage vertex or a joint.
pub const PICK_PIXELS: f64 = 12.0;

/// The rig as one view shows it, for picking.
pub struct ViewPicker<'a> {
    session: &'a RigSession,
    /// The joints the view shows (`#J` of its skeleton).
    joints: Vec<DVec3>,
    layers: Layers,
    projection: ViewProjection,
    /// The current-pose view (else the rest-pose view).
    current: bool,
}

impl<'a> ViewPicker<'a> {
    /// Picking in view `view` of `views` as last shown.
    pub fn new(doc: &'a Document, views: &ViewState, view: usize) -> Self {
        Self {
            session: &doc.session,
            joints: doc.shown_skeleton(view == REST).positions,
            layers: views.layers,
            projection: views.projection(view),
            current: view == CURRENT,
        }
    }

    /// The skin of the view's pose as an occluder of picking (`None` when the skin is hidden).
    fn skin_occluder(&self) -> Option<Occluder<'a>> {
        let s = self.session;
        self.layers.mesh.then(|| Occluder {
            positions: if self.current {
                s.posed_mesh()
            } else {
                s.rest_mesh()
            },
            triangles: s.mesh_triangles(),
        })
    }

    fn cage(&self) -> &'a [DVec3] {
        if self.current {
            self.session.posed_cage()
        } else {
            self.session.rest_cage()
        }
    }

    /// The element under `mouse` (view pixels): the nearest on screen of the visible joints
    /// (drawn on top) and the cage vertices not hidden by the skin.
    pub fn pick(&self, mouse: DVec2) -> Option<Picked> {
        let projection = &self.projection;
        let occluder = self.skin_occluder();
        let joints = &self.joints;
        let cage = self.cage();
        let screen_distance = |p: DVec3| {
            projection
                .project(p)
                .map_or(f64::INFINITY, |q| q.distance(mouse))
        };
        let joint = self
            .layers
            .skeleton
            .then(|| pick_nearest(projection, joints, mouse, PICK_PIXELS, None))
            .flatten();
        let vertex = self
            .layers
            .cage
            .then(|| pick_nearest(projection, cage, mouse, PICK_PIXELS, occluder))
            .flatten();
        match (joint, vertex) {
            (Some(j), Some(k)) if screen_distance(cage[k]) < screen_distance(joints[j]) => {
                Some(Picked::CageVertex(k))
            }
            (Some(j), _) => Some(Picked::Joint(j)),
            (None, Some(k)) => Some(Picked::CageVertex(k)),
            (None, None) => None,
        }
    }

    /// The joint under `mouse` (joints are drawn on top: no occlusion).
    pub fn pick_joint(&self, mouse: DVec2) -> Option<usize> {
        if !self.layers.skeleton {
            return None;
        }
        pick_nearest(&self.projection, &self.joints, mouse, PICK_PIXELS, None)
    }

    /// The visible cage vertices inside the box between two corners (view pixels).
    pub fn cage_in_box(&self, a: DVec2, b: DVec2) -> Vec<usize> {
        pick_box(&self.projection, self.cage(), a, b, self.skin_occluder())
    }
}
