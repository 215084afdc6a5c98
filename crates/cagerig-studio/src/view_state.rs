//! What the views show and from where: the two views with their cameras, how they share the
//! window, the layers and the colour map.

use cagerig::session::RigSession;
use cagerig_render::CameraPreset;
use cagerig_render::rig_scene::{ColorBy, Layers, Pose};

use crate::picking::ViewProjection;
use crate::selection::Selection;
use crate::viewport::{View, camera_key};

/// Index of the current-pose view in [`ViewState::views`].
pub const CURRENT: usize = 0;
/// Index of the rest-pose view.
pub const REST: usize = 1;

/// Which colour map the views show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorMode {
    #[default]
    None,
    /// Ω of the selected joint.
    Weights,
    /// Φ of the selected cage vertex.
    CageCoords,
    /// Ψ of the selected joint.
    JointCoords,
    /// The cage handles' distance from the skin (red where C' strays from the body).
    CageReach,
}

/// How the two views share the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Split,
    CurrentOnly,
    RestOnly,
}

/// The views and what they show.
pub struct ViewState {
    /// The current-pose view ([`CURRENT`]) and the rest-pose view ([`REST`]).
    pub views: [View; 2],
    pub layout: Layout,
    pub layers: Layers,
    pub color_mode: ColorMode,
    /// The last error drawing a view (logged once, not every frame).
    pub render_error: Option<String>,
}

impl Default for ViewState {
    fn default() -> Self {
        Self {
            views: [View::new(Pose::Current), View::new(Pose::Rest)],
            layout: Layout::Split,
            layers: Layers::default(),
            color_mode: ColorMode::None,
            render_error: None,
        }
    }
}

impl ViewState {
    /// The projection of view `view` as last shown.
    pub fn projection(&self, view: usize) -> ViewProjection {
        self.views[view].projection()
    }

    /// The views shown by the layout, left to right.
    pub fn visible(&self) -> Vec<usize> {
        match self.layout {
            Layout::Split => vec![CURRENT, REST],
            Layout::CurrentOnly => vec![CURRENT],
            Layout::RestOnly => vec![REST],
        }
    }

    /// Frames the rig in both views, from `preset` (or the current angles).
    pub fn frame_views(&mut self, session: &RigSession, preset: Option<CameraPreset>) {
        for v in [CURRENT, REST] {
            self.views[v].frame_all(session, preset);
        }
    }

    /// Both views frame the next rig shown (a new document).
    pub fn unframe(&mut self) {
        for v in &mut self.views {
            v.framed = false;
        }
    }

    /// The cameras of both views for a session file, once both were framed.
    pub fn camera_keys(&self) -> Option<[[f64; 7]; 2]> {
        self.views.iter().all(|v| v.framed).then(|| {
            [
                camera_key(&self.views[CURRENT].camera),
                camera_key(&self.views[REST].camera),
            ]
        })
    }

    /// The colour map of `selection`.
    pub fn color_by(&self, selection: &Selection) -> ColorBy {
        match self.color_mode {
            ColorMode::None => ColorBy::None,
            ColorMode::Weights => selection.joint.map_or(ColorBy::None, ColorBy::JointWeights),
            ColorMode::JointCoords => selection
                .joint
                .map_or(ColorBy::None, ColorBy::JointCageCoords),
            ColorMode::CageCoords => selection
                .cage
                .first()
                .map_or(ColorBy::None, |&k| ColorBy::CageCoords(k)),
            ColorMode::CageReach => ColorBy::CageReach,
        }
    }
}
