//! Errors of the renderer.

use std::path::PathBuf;

/// What to install when no graphics adapter is found (software Vulkan and GL on Debian/Ubuntu).
pub const ADAPTER_HINT: &str = "install a Vulkan or OpenGL driver; without a GPU the software \
ones work: `apt-get install mesa-vulkan-drivers libvulkan1` (lavapipe) or `libegl-mesa0 \
libgl1-mesa-dri` (llvmpipe)";

/// A rendering failure.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No adapter on any enabled backend.
    #[error("no graphics adapter found on backends {backends} ({reason}); {hint}")]
    NoAdapter {
        /// The backends tried (e.g. `VULKAN | GL`).
        backends: String,
        /// wgpu's reason.
        reason: String,
        /// What to install ([`ADAPTER_HINT`]).
        hint: &'static str,
    },
    /// The adapter refused to create a device.
    #[error("the graphics adapter {adapter:?} could not create a device: {reason}")]
    Device {
        /// Name and backend of the adapter.
        adapter: String,
        /// wgpu's reason.
        reason: String,
    },
    /// A requested image size is zero or beyond the adapter's texture limit.
    #[error("image size {width}×{height} is not supported: expected 1 … {max} pixels per side")]
    ImageSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// The adapter's largest texture side in pixels.
        max: u32,
    },
    /// Geometry handed to the renderer is inconsistent (the message names the element).
    #[error("{0}")]
    Geometry(String),
    /// The GPU reported an error (out of memory, or an internal inconsistency).
    #[error("the GPU reported an error: {0}")]
    Gpu(String),
    /// The GPU did not deliver the rendered image.
    #[error("reading the rendered image back from the GPU failed: {0}")]
    Readback(String),
    /// Writing an image file failed.
    #[error("writing {path}: {reason}")]
    Write {
        /// The image file.
        path: PathBuf,
        /// Why it could not be written.
        reason: String,
    },
}
