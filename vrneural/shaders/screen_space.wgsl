// Screen-space shading of one neural object for one eye (the paper's "ours in screen space"
// baseline, and --mode reference with buffer weights): one thread per pixel, every frame. The
// visibility pass wrote (object id + 1, triangle) per pixel; the pixel's view ray is intersected
// with that triangle's plane for barycentrics, then the surface frame, material uv and lights
// are computed exactly as in texture_space.wgsl. Pixels do NOT share the coarse MLP: each pixel
// runs the coarse MLP and the fine MLP once per light at its own material uv (u_c = u_k).
// numpy twin of the per-point shading: runtime/reference.py:shade_points.
{% import 'neural_material.wgsl' as nm %}
{% import 'compact.wgsl' as cmp %}
{% if T == 'f16' %}
enable f16;
{% endif %}

// The uniforms and bindings (declared once, in runtime/interface.py: SCREEN_PARAMS, LIGHT,
// screen_bindings).
{{ structs }}

{{ bindings }}
const EMPTY: u32 = 0xFFFFFFFFu;

{{ nm.frame_fns() }}
{{ nm.material_fns(mat, T, nets, samplers) }}
{{ nm.surface_fns() }}
{{ nm.mesh_fns() }}

// Barycentrics of the ray (o, d) hitting the plane of triangle tri (world space).
fn ray_bary(tri: u32, o: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let v0 = (P.model * vec4<f32>(vtx(faces[tri * 3u], 0u).xyz, 1.0)).xyz;
    let v1 = (P.model * vec4<f32>(vtx(faces[tri * 3u + 1u], 0u).xyz, 1.0)).xyz;
    let v2 = (P.model * vec4<f32>(vtx(faces[tri * 3u + 2u], 0u).xyz, 1.0)).xyz;
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if (abs(det) < 1e-20) { return vec3<f32>(1.0 / 3.0); }
    let inv = 1.0 / det;
    let tv = o - v0;
    let u = dot(tv, pv) * inv;
    let v = dot(d, cross(tv, e1)) * inv;
    return vec3<f32>(1.0 - u - v, u, v);
}

fn shade_pixel(px: vec2<u32>) -> vec4<u32> {
    let id = textureLoad(vis, px, 0);
    if (id.x != P.screen.w + 1u) { return vec4<u32>(0u); }
    let ndc = vec2<f32>(
        (f32(px.x) + 0.5) / f32(P.screen.x) * 2.0 - 1.0,
        1.0 - (f32(px.y) + 0.5) / f32(P.screen.y) * 2.0,
    );
    let far = P.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    let near = P.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
    let dir = normalize(far.xyz / far.w - near.xyz / near.w);
    let l = ray_bary(id.y, near.xyz / near.w, dir);
    let s = surface_l(id.y, l);
    let wo = to_local(s, safe_normalize(P.eye.xyz - s.pos, s.n));
    if (wo.z <= 0.0) {
        textureStore(out_tex, px, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return vec4<u32>(0u, 1u, 0u, 0u);
    }
{% if mat.parallax_steps > 0 %}
    // height-field parallax (neural_material.parallax_uv): the pixel's lookup where its view
    // ray meets the height field
    let uv = parallax_uv(material_uv_l(id.y, l), parallax_d(view_ext(wo)));
{% elif mat.offset_net %}
    // NeuMIP's neural offset (neural_material offset_r, offset_d): the pixel's lookup moved
    // along its (extended) view by the offset MLP's depth at the unmoved uv
    let ow = view_ext(wo);
    let u0 = material_uv_l(id.y, l);
    let uv = u0 + offset_r(u0, ow) * offset_d(ow);
{% else %}
    let uv = material_uv_l(id.y, l);
{% endif %}
    let pa = pre_a(sample_a(uv));  // light-independent first-layer parts (neural_material)
{% if mat.arch == 'coarse_fine' %}
    let pb = pre_b(sample_b(uv));
{% endif %}
    // directions beyond the data's range: evaluated at its boundary (neural_material.to_range)
    let wo_e = view_ext(wo);
    var acc = vec3<f32>(0.0);
    var n = 0u;
    for (var li = 0u; li < {{ n_active }}u; li++) {
        let lv = lights[li].pos.xyz - s.pos;
        let d2 = max(dot(lv, lv), 1e-12);
        let wi = to_local(s, lv * inverseSqrt(d2));
        if (wi.z <= 0.0) { continue; }
        let d = dirs9_ext(wi, wo_e);
        let lw = light_weight(wi.z);  // 1 inside the range: the same arithmetic as before
        n += 1u;
{% if mat.arch == 'coarse_fine' %}
        acc += eval_fine(fine_z(eval_coarse(d, pa)), pb) * lw * lights[li].radiance.rgb / d2;
{% else %}
        acc += eval_single(d, pa) * lw * lights[li].radiance.rgb / d2;
{% endif %}
    }
    textureStore(out_tex, px, vec4<f32>(clamp(acc, vec3<f32>(0.0), vec3<f32>(F16_MAX)), 1.0));
{% if mat.arch == 'coarse_fine' %}
    return vec4<u32>(1u, 0u, n, n);
{% else %}
    return vec4<u32>(1u, 0u, 0u, n);
{% endif %}
}

// cull: the rectangle's pixels that show this object -> todo; args: indirect workgroup counts;
// main: shade the listed pixels only (a CPU adapter pays for every dispatched lane, so the
// pixels of other objects and of the background inside the rectangle cost nothing).
{{ cmp.fns(subgroups) }}

@compute @workgroup_size(8, 8)
fn cull(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let px = gid.xy + P.rect.xy;
    var keep = false;
    if (gid.x < P.rect.z && gid.y < P.rect.w && px.x < P.screen.x && px.y < P.screen.y) {
        keep = textureLoad(vis, px, 0).x == P.screen.w + 1u;
    }
    compact_append(keep, (px.y << 16u) | px.x, lid);
}

var<workgroup> wg_count: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    if (lid < 4u) { atomicStore(&wg_count[lid], 0u); }
    workgroupBarrier();
    var c = vec4<u32>(0u);
    let packed = todo[todo_index(wid, nwg, lid)];
    if (packed != EMPTY) { c = shade_pixel(vec2<u32>(packed & 0xFFFFu, packed >> 16u)); }
    for (var k = 0u; k < 4u; k++) {
        if (c[k] != 0u) { atomicAdd(&wg_count[k], c[k]); }
    }
    workgroupBarrier();
    if (lid < 4u) {
        let v = atomicLoad(&wg_count[lid]);
        if (v != 0u) { atomicAdd(&counters[P.screen.z * 4u + lid], v); }
    }
}
