// The backdrop: a vertical gradient, then a ground plane with a fading grid and a soft contact
// shadow under the model.

struct BackdropOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_gradient(@builtin(vertex_index) index: u32) -> BackdropOut {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: BackdropOut;
    out.clip = vec4<f32>(uv * 2.0 - 1.0, 1.0, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_gradient(in: BackdropOut) -> @location(0) vec4<f32> {
    let top = srgb_to_linear(vec3<f32>(0.93, 0.94, 0.96));
    let bottom = srgb_to_linear(vec3<f32>(0.74, 0.76, 0.80));
    return vec4<f32>(mix(top, bottom, in.uv.y), 1.0);
}

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_ground(@builtin(vertex_index) index: u32) -> GroundOut {
    let c = corner(index);
    let half = frame.ground.y;
    let world = vec3<f32>(frame.ground_centre.x + c.x * half, frame.ground.x, frame.ground_centre.y + c.y * half);
    var out: GroundOut;
    out.clip = frame.clip_from_world * vec4<f32>(world, 1.0);
    out.world = world;
    return out;
}

@fragment
fn fs_ground(in: GroundOut) -> @location(0) vec4<f32> {
    let rel = in.world.xz - frame.ground_centre.xy;
    let fade = 1.0 - smoothstep(0.35, 1.0, length(rel) / frame.ground.y);
    let cell = in.world.xz / frame.ground.z;
    let width = fwidth(cell);
    let grid = abs(fract(cell - 0.5) - 0.5) / max(width, vec2<f32>(1e-6));
    let line = 1.0 - min(min(grid.x, grid.y), 1.0);
    let major_cell = cell / 5.0;
    let major_width = fwidth(major_cell);
    let major_grid = abs(fract(major_cell - 0.5) - 0.5) / max(major_width, vec2<f32>(1e-6));
    let major = 1.0 - min(min(major_grid.x, major_grid.y), 1.0);
    // Contact shadow: a soft ellipse under the model's footprint.
    let footprint = rel / max(frame.ground_centre.zw, vec2<f32>(1e-6));
    let shadow = frame.ground.w * (1.0 - smoothstep(0.2, 1.25, length(footprint)));
    let alpha = clamp(fade * (0.10 * line + 0.16 * major) + shadow, 0.0, 1.0);
    let rgb = mix(vec3<f32>(0.35, 0.37, 0.40), vec3<f32>(0.10, 0.10, 0.12), clamp(shadow * 2.0, 0.0, 1.0));
    return vec4<f32>(rgb, alpha);
}
