// The display path's rest skin on the GPU: M̃ = K̃·P, one invocation per skin vertex
// (`gpu_rest_map.rs` documents the shapes and the error bound).
//
// `coords` is K̃ (`#V × 4B` f32, the columns padded with zeros to B blocks of four) as B
// column blocks of `#V` vec4s: block b occupies [b·#V, (b + 1)·#V), and coords[b·#V + i] holds
// row i's coefficients of columns 4b … 4b + 3. At each step of the loop neighbouring
// invocations read neighbouring 16-byte words (coalesced). `points` holds the 4B points P the
// columns multiply (xyz; w unused; zero past the last column) in a uniform buffer, read at the
// same index by every invocation. `skin` is M̃, xyz packed (`3·#V` floats).

struct Params {
    num_vertices: u32,
    // B, the blocks of four columns.
    num_blocks: u32,
    // Invocations per row of the 2-D dispatch (workgroups along x × workgroup size).
    row_width: u32,
    _pad: u32,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> coords: array<vec4<f32>>;
@group(0) @binding(2) var<uniform> points: array<vec4<f32>, 1024>;
@group(0) @binding(3) var<storage, read_write> skin: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_width + id.x;
    let n = params.num_vertices;
    if (i >= n) {
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var b = 0u; b < params.num_blocks; b++) {
        let w = coords[b * n + i];
        let k = 4u * b;
        sum += w.x * points[k].xyz + w.y * points[k + 1u].xyz + w.z * points[k + 2u].xyz
            + w.w * points[k + 3u].xyz;
    }
    skin[3u * i] = sum.x;
    skin[3u * i + 1u] = sum.y;
    skin[3u * i + 2u] = sum.z;
}
