//! `cagerig-render`: a wgpu renderer for cagerig rigs, without any GUI dependency.
//!
//! It draws a character's skin (smooth or flat shading, wireframe, per-vertex colour maps), its
//! cage (translucent faces, edges and handles, with the parts hidden behind the skin shown
//! faintly) and its skeleton (bones and joints on top) over a gradient backdrop and a ground
//! grid with a contact shadow, 4× multisampled, into its own colour + depth textures. The same
//! code serves offscreen pictures ([`OffscreenRenderer`]) and a GUI's viewports
//! ([`Renderer::encode`] into a [`RenderTarget`] whose colour texture the GUI shows).
//!
//! | file | concern |
//! |---|---|
//! | `gpu.rs` | headless device, clear error when no adapter exists |
//! | `gpu_rest_map.rs`, `shaders/rest_map.wgsl` | the display path's rest skin M̃ = K̃·[C; g] as a compute pass ([`GpuRestMap`], a `cagerig::session::DisplayRestMapBackend`) |
//! | `camera.rs` | orbit camera, presets, frame-all, projection |
//! | `palette.rs` | sequential and diverging colour maps |
//! | `scene.rs` | what to draw (borrowed slices) and the style |
//! | `scene_buffers.rs` | GPU buffers updated in place per frame |
//! | `vertex_normals.rs` | parallel smooth normals of a deforming mesh |
//! | `vertex_packing.rs` | one parallel pass packing a layer's vertices into staging memory |
//! | `pipelines.rs`, `shaders/` | pipeline states and WGSL |
//! | `renderer.rs` | per-frame uniforms, lights, pass recording |
//! | `target.rs` | colour + depth targets, readback |
//! | `image.rs` | side-by-side composition, PNG and animated PNG |
//! | `annotate.rs` | text labels and colour-map legends on pictures |
//! | `rig_scene.rs` | a [`cagerig::session::RigSession`]'s rest or current pose as a scene |
//!
//! Positions are converted to f32 for display only; the rig's exact state stays f64.

#![warn(missing_docs)]

pub mod annotate;
pub mod camera;
pub mod error;
pub mod gpu;
mod gpu_buffer;
pub mod gpu_rest_map;
pub mod gpu_types;
pub mod image;
pub mod offscreen;
pub mod palette;
pub mod pipelines;
pub mod renderer;
pub mod rig_scene;
pub mod scene;
pub mod scene_buffers;
pub mod target;
pub mod vertex_normals;
pub mod vertex_packing;

pub use camera::{CameraPreset, OrbitCamera};
pub use error::RenderError;
pub use gpu::GpuContext;
pub use gpu_rest_map::{GpuRestMap, GpuRestMapError, GpuRestMapProduct};
pub use image::RgbaImage;
pub use offscreen::OffscreenRenderer;
pub use palette::ColorMap;
pub use renderer::Renderer;
pub use scene::{CageLayer, MeshLayer, MeshPositions, Scene, SkeletonLayer, Style};
pub use scene_buffers::SceneBuffers;
pub use target::RenderTarget;
