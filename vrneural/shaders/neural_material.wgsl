// Neural material evaluation shared by the texture-space and screen-space kernels.
// Semantics: vrneural/material.py (material_forward). Generated per material pack:
//   arch coarse_fine: eval_coarse(dirs, U_c(u_c)) -> latent z, eval_fine(z, U_f(u_k)) -> RGB
//   arch single:      eval_single(dirs, U(u_k)) -> RGB
// with features from sample_a / sample_b, sampled once per texel outside the light loop.
// dirs = [wi, wo, h] in the local frame (9 floats). Neural textures are texture_2d_array<u32>
// (rgba32uint: 8 float16 channels per texel and layer, two per u32, see gpu_material.py)
// sampled by manual bilinear wrap (4 textureLoads per 8 channels, unpack2x16float),
// exactly like sample_bilinear_wrap; or, with mat.filtering "hardware", texture_2d_array<f32>
// (rgba16float) read through the sampler neural_samp (runtime/codegen_sample.py). The
// bindings are declared by runtime/interface.py (material_bindings). Weights are WGSL
// constants in unrolled code, or read from buffers in loops (storage or uniform weights; wide
// teachers and the >=10x comparison).


{% macro wrap_fn() %}
// i mod n in [0, n) for an integer-valued float i (|i| < 2^24), without an integer division:
// CPU adapters have no vector integer divide (LLVM scalarises it), and this is the sampler's
// inner loop. The reciprocal's rounding can leave the result one period off; the selects fix it.
fn wrap_index(i: f32, n: i32) -> i32 {
    let fn_ = f32(n);
    var m = i - fn_ * floor(i * (1.0 / fn_));
    m = select(m, m - fn_, m >= fn_);
    m = select(m, m + fn_, m < 0.0);
    return i32(m);
}

// The wrapped texels and weights of a bilinear lookup at uv in a dims-sized texel grid
// (texel centres at (i + 0.5) / W): corners i0, i1 and the weight f of i1 per axis.
struct Taps {
    i0: vec2<i32>,
    i1: vec2<i32>,
    f: vec2<f32>,
}

fn bilinear_taps(uv: vec2<f32>, dims: vec2<i32>) -> Taps {
    let x = uv.x * f32(dims.x) - 0.5;
    let y = uv.y * f32(dims.y) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let xi0 = wrap_index(x0, dims.x);
    let yi0 = wrap_index(y0, dims.y);
    let xi1 = select(xi0 + 1, 0, xi0 + 1 == dims.x);
    let yi1 = select(yi0 + 1, 0, yi0 + 1 == dims.y);
    return Taps(vec2<i32>(xi0, yi0), vec2<i32>(xi1, yi1), vec2<f32>(x - x0, y - y0));
}
{% endmacro %}

{% macro parallax_fns(mat) %}
{% if mat.parallax_steps > 0 %}
// Height-field parallax: lookups where the view ray meets the height field, parallax-occlusion
// mapping from its maximum to its minimum in up to {{ mat.parallax_steps }} steps (fewer at
// steeper views: step_count) with the linear refinement, per {{ mat.parallax_march }}.
// Twin: vrneural/parallax.py:parallax_uv.
const H_MIN: f32 = {{ mat.height_consts[0] }};
const H_MAX: f32 = {{ mat.height_consts[1] }};
const H_ASPECT: f32 = {{ mat.height_consts[2] }};  // W / H of the texel grid
const T_MAX: f32 = {{ mat.height_consts[3] }};  // the steepest view's |d| (parallax.slope_max)

{% if mat.filtering == 'hardware' %}
// Bilinear wrap lookup of the height field (the neural textures' texel grid), by the sampler
// (r16float: the pack's float16 heights).
fn height_at(uv: vec2<f32>) -> f32 {
    return textureSampleLevel(height_tex, neural_samp, uv, 0.0).x;
}
{% else %}
// Bilinear wrap lookup of the height field (the neural textures' texel grid).
fn height_at(uv: vec2<f32>) -> f32 {
    let dims = vec2<i32>(textureDimensions(height_tex));
    let tp = bilinear_taps(uv, dims);
    let xi0 = tp.i0.x;
    let yi0 = tp.i0.y;
    let xi1 = tp.i1.x;
    let yi1 = tp.i1.y;
    let fx = tp.f.x;
    let fy = tp.f.y;
    let top = textureLoad(height_tex, vec2<i32>(xi0, yi0), 0).x * (1.0 - fx)
        + textureLoad(height_tex, vec2<i32>(xi1, yi0), 0).x * fx;
    let bot = textureLoad(height_tex, vec2<i32>(xi0, yi1), 0).x * (1.0 - fx)
        + textureLoad(height_tex, vec2<i32>(xi1, yi1), 0).x * fx;
    return top * (1.0 - fy) + bot * fy;
}
{% endif %}

// UV shift per unit height along the (extended, wo.z > 0) view: vrneural/parallax.py:ray_slope.
fn parallax_d(wo: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(wo.x / wo.z, wo.y / wo.z * H_ASPECT);
}

// The march's steps for slope d: ceil(steps |d| / T_MAX) in [1, steps] (parallax.step_count).
fn parallax_n(d: vec2<f32>) -> i32 {
    let n = ceil({{ mat.parallax_steps }}.0 * sqrt(dot(d, d)) / T_MAX);
    return clamp(i32(n), 1, {{ mat.parallax_steps }});
}

// The ray height where the ray through uv with slope d meets the field (parallax.march_hits).
fn parallax_z(uv: vec2<f32>, d: vec2<f32>) -> f32 {
    let n = parallax_n(d);
    let dz = (H_MAX - H_MIN) / f32(n);
    var z_prev = H_MAX;
    var h_prev = height_at(uv + z_prev * d);
    if (h_prev >= z_prev) { return H_MAX; }
    var hit = H_MIN;
    for (var k = 1; k <= n; k++) {
        let z = H_MAX - f32(k) * dz;
        let h = height_at(uv + z * d);
        if (z <= h) {
            let a = z_prev - h_prev;
            hit = z_prev + a / (a - (z - h)) * (z - z_prev);
            break;
        }
        z_prev = z;
        h_prev = h;
    }
    return hit;
}

fn parallax_uv(uv: vec2<f32>, d: vec2<f32>) -> vec2<f32> { return uv + parallax_z(uv, d) * d; }
{% endif %}
{% endmacro %}

{% macro output_fn(output) %}
// Output transform of the last layer's raw value (material.apply_output).
fn apply_output(r: vec3<f32>) -> vec3<f32> {
{% if output == 'log1p' %}
    return exp(max(r, vec3<f32>(0.0))) - vec3<f32>(1.0);
{% else %}
    return max(r, vec3<f32>(0.0));
{% endif %}
}
{% endmacro %}

{% macro material_fns(mat, T, nets, samplers) %}
{% if mat.filtering != 'hardware' %}
{{ wrap_fn() }}
{% endif %}
// The training data's direction range (vrneural/grazing.py): cos and sin of theta_i_max and
// theta_o_max, exact float32 values.
const COS_I_MAX: f32 = {{ mat.dir_consts[0] }};
const SIN_I_MAX: f32 = {{ mat.dir_consts[1] }};
const COS_O_MAX: f32 = {{ mat.dir_consts[2] }};
const SIN_O_MAX: f32 = {{ mat.dir_consts[3] }};

// A direction below polar angle acos(c) moved onto it at the same azimuth (+x where the
// azimuth is undefined); others unchanged. Twin: vrneural/grazing.py:to_range.
fn to_range(w: vec3<f32>, c: f32, s: f32) -> vec3<f32> {
    if (w.z >= c) { return w; }
    let r2 = dot(w.xy, w.xy);
    if (r2 < 1e-20) { return vec3<f32>(s, 0.0, c); }
    return vec3<f32>(w.xy * (s / sqrt(r2)), c);
}

// Scale of a light's value: 1 inside the range, wi.z / cos(theta_i_max) beyond it, 0 at the
// horizon. Twin: vrneural/grazing.py:light_weight.
fn light_weight(wi_z: f32) -> f32 { return clamp(wi_z / COS_I_MAX, 0.0, 1.0); }

// The network inputs (wi, wo, h) for a light and view extended beyond the range.
fn dirs9_ext(wi: vec3<f32>, wo_ext: vec3<f32>) -> array<f32, 9> {
    return dirs9(to_range(wi, COS_I_MAX, SIN_I_MAX), wo_ext);
}
fn view_ext(wo: vec3<f32>) -> vec3<f32> { return to_range(wo, COS_O_MAX, SIN_O_MAX); }
// Neural-texture samplers (generated in Python: runtime/codegen_sample.py).
{{ samplers }}
{{ output_fn(mat.output) }}
{{ parallax_fns(mat) }}
// Evaluation API (every weight variant; generated in Python: runtime/codegen_mlp.py). The first
// layer of every network is split into the part that does not change with the light (bias + W_f
// features: pre_a, pre_b, computed once per texel or block outside the light loop) and the part
// that does (W_d dirs, and for the fine network W_z z_c, computed once per block per light by
// fine_z and shared by the block's 4 texels):
//   coarse_fine: z = eval_coarse(dirs, pre_a(U_c(u_c))); zz = fine_z(z);
//                rgb_k = eval_fine(zz, pre_b(U_f(u_k)))
//   single:      rgb_k = eval_single(dirs, pre_a(U(u_k)))
{{ nets }}
{% endmacro %}

{% macro frame_fns() %}
const PI: f32 = 3.14159265;
const F16_MAX: f32 = 65504.0;

// Barycentrics of p in the 2D triangle (a, b, c); extrapolated outside it (gutter texels);
// (1/3, 1/3, 1/3) for a degenerate triangle. Twin: runtime/reference.py:barycentric_2d.
fn bary2(p: vec2<f32>, a: vec2<f32>, b: vec2<f32>, c: vec2<f32>) -> vec3<f32> {
    let v0 = b - a;
    let v1 = c - a;
    let v2 = p - a;
    let den = v0.x * v1.y - v1.x * v0.y;
    if (abs(den) < 1e-20) { return vec3<f32>(1.0 / 3.0); }
    let l1 = (v2.x * v1.y - v1.x * v2.y) / den;
    let l2 = (v0.x * v2.y - v2.x * v0.y) / den;
    return vec3<f32>(1.0 - l1 - l2, l1, l2);
}

fn safe_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let n2 = dot(v, v);
    if (n2 < 1e-20) { return fallback; }
    return v * inverseSqrt(n2);
}

// Any unit vector orthogonal to unit n (for a degenerate tangent).
fn ortho(n: vec3<f32>) -> vec3<f32> {
    if (abs(n.x) < 0.9) { return normalize(cross(n, vec3<f32>(1.0, 0.0, 0.0))); }
    return normalize(cross(n, vec3<f32>(0.0, 1.0, 0.0)));
}

// half_vector in material.py: normalize(wi + wo), (0, 0, 1) when |wi + wo|^2 < 1e-12.
fn half_vec(wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let s = wi + wo;
    let n2 = dot(s, s);
    if (n2 < 1e-12) { return vec3<f32>(0.0, 0.0, 1.0); }
    return s / sqrt(n2);
}

fn dirs9(wi: vec3<f32>, wo: vec3<f32>) -> array<f32, 9> {
    let h = half_vec(wi, wo);
    return array<f32, 9>(wi.x, wi.y, wi.z, wo.x, wo.y, wo.z, h.x, h.y, h.z);
}
{% endmacro %}

{% macro surface_fns() %}
// Surface frames (need a global P: Params with model and normal_mat).
struct Surf {
    pos: vec3<f32>,  // world
    n: vec3<f32>,    // unit normal, world
    t: vec3<f32>,    // unit tangent, world
    b: vec3<f32>,    // unit bitangent, world
}

// World-space frame from object-space attributes (normal not normalised, tangent w: handedness):
// normal matrix, Gram-Schmidt tangent. Twin: runtime/reference.py:world_frames.
fn frame_of(pos: vec3<f32>, nrm: vec3<f32>, tan: vec4<f32>) -> Surf {
    let m3 = mat3x3<f32>(P.model[0].xyz, P.model[1].xyz, P.model[2].xyz);
    let nm3 = mat3x3<f32>(P.normal_mat[0].xyz, P.normal_mat[1].xyz, P.normal_mat[2].xyz);
    var s: Surf;
    s.pos = (P.model * vec4<f32>(pos, 1.0)).xyz;
    s.n = safe_normalize(nm3 * nrm, vec3<f32>(0.0, 0.0, 1.0));
    let tw = m3 * tan.xyz;
    s.t = safe_normalize(tw - s.n * dot(s.n, tw), ortho(s.n));
    s.b = select(-1.0, 1.0, tan.w >= 0.0) * cross(s.n, s.t);
    return s;
}

// World position and unit normal only (the cull's facing test; same math as frame_of).
fn pos_normal_of(pos: vec3<f32>, nrm: vec3<f32>) -> array<vec3<f32>, 2> {
    let nm3 = mat3x3<f32>(P.normal_mat[0].xyz, P.normal_mat[1].xyz, P.normal_mat[2].xyz);
    return array<vec3<f32>, 2>((P.model * vec4<f32>(pos, 1.0)).xyz,
                               safe_normalize(nm3 * nrm, vec3<f32>(0.0, 0.0, 1.0)));
}

fn to_local(s: Surf, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, s.t), dot(v, s.b), dot(v, s.n));
}
{% endmacro %}

{% macro mesh_fns() %}
// Mesh access (needs globals P: Params with model/normal_mat/tiling, verts, faces).
fn vtx(i: u32, k: u32) -> vec4<f32> { return verts[i * 4u + k]; }

// Material uv (tiled) of triangle tri at barycentrics l.
fn material_uv_l(tri: u32, l: vec3<f32>) -> vec2<f32> {
    let i0 = faces[tri * 3u];
    let i1 = faces[tri * 3u + 1u];
    let i2 = faces[tri * 3u + 2u];
    let uv = l.x * vtx(i0, 3u).xy + l.y * vtx(i1, 3u).xy + l.z * vtx(i2, 3u).xy;
    return uv * P.tiling.xy + P.tiling.zw;
}

// Interpolated world-space surface frame of triangle tri at barycentrics l.
fn surface_l(tri: u32, l: vec3<f32>) -> Surf {
    let i0 = faces[tri * 3u];
    let i1 = faces[tri * 3u + 1u];
    let i2 = faces[tri * 3u + 2u];
    let pos = l.x * vtx(i0, 0u).xyz + l.y * vtx(i1, 0u).xyz + l.z * vtx(i2, 0u).xyz;
    let nrm = l.x * vtx(i0, 1u).xyz + l.y * vtx(i1, 1u).xyz + l.z * vtx(i2, 1u).xyz;
    let tan = l.x * vtx(i0, 2u) + l.y * vtx(i1, 2u) + l.z * vtx(i2, 2u);
    return frame_of(pos, nrm, tan);
}

{% endmacro %}
