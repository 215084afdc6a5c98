//! The render pipelines: backdrop, ground, shaded meshes (opaque and translucent) and screen-space
//! overlays (lines and discs, depth-tested or drawn on top), all multisampled into the same
//! colour + depth formats.

use crate::gpu_types::{
    LINE_ATTRIBUTES, LineInstance, MESH_VERTEX_ATTRIBUTES, MeshVertex, POINT_ATTRIBUTES,
    PointInstance,
};

/// Colour format of the offscreen targets (the shaders write linear colour; stored as sRGB).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Depth format of the offscreen targets.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Samples per pixel (MSAA).
pub const SAMPLE_COUNT: u32 = 4;

const COMMON: &str = include_str!("shaders/common.wgsl");

/// How a pipeline uses the depth buffer.
#[derive(Clone, Copy)]
enum Depth {
    /// Tested and written (opaque surfaces).
    Write,
    /// Tested, not written (translucent surfaces, overlays on surfaces).
    Test,
    /// Ignored: always drawn (the skeleton on top, the backdrop).
    Ignore,
}

/// Every pipeline, built once per device.
pub struct Pipelines {
    /// Bind group layout of the per-frame uniforms ([`crate::gpu_types::FrameUniform`]).
    pub frame_layout: wgpu::BindGroupLayout,
    /// Bind group layout of a mesh material ([`crate::gpu_types::MaterialUniform`]).
    pub material_layout: wgpu::BindGroupLayout,
    /// Background gradient (depth ignored).
    pub gradient: wgpu::RenderPipeline,
    /// Ground grid with contact shadow (depth tested, blended).
    pub ground: wgpu::RenderPipeline,
    /// Shaded opaque meshes (depth written).
    pub mesh_opaque: wgpu::RenderPipeline,
    /// Shaded translucent meshes, e.g. cage faces (depth tested, blended).
    pub mesh_translucent: wgpu::RenderPipeline,
    /// Thick lines hidden by surfaces (depth tested).
    pub lines_tested: wgpu::RenderPipeline,
    /// Thick lines drawn over everything (depth ignored).
    pub lines_on_top: wgpu::RenderPipeline,
    /// Discs hidden by surfaces (depth tested).
    pub points_tested: wgpu::RenderPipeline,
    /// Discs drawn over everything (depth ignored).
    pub points_on_top: wgpu::RenderPipeline,
}

fn uniform_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

fn shader(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(format!("{COMMON}\n{source}").into()),
    })
}

struct PipelineSpec<'a> {
    label: &'a str,
    module: &'a wgpu::ShaderModule,
    layout: &'a wgpu::PipelineLayout,
    vertex: &'a str,
    fragment: &'a str,
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    depth: Depth,
    blend: bool,
    cull: Option<wgpu::Face>,
}

fn pipeline(device: &wgpu::Device, spec: PipelineSpec<'_>) -> wgpu::RenderPipeline {
    let (depth_write_enabled, depth_compare) = match spec.depth {
        Depth::Write => (true, wgpu::CompareFunction::Less),
        Depth::Test => (false, wgpu::CompareFunction::LessEqual),
        Depth::Ignore => (false, wgpu::CompareFunction::Always),
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vertex),
            compilation_options: Default::default(),
            buffers: spec.buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: spec.cull,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(depth_write_enabled),
            depth_compare: Some(depth_compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: SAMPLE_COUNT,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(spec.fragment),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: COLOR_FORMAT,
                blend: spec.blend.then_some(wgpu::BlendState::ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl Pipelines {
    /// Compiles the shaders and builds every pipeline for `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        let frame_layout = uniform_layout(device, "frame");
        let material_layout = uniform_layout(device, "material");
        let frame_only = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("frame only"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });
        let with_material = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("frame and material"),
            bind_group_layouts: &[Some(&frame_layout), Some(&material_layout)],
            immediate_size: 0,
        });
        let backdrop = shader(device, "backdrop", include_str!("shaders/backdrop.wgsl"));
        let mesh = shader(device, "mesh", include_str!("shaders/mesh.wgsl"));
        let overlay = shader(device, "overlay", include_str!("shaders/overlay.wgsl"));
        let mesh_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &MESH_VERTEX_ATTRIBUTES,
        })];
        let line_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &LINE_ATTRIBUTES,
        })];
        let point_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PointInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &POINT_ATTRIBUTES,
        })];
        let spec = |label, module, layout, vertex, fragment, buffers, depth, blend| PipelineSpec {
            label,
            module,
            layout,
            vertex,
            fragment,
            buffers,
            depth,
            blend,
            cull: None,
        };
        Self {
            gradient: pipeline(
                device,
                spec(
                    "gradient",
                    &backdrop,
                    &frame_only,
                    "vs_gradient",
                    "fs_gradient",
                    &[],
                    Depth::Ignore,
                    false,
                ),
            ),
            ground: pipeline(
                device,
                spec(
                    "ground",
                    &backdrop,
                    &frame_only,
                    "vs_ground",
                    "fs_ground",
                    &[],
                    Depth::Test,
                    true,
                ),
            ),
            mesh_opaque: pipeline(
                device,
                spec(
                    "mesh",
                    &mesh,
                    &with_material,
                    "vs_main",
                    "fs_main",
                    &mesh_buffers,
                    Depth::Write,
                    false,
                ),
            ),
            mesh_translucent: pipeline(
                device,
                spec(
                    "translucent mesh",
                    &mesh,
                    &with_material,
                    "vs_main",
                    "fs_main",
                    &mesh_buffers,
                    Depth::Test,
                    true,
                ),
            ),
            lines_tested: pipeline(
                device,
                spec(
                    "lines",
                    &overlay,
                    &frame_only,
                    "vs_line",
                    "fs_line",
                    &line_buffers,
                    Depth::Test,
                    true,
                ),
            ),
            lines_on_top: pipeline(
                device,
                spec(
                    "lines on top",
                    &overlay,
                    &frame_only,
                    "vs_line",
                    "fs_line",
                    &line_buffers,
                    Depth::Ignore,
                    true,
                ),
            ),
            points_tested: pipeline(
                device,
                spec(
                    "points",
                    &overlay,
                    &frame_only,
                    "vs_point",
                    "fs_point",
                    &point_buffers,
                    Depth::Test,
                    true,
                ),
            ),
            points_on_top: pipeline(
                device,
                spec(
                    "points on top",
                    &overlay,
                    &frame_only,
                    "vs_point",
                    "fs_point",
                    &point_buffers,
                    Depth::Ignore,
                    true,
                ),
            ),
            frame_layout,
            material_layout,
        }
    }
}
