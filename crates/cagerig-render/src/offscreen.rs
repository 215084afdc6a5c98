//! Headless pictures: a device, the pipelines, one view's buffers and targets, reused from
//! picture to picture (buffers and targets are re-created only when sizes grow or change).

use crate::camera::OrbitCamera;
use crate::error::RenderError;
use crate::gpu::GpuContext;
use crate::image::RgbaImage;
use crate::renderer::Renderer;
use crate::scene::{Scene, Style};
use crate::scene_buffers::SceneBuffers;
use crate::target::RenderTarget;

/// Renders scenes to CPU images without a window.
pub struct OffscreenRenderer {
    gpu: GpuContext,
    renderer: Renderer,
    buffers: SceneBuffers,
    target: Option<RenderTarget>,
}

impl OffscreenRenderer {
    /// Opens a headless device (see [`GpuContext::new_headless`]).
    pub fn new() -> Result<Self, RenderError> {
        let gpu = GpuContext::new_headless()?;
        let renderer = Renderer::new(&gpu.device);
        let buffers = SceneBuffers::new(&gpu.device, renderer.pipelines());
        Ok(Self {
            gpu,
            renderer,
            buffers,
            target: None,
        })
    }

    /// Name and backend of the adapter in use.
    pub fn adapter_name(&self) -> &str {
        &self.gpu.adapter_name
    }

    /// Runs `work` with the device's errors (validation, out of memory) captured and returned
    /// as [`RenderError::Gpu`] instead of wgpu's default handler, which panics.
    fn checked<T>(
        &mut self,
        work: impl FnOnce(&mut Self) -> Result<T, RenderError>,
    ) -> Result<T, RenderError> {
        let validation = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let result = work(self);
        let memory = pollster::block_on(memory.pop());
        let validation = pollster::block_on(validation.pop());
        match memory.or(validation) {
            Some(e) => Err(RenderError::Gpu(e.to_string())),
            None => result,
        }
    }

    /// Uploads `scene` (in place), so that [`draw`](Self::draw) can render it.
    pub fn upload(&mut self, scene: &Scene<'_>, style: &Style) -> Result<(), RenderError> {
        self.checked(|r| r.buffers.update(&r.gpu.device, &r.gpu.queue, scene, style))
    }

    /// GPU buffers created so far (constant across uploads of same-sized scenes).
    pub fn buffers_created(&self) -> u64 {
        self.buffers.buffers_created()
    }

    /// Renders the last uploaded scene at `width × height` and reads it back.
    pub fn draw(
        &mut self,
        camera: &OrbitCamera,
        width: u32,
        height: u32,
    ) -> Result<RgbaImage, RenderError> {
        self.checked(|r| r.draw_unchecked(camera, width, height))
    }

    fn draw_unchecked(
        &mut self,
        camera: &OrbitCamera,
        width: u32,
        height: u32,
    ) -> Result<RgbaImage, RenderError> {
        if self.target.as_ref().map(RenderTarget::size) != Some((width, height)) {
            self.target = Some(RenderTarget::new(
                &self.gpu.device,
                self.renderer.pipelines(),
                width,
                height,
            )?);
        }
        let Some(target) = self.target.as_mut() else {
            return Err(RenderError::Readback("no render target".into()));
        };
        self.renderer.render(
            &self.gpu.device,
            &self.gpu.queue,
            target,
            camera,
            &self.buffers,
        );
        target.read_rgba(&self.gpu.device, &self.gpu.queue)
    }

    /// [`upload`](Self::upload) then [`draw`](Self::draw).
    pub fn render(
        &mut self,
        scene: &Scene<'_>,
        style: &Style,
        camera: &OrbitCamera,
        width: u32,
        height: u32,
    ) -> Result<RgbaImage, RenderError> {
        self.upload(scene, style)?;
        self.draw(camera, width, height)
    }

    /// Waits until the GPU has finished all submitted work (for timing uploads).
    pub fn wait_idle(&self) -> Result<(), RenderError> {
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| RenderError::Readback(e.to_string()))
    }
}
