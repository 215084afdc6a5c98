//! A 3D view of the rig (rest or current pose): the renderer of `cagerig-render` draws into the
//! view's own colour + depth textures, whose colour texture egui shows as an image; overlays
//! (selection, gizmo, names) are painted over it by egui.

use std::sync::Arc;
use web_time::Instant;

use cagerig::session::RigSession;
use cagerig_render::rig_scene::{ColorBy, Layers, Pose, RigSceneData};
use cagerig_render::{CameraPreset, OrbitCamera, RenderTarget, Renderer, SceneBuffers, Style};
use egui_wgpu::RenderState;
use glam::DVec3;

use crate::document_skeleton::ShownSkeleton;
use crate::picking::ViewProjection;

/// What a view's picture depends on; the view re-renders only when it changes.
#[derive(Debug, Clone, PartialEq)]
struct PictureKey {
    revision: u64,
    layers: Layers,
    color_by: ColorBy,
    size: (u32, u32),
    camera: [f64; 7],
}

/// A camera as seven numbers (target x, y, z, distance, yaw, pitch, fov_y), for session files.
pub fn camera_key(c: &OrbitCamera) -> [f64; 7] {
    [
        c.target.x, c.target.y, c.target.z, c.distance, c.yaw, c.pitch, c.fov_y,
    ]
}

struct ViewGpu {
    buffers: SceneBuffers,
    target: RenderTarget,
    texture: egui::TextureId,
}

/// One 3D view.
pub struct View {
    pub pose: Pose,
    pub camera: OrbitCamera,
    /// Whether the camera was framed on the rig yet.
    pub framed: bool,
    gpu: Option<ViewGpu>,
    scene_data: RigSceneData,
    uploaded: Option<(u64, Layers, ColorBy)>,
    rendered: Option<PictureKey>,
    /// Milliseconds of the last scene upload (normals and vertex buffers), 0 when none.
    pub last_upload_ms: f64,
    /// Size of the view in points, as last shown.
    pub size_points: egui::Vec2,
    /// Milliseconds recording and submitting the view's GPU work (with a software driver
    /// such as lavapipe, rasterisation shows up here), 0 when not re-rendered.
    pub last_render_ms: f64,
}

impl View {
    pub fn new(pose: Pose) -> Self {
        Self {
            pose,
            camera: OrbitCamera::default(),
            framed: false,
            gpu: None,
            scene_data: RigSceneData::new(),
            uploaded: None,
            rendered: None,
            last_upload_ms: 0.0,
            size_points: egui::vec2(1.0, 1.0),
            last_render_ms: 0.0,
        }
    }

    /// The projection of this view as last shown (for picking and overlays).
    pub fn projection(&self) -> ViewProjection {
        ViewProjection::new(
            self.camera,
            f64::from(self.size_points.x),
            f64::from(self.size_points.y),
        )
    }

    /// Frames the whole rig (skin and cage; the cage is what the user edits) from `preset` (or
    /// the current angles).
    pub fn frame_all(&mut self, session: &RigSession, preset: Option<CameraPreset>) {
        let (mut lo, mut hi) = bounds(session, self.pose);
        if !(lo.is_finite() && hi.is_finite()) {
            (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        }
        if let Some(p) = preset {
            let (yaw, pitch) = p.angles();
            self.camera.yaw = yaw;
            self.camera.pitch = pitch;
        }
        let aspect = f64::from(self.size_points.x / self.size_points.y.max(1.0));
        self.camera.frame_box(lo, hi, aspect);
        self.framed = true;
    }

    /// Uploads (when the rig or the layers changed) and renders (when anything the picture
    /// depends on changed) at `size` pixels; returns the texture to show.
    #[expect(clippy::too_many_arguments)]
    pub fn prepare(
        &mut self,
        render_state: &RenderState,
        renderer: &Arc<Renderer>,
        session: &RigSession,
        revision: u64,
        layers: Layers,
        color_by: ColorBy,
        size: (u32, u32),
        skeleton: &ShownSkeleton,
    ) -> Result<egui::TextureId, cagerig_render::RenderError> {
        let device = &render_state.device;
        let queue = &render_state.queue;
        let size = (size.0.max(1), size.1.max(1));
        if self.gpu.as_ref().is_none_or(|g| g.target.size() != size) {
            let target = RenderTarget::new(device, renderer.pipelines(), size.0, size.1)?;
            let mut egui_renderer = render_state.renderer.write();
            let texture = match self.gpu.take() {
                Some(old) => {
                    egui_renderer.update_egui_texture_from_wgpu_texture(
                        device,
                        target.color_view(),
                        wgpu::FilterMode::Linear,
                        old.texture,
                    );
                    self.gpu = Some(ViewGpu {
                        buffers: old.buffers,
                        target,
                        texture: old.texture,
                    });
                    old.texture
                }
                None => {
                    let texture = egui_renderer.register_native_texture(
                        device,
                        target.color_view(),
                        wgpu::FilterMode::Linear,
                    );
                    self.gpu = Some(ViewGpu {
                        buffers: SceneBuffers::new(device, renderer.pipelines()),
                        target,
                        texture,
                    });
                    texture
                }
            };
            self.rendered = None;
            let _ = texture;
        }
        let Some(gpu) = self.gpu.as_mut() else {
            return Err(cagerig_render::RenderError::Readback(
                "no view target".into(),
            ));
        };
        // One encoder (and one submission) per view for the upload's copies and the picture:
        // with a software driver the submission is where the CPU rasterises, which is counted
        // as rendering, not as upload.
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("cagerig view"),
        });
        let upload_key = (revision, layers, color_by);
        let uploaded = self.uploaded != Some(upload_key);
        if uploaded {
            let t = Instant::now();
            let scene = self.scene_data.scene_with_skeleton(
                session,
                self.pose,
                layers,
                color_by,
                Some((&skeleton.positions, &skeleton.parents)),
            );
            gpu.buffers
                .update_into(device, queue, &mut encoder, &scene, &editor_style())?;
            self.last_upload_ms = t.elapsed().as_secs_f64() * 1e3;
            self.uploaded = Some(upload_key);
        } else {
            self.last_upload_ms = 0.0;
        }
        let key = PictureKey {
            revision,
            layers,
            color_by,
            size,
            camera: camera_key(&self.camera),
        };
        self.last_render_ms = 0.0;
        let render = self.rendered.as_ref() != Some(&key);
        if render || uploaded {
            let t = Instant::now();
            if render {
                renderer.encode(queue, &mut encoder, &gpu.target, &self.camera, &gpu.buffers);
                self.rendered = Some(key);
            }
            queue.submit([encoder.finish()]);
            gpu.buffers.recall_staging();
            self.last_render_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        Ok(gpu.texture)
    }

    /// Frees the egui texture of this view.
    pub fn release(&mut self, render_state: &RenderState) {
        if let Some(gpu) = self.gpu.take() {
            render_state.renderer.write().free_texture(&gpu.texture);
        }
    }
}

/// The camera of [`camera_key`]'s numbers (`None` if they do not make a camera).
pub fn camera_from_key(k: [f64; 7]) -> Option<OrbitCamera> {
    (k.iter().all(|v| v.is_finite()) && k[3] > 0.0 && k[6] > 0.0 && k[6] < 3.1).then(|| {
        OrbitCamera {
            target: DVec3::new(k[0], k[1], k[2]),
            distance: k[3],
            yaw: k[4],
            pitch: k[5],
            fov_y: k[6],
        }
    })
}

/// Bounding box of the skin and the cage of a pose.
pub fn bounds(session: &RigSession, pose: Pose) -> (DVec3, DVec3) {
    let (mesh, cage) = match pose {
        Pose::Rest => (session.rest_mesh(), session.rest_cage()),
        Pose::Current => (session.posed_mesh(), session.posed_cage()),
    };
    mesh.iter().chain(cage).fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// The editor's drawing style: the offscreen pictures' style with a lighter cage (fainter faces,
/// thinner and translucent edges, smaller handles), so that the character reads through the
/// cage while the cage stays easy to pick.
pub fn editor_style() -> Style {
    Style {
        cage_faces: [255, 140, 30, 14],
        cage_edges: [235, 110, 10, 150],
        cage_handles: [255, 150, 40, 230],
        hidden_alpha: 35,
        line_width: 1.2,
        handle_radius: 3.5,
        ..Style::default()
    }
}
