// Texture-space shading of one object for one eye (paper section 4.2). One thread per 2x2
// radiance-texel block: read the 4 triangle IDs, leave early when all are empty or when the block
// faces away from the eye, build the local frame at the block centre, sample the neural textures
// and hoist the light-independent part of the first layers, then per light: coarse MLP once at
// the mean material uv, fine MLP 4 times, sum lights with inverse-square falloff, clamp
// to the f16 range and store rgba16float (or, as an option, rgba32float). numpy twin: runtime/reference.py:shade_texture_space.
// Template parameters: T (f32|f16), mat (runtime/codegen.py:MaterialSpec), n_lights (uniform
// array size, >= 1), n_active (lights shaded, 0 allowed: black).
{% import 'neural_material.wgsl' as nm %}
{% import 'compact.wgsl' as cmp %}
{% if T == 'f16' %}
enable f16;
{% endif %}

struct Params {
    model: mat4x4<f32>,       // object -> world
    normal_mat: mat4x4<f32>,  // inverse transpose of the model's 3x3 (upper-left)
    eye: vec4<f32>,           // eye position, world, metres
    tiling: vec4<f32>,        // material uv = uv * tiling.xy + tiling.zw
    sched: vec4<u32>,         // (candidate list offset, candidate count, counter slot, unused)
}

struct Light {
    pos: vec4<f32>,       // world position, metres
    radiance: vec4<f32>,  // colour * intensity, W/sr
}

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<uniform> lights: array<Light, {{ n_lights }}>;
@group(0) @binding(2) var<storage, read> verts: array<vec4<f32>>;  // 4 per vertex, see gpu_material
@group(0) @binding(3) var<storage, read> faces: array<u32>;        // [F * 3]
@group(0) @binding(4) var<storage, read> tri_ids: array<u32>;      // [R * R], 0xFFFFFFFF = empty
@group(0) @binding(5) var out_tex: texture_storage_2d<{{ fmt | default('rgba16float') }}, write>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;  // 4 per slot
{{ nm.bindings(mat, 7) }}
// Compaction (compact.wgsl): candidate blocks (non-empty, in this dispatch's block rows; packed
// by << 16 | bx, built once per atlas), the blocks to shade this time (front-facing candidates).
@group(0) @binding(12) var<storage, read> cand: array<u32>;
{{ cmp.bindings() }}

override R: u32;  // radiance texture side (even)

const EMPTY: u32 = 0xFFFFFFFFu;
// Largest stored radiance: the f16 maximum for rgba16float, 1e30 for the wide rgba32float option
// (finite, far above any scene: colour * intensity <= 1e6 W/sr, d^2 >= 1e-12 m^2).
const OUT_MAX: f32 = {{ '1e30' if fmt == 'rgba32float' else '65504.0' }};

{{ nm.frame_fns() }}
{{ nm.material_fns(mat, T) }}
{{ nm.mesh_fns() }}

fn texel_uv(x: u32, y: u32) -> vec2<f32> {
    return (vec2<f32>(f32(x), f32(y)) + 0.5) / f32(R);
}

// Barycentrics of atlas point p in triangle tri.
fn tri_bary(tri: u32, p: vec2<f32>) -> vec3<f32> {
    let i0 = faces[tri * 3u];
    let i1 = faces[tri * 3u + 1u];
    let i2 = faces[tri * 3u + 2u];
    let a = vec2<f32>(vtx(i0, 0u).w, vtx(i0, 1u).w);
    let b = vec2<f32>(vtx(i1, 0u).w, vtx(i1, 1u).w);
    let c = vec2<f32>(vtx(i2, 0u).w, vtx(i2, 1u).w);
    return bary2(p, a, b, c);
}

fn surface(tri: u32, p: vec2<f32>) -> Surf { return surface_l(tri, tri_bary(tri, p)); }

// Atlas and material uvs of one triangle's corners (fetched once per block and reused by its
// texels that lie in the same triangle, the common case).
struct TriUV {
    a: vec2<f32>, b: vec2<f32>, c: vec2<f32>,     // atlas uv
    ua: vec2<f32>, ub: vec2<f32>, uc: vec2<f32>,  // material uv
}

fn fetch_tri(tri: u32) -> TriUV {
    let i0 = faces[tri * 3u];
    let i1 = faces[tri * 3u + 1u];
    let i2 = faces[tri * 3u + 2u];
    var t: TriUV;
    t.a = vec2<f32>(vtx(i0, 0u).w, vtx(i0, 1u).w);
    t.b = vec2<f32>(vtx(i1, 0u).w, vtx(i1, 1u).w);
    t.c = vec2<f32>(vtx(i2, 0u).w, vtx(i2, 1u).w);
    t.ua = vtx(i0, 3u).xy;
    t.ub = vtx(i1, 3u).xy;
    t.uc = vtx(i2, 3u).xy;
    return t;
}

// Tiled material uv at atlas point p of a fetched triangle (same math as material_uv).
fn tri_material_uv(t: TriUV, p: vec2<f32>) -> vec2<f32> {
    let l = bary2(p, t.a, t.b, t.c);
    let uv = l.x * t.ua + l.y * t.ub + l.z * t.uc;
    return uv * P.tiling.xy + P.tiling.zw;
}

// Shade one block; returns the counter increments (shaded, back-facing, coarse, fine evals).
// (Blocks reach it through the cull pass, so the empty / back-facing returns are a safety net.)
// Loops over the 4 texels are unrolled by the template (constant indices, no private arrays).
fn shade_block(bx: u32, by: u32) -> vec4<u32> {
    let x0 = bx * 2u;
    let y0 = by * 2u;
{% for k in range(4) %}
    let id{{ k }} = tri_ids[(y0 + {{ k // 2 }}u) * R + x0 + {{ k % 2 }}u];
{% endfor %}
    // the first non-empty texel's triangle
    let tc = select(select(select(id3, id2, id2 != EMPTY), id1, id1 != EMPTY), id0, id0 != EMPTY);
    if (tc == EMPTY) { return vec4<u32>(0u); }
    // Directions at the block centre, through that triangle.
    let centre = vec2<f32>(f32(x0 + 1u), f32(y0 + 1u)) / f32(R);
    let s = surface(tc, centre);
    let wo = to_local(s, safe_normalize(P.eye.xyz - s.pos, s.n));
    if (wo.z <= 0.0) { return vec4<u32>(0u, 1u, 0u, 0u); }
    let tri_c = fetch_tri(tc);
{% for k in range(4) %}
    let p{{ k }} = texel_uv(x0 + {{ k % 2 }}u, y0 + {{ k // 2 }}u);
    var uv{{ k }} = tri_material_uv(tri_c, p{{ k }});
    if (id{{ k }} != tc && id{{ k }} != EMPTY) { uv{{ k }} = tri_material_uv(fetch_tri(id{{ k }}), p{{ k }}); }
{% endfor %}
    let uc = (uv0 + uv1 + uv2 + uv3) * 0.25;
{% for k in range(4) %}
    var acc{{ k }} = vec3<f32>(0.0);
{% endfor %}
    // the light-independent part of every first layer, once per block / texel (neural_material)
{% if mat.arch == 'coarse_fine' %}
    let pa = pre_a(sample_a(uc));
{% for k in range(4) %}
    let pb{{ k }} = pre_b(sample_b(uv{{ k }}));
{% endfor %}
{% else %}
{% for k in range(4) %}
    let pa{{ k }} = pre_a(sample_a(uv{{ k }}));
{% endfor %}
{% endif %}
    var n_coarse = 0u;
    for (var li = 0u; li < {{ n_active }}u; li++) {
        let lv = lights[li].pos.xyz - s.pos;
        let d2 = max(dot(lv, lv), 1e-12);
        let wi = to_local(s, lv * inverseSqrt(d2));
        if (wi.z > 0.0) {
            let e = lights[li].radiance.rgb / d2;
            let d = dirs9(wi, wo);
            n_coarse += 1u;
{% if mat.arch == 'coarse_fine' %}
            let zz = fine_z(eval_coarse(d, pa));  // W_z z_c, shared by the 4 texels
{% for k in range(4) %}
            acc{{ k }} += eval_fine(zz, pb{{ k }}) * e;
{% endfor %}
{% else %}
{% for k in range(4) %}
            acc{{ k }} += eval_single(d, pa{{ k }}) * e;
{% endfor %}
{% endif %}
        }
    }
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

// Geometry-only test of one block: 0 empty, 1 back-facing, 2 to be shaded (same rule as
// shade_block, so a block shade_block is given never turns out back-facing there).
fn block_state(bx: u32, by: u32) -> u32 {
    let x0 = bx * 2u;
    let y0 = by * 2u;
    let id0 = tri_ids[y0 * R + x0];
    let id1 = tri_ids[y0 * R + x0 + 1u];
    let id2 = tri_ids[(y0 + 1u) * R + x0];
    let id3 = tri_ids[(y0 + 1u) * R + x0 + 1u];
    let tc = select(select(select(id3, id2, id2 != EMPTY), id1, id1 != EMPTY), id0, id0 != EMPTY);
    if (tc == EMPTY) { return 0u; }
    let s = surface(tc, vec2<f32>(f32(x0 + 1u), f32(y0 + 1u)) / f32(R));
    let wo = to_local(s, safe_normalize(P.eye.xyz - s.pos, s.n));
    return select(2u, 1u, wo.z <= 0.0);
}

// Three dispatches per (object, eye) update, in one compute pass:
//   cull  over the candidate list: keep the front-facing blocks (workgroup-compacted append);
//   args  one thread: indirect workgroup counts for the kept blocks, padding with EMPTY,
//         and the count back to zero;
//   main  over the kept blocks only (dispatch_workgroups_indirect).
// A CPU adapter (lavapipe) runs every lane of a SIMD group through both sides of a branch, so
// an early out saves nothing there; dispatching only the work is what makes cost follow the
// scene (it also keeps GPU warps full).
{{ cmp.fns() }}
var<workgroup> wg_back: atomic<u32>;

@compute @workgroup_size(64)
fn cull(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = todo_index(wid, nwg, lid);
    if (lid == 0u) { atomicStore(&wg_back, 0u); }  // see compact_append
    workgroupBarrier();
    var packed = EMPTY;
    var st = 0u;
    if (i < P.sched.y) {
        packed = cand[P.sched.x + i];
        st = block_state(packed & 0xFFFFu, packed >> 16u);
        if (st == 1u) { atomicAdd(&wg_back, 1u); }
    }
    compact_append(st == 2u, packed, lid);
    if (lid == 0u) {
        let b = atomicLoad(&wg_back);
        if (b != 0u) { atomicAdd(&counters[P.sched.z * 4u + 1u], b); }
    }
}

var<workgroup> wg_count: array<vec4<u32>, 64>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let packed = todo[todo_index(wid, nwg, lid)];
    var c = vec4<u32>(0u);
    if (packed != EMPTY) { c = shade_block(packed & 0xFFFFu, packed >> 16u); }
    // counters: one slot per thread, summed by thread 0, one global atomic per counter
    wg_count[lid] = c;
    workgroupBarrier();
    if (lid == 0u) {
        var t = vec4<u32>(0u);
        for (var k = 0u; k < 64u; k++) { t += wg_count[k]; }
        for (var k = 0u; k < 4u; k++) {
            if (t[k] != 0u) { atomicAdd(&counters[P.sched.z * 4u + k], t[k]); }
        }
    }
}
