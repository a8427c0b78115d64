// Batched small-MLP evaluator: one thread per texel, inputs from a storage buffer, the first
// (up to) four outputs written to an rgba32float storage texture. Weights are either WGSL
// constants in fully unrolled code (buffer_weights = false) or read from a storage buffer in
// loops (buffer_weights = true; the slow baseline the codegen is measured against). The unrolled
// body comes from Python (gpu/mlp_kernel.py:unrolled_body, gpu/unroll.py).
{% if T == 'f16' %}
enable f16;
{% endif %}

// Bindings: gpu/mlp_kernel.py:BINDINGS.
{{ bindings }}

override N: u32;        // number of evaluations
override WIDTH: u32;    // output texture width
override STRIDE: u32;   // threads per dispatch row (workgroups in x * 64)

{% if buffer_weights %}
const N_LAYERS: u32 = {{ layers|length }}u;
const MAXW: u32 = {{ max_width }}u;
const DIMS = array<u32, {{ layers|length + 1 }}>({{ dims|join('u, ') }}u);
const ACTS = array<u32, {{ layers|length }}>({{ acts|join('u, ') }}u);  // vrneural.mlp.ACT_CODE
{% endif %}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * STRIDE;
    if (i >= N) { return; }
    let base = i * {{ n_in }}u;
{% if not buffer_weights %}
{{ body }}
{% else %}
    var a: array<{{ T }}, MAXW>;
    var b: array<{{ T }}, MAXW>;
    for (var k = 0u; k < DIMS[0]; k++) { a[k] = {{ T }}(inputs[base + k]); }
    var off = 0u;
    for (var l = 0u; l < N_LAYERS; l++) {
        let n_in = DIMS[l];
        let n_out = DIMS[l + 1u];
        for (var o = 0u; o < n_out; o++) {
            var s = {{ T }}(weights[off + n_out * n_in + o]);
            for (var k = 0u; k < n_in; k++) {
                s += {{ T }}(weights[off + o * n_in + k]) * a[k];
            }
            if (ACTS[l] == {{ act_code['relu'] }}u) { s = max(s, {{ T }}(0)); }
            else if (ACTS[l] == {{ act_code['leaky_relu'] }}u) { s = max(s, {{ T }}(0.01) * s); }
            b[o] = s;
        }
        off += n_out * n_in + n_out;
        for (var o = 0u; o < n_out; o++) { a[o] = b[o]; }
    }
    var y = vec4<f32>(0.0);
    for (var k = 0u; k < min({{ n_out }}u, 4u); k++) { y[k] = f32(a[k]); }
{% endif %}
    textureStore(out_tex, vec2<u32>(i % WIDTH, i / WIDTH), y);
}
