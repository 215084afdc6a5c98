//! Records one view: backdrop, then the scene's layers, into a [`RenderTarget`].

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::gpu_types::FrameUniform;
use crate::pipelines::Pipelines;
use crate::scene_buffers::SceneBuffers;
use crate::target::RenderTarget;

/// The device's pipelines; one per device, shared by every view.
pub struct Renderer {
    pipelines: Pipelines,
}

/// A "nice" grid step (1, 2 or 5 × 10^k) near `length / 12`.
pub fn grid_step(length: f64) -> f64 {
    let raw = (length / 12.0).max(1e-12);
    let power = 10f64.powf(raw.log10().floor());
    let mantissa = raw / power;
    let nice = if mantissa < 1.5 {
        1.0
    } else if mantissa < 3.5 {
        2.0
    } else if mantissa < 7.5 {
        5.0
    } else {
        10.0
    };
    nice * power
}

/// The frame uniforms of `camera` looking at content bounded by `bounds`, in a
/// `width × height` viewport, with an optional ground under the content.
pub fn frame_uniform(
    camera: &OrbitCamera,
    bounds: Option<(DVec3, DVec3)>,
    ground: bool,
    (width, height): (u32, u32),
) -> FrameUniform {
    let (lo, hi) = bounds.unwrap_or((DVec3::splat(-1.0), DVec3::splat(1.0)));
    let diagonal = (hi - lo).length().max(1e-9);
    let centre = 0.5 * (lo + hi);
    // Everything drawn lies within this radius of the camera target.
    let mut radius = camera.target.distance(centre) + 0.5 * diagonal;
    if ground {
        radius += 1.3 * diagonal;
    }
    let aspect = width as f64 / height as f64;
    let (right, up) = camera.right_up();
    let back = camera.backward();
    let key = (-0.45 * right + 0.75 * up + 0.55 * back).normalize();
    let fill = (0.75 * right - 0.15 * up + 0.45 * back).normalize();
    let half = 0.5 * (hi - lo);
    FrameUniform {
        clip_from_world: camera.clip_from_world(aspect, radius).to_cols_array_2d(),
        eye: camera.eye().as_vec3().extend(1.0).to_array(),
        viewport: [
            width as f32,
            height as f32,
            1.0 / width as f32,
            1.0 / height as f32,
        ],
        key_light: key.as_vec3().extend(0.0).to_array(),
        fill_light: fill.as_vec3().extend(0.0).to_array(),
        ground: [
            (lo.y - 0.01 * diagonal) as f32,
            (1.3 * diagonal) as f32,
            grid_step(diagonal) as f32,
            if ground { 0.35 } else { 0.0 },
        ],
        ground_centre: [
            centre.x as f32,
            centre.z as f32,
            (half.x + 0.05 * diagonal) as f32,
            (half.z + 0.05 * diagonal) as f32,
        ],
    }
}

impl Renderer {
    /// Builds the pipelines for `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        Self {
            pipelines: Pipelines::new(device),
        }
    }

    /// The pipelines (to create [`crate::scene_buffers::SceneBuffers`]).
    pub fn pipelines(&self) -> &Pipelines {
        &self.pipelines
    }

    /// Draws `scene` seen by `camera` into `target` and submits the work.
    pub fn render(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &RenderTarget,
        camera: &OrbitCamera,
        scene: &SceneBuffers,
    ) {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("view"),
        });
        self.encode(queue, &mut encoder, target, camera, scene);
        queue.submit([encoder.finish()]);
    }

    /// Records the view into `encoder` (the caller submits), e.g. inside a GUI's frame.
    pub fn encode(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &RenderTarget,
        camera: &OrbitCamera,
        scene: &SceneBuffers,
    ) {
        let uniform = frame_uniform(camera, scene.bounds(), scene.ground(), target.size());
        queue.write_buffer(&target.frame_uniform, 0, bytemuck::bytes_of(&uniform));
        let (msaa, resolved, depth) = target.attachments();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("view"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: msaa,
                depth_slice: None,
                resolve_target: Some(resolved),
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                    store: wgpu::StoreOp::Discard,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &target.frame_bind, &[]);
        pass.set_pipeline(&self.pipelines.gradient);
        pass.draw(0..3, 0..1);
        scene.draw(&mut pass, &self.pipelines);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_steps_are_one_two_or_five_times_a_power_of_ten() {
        assert_eq!(grid_step(12.0), 1.0);
        assert_eq!(grid_step(30.0), 2.0);
        assert_eq!(grid_step(60.0), 5.0);
        assert!((grid_step(1.2) - 0.1).abs() < 1e-15);
        assert_eq!(grid_step(110.0), 10.0);
    }
}
