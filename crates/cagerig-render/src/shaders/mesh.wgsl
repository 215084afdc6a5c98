// Shaded triangle meshes (the skin, opaque; the cage faces, translucent).

struct Material {
    // rgb: base colour (linear), a: opacity.
    color: vec4<f32>,
    // x: 1 = use the per-vertex colour, y: 1 = flat shading, z: specular strength.
    params: vec4<f32>,
};

@group(1) @binding(0) var<uniform> material: Material;

struct VertexIn {
    @location(0) position: vec3<f32>,
    // Smooth normal, not normalised (see `vs_main`).
    @location(1) normal: vec3<f32>,
    // sRGB, 8 bits per channel.
    @location(2) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.clip_from_world * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    // The CPU uploads the unnormalised sum of the area-weighted triangle normals: scale it to
    // its largest component first (no overflow or underflow of the squared length), then to
    // unit length. A zero sum stays zero (the fragment stage then uses the flat normal).
    let largest = max(abs(v.normal.x), max(abs(v.normal.y), abs(v.normal.z)));
    out.normal = select(vec3<f32>(0.0), normalize(v.normal / largest), largest > 0.0);
    out.color = select(material.color.rgb, srgb_to_linear(v.color.rgb), material.params.x > 0.5);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    var n = normalize(in.normal);
    if (material.params.y > 0.5 || dot(in.normal, in.normal) < 1e-12) {
        n = normalize(cross(dpdx(in.world), dpdy(in.world)));
    }
    let to_eye = frame.eye.xyz - in.world;
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    return vec4<f32>(shade(n, in.world, in.color, material.params.z), material.color.a);
}
