// Texture-space shading of one object for one eye (paper section 4.2). One thread per 2x2
// radiance-texel block: read the block's record of the geometry atlas (object-space attributes at
// the block centre and its 4 texels' material uvs, gpu_material.GpuAtlas.geometry, built once per
// atlas), leave early when the block faces away from the eye, build the local frame, sample the neural textures
// and hoist the light-independent part of the first layers, then per light: coarse MLP once at
// the mean material uv, fine MLP 4 times, sum lights with inverse-square falloff, clamp
// to the f16 range and store rgba16float (or, as an option, rgba32float). numpy twin: runtime/reference.py:shade_texture_space.
// Template parameters: T (f32|f16), mat (runtime/codegen.py:MaterialSpec), n_active (lights
// shaded, 0 allowed: black), the generated structs, bindings and networks.

// The uniforms and bindings (declared once, in runtime/interface.py: TEXTURE_PARAMS, LIGHT,
// texture_bindings).
struct Params {
    model: mat4x4<f32>,  // object -> world (camera-relative: the eye at the origin)
    normal_mat: mat4x4<f32>,  // inverse transpose of the model's 3x3 (upper-left)
    eye: vec4<f32>,  // eye position (camera-relative: 0); w: facing margin, metres
    tiling: vec4<f32>,  // material uv = uv * tiling.xy + tiling.zw
    sched: vec4<u32>,  // (candidate list offset, candidate count, counter slot, unused)
    lod: vec4<f32>,  // x: the neural-texture footprint's scale (1: one atlas texel; Settings.lod_footprint), yzw unused
}
struct Light {
    pos: vec4<f32>,  // world position, metres (relative to the shaded eye where noted)
    radiance: vec4<f32>,  // colour * intensity, W/sr
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<uniform> lights: array<Light, 2>;
@group(0) @binding(2) var<storage, read> geo_pos: array<vec4<f32>>;  // object pos, bitcast(by << 16 | bx)
@group(0) @binding(3) var<storage, read> geo_nrm: array<vec4<f32>>;  // object normal, tangent sign
@group(0) @binding(4) var<storage, read> geo_tan: array<vec4<f32>>;  // object tangent, texel foot
@group(0) @binding(16) var<storage, read> geo_uv01: array<vec4<f32>>;  // untiled uv of texels 0, 1
@group(0) @binding(17) var<storage, read> geo_uv23: array<vec4<f32>>;  // untiled uv of texels 2, 3
@group(0) @binding(5) var out_tex: texture_storage_2d<rgba16float, write>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;  // 4 per slot
@group(0) @binding(7) var tex_a: texture_2d_array<u32>;  // coarse / features
@group(0) @binding(8) var tex_b: texture_2d_array<u32>;  // fine
@group(0) @binding(12) var<storage, read> cand: array<u32>;  // candidate blocks
@group(0) @binding(13) var<storage, read_write> todo: array<u32>;
@group(0) @binding(14) var<storage, read_write> todo_n: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read_write> ind: array<u32>;  // (x, y, z) workgroups

const EMPTY: u32 = 0xFFFFFFFFu;  // padding of the compacted list

// Largest stored radiance: the f16 maximum for rgba16float, 1e30 for the wide rgba32float option
// (finite, far above any scene: colour * intensity <= 1e6 W/sr, d^2 >= 1e-12 m^2).
const OUT_MAX: f32 = 65504.0;

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

// The training data's direction range (vrneural/grazing.py): cos and sin of theta_i_max and
// theta_o_max, exact float32 values.
const COS_I_MAX: f32 = 0.258819043636322;
const SIN_I_MAX: f32 = 0.9659258127212524;
const COS_O_MAX: f32 = 0.258819043636322;
const SIN_O_MAX: f32 = 0.9659258127212524;

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
// Bilinear wrap lookup of 2 channels at material uv (texel centres at (i + 0.5) / W).
fn sample_a(uv: vec2<f32>) -> array<f32, 2> {
    let dims = vec2<i32>(textureDimensions(tex_a));
    let tp = bilinear_taps(uv, dims);
    let xi0 = tp.i0.x;
    let yi0 = tp.i0.y;
    let xi1 = tp.i1.x;
    let yi1 = tp.i1.y;
    let fx = tp.f.x;
    let fy = tp.f.y;
    var out: array<f32, 2>;
    {
        let t00 = textureLoad(tex_a, vec2<i32>(xi0, yi0), 0, 0);
        let t10 = textureLoad(tex_a, vec2<i32>(xi1, yi0), 0, 0);
        let t01 = textureLoad(tex_a, vec2<i32>(xi0, yi1), 0, 0);
        let t11 = textureLoad(tex_a, vec2<i32>(xi1, yi1), 0, 0);
        {
            let top = unpack2x16float(t00[0]) * (1.0 - fx) + unpack2x16float(t10[0]) * fx;
            let bot = unpack2x16float(t01[0]) * (1.0 - fx) + unpack2x16float(t11[0]) * fx;
            let v = top * (1.0 - fy) + bot * fy;
            out[0] = v.x;
            out[1] = v.y;
        }
    }
    return out;
}
// Bilinear wrap lookup of 2 channels at material uv (texel centres at (i + 0.5) / W).
fn sample_b(uv: vec2<f32>) -> array<f32, 2> {
    let dims = vec2<i32>(textureDimensions(tex_b));
    let tp = bilinear_taps(uv, dims);
    let xi0 = tp.i0.x;
    let yi0 = tp.i0.y;
    let xi1 = tp.i1.x;
    let yi1 = tp.i1.y;
    let fx = tp.f.x;
    let fy = tp.f.y;
    var out: array<f32, 2>;
    {
        let t00 = textureLoad(tex_b, vec2<i32>(xi0, yi0), 0, 0);
        let t10 = textureLoad(tex_b, vec2<i32>(xi1, yi0), 0, 0);
        let t01 = textureLoad(tex_b, vec2<i32>(xi0, yi1), 0, 0);
        let t11 = textureLoad(tex_b, vec2<i32>(xi1, yi1), 0, 0);
        {
            let top = unpack2x16float(t00[0]) * (1.0 - fx) + unpack2x16float(t10[0]) * fx;
            let bot = unpack2x16float(t01[0]) * (1.0 - fx) + unpack2x16float(t11[0]) * fx;
            let v = top * (1.0 - fy) + bot * fy;
            out[0] = v.x;
            out[1] = v.y;
        }
    }
    return out;
}
// Output transform of the last layer's raw value (material.apply_output).
fn apply_output(r: vec3<f32>) -> vec3<f32> {
    return max(r, vec3<f32>(0.0));
}


// Evaluation API (every weight variant; generated in Python: runtime/codegen_mlp.py). The first
// layer of every network is split into the part that does not change with the light (bias + W_f
// features: pre_a, pre_b, computed once per texel or block outside the light loop) and the part
// that does (W_d dirs, and for the fine network W_z z_c, computed once per block per light by
// fine_z and shared by the block's 4 texels):
//   coarse_fine: z = eval_coarse(dirs, pre_a(U_c(u_c))); zz = fine_z(z);
//                rgb_k = eval_fine(zz, pre_b(U_f(u_k)))
//   single:      rgb_k = eval_single(dirs, pre_a(U(u_k)))
fn pre_a(f: array<f32, 2>) -> array<f32, 4> {
    let in_0 = f32(f[0]);
    let in_1 = f32(f[1]);
    let cp_0 = 0.13588234782218933f + -0.2645713984966278f * in_0 + 0.2088693529367447f * in_1;
    let cp_1 = -0.1547144651412964f + -0.7853184342384338f * in_0 + -0.10024319589138031f * in_1;
    let cp_2 = 0.08593826740980148f + -0.20371468365192413f * in_0 + -0.4172419309616089f * in_1;
    let cp_3 = 0.011935402639210224f + -0.5223655700683594f * in_0 + 0.032466303557157516f * in_1;
    return array<f32, 4>(cp_0, cp_1, cp_2, cp_3);
}
fn pre_b(f: array<f32, 2>) -> array<f32, 4> {
    let in_0 = f32(f[0]);
    let in_1 = f32(f[1]);
    let qp_0 = -0.011849770322442055f + -1.3351695537567139f * in_0 + -0.10905984789133072f * in_1;
    let qp_1 = -0.023974785581231117f + 0.44309908151626587f * in_0 + -0.03061675652861595f * in_1;
    let qp_2 = -0.01553016621619463f + -0.024637745693325996f * in_0 + 0.8313940167427063f * in_1;
    let qp_3 = 0.021897170692682266f + -0.9465357065200806f * in_0 + 0.20793572068214417f * in_1;
    return array<f32, 4>(qp_0, qp_1, qp_2, qp_3);
}
fn fine_z(z: array<f32, 4>) -> array<f32, 4> {
    let zz_0 = -1.0035885572433472f * z[0] + -0.7717110514640808f * z[1] + -0.785835325717926f * z[2] + -0.20300625264644623f * z[3];
    let zz_1 = -0.5526565313339233f * z[0] + 0.5159202814102173f * z[1] + 0.5524359941482544f * z[2] + 0.8038206696510315f * z[3];
    let zz_2 = 0.4964022934436798f * z[0] + 0.869189977645874f * z[1] + -0.3773529827594757f * z[2] + 0.35238638520240784f * z[3];
    let zz_3 = -0.48318156599998474f * z[0] + -0.17409801483154297f * z[1] + 0.2091962844133377f * z[2] + 0.1490200310945511f * z[3];
    return array<f32, 4>(zz_0, zz_1, zz_2, zz_3);
}
fn eval_coarse(d: array<f32, 9>, pa: array<f32, 4>) -> array<f32, 4> {
    let in_0 = f32(d[0]);
    let in_1 = f32(d[1]);
    let in_2 = f32(d[2]);
    let in_3 = f32(d[3]);
    let in_4 = f32(d[4]);
    let in_5 = f32(d[5]);
    let in_6 = f32(d[6]);
    let in_7 = f32(d[7]);
    let in_8 = f32(d[8]);
    let c1_0 = max(pa[0] + 0.0005245391512289643f * in_0 + 0.12738552689552307f * in_1 + -0.11689277738332748f * in_2 + -0.3797496259212494f * in_3 + -0.19387227296829224f * in_4 + -0.42283952236175537f * in_5 + 0.025645317509770393f * in_6 + 0.5714697241783142f * in_7 + -0.20987756550312042f * in_8, f32(0));
    let c1_1 = max(pa[1] + 0.1521771252155304f * in_0 + 0.04494878649711609f * in_1 + -0.39675289392471313f * in_2 + -0.01247301883995533f * in_3 + 0.296478271484375f * in_4 + -0.5731750130653381f * in_5 + -0.19512800872325897f * in_6 + -0.810684084892273f * in_7 + -0.5498607158660889f * in_8, f32(0));
    let c1_2 = max(pa[2] + -0.5404409766197205f * in_0 + 0.11566751450300217f * in_1 + 0.06683889031410217f * in_2 + -0.07970762252807617f * in_3 + -1.0731499195098877f * in_4 + -0.22969941794872284f * in_5 + -0.020680872723460197f * in_6 + 0.04831511527299881f * in_7 + -0.6524521112442017f * in_8, f32(0));
    let c1_3 = max(pa[3] + -0.344889372587204f * in_0 + 0.45236870646476746f * in_1 + -0.3443339467048645f * in_2 + -0.013867301866412163f * in_3 + 0.37710511684417725f * in_4 + -0.2488480657339096f * in_5 + -0.04762987047433853f * in_6 + 0.04710206761956215f * in_7 + 0.027196640148758888f * in_8, f32(0));
    let c2_0 = max(-0.05793016031384468f + -0.45358806848526f * c1_0 + 1.4145081043243408f * c1_1 + 0.5389990210533142f * c1_2 + -0.8480253219604492f * c1_3, f32(0));
    let c2_1 = max(-0.019619597122073174f + 0.05269093066453934f * c1_0 + 0.40778112411499023f * c1_1 + -0.13348911702632904f * c1_2 + 0.4828904867172241f * c1_3, f32(0));
    let c2_2 = max(0.08987638354301453f + -0.0470348484814167f * c1_0 + 0.471815288066864f * c1_1 + 1.0171890258789062f * c1_2 + -0.47776535153388977f * c1_3, f32(0));
    let c2_3 = max(0.11452220380306244f + 0.1436406821012497f * c1_0 + -0.3276079297065735f * c1_1 + 0.08999235928058624f * c1_2 + -0.839473307132721f * c1_3, f32(0));
    return array<f32, 4>(c2_0, c2_1, c2_2, c2_3);
}
fn fine_net(zz: array<f32, 4>, pb: array<f32, 4>) -> vec3<f32> {
    let q1_0 = max((zz[0] + pb[0]), f32(0));
    let q1_1 = max((zz[1] + pb[1]), f32(0));
    let q1_2 = max((zz[2] + pb[2]), f32(0));
    let q1_3 = max((zz[3] + pb[3]), f32(0));
    let q2_0 = 0.11874322593212128f + -1.2843856811523438f * q1_0 + 1.0977596044540405f * q1_1 + -0.6091312766075134f * q1_2 + -1.5848864316940308f * q1_3;
    let q2_1 = -0.08167722076177597f + -0.05796471983194351f * q1_0 + 1.0305942296981812f * q1_1 + -0.3667062520980835f * q1_2 + 1.0969175100326538f * q1_3;
    let q2_2 = -0.15106774866580963f + 1.1009242534637451f * q1_0 + -0.6100435853004456f * q1_1 + -1.7431036233901978f * q1_2 + -0.8734061121940613f * q1_3;
    return vec3<f32>(f32(q2_0), f32(q2_1), f32(q2_2));
}
fn eval_fine(zz: array<f32, 4>, pb: array<f32, 4>) -> vec3<f32> {
    return apply_output(fine_net(zz, pb));
}

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


fn tiled(uv: vec2<f32>) -> vec2<f32> { return uv * P.tiling.xy + P.tiling.zw; }

// Shade block k of the geometry atlas; returns the counter increments (shaded, back-facing,
// coarse, fine evals). `main` calls it for the blocks block_front keeps, so the back-facing
// return is a safety net. Loops over the 4 texels are unrolled by the template (no private arrays).
fn shade_block(k: u32) -> vec4<u32> {
    let g0 = geo_pos[k];
    let g1 = geo_nrm[k];
    let packed = bitcast<u32>(g0.w);
    let x0 = (packed & 0xFFFFu) * 2u;
    let y0 = (packed >> 16u) * 2u;
    let s = frame_of(g0.xyz, g1.xyz, vec4<f32>(geo_tan[k].xyz, g1.w));
    let wo = to_local(s, safe_normalize(P.eye.xyz - s.pos, s.n));
    if (wo.z <= 0.0 && dot(P.eye.xyz - s.pos, s.n) <= -P.eye.w) {
        return vec4<u32>(0u, 1u, 0u, 0u);
    }
    let q01 = geo_uv01[k];
    let q23 = geo_uv23[k];
    let uv0 = tiled(q01.xy);
    let uv1 = tiled(q01.zw);
    let uv2 = tiled(q23.xy);
    let uv3 = tiled(q23.zw);
    let uc = (uv0 + uv1 + uv2 + uv3) * 0.25;
    var acc0 = vec3<f32>(0.0);
    var acc1 = vec3<f32>(0.0);
    var acc2 = vec3<f32>(0.0);
    var acc3 = vec3<f32>(0.0);
    // the light-independent part of every first layer, once per block / texel (neural_material)
    let pa = pre_a(sample_a(uc));
    let pb0 = pre_b(sample_b(uv0));
    let pb1 = pre_b(sample_b(uv1));
    let pb2 = pre_b(sample_b(uv2));
    let pb3 = pre_b(sample_b(uv3));
    // directions beyond the data's range: evaluated at its boundary (neural_material.to_range)
    let wo_e = view_ext(wo);
    var n_coarse = 0u;
    for (var li = 0u; li < 2u; li++) {
        let lv = lights[li].pos.xyz - s.pos;
        let d2 = max(dot(lv, lv), 1e-12);
        let wi = to_local(s, lv * inverseSqrt(d2));
        if (wi.z > 0.0) {
            let e = lights[li].radiance.rgb / d2;
            let lw = light_weight(wi.z);  // 1 inside the range: the same arithmetic as before
            let d = dirs9_ext(wi, wo_e);
            n_coarse += 1u;
            let zz = fine_z(eval_coarse(d, pa));  // W_z z_c, shared by the 4 texels
            acc0 += eval_fine(zz, pb0) * lw * e;
            acc1 += eval_fine(zz, pb1) * lw * e;
            acc2 += eval_fine(zz, pb2) * lw * e;
            acc3 += eval_fine(zz, pb3) * lw * e;
        }
    }
    textureStore(out_tex, vec2<u32>(x0 + 0u, y0 + 0u),
                 vec4<f32>(clamp(acc0, vec3<f32>(0.0), vec3<f32>(OUT_MAX)), 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0 + 0u),
                 vec4<f32>(clamp(acc1, vec3<f32>(0.0), vec3<f32>(OUT_MAX)), 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 0u, y0 + 1u),
                 vec4<f32>(clamp(acc2, vec3<f32>(0.0), vec3<f32>(OUT_MAX)), 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0 + 1u),
                 vec4<f32>(clamp(acc3, vec3<f32>(0.0), vec3<f32>(OUT_MAX)), 1.0));
    return vec4<u32>(1u, 0u, n_coarse, 4u * n_coarse);
}

// Facing test of block k (same rule as shade_block, so a block it keeps never turns out
// back-facing there): true when the eye, or a point within the margin P.eye.w of it, sees its
// front.
fn block_front(k: u32) -> bool {
    let pn = pos_normal_of(geo_pos[k].xyz, geo_nrm[k].xyz);
    let v = P.eye.xyz - pn[0];
    return dot(safe_normalize(v, pn[1]), pn[1]) > 0.0 || dot(v, pn[1]) > -P.eye.w;
}

// An update of a span of candidates (P.sched.x, P.sched.y), in one of two ways (texture_pass.py
// picks by the span's length, COMPACT_MIN):
//   main       one dispatch, a thread per candidate: the facing test, then the shading of the
//              front-facing block. Neighbouring candidates lie in one atlas chart and mostly
//              agree on the branch (llvmpipe runs a branch when any lane of its SIMD group
//              takes it; a GPU warp likewise).
//   cull, args, main_compacted
//              three dispatches: cull appends the front-facing blocks to a list
//              (compact.wgsl), args turns its length into indirect workgroup counts,
//              main_compacted shades the list: every lane busy, worth its two extra dispatches
//              and barriers on long spans only (on lavapipe: 2.3x slower than main on a staggered
//              update at 128^2, 7-16% faster on full and staggered updates at 512-800^2).
var<workgroup> wg_n: atomic<u32>;
var<workgroup> wg_base: u32;

// Append `value` to todo where `keep`: one workgroup atomic per item, one global atomic per
// workgroup. Call from uniform control flow (it holds barriers; they also complete any other
// workgroup atomics done before the call). The workgroup counter is reset explicitly, not left
// to WGSL's zero initialisation: without this reset the render tests hung on llvmpipe.
fn compact_append(keep: bool, value: u32, lid: u32) {
    if (lid == 0u) { atomicStore(&wg_n, 0u); }
    workgroupBarrier();
    var slot = 0u;
    if (keep) { slot = atomicAdd(&wg_n, 1u); }
    workgroupBarrier();
    if (lid == 0u) { wg_base = atomicAdd(&todo_n[0], atomicLoad(&wg_n)); }
    let base = workgroupUniformLoad(&wg_base);
    if (keep) { todo[base + slot] = value; }
}

var<workgroup> wg_sum: atomic<u32>;

// Add `x`, summed over the workgroup, to counters[idx] (one workgroup atomic per invocation,
// one global atomic per workgroup). `idx` must be workgroup-uniform; call from uniform control
// flow (barriers; the sum is reset explicitly, as in compact_append).
fn count_add(idx: u32, x: u32, lid: u32) {
    if (lid == 0u) { atomicStore(&wg_sum, 0u); }
    workgroupBarrier();
    if (x != 0u) { atomicAdd(&wg_sum, x); }
    workgroupBarrier();
    if (lid == 0u) {
        let t = atomicLoad(&wg_sum);
        if (t != 0u) { atomicAdd(&counters[idx], t); }
    }
}

// Index of a 1D, 64-wide invocation in a grid of (x, y) workgroups (runtime.texture_pass.grid).
fn todo_index(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> u32 {
    return (wid.y * nwg.x + wid.x) * 64u + lid;
}

@compute @workgroup_size(1)
fn args() {
    let n = atomicExchange(&todo_n[0], 0u);  // and zero for the next use
    let wg = (n + 63u) / 64u;
    let y = max(1u, (wg + 65534u) / 65535u);
    let x = (wg + y - 1u) / y;
    ind[0] = x;
    ind[1] = y;
    ind[2] = 1u;
    for (var k = n; k < x * y * 64u; k++) { todo[k] = EMPTY; }
}


var<workgroup> wg_count: array<atomic<u32>, 4>;

// counters: summed with workgroup atomics, one global atomic per counter and workgroup. Call
// from uniform control flow (barriers; the sums are reset explicitly, as in compact.wgsl).
fn count4(c: vec4<u32>, lid: u32) {
    if (lid < 4u) { atomicStore(&wg_count[lid], 0u); }
    workgroupBarrier();
    for (var k = 0u; k < 4u; k++) {
        if (c[k] != 0u) { atomicAdd(&wg_count[k], c[k]); }
    }
    workgroupBarrier();
    if (lid < 4u) {
        let t = atomicLoad(&wg_count[lid]);
        if (t != 0u) { atomicAdd(&counters[P.sched.z * 4u + lid], t); }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = todo_index(wid, nwg, lid);
    var c = vec4<u32>(0u);
    if (i < P.sched.y) {
        let k = cand[P.sched.x + i];
        if (block_front(k)) {
            c = shade_block(k);
        } else {
            c.y = 1u;
        }
    }
    count4(c, lid);
}

@compute @workgroup_size(64)
fn cull(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = todo_index(wid, nwg, lid);
    var k = EMPTY;
    var front = false;
    if (i < P.sched.y) {
        k = cand[P.sched.x + i];
        front = block_front(k);
    }
    compact_append(front, k, lid);
    count_add(P.sched.z * 4u + 1u, select(0u, 1u, i < P.sched.y && !front), lid);
}

@compute @workgroup_size(64)
fn main_compacted(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) lid: u32) {
    let k = todo[todo_index(wid, nwg, lid)];
    var c = vec4<u32>(0u);
    if (k != EMPTY) { c = shade_block(k); }
    count4(c, lid);
}

// The floors of this pass (`vrneural bench frame`): the same candidates, the same facing test,
// the same geometry records read and the same texels stored as `main`, and nothing else (no
// frame, sampling, network or counters): `bare`; `bare_loads` adds the neural-texture lookups at
// the block's texels (level 0 at the unmoved uvs: those of a material without parallax or
// pyramid), the traffic every shading of them needs.

@compute @workgroup_size(64)
fn bare(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = todo_index(wid, nwg, lid);
    if (i >= P.sched.y) { return; }
    let k = cand[P.sched.x + i];
    if (!block_front(k)) { return; }
    let g0 = geo_pos[k];
    let packed = bitcast<u32>(g0.w);
    let x0 = (packed & 0xFFFFu) * 2u;
    let y0 = (packed >> 16u) * 2u;
    var v = g0.xyz + geo_nrm[k].xyz + geo_tan[k].xyz;
    let q01 = geo_uv01[k];
    let q23 = geo_uv23[k];
    var w = vec4<f32>(q01.x, q01.z, q23.x, q23.z);
    textureStore(out_tex, vec2<u32>(x0, y0), vec4<f32>(v + w.x, 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0), vec4<f32>(v + w.y, 1.0));
    textureStore(out_tex, vec2<u32>(x0, y0 + 1u), vec4<f32>(v + w.z, 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0 + 1u), vec4<f32>(v + w.w, 1.0));
}

@compute @workgroup_size(64)
fn bare_loads(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
              @builtin(local_invocation_index) lid: u32) {
    let i = todo_index(wid, nwg, lid);
    if (i >= P.sched.y) { return; }
    let k = cand[P.sched.x + i];
    if (!block_front(k)) { return; }
    let g0 = geo_pos[k];
    let packed = bitcast<u32>(g0.w);
    let x0 = (packed & 0xFFFFu) * 2u;
    let y0 = (packed >> 16u) * 2u;
    var v = g0.xyz + geo_nrm[k].xyz + geo_tan[k].xyz;
    let q01 = geo_uv01[k];
    let q23 = geo_uv23[k];
    var w = vec4<f32>(q01.x, q01.z, q23.x, q23.z);
    let t0 = tiled(q01.xy);
    let t1 = tiled(q01.zw);
    let t2 = tiled(q23.xy);
    let t3 = tiled(q23.zw);
    v.x += sample_a((t0 + t1 + t2 + t3) * 0.25)[0];
    let f0 = sample_b(t0);
    let f1 = sample_b(t1);
    let f2 = sample_b(t2);
    let f3 = sample_b(t3);
    w[0] += f0[0] + f0[1];
    w[1] += f1[0] + f1[1];
    w[2] += f2[0] + f2[1];
    w[3] += f3[0] + f3[1];
    textureStore(out_tex, vec2<u32>(x0, y0), vec4<f32>(v + w.x, 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0), vec4<f32>(v + w.y, 1.0));
    textureStore(out_tex, vec2<u32>(x0, y0 + 1u), vec4<f32>(v + w.z, 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0 + 1u), vec4<f32>(v + w.w, 1.0));
}
