// Controlled workloads for gpu/coverage.py: a compute pass and a render pass whose cost is set
// by a loop count (uniform), to compare an adapter's timestamps with the wall clock.

struct Work {
    iterations: u32,
}

@group(0) @binding(0) var<uniform> W: Work;
@group(0) @binding(1) var<storage, read_write> sink: array<f32>;

fn spin(seed: f32) -> f32 {
    var x = seed;
    for (var i = 0u; i < W.iterations; i++) { x = fract(sin(x) * 43758.5453 + 0.25); }
    return x;
}

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) g: vec3<u32>) {
    sink[g.x] = spin(f32(g.x) * 0.001);
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.5, 1.0);
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    var x = p.x * 0.001 + p.y;
    for (var i = 0u; i < W.iterations; i++) { x = fract(sin(x) * 43758.5453 + 0.25); }
    return vec4<f32>(x);
}
