//! An offscreen view: multisampled colour + depth textures, the single-sample colour they
//! resolve to (readable back to the CPU, or shown by a GUI as a texture), and the view's
//! per-frame uniforms.

use crate::error::RenderError;
use crate::gpu_types::FrameUniform;
use crate::image::RgbaImage;
use crate::pipelines::{COLOR_FORMAT, DEPTH_FORMAT, Pipelines, SAMPLE_COUNT};

/// One view's render targets.
pub struct RenderTarget {
    width: u32,
    height: u32,
    msaa_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    pub(crate) frame_uniform: wgpu::Buffer,
    pub(crate) frame_bind: wgpu::BindGroup,
    readback: Option<wgpu::Buffer>,
}

fn texture(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    samples: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// Bytes per row of a readback, padded to wgpu's copy alignment.
fn padded_row_bytes(width: u32) -> u32 {
    (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
}

impl RenderTarget {
    /// Targets of `width × height` pixels (each 1 … the adapter's maximum texture size).
    pub fn new(
        device: &wgpu::Device,
        pipelines: &Pipelines,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        let max = device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::ImageSize { width, height, max });
        }
        let size = (width, height);
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let msaa = texture(
            device,
            "msaa colour",
            size,
            COLOR_FORMAT,
            SAMPLE_COUNT,
            attachment,
        );
        let depth = texture(
            device,
            "depth",
            size,
            DEPTH_FORMAT,
            SAMPLE_COUNT,
            attachment,
        );
        let resolved = texture(
            device,
            "colour",
            size,
            COLOR_FORMAT,
            1,
            attachment | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let frame_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &pipelines.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_uniform.as_entire_binding(),
            }],
        });
        Ok(Self {
            width,
            height,
            msaa_view: msaa.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            resolved_view: resolved.create_view(&Default::default()),
            resolved,
            frame_uniform,
            frame_bind,
            readback: None,
        })
    }

    /// `(width, height)` in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The resolved colour texture (sRGB, single sample), e.g. for a GUI to display.
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.resolved_view
    }

    pub(crate) fn attachments(
        &self,
    ) -> (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView) {
        (&self.msaa_view, &self.resolved_view, &self.depth_view)
    }

    /// Copies the resolved colour back to the CPU (waits for the GPU).
    pub fn read_rgba(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<RgbaImage, RenderError> {
        let row = padded_row_bytes(self.width);
        let size = row as u64 * self.height as u64;
        let readback = self.readback.get_or_insert_with(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.resolved.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        queue.submit([encoder.finish()]);
        let (sender, receiver) = std::sync::mpsc::channel();
        readback.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = sender.send(result);
        });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        receiver
            .recv()
            .map_err(|e| RenderError::Readback(e.to_string()))?
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        let mut pixels = Vec::with_capacity((self.width * self.height * 4) as usize);
        {
            let mapped = readback
                .get_mapped_range(..)
                .map_err(|e| RenderError::Readback(e.to_string()))?;
            for y in 0..self.height as usize {
                let start = y * row as usize;
                pixels.extend_from_slice(&mapped[start..start + self.width as usize * 4]);
            }
        }
        readback.unmap();
        Ok(RgbaImage::new(self.width, self.height, pixels))
    }
}
