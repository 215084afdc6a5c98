//! Pictures of a rig's state for `render`, `demo`, `edit --render` and `animate --render`:
//! the rest pose (M, C, S) and/or the current pose (M', C', S') rendered offscreen, side by side
//! for `both` (rest on the left, current on the right, as the paper tool shows them).

use std::path::Path;

use anyhow::Context;
use cagerig::session::RigSession;
use cagerig_render::annotate;
use cagerig_render::rig_scene::{ColorBy, Layers, Pose, RigSceneData};
use cagerig_render::{CameraPreset, OffscreenRenderer, OrbitCamera, RgbaImage, Style};
use clap::ValueEnum;
use glam::DVec3;

/// Which pose(s) a picture shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum ViewArg {
    /// The current pose M', C', S'.
    Current,
    /// The rest pose M, C, S.
    Rest,
    /// Rest pose on the left, current pose on the right.
    #[default]
    Both,
}

/// Where the camera is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraChoice {
    /// A preset, framing everything shown.
    Preset(CameraPreset),
    /// An explicit eye and target (world space).
    LookAt { eye: DVec3, target: DVec3 },
}

/// Everything that decides how a picture looks.
#[derive(Debug, Clone, Copy)]
pub struct PictureOptions {
    pub view: ViewArg,
    /// Size of the whole picture in pixels (both views together for `both`).
    pub size: (u32, u32),
    pub camera: CameraChoice,
    pub layers: Layers,
    pub color_by: ColorBy,
    /// Name the pose(s) in the picture's top-left corner.
    pub labels: bool,
}

impl Default for PictureOptions {
    fn default() -> Self {
        Self {
            view: ViewArg::Both,
            size: (1600, 700),
            camera: CameraChoice::Preset(CameraPreset::ThreeQuarter),
            layers: Layers::default(),
            color_by: ColorBy::None,
            labels: true,
        }
    }
}

/// Gap between the two views of a `both` picture (pixels).
const GAP: u32 = 4;

/// An offscreen renderer with its scratch data, reused from picture to picture.
pub struct PictureMaker {
    renderer: OffscreenRenderer,
    data: RigSceneData,
    pub options: PictureOptions,
    /// What the next pictures show (the step, the sample time), drawn under each view's label.
    pub caption: Option<String>,
    /// The cage vertices the next pictures mark (those an edit moved).
    pub marked: MarkedHandles,
}

/// Cage vertices marked in the pictures: those a script moved in the rest cage C (marked in
/// the rest view) and those it grabbed in the current cage C' (marked in the current view).
#[derive(Debug, Clone, Default)]
pub struct MarkedHandles {
    pub rest: Vec<usize>,
    pub current: Vec<usize>,
}

impl MarkedHandles {
    /// The vertices moved by `steps`.
    pub fn of_steps<'a>(steps: impl IntoIterator<Item = &'a cagerig::script::EditStep>) -> Self {
        let mut marked = Self::default();
        for step in steps {
            match step {
                cagerig::script::EditStep::MoveRestCage { vertices, .. } => {
                    marked.rest.extend(vertices)
                }
                cagerig::script::EditStep::MovePosedCage { vertices, .. } => {
                    marked.current.extend(vertices)
                }
                cagerig::script::EditStep::RotateJoint { .. }
                | cagerig::script::EditStep::SetSkinning { .. }
                | cagerig::script::EditStep::ResetPose {} => {}
            }
        }
        marked
    }
}

impl PictureMaker {
    /// Opens the GPU (fails with what to install when there is no adapter).
    pub fn new(options: PictureOptions) -> anyhow::Result<Self> {
        let renderer = OffscreenRenderer::new().context("starting the renderer")?;
        Ok(Self {
            renderer,
            data: RigSceneData::new(),
            options,
            caption: None,
            marked: MarkedHandles::default(),
        })
    }

    pub fn adapter_name(&self) -> &str {
        self.renderer.adapter_name()
    }

    fn poses(&self) -> &'static [Pose] {
        match self.options.view {
            ViewArg::Current => &[Pose::Current],
            ViewArg::Rest => &[Pose::Rest],
            ViewArg::Both => &[Pose::Rest, Pose::Current],
        }
    }

    /// Bounds of what the picture shows in every pose drawn (one camera frames all views).
    fn bounds(&mut self, session: &RigSession) -> (DVec3, DVec3) {
        let mut bounds: Option<(DVec3, DVec3)> = None;
        for &pose in self.poses() {
            let scene = self
                .data
                .scene(session, pose, self.options.layers, ColorBy::None);
            if let Some((lo, hi)) = scene.bounds() {
                bounds = Some(match bounds {
                    Some((a, b)) => (a.min(lo), b.max(hi)),
                    None => (lo, hi),
                });
            }
        }
        bounds.unwrap_or((DVec3::splat(-1.0), DVec3::splat(1.0)))
    }

    /// Size of one view of the picture.
    fn view_size(&self) -> (u32, u32) {
        let (w, h) = self.options.size;
        match self.options.view {
            ViewArg::Both => (w.saturating_sub(GAP).div_ceil(2).max(1), h.max(1)),
            _ => (w.max(1), h.max(1)),
        }
    }

    /// The camera for `session`, turned by `extra_yaw` radians about the vertical axis.
    pub fn camera(&mut self, session: &RigSession, extra_yaw: f64) -> OrbitCamera {
        let (w, h) = self.view_size();
        let mut camera = match self.options.camera {
            CameraChoice::Preset(preset) => {
                let (lo, hi) = self.bounds(session);
                OrbitCamera::framing(preset, lo, hi, w as f64 / h as f64)
            }
            CameraChoice::LookAt { eye, target } => OrbitCamera::looking_at(eye, target),
        };
        camera.yaw += extra_yaw;
        camera
    }

    /// Renders the picture of `session` with `camera`.
    pub fn picture(
        &mut self,
        session: &RigSession,
        camera: &OrbitCamera,
    ) -> anyhow::Result<RgbaImage> {
        let (w, h) = self.view_size();
        let style = Style {
            scale: (h as f32 / 700.0).max(0.75),
            ..Style::default()
        };
        let text_scale = (h.saturating_add(150) / 300).clamp(1, 4);
        let legend = self.data.legend(session, self.options.color_by);
        let margin = 6 * text_scale;
        let legend_bar = 6 * text_scale;
        // The legend's place at the top right, kept clear of the labels on the left.
        let legend_width = legend.as_ref().map_or(0, |(map, title)| {
            annotate::legend_width(*map, title, legend_bar, text_scale) + margin
        });
        let mut views = Vec::with_capacity(2);
        for &pose in self.poses() {
            self.data.marked_handles = match pose {
                Pose::Rest => self.marked.rest.clone(),
                Pose::Current => self.marked.current.clone(),
            };
            let scene = self
                .data
                .scene(session, pose, self.options.layers, self.options.color_by);
            let mut image = self.renderer.render(&scene, &style, camera, w, h)?;
            // The moved cage vertices, ringed (their handles alone are too small to find).
            let cage = match pose {
                Pose::Rest => session.rest_cage(),
                Pose::Current => session.posed_cage(),
            };
            for &k in &self.data.marked_handles {
                if let Some((x, y, _)) = cage
                    .get(k)
                    .and_then(|&p| camera.project(p, f64::from(w), f64::from(h), 1.0))
                {
                    let radius = 7.0 * f64::from(style.scale).max(1.0);
                    annotate::draw_ring(
                        &mut image,
                        x,
                        y,
                        radius,
                        radius / 3.0,
                        cagerig_render::rig_scene::MARKED_HANDLE,
                    );
                }
            }
            if self.options.labels {
                let label = match pose {
                    Pose::Rest => "rest pose (M, C, S)",
                    Pose::Current => "current pose (M', C', S')",
                };
                annotate::draw_text(
                    &mut image,
                    margin,
                    margin,
                    label,
                    text_scale,
                    [30, 32, 38, 255],
                );
                if let Some(caption) = &self.caption {
                    // Wrapped within the view, clear of the legend.
                    let width = w.saturating_sub(2 * margin + legend_width);
                    for (k, line) in annotate::wrap_text(caption, width, text_scale)
                        .iter()
                        .enumerate()
                    {
                        annotate::draw_text(
                            &mut image,
                            margin,
                            margin + (11 + 10 * k as u32) * text_scale,
                            line,
                            text_scale,
                            [70, 74, 84, 255],
                        );
                    }
                }
            }
            if let Some((map, title)) = &legend {
                let bar_height = h / 3;
                let x = w.saturating_sub(legend_width);
                let y = margin;
                annotate::draw_legend(
                    &mut image, *map, x, y, legend_bar, bar_height, text_scale, title,
                );
            }
            views.push(image);
        }
        Ok(match views.as_slice() {
            [rest, current] => RgbaImage::side_by_side(rest, current, GAP),
            _ => views.remove(0),
        })
    }

    /// Renders `session` (framed) as `name` into a staged output folder.
    pub fn write_staged(
        &mut self,
        session: &RigSession,
        staged: &mut crate::output_dir::StagedDir,
        name: &str,
    ) -> anyhow::Result<()> {
        let camera = self.camera(session, 0.0);
        let png = self.picture(session, &camera)?.to_png()?;
        Ok(staged.write(name, &|w| w.write_all(&png))?)
    }

    /// Pictures for `edit --render` / `animate --render`: rest | current side by side.
    pub fn for_steps(render: bool) -> anyhow::Result<Option<Self>> {
        render
            .then(|| Self::new(PictureOptions::default()))
            .transpose()
            .context("--render")
    }

    /// Renders `session` (framed) and writes the PNG at `path`.
    pub fn write(&mut self, session: &RigSession, path: &Path) -> anyhow::Result<()> {
        let camera = self.camera(session, 0.0);
        let image = self.picture(session, &camera)?;
        image.write_png(path)?;
        Ok(())
    }
}
