// Per-frame uniforms shared by every pipeline (group 0, binding 0).
struct Frame {
    clip_from_world: mat4x4<f32>,
    // xyz: eye position (world).
    eye: vec4<f32>,
    // x, y: viewport size in pixels; z, w: their reciprocals.
    viewport: vec4<f32>,
    // xyz: direction towards the key light (world, unit).
    key_light: vec4<f32>,
    // xyz: direction towards the fill light (world, unit).
    fill_light: vec4<f32>,
    // Ground: x = height (world y), y = half extent, z = grid cell size, w = shadow strength.
    ground: vec4<f32>,
    // Ground centre (x, z) and the model's footprint half sizes (x, z) for the contact shadow.
    ground_centre: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(hi, lo, c <= vec3<f32>(0.04045));
}

// Two lights, a sky/ground hemisphere and a Blinn-Phong highlight; `n` faces the eye.
fn shade(n: vec3<f32>, world: vec3<f32>, base: vec3<f32>, specular: f32) -> vec3<f32> {
    let v = normalize(frame.eye.xyz - world);
    let sky = vec3<f32>(0.36, 0.38, 0.42);
    let ground = vec3<f32>(0.18, 0.17, 0.16);
    let ambient = mix(ground, sky, 0.5 + 0.5 * n.y);
    let key = max(dot(n, frame.key_light.xyz), 0.0) * vec3<f32>(0.95, 0.93, 0.88);
    let fill = max(dot(n, frame.fill_light.xyz), 0.0) * vec3<f32>(0.30, 0.33, 0.38);
    let h = normalize(frame.key_light.xyz + v);
    let spec = specular * pow(max(dot(n, h), 0.0), 48.0);
    let rim = 0.10 * pow(1.0 - max(dot(n, v), 0.0), 3.0);
    return base * (ambient + key + fill) + vec3<f32>(spec + rim);
}

// Corners of a quad as two triangles, each coordinate in {-1, 1}.
fn corner(index: u32) -> vec2<f32> {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    return corners[index];
}
