// Forward pass per eye (and the visibility pass of the screen-space modes).
// Vertex buffer: triangles expanded (3 vertices per face), per vertex position.xyz, normal.xyz,
// atlas uv, triangle index (u32). Colour target rgba16float (HDR), or with `display` an 8-bit
// target holding Reinhard x / (1 + x) sRGB-encoded (twin: output.tonemap): by the target
// (rgba8unorm-srgb), or here with `encode_srgb` (rgba8unorm, which a compute pass can clear);
// depth32float, less-test.
// Template parameters: n_active (lights shaded, a
// compile-time loop count, 0 allowed), display (bool), encode_srgb (bool: display's sRGB
// encoding in the shader), mips (bool: neural objects sample their radiance textures' mip
// chains).
//   fs_neural: bilinear sample of this eye's radiance texture at the atlas uv (clamp-to-edge;
//              the atlas gutter guarantees valid taps); with mips, trilinear over the chain.
//   fs_plain:  ordinary material: Lambert + Blinn-Phong under the same point lights
//              (twin: runtime/reference.py:shade_plain).
//   *_vis:     screen-space modes: plain objects write colour, neural objects write (id + 1, tri)
//              into an rg32uint visibility target and leave colour 0 for the compute pass.

// The uniforms and bindings (declared once, in runtime/interface.py: FRAME, LIGHT, OBJECT,
// forward_bindings).
{{ structs }}

{{ bindings }}

struct VIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tri: u32,
}
struct VOut {
    @builtin(position) clip: vec4<f32>,
    // centroid: with MSAA a pixel that a triangle's edge crosses is shaded at a point inside
    // the triangle's covered samples, not at the pixel's centre outside it (an atlas uv
    // extrapolated past the chart, into its gutter); with one sample it is the centre
    @location(0) @interpolate(perspective, centroid) world: vec3<f32>,
    @location(1) @interpolate(perspective, centroid) normal: vec3<f32>,
    @location(2) @interpolate(perspective, centroid) uv: vec2<f32>,
    @location(3) @interpolate(flat) tri: u32,
}

@vertex
fn vs_main(v: VIn) -> VOut {
    var o: VOut;
    let w = O.model * vec4<f32>(v.pos, 1.0);
    o.clip = F.view_proj * w;
    o.world = w.xyz;
    o.normal = (O.normal_mat * vec4<f32>(v.normal, 0.0)).xyz;
    o.uv = v.uv;
    o.tri = v.tri;
    return o;
}

// The raster floor of `bench frame`: one triangle covering the viewport (vertex_index 0..2, no
// vertex buffer, no bindings), at depth 0.5, drawn with fs_floor_constant.
@vertex
fn vs_screen(@builtin(vertex_index) i: u32) -> VOut {
    var o: VOut;
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    o.clip = vec4<f32>(p * 2.0 - 1.0, 0.5, 1.0);
    return o;
}

// 1 / pi and 1 / (8 pi): the BRDF's constant factors as multiplies (a division per fragment
// and light cost 10% of the pass on lavapipe, `vrneural bench frame`)
const INV_PI: f32 = 0.3183098861837907;
const INV_8PI: f32 = 0.039788735772973836;

// Lambert + normalised Blinn-Phong, two-sided, under the point lights (inverse-square falloff).
// Twin: runtime/reference.py:shade_plain (the same operations in the same order).
fn plain_colour(world: vec3<f32>, normal: vec3<f32>) -> vec3<f32> {
    let n0 = normal * inverseSqrt(dot(normal, normal));
    let v = F.eye.xyz - world;
    let wo = v * inverseSqrt(dot(v, v));
    let n = select(n0, -n0, dot(n0, wo) < 0.0);  // two-sided
    let kd = O.albedo.rgb * INV_PI;
    let ks = O.spec.x * (O.spec.y + 8.0) * INV_8PI;
    var c = vec3<f32>(0.0);
    for (var i = 0u; i < {{ n_active }}u; i++) {
        let lv = lights[i].pos.xyz - world;
        let r = inverseSqrt(max(dot(lv, lv), 1e-12));  // 1 / distance
        let wi = lv * r;
        let cos_i = dot(n, wi);
        if (cos_i <= 0.0) { continue; }
        let hv = wi + wo;
        let s = ks * pow(max(dot(n, hv) * inverseSqrt(dot(hv, hv)), 0.0), O.spec.y);
        c += (kd + vec3<f32>(s)) * (cos_i * r * r) * lights[i].radiance.rgb;
    }
    return min(c, vec3<f32>(65504.0));
}

// what the colour target stores: HDR radiance, or (display) its Reinhard tonemap
fn out_colour(c: vec3<f32>) -> vec4<f32> {
{% if display %}
    let x = c / (vec3<f32>(1.0) + c);
{% if encode_srgb %}
    let srgb = select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * x,
                      x <= vec3<f32>(0.0031308));
    return vec4<f32>(srgb, 1.0);
{% else %}
    return vec4<f32>(x, 1.0);
{% endif %}
{% else %}
    return vec4<f32>(c, 1.0);
{% endif %}
}

@fragment
fn fs_neural(v: VOut) -> @location(0) vec4<f32> {
{% if mips %}
    // trilinear (anisotropic where the sampler allows) over the coverage-premultiplied mip
    // chain (runtime/radiance_mips.py): the colour over the filtered coverage
    let c = textureSample(radiance, samp, v.uv);
    return out_colour(select(vec3<f32>(0.0), c.rgb / c.a, c.a > 1e-4));
{% else %}
    let c = textureSampleLevel(radiance, samp, v.uv, 0.0);
    return out_colour(c.rgb);
{% endif %}
}

@fragment
fn fs_plain(v: VOut) -> @location(0) vec4<f32> {
    return out_colour(plain_colour(v.world, v.normal));
}

// The floors of this pass (`vrneural bench frame`), over the same geometry and targets: a
// constant colour, and one bilinear sample per fragment at its atlas uv (plain objects too:
// their uv is 0) with nothing else.
@fragment
fn fs_floor_constant(v: VOut) -> @location(0) vec4<f32> {
    return out_colour(vec3<f32>(0.5));
}

@fragment
fn fs_floor_sample(v: VOut) -> @location(0) vec4<f32> {
{% if mips %}
    let c = textureSample(radiance, samp, v.uv);  // the same sampling as fs_neural
    return out_colour(select(vec3<f32>(0.0), c.rgb / c.a, c.a > 1e-4));
{% else %}
    return out_colour(textureSampleLevel(radiance, samp, v.uv, 0.0).rgb);
{% endif %}
}

struct VisOut {
    @location(0) colour: vec4<f32>,
    @location(1) vis: vec2<u32>,
}

@fragment
fn fs_plain_vis(v: VOut) -> VisOut {
    var o: VisOut;
    o.colour = vec4<f32>(plain_colour(v.world, v.normal), 1.0);
    o.vis = vec2<u32>(0u, 0u);
    return o;
}

@fragment
fn fs_neural_vis(v: VOut) -> VisOut {
    var o: VisOut;
    o.colour = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    o.vis = vec2<u32>(u32(O.spec.z) + 1u, v.tri);
    return o;
}
