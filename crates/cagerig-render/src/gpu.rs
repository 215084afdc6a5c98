//! A headless wgpu device: adapter selection without a window, with a clear error when none
//! exists.

use crate::error::{ADAPTER_HINT, RenderError};

/// Device, queue and a description of the adapter they run on.
pub struct GpuContext {
    /// The logical device.
    pub device: wgpu::Device,
    /// Its command queue.
    pub queue: wgpu::Queue,
    /// Adapter name and backend, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub adapter_name: String,
}

impl GpuContext {
    /// Opens the first adapter of the backends allowed by `WGPU_BACKEND` (default: Vulkan, GL,
    /// Metal, DX12), preferring a hardware one; software adapters (lavapipe, llvmpipe) are
    /// accepted. The device takes the downlevel default limits, with the adapter's texture
    /// resolution and its storage-buffer and buffer sizes. Fails with [`RenderError::NoAdapter`]
    /// naming what to install.
    pub fn new_headless() -> Result<Self, RenderError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = wgpu::Backends::from_env().unwrap_or(
            wgpu::Backends::VULKAN
                | wgpu::Backends::GL
                | wgpu::Backends::METAL
                | wgpu::Backends::DX12,
        );
        let backends = format!("{:?}", descriptor.backends);
        let instance = wgpu::Instance::new(descriptor);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| RenderError::NoAdapter {
            backends,
            reason: e.to_string(),
            hint: ADAPTER_HINT,
        })?;
        let info = adapter.get_info();
        let adapter_name = format!("{} ({:?})", info.name, info.backend);
        // The adapter's own buffer limits (the downlevel defaults stop at 128 MiB per storage
        // binding, less than the rest map's coefficients of a 532k-vertex skin).
        let supported = adapter.limits();
        let mut required_limits =
            wgpu::Limits::downlevel_defaults().using_resolution(supported.clone());
        required_limits.max_storage_buffer_binding_size = required_limits
            .max_storage_buffer_binding_size
            .max(supported.max_storage_buffer_binding_size);
        required_limits.max_buffer_size = required_limits
            .max_buffer_size
            .max(supported.max_buffer_size);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("cagerig-render"),
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device {
            adapter: adapter_name.clone(),
            reason: e.to_string(),
        })?;
        Ok(Self {
            device,
            queue,
            adapter_name,
        })
    }
}
