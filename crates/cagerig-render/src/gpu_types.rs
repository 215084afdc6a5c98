//! Plain-old-data layouts shared with the WGSL shaders (`shaders/*.wgsl`).

use bytemuck::{Pod, Zeroable};

/// Per-frame uniforms (`Frame` in `common.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameUniform {
    /// Clip-from-world matrix (projection · view), column-major.
    pub clip_from_world: [[f32; 4]; 4],
    /// Camera position (world, w = 1).
    pub eye: [f32; 4],
    /// Width, height, 1/width, 1/height (pixels).
    pub viewport: [f32; 4],
    /// Unit direction towards the key light (world, w = 0).
    pub key_light: [f32; 4],
    /// Unit direction towards the fill light (world, w = 0).
    pub fill_light: [f32; 4],
    /// Height (world y), half extent, grid cell size, shadow strength (0 = no ground).
    pub ground: [f32; 4],
    /// Ground centre x, z; footprint half sizes x, z.
    pub ground_centre: [f32; 4],
}

/// Material of a shaded mesh (`Material` in `mesh.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MaterialUniform {
    /// Base colour (linear RGB) and opacity.
    pub color: [f32; 4],
    /// 1 = per-vertex colour, 1 = flat shading, specular strength, unused.
    pub params: [f32; 4],
}

/// One vertex of a shaded mesh: position and smooth normal in world space (f32; display only;
/// the normal is the unnormalised sum of the area-weighted triangle normals, which the vertex
/// shader normalises), colour in 8-bit sRGB.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MeshVertex {
    /// Position (world).
    pub position: [f32; 3],
    /// Unnormalised smooth normal (world; zero for flat shading).
    pub normal: [f32; 3],
    /// sRGB colour and alpha, 8 bits each.
    pub color: [u8; 4],
}

/// A screen-space thick line segment between two world points.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LineInstance {
    /// First end point (world).
    pub a: [f32; 3],
    /// Second end point (world).
    pub b: [f32; 3],
    /// sRGB colour and alpha, 8 bits each.
    pub color: [u8; 4],
    /// Width in pixels, depth bias towards the eye (NDC).
    pub style: [f32; 2],
}

/// A screen-space shaded disc at a world point.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PointInstance {
    /// Centre of the disc (world).
    pub centre: [f32; 3],
    /// Radius in pixels, depth bias towards the eye (NDC).
    pub style: [f32; 2],
    /// sRGB colour and alpha, 8 bits each.
    pub color: [u8; 4],
}

pub(crate) const MESH_VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Unorm8x4];
pub(crate) const LINE_ATTRIBUTES: [wgpu::VertexAttribute; 4] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Unorm8x4, 3 => Float32x2];
pub(crate) const POINT_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2, 2 => Unorm8x4];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_match_the_shader_attribute_offsets() {
        assert_eq!(std::mem::size_of::<MeshVertex>(), 28);
        assert_eq!(std::mem::size_of::<LineInstance>(), 36);
        assert_eq!(std::mem::size_of::<PointInstance>(), 24);
        assert_eq!(MESH_VERTEX_ATTRIBUTES[2].offset, 24);
        assert_eq!(LINE_ATTRIBUTES[3].offset, 28);
        assert_eq!(POINT_ATTRIBUTES[2].offset, 20);
        assert_eq!(std::mem::size_of::<FrameUniform>(), 160);
    }
}
