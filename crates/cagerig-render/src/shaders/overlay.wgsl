// Screen-space overlays: thick line segments (bones, cage edges, wireframe) and shaded discs
// (joints, cage handles), one instance each, expanded to a quad in the vertex shader.

struct LineIn {
    @location(0) a: vec3<f32>,
    @location(1) b: vec3<f32>,
    @location(2) color: vec4<f32>,
    // x: width in pixels, y: depth bias towards the eye (NDC units).
    @location(3) style: vec2<f32>,
};

struct PointIn {
    @location(0) centre: vec3<f32>,
    // x: radius in pixels, y: depth bias towards the eye (NDC units).
    @location(1) style: vec2<f32>,
    @location(2) color: vec4<f32>,
};

struct OverlayOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
    // Position inside the quad: x along, y across, each in [-1, 1].
    @location(1) local: vec2<f32>,
};

fn to_pixels(clip: vec4<f32>) -> vec2<f32> {
    return clip.xy / clip.w * 0.5 * frame.viewport.xy;
}

// The corner `c` of an overlay quad: `clip` moved by `offset_px` pixels on screen and by `bias`
// (NDC units) towards the eye, with the sRGB `color` made linear.
fn overlay_corner(clip: vec4<f32>, offset_px: vec2<f32>, bias: f32, color: vec4<f32>, c: vec2<f32>) -> OverlayOut {
    var out: OverlayOut;
    out.clip = vec4<f32>(clip.xy + offset_px * 2.0 * frame.viewport.zw * clip.w, clip.z - bias * clip.w, clip.w);
    out.color = vec4<f32>(srgb_to_linear(color.rgb), color.a);
    out.local = c;
    return out;
}

@vertex
fn vs_line(@builtin(vertex_index) index: u32, line: LineIn) -> OverlayOut {
    let c = corner(index);
    let clip_a = frame.clip_from_world * vec4<f32>(line.a, 1.0);
    let clip_b = frame.clip_from_world * vec4<f32>(line.b, 1.0);
    let delta = to_pixels(clip_b) - to_pixels(clip_a);
    var along = vec2<f32>(1.0, 0.0);
    if (dot(delta, delta) > 1e-8) {
        along = normalize(delta);
    }
    let across = vec2<f32>(-along.y, along.x);
    let clip = select(clip_a, clip_b, c.x > 0.0);
    let half_width = 0.5 * line.style.x;
    let offset_px = across * c.y * half_width + along * c.x * half_width;
    return overlay_corner(clip, offset_px, line.style.y, line.color, c);
}

@fragment
fn fs_line(in: OverlayOut) -> @location(0) vec4<f32> {
    return in.color;
}

@vertex
fn vs_point(@builtin(vertex_index) index: u32, point: PointIn) -> OverlayOut {
    let c = corner(index);
    let clip = frame.clip_from_world * vec4<f32>(point.centre, 1.0);
    return overlay_corner(clip, c * point.style.x, point.style.y, point.color, c);
}

@fragment
fn fs_point(in: OverlayOut) -> @location(0) vec4<f32> {
    let r2 = dot(in.local, in.local);
    if (r2 > 1.0) {
        discard;
    }
    // A lit sphere seen head-on, with a dark outline so handles read on any background.
    let n = vec3<f32>(in.local.x, -in.local.y, sqrt(1.0 - r2));
    let light = normalize(vec3<f32>(-0.4, 0.6, 0.7));
    let diffuse = 0.45 + 0.55 * max(dot(n, light), 0.0);
    let spec = 0.35 * pow(max(dot(reflect(-light, n), vec3<f32>(0.0, 0.0, 1.0)), 0.0), 24.0);
    var rgb = in.color.rgb * diffuse + vec3<f32>(spec);
    if (r2 > 0.72) {
        rgb = in.color.rgb * 0.25;
    }
    return vec4<f32>(rgb, in.color.a);
}
