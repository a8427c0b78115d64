// Texture-space shading of one object for one eye (paper section 4.2). One thread per 2x2
// radiance-texel block: read the block's record of the geometry atlas (object-space attributes at
// the block centre and its 4 texels' material uvs, gpu_material.GpuAtlas.geometry, built once per
// atlas), leave early when the block faces away from the eye, build the local frame, sample the neural textures
// and hoist the light-independent part of the first layers, then per light: coarse MLP once at
// the mean material uv, fine MLP 4 times, sum lights with inverse-square falloff, clamp
// to the f16 range and store rgba16float (or, as an option, rgba32float). numpy twin: runtime/reference.py:shade_texture_space.
// Template parameters: T (f32|f16), mat (runtime/codegen.py:MaterialSpec), n_active (lights
// shaded, 0 allowed: black), the generated structs, bindings and networks.
{# and taps (the most footprint taps per axis, Settings.lod_taps: 1 compiles no tap loop), stretch_max
   (reference.STRETCH_MAX); a Jinja comment, so that packs without taps compile the code of before #}
{% import 'neural_material.wgsl' as nm %}
{% import 'compact.wgsl' as cmp %}
{% if T == 'f16' %}
enable f16;
{% endif %}

// The uniforms and bindings (declared once, in runtime/interface.py: TEXTURE_PARAMS, LIGHT,
// texture_bindings).
{{ structs }}

{{ bindings }}

const EMPTY: u32 = 0xFFFFFFFFu;  // padding of the compacted list

// Largest stored radiance: the f16 maximum for rgba16float, 1e30 for the wide rgba32float option
// (finite, far above any scene: colour * intensity <= 1e6 W/sr, d^2 >= 1e-12 m^2).
const OUT_MAX: f32 = {{ '1e30' if fmt == 'rgba32float' else '65504.0' }};

{{ nm.frame_fns() }}
{{ nm.material_fns(mat, T, nets, samplers) }}
{{ nm.surface_fns() }}

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
{% if mat.parallax_steps > 0 or mat.offset_net %}
    // lookups that move along this eye's (extended) view, as the networks see it: where the
    // view ray meets the height field (neural_material.parallax_z), or by NeuMIP's offset
    // MLP's depth at the unmoved uv (offset_r, offset_d); per texel, once per block at the
    // texels' mean, or "auto" (twins: parallax.parallax_uv, neural_offset.offset_uv)
    let t0 = tiled(q01.xy);
    let t1 = tiled(q01.zw);
    let t2 = tiled(q23.xy);
    let t3 = tiled(q23.zw);
{% if mat.parallax_steps > 0 %}
    let pd = parallax_d(view_ext(wo));
{% set moved = 'parallax_z(%s, pd) * pd' %}
{% else %}
    let ow = view_ext(wo);
    let od = offset_d(ow);
{% set moved = 'offset_r(%s, ow) * od' %}
{% endif %}
{% if mat.parallax_march == 'auto' %}
    // once per block where the block spans at most one texel of the march's grid (an atlas
    // texel at most {{ auto_foot }} of them), else per texel (parallax.auto_blocks): one march
    // in a loop run once or 4 times (a copy of the march per route made it 25% slower)
    let once = geo_tan[k].w * max(P.tiling.x, P.tiling.y) * {{ march_side }} <= {{ auto_foot }};
    let tc = (t0 + t1 + t2 + t3) * 0.25;
    var s0 = vec2<f32>(0.0);
    var s1 = vec2<f32>(0.0);
    var s2 = vec2<f32>(0.0);
    var s3 = vec2<f32>(0.0);
    for (var i = 0u; i < select(4u, 1u, once); i = i + 1u) {
        let q = select(select(select(select(t3, t2, i == 2u), t1, i == 1u), t0, i == 0u), tc, once);
        let s = {{ moved % 'q' }};
        s0 = select(s0, s, once || i == 0u);
        s1 = select(s1, s, once || i == 1u);
        s2 = select(s2, s, once || i == 2u);
        s3 = select(s3, s, once || i == 3u);
    }
{% elif mat.parallax_march == 'block' %}
    let shift = {{ moved % '(t0 + t1 + t2 + t3) * 0.25' }};
{% for i in range(4) %}
    let s{{ i }} = shift;
{% endfor %}
{% else %}
{% for i in range(4) %}
    let s{{ i }} = {{ moved % ('t%d' % i) }};
{% endfor %}
{% endif %}
    let uv0 = t0 + s0;
    let uv1 = t1 + s1;
    let uv2 = t2 + s2;
    let uv3 = t3 + s3;
{% else %}
    let uv0 = tiled(q01.xy);
    let uv1 = tiled(q01.zw);
    let uv2 = tiled(q23.xy);
    let uv3 = tiled(q23.zw);
{% endif %}
    let uc = (uv0 + uv1 + uv2 + uv3) * 0.25;
{% if taps > 1 %}
    // the footprint the taps cover (below): one atlas texel, or a pixel where that is larger
    // (P.lod.x), in tiled material UV and in the full-resolution neural texture's texels
    let tap_uv = geo_tan[k].w * max(P.tiling.x, P.tiling.y) * P.lod.x;
    let tap_dims = vec2<f32>(textureDimensions({{ 'tex_b' if mat.arch == 'coarse_fine' else 'tex_a' }}, 0));
    let tap_foot = tap_uv * max(tap_dims.x, tap_dims.y);
{% endif %}
{% if mat.lod_levels > 1 %}
    // prefiltered neural textures: the level of detail of the block's footprint, one atlas
    // texel in the full-resolution texture's texels, from its triangle's uv Jacobian (the
    // geometry atlas's tangent w), or a pixel's where that is larger (P.lod.x, resolution from
    // the screen; twin: reference.block_lod)
    let dims = vec2<f32>(textureDimensions({{ 'tex_b' if mat.arch == 'coarse_fine' else 'tex_a' }}, 0));
    let foot = geo_tan[k].w * max(P.tiling.x, P.tiling.y) * P.lod.x * max(dims.x, dims.y);
    let lod = log2(max(foot, 1.0));
{% set L = '_lod' %}
{% set LA = ', lod' %}
{% else %}
{% set L = '' %}
{% set LA = '' %}
{% endif %}
{% set hoist %}
    // the light-independent part of every first layer, once per block / texel (neural_material)
{% if mat.arch == 'coarse_fine' %}
    let pa = pre_a(sample_a{{ L }}(uc{{ LA }}));
{% for k in range(4) %}
    let pb{{ k }} = pre_b(sample_b{{ L }}(uv{{ k }}{{ LA }}));
{% endfor %}
{% else %}
{% for k in range(4) %}
    let pa{{ k }} = pre_a(sample_a{{ L }}(uv{{ k }}{{ LA }}));
{% endfor %}
{% endif %}
{% endset %}
{% set light_loop %}
    for (var li = 0u; li < {{ n_active }}u; li++) {
        let lv = lights[li].pos.xyz - s.pos;
        let d2 = max(dot(lv, lv), 1e-12);
        let wi = to_local(s, lv * inverseSqrt(d2));
        if (wi.z > 0.0) {
            let e = lights[li].radiance.rgb / d2;
            let lw = light_weight(wi.z);  // 1 inside the range: the same arithmetic as before
            let d = dirs9_ext(wi, wo_e);
            n_coarse += 1u;
{% if mat.arch == 'coarse_fine' %}
            let zz = fine_z(eval_coarse(d, pa));  // W_z z_c, shared by the 4 texels
{% for k in range(4) %}
            acc{{ k }} += eval_fine(zz, pb{{ k }}) * lw * e;
{% endfor %}
{% else %}
{% for k in range(4) %}
            acc{{ k }} += eval_single(d, pa{{ k }}) * lw * e;
{% endfor %}
{% endif %}
        }
    }
{% endset %}
{% for k in range(4) %}
    var acc{{ k }} = vec3<f32>(0.0);
{% endfor %}
{% if taps > 1 %}
    // directions beyond the data's range: evaluated at its boundary (neural_material.to_range)
    let wo_e = view_ext(wo);
    var n_coarse = 0u;
    // footprint taps (Settings.lod_taps; twin: reference.footprint_taps): na x nb taps over the
    // footprint (tap_foot; a pixel's, P.lod.x > 1, stretched along the view by 1 / cos, as on a
    // surface seen obliquely), each count its width there in texels rounded (1 to {{ taps }}),
    // each tap looked up at its share's level and shaded; the texel keeps their mean, the
    // network's output averaged over the footprint rather than the network of averaged inputs
    let pixel = P.lod.x > 1.0;
    let stretch = select(1.0, 1.0 / max(wo.z, {{ 1.0 / stretch_max }}), pixel);
    let along = pixel && dot(wo.xy, wo.xy) > 1e-12;
    let ma = select(vec2<f32>(1.0, 0.0), wo.xy / max(length(wo.xy), 1e-30), along);
    let mb = vec2<f32>(-ma.y, ma.x);
    let ta = tap_foot * stretch;
    let na = clamp(floor(ta + 0.5), 1.0, {{ taps }}.0);
    let nb = clamp(floor(tap_foot + 0.5), 1.0, {{ taps }}.0);
    let nta = u32(na);
    let step_a = (tap_uv * stretch) / na * ma;
    let step_b = tap_uv / nb * mb;
{% if mat.lod_levels > 1 %}
    let lod_t = log2(max(max(ta / na, tap_foot / nb), 1.0));
{% endif %}
    for (var j = 0u; j < nta * u32(nb); j++) {
        let o = (f32(j % nta) + 0.5 - 0.5 * na) * step_a + (f32(j / nta) + 0.5 - 0.5 * nb) * step_b;
        let uc = uc + o;
{% for k in range(4) %}
        let uv{{ k }} = uv{{ k }} + o;
{% endfor %}
{% if mat.lod_levels > 1 %}
        let lod = lod_t;
{% endif %}
{{ hoist | indent(4, first=true) }}{{ light_loop | indent(4, first=true) }}    }
    let wt = 1.0 / (na * nb);
{% for k in range(4) %}
    acc{{ k }} *= wt;
{% endfor %}
{% else %}
{{ hoist }}    // directions beyond the data's range: evaluated at its boundary (neural_material.to_range)
    let wo_e = view_ext(wo);
    var n_coarse = 0u;
{{ light_loop }}{% endif %}
{% for k in range(4) %}
    textureStore(out_tex, vec2<u32>(x0 + {{ k % 2 }}u, y0 + {{ k // 2 }}u),
                 vec4<f32>(clamp(acc{{ k }}, vec3<f32>(0.0), vec3<f32>(OUT_MAX)), 1.0));
{% endfor %}
{% if mat.arch == 'coarse_fine' %}
    return vec4<u32>(1u, 0u, n_coarse, 4u * n_coarse);
{% else %}
    return vec4<u32>(1u, 0u, 0u, 4u * n_coarse);
{% endif %}
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
{{ cmp.fns(subgroups) }}

{% if subgroups %}
// counters: summed over the subgroup, one atomic per counter and subgroup (device feature
// "subgroup"; no workgroup barrier). Call from uniform control flow.
fn count4(c: vec4<u32>, lid: u32) {
    let t = subgroupAdd(c);
    if (subgroupBroadcastFirst(lid) == lid) {  // the first active invocation
        for (var k = 0u; k < 4u; k++) {
            if (t[k] != 0u) { atomicAdd(&counters[P.sched.z * 4u + k], t[k]); }
        }
    }
}
{% else %}
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
{% endif %}

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
{% macro bare_block(loads) %}
    let g0 = geo_pos[k];
    let packed = bitcast<u32>(g0.w);
    let x0 = (packed & 0xFFFFu) * 2u;
    let y0 = (packed >> 16u) * 2u;
    var v = g0.xyz + geo_nrm[k].xyz + geo_tan[k].xyz;
    let q01 = geo_uv01[k];
    let q23 = geo_uv23[k];
    var w = vec4<f32>(q01.x, q01.z, q23.x, q23.z);
{% if loads %}
    let t0 = tiled(q01.xy);
    let t1 = tiled(q01.zw);
    let t2 = tiled(q23.xy);
    let t3 = tiled(q23.zw);
{% if mat.arch == 'coarse_fine' %}
    v.x += sample_a((t0 + t1 + t2 + t3) * 0.25)[0];
{% for i in range(4) %}
    let f{{ i }} = sample_b(t{{ i }});
{% endfor %}
{% else %}
{% for i in range(4) %}
    let f{{ i }} = sample_a(t{{ i }});
{% endfor %}
{% endif %}
{% for i in range(4) %}
    w[{{ i }}] += {% for c in range(mat.cb if mat.arch == 'coarse_fine' else mat.ca) %}{{ ' + ' if c else '' }}f{{ i }}[{{ c }}]{% endfor %};
{% endfor %}
{% endif %}
    textureStore(out_tex, vec2<u32>(x0, y0), vec4<f32>(v + w.x, 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0), vec4<f32>(v + w.y, 1.0));
    textureStore(out_tex, vec2<u32>(x0, y0 + 1u), vec4<f32>(v + w.z, 1.0));
    textureStore(out_tex, vec2<u32>(x0 + 1u, y0 + 1u), vec4<f32>(v + w.w, 1.0));
{%- endmacro %}
{% for entry, loads in (('bare', false), ('bare_loads', true)) %}

@compute @workgroup_size(64)
fn {{ entry }}(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
{{ ' ' * (entry | length + 4) }}@builtin(local_invocation_index) lid: u32) {
    let i = todo_index(wid, nwg, lid);
    if (i >= P.sched.y) { return; }
    let k = cand[P.sched.x + i];
    if (!block_front(k)) { return; }
{{ bare_block(loads) }}
}
{% endfor %}
